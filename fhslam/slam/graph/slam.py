"""The default SLAM's loop (:class:`GraphFastHoughSLAM`): track each scan, start keyframes,
give the pose graph its edges, and at the end revise every pose and build the line map.

The loop-closure and global-search parts are mixins (:mod:`fhslam.slam.graph.closure`,
:mod:`fhslam.slam.graph.search`); the package docs (:mod:`fhslam.slam.graph`) give the
whole method.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.extraction import extract_lines
from fhslam.geometry import as_pose, compose, relative, transform_points
from fhslam.lines import Line, transform_lines
from fhslam.posegraph import PoseGraph
from fhslam.reference_map import ReferenceMap
from fhslam.scan import Scan
from fhslam.scanmatch import Refinement, densify, scan_normals, smooth_scan, voxel_index
from fhslam.slam.base import FinalEstimate, StepResult
from fhslam.slam.fht import SlamParams
from fhslam.slam.graph.closure import HeldClosure, LoopClosing, LoopClosure
from fhslam.slam.graph.params import GraphSlamParams
from fhslam.slam.graph.search import GlobalSearch
from fhslam.slam.graph.tracker import ScanTracker, is_glitch
from fhslam.slam.graph.worker import InOrder, LoopTargetCache

__all__ = ["GraphFastHoughSLAM", "scan_cloud"]

# Fixed by the method (measured; not a parameter):
MAX_DOUBTFUL = 5
"""A scan the tracker is not sure of starts no keyframe and adds no points, unless this many
in a row were doubtful, or the doubtful scans in a row span ``keyframes.distance`` of
odometry (new ground: a sparse log moves a metre between two scans)."""


def scan_cloud(points: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A scan's points (laser frame, beam order) as they enter a keyframe's cloud, with
    their normals (NaN: none): moved onto the line of their beam neighbours where the
    surface is straight (:func:`fhslam.scanmatch.smooth_scan`: the range noise across a wall
    is averaged out of the map the scans are tracked against, not out of the scans), filled
    in between beams (:func:`fhslam.scanmatch.densify`), the points with a normal first (so
    that thinning to one point per voxel keeps them)."""
    normals = scan_normals(points)
    points = smooth_scan(points, normals)
    dense, dense_normals = densify(points, normals)
    first = np.argsort(np.isnan(dense_normals[:, 0]), kind="stable")
    return dense[first], dense_normals[first]


def _rotate_information(h: NDArray[np.float64], theta: float) -> NDArray[np.float64]:
    """A pose's information ``h`` (translation in the target frame) re-expressed for the
    pose-graph error, whose translation part is in the frame of the pose itself."""
    c, s = np.cos(theta), np.sin(theta)
    b = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return b.T @ h @ b


class GraphFastHoughSLAM(LoopClosing, GlobalSearch):
    """Pose-graph SLAM with scan-to-map tracking, verified loop closures and a map of fast
    Hough lines (see the module docs).

    Parameters
    ----------
    params : GraphSlamParams, optional
        The parameters of the estimate (default: the defaults).
    initial_pose : array-like, shape (3,), optional
        The pose of the first scan; default: the first odometry pose.
    background : bool
        Run the back end (the pose graph, loop closures, optimisation) on a thread of its
        own while the front end tracks the next scans (see :class:`InOrder`): the same
        results, bit for bit, as ``False``, which runs it in turn.
    lines : SlamParams, optional
        The paper's Loops 1 and 2 (the ``fht`` method's parameters, default its defaults):
        each keyframe's fast Hough extraction, and the matching and merging of the map of
        reference lines (:meth:`build_map`). They shape the map only, never a pose.
    """

    def __init__(
        self,
        params: GraphSlamParams | None = None,
        initial_pose: ArrayLike | None = None,
        background: bool = True,
        lines: SlamParams | None = None,
    ):
        self.params = params or GraphSlamParams()
        self.lines = lines or SlamParams()
        for name, kind in (("params", GraphSlamParams), ("lines", SlamParams)):
            if not isinstance(value := getattr(self, name), kind):
                raise TypeError(
                    f"GraphFastHoughSLAM: {name} must be a {kind.__name__}, "
                    f"got {type(value).__name__}"
                )
        self.tracker = ScanTracker(self.params.tracker)
        self._graph = PoseGraph()
        self._loops: list[LoopClosure] = []
        self._background = background
        self._worker: InOrder | None = None
        self._initial = None if initial_pose is None else as_pose(initial_pose, "initial_pose")
        self.origin: NDArray[np.float64] | None = None
        """The first scan's pose: the graph runs in its frame (see :meth:`step`)."""
        self._pose: NDArray[np.float64] | None = None
        self._last_odometry: NDArray[np.float64] | None = None
        self._kf_front: list[NDArray[np.float64]] = []  # keyframe poses, tracking frame
        self._kf_odometry: list[NDArray[np.float64]] = []  # the odometry at each keyframe
        self._clouds: list[NDArray[np.float64]] = []
        self._normals: list[NDArray[np.float64]] = []  # each cloud point's normal or NaN
        self._chunks: list[list[tuple[NDArray, NDArray]]] = []  # scans not yet thinned in
        self._kf_lines: list[list[Line]] = []
        self._views = np.zeros((0, 3))  # each complete keyframe's cloud mean (its frame), θ 0
        self._path: list[float] = []  # distance travelled at each keyframe
        self._last_loop_path = 0.0
        self._doubtful = 0  # doubtful scans in a row
        self._doubt_path = 0.0  # the odometry's path over them, metres
        self._pending: list[HeldClosure] = []
        self._failed: dict[int, int] = {}  # candidate -> the last keyframe it failed for
        self._hypothesis: tuple | None = None  # a global match waiting for another's support
        self._last_global = 0  # the keyframe of the last global search
        self._blind = (0.0, 0.0)  # (blind stretch a global closure ended, path it holds to)
        self._kf_doubt = False  # whether a scan since the last keyframe was doubtful
        self._kf_glitch = False  # whether the odometry glitched since the last keyframe
        self._scan_kf: list[int] = []
        self._scan_rel: list[NDArray[np.float64]] = []
        self.loop_targets = LoopTargetCache()
        """Loop candidates' targets kept between keyframes (see :class:`LoopTargetCache`)."""

    @property
    def keyframe_steps(self) -> NDArray[np.intp]:
        """For each keyframe of :attr:`graph`, the index of the step (the scan) that started
        it, shape (K,)."""
        kf = np.asarray(self._scan_kf, dtype=np.intp)
        return np.flatnonzero(np.diff(kf, prepend=-1))

    # -- the per-scan step -----------------------------------------------------------------
    def step(self, scan: Scan | None, odometry: ArrayLike) -> StepResult:
        """Track one scan, start a keyframe when due, attach the scan to it; returns the
        tracked pose (the tracking frame; :meth:`finish` revises every pose)."""
        p = self.params
        odometry = as_pose(odometry, "odometry")
        pts = None if scan is None else scan.points(max_range=p.keyframes.max_range)[0]
        track = None
        moved = 0.0
        if self._pose is None:
            # Everything inside runs in the first pose's frame, so that where the world frame
            # lies changes nothing but the final composition (grids and voxels are aligned
            # with the axes of this frame).
            self.origin = odometry.copy() if self._initial is None else self._initial.copy()
            pose = np.zeros(3)
        else:
            step = relative(self._last_odometry, odometry)
            moved = float(np.hypot(step[0], step[1]))
            self._kf_glitch = self._kf_glitch or is_glitch(moved, np.degrees(step[2]))
            predicted = compose(self._pose, step)
            pose = predicted
            if pts is not None and len(pts) >= 10:
                track = self.tracker.track(pts, predicted, self._pose)
                pose = track.pose
        self._last_odometry, self._pose = odometry, pose
        lines: list[Line] = []
        # A doubtful scan starts no keyframe and adds no points, unless doubt lasts.
        sure = track is None or track.sure
        self._doubtful = 0 if sure else self._doubtful + 1
        self._doubt_path = 0.0 if sure else self._doubt_path + moved
        lasting = self._doubtful >= MAX_DOUBTFUL or self._doubt_path >= p.keyframes.distance
        self._kf_doubt = self._kf_doubt or not sure
        new = not self._kf_front or ((sure or lasting) and self._keyframe_due(pose))
        if new:
            if scan is not None:
                all_points = scan.points()[0]
                lines = (
                    self.lines.extractor(all_points)
                    if self.lines.extractor
                    else extract_lines(all_points, self.lines.extraction)
                )
            self._new_keyframe(pose, lines, track, odometry)
        k = len(self._kf_front) - 1
        rel = relative(self._kf_front[k], pose)
        self._scan_kf.append(k)
        self._scan_rel.append(rel)
        if pts is not None and len(pts) and (sure or new):
            c, s = np.cos(rel[2]), np.sin(rel[2])
            dense, dense_normals = scan_cloud(pts)
            # thinned to one point per voxel when the cloud is next read (see _cloud)
            self._chunks[k].append(
                (transform_points(rel, dense), dense_normals @ [[c, s], [-s, c]])
            )
        if new:
            self._update_local_map()
        matched = track is not None and track.matched
        return StepResult(compose(self.origin, pose), len(lines), 0, 0, matched, lines)

    def _keyframe_due(self, pose: NDArray[np.float64]) -> bool:
        rel = relative(self._kf_front[-1], pose)
        return bool(
            np.hypot(rel[0], rel[1]) >= self.params.keyframes.distance
            or abs(np.degrees(rel[2])) >= self.params.keyframes.angle_deg
        )

    def _update_local_map(self) -> None:
        k = len(self._kf_front) - 1
        members = range(max(0, k - self.params.keyframes.submap + 1), k + 1)
        self.tracker.set_map(*self._in_frame(self._kf_front, members))

    def _in_frame(self, poses, members, frame=None):
        """The clouds and normals of keyframes ``members`` placed at ``poses`` (in the frame
        of ``frame``, a pose in the same frame, if given)."""
        pts, nrm = [], []
        for m in members:
            x = poses[m] if frame is None else relative(frame, poses[m])
            c, s = np.cos(x[2]), np.sin(x[2])
            cloud, normals = self._cloud(m)
            pts.append(transform_points(x, cloud))
            nrm.append(normals @ [[c, s], [-s, c]])
        return np.vstack(pts), np.vstack(nrm)

    def _cloud(self, m: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Keyframe ``m``'s cloud and normals (its frame): the first point of each
        ``cloud_voxel`` cell, scans in order, within a scan points with a normal first. The
        scans added since the last read are merged here, once: the same points as thinning
        after every scan, without re-sorting the growing cloud each time."""
        if self._chunks[m]:
            cloud = np.vstack([self._clouds[m], *(c for c, _ in self._chunks[m])])
            normals = np.vstack([self._normals[m], *(n for _, n in self._chunks[m])])
            keep = voxel_index(cloud, self.params.keyframes.voxel)
            self._clouds[m], self._normals[m] = cloud[keep], normals[keep]
            self._chunks[m] = []
        return self._clouds[m], self._normals[m]

    def _complete(self, m: int) -> None:
        """Keyframe ``m`` is complete: thin its cloud and note where it looked (the cloud's
        mean, its frame; its origin if it saw nothing)."""
        cloud = self._cloud(m)[0]
        view = [*cloud.mean(axis=0), 0.0] if len(cloud) else np.zeros(3)
        self._views = np.vstack([self._views, view])  # a new array: the back end reads it

    # -- keyframes and edges ---------------------------------------------------------------
    def _information(self, ref: Refinement | None, theta: float) -> NDArray[np.float64]:
        """The information of a refined match (see ``edge_sigma``), in the edge's frame."""
        p = self.params
        if ref is None or ref.n_matched < 10:
            return np.zeros((3, 3))
        h = ref.hessian * (p.edges.points / (ref.n_matched * p.edges.sigma**2))
        return _rotate_information(h, theta)

    def _new_keyframe(self, pose, lines: list[Line], track, odometry) -> None:
        """Start a keyframe at ``pose`` (tracking frame; ``odometry``: the odometry there) and
        give the graph its edge from the previous one."""
        p = self.params
        n = len(self._kf_front)
        if n == 0:
            self._path.append(0.0)
            self._in_turn(self._graph.add_node, pose)
        else:
            z = relative(self._kf_front[-1], pose)
            self._path.append(self._path[-1] + float(np.hypot(z[0], z[1])))
            s_xy, s_deg = p.edges.odometry_sigma
            info = np.diag([1 / s_xy**2, 1 / s_xy**2, 1 / np.radians(s_deg) ** 2])
            sure = track is not None and track.sure and not self._kf_doubt
            if sure:
                info = info + self._information(track.refinement, float(pose[2]))
            elif not self._kf_glitch:
                # The edge carries the odometry's information only: so its measurement is the
                # odometry's too. A doubtful track can be placed far off an odometry that
                # hardly turns (Freiburg hospital, among people: 7-15 degrees at one scan).
                z = relative(self._kf_odometry[-1], odometry)
            self._kf_doubt = self._kf_glitch = False
            # Keyframe n-1 is complete: its cloud is thinned now, so that from here on the
            # back end only reads it.
            self._complete(n - 1)
            self._in_turn(self._add_keyframe, n, z, info)
        self._kf_front.append(pose.copy())
        self._kf_odometry.append(odometry.copy())
        self._clouds.append(np.zeros((0, 2)))
        self._normals.append(np.zeros((0, 2)))
        self._chunks.append([])
        self._kf_lines.append(lines)

    # -- the back end: the graph, in turn (see InOrder) ------------------------------------
    def _in_turn(self, fn, *args) -> None:
        """Run ``fn(*args)`` on the back end's thread after everything given before it (at
        once without a background thread)."""
        if not self._background:
            fn(*args)
            return
        if self._worker is None:
            self._worker = InOrder()
        self._worker.submit(fn, *args)

    def sync(self) -> None:
        """Wait until the back end has done everything given to it so far (and raise what
        it raised)."""
        if self._worker is not None:
            self._worker.wait()

    def _add_keyframe(self, n: int, z, info) -> None:
        """Keyframe ``n`` at ``z`` from keyframe ``n - 1`` with ``info``; then look for loops
        of keyframe ``n - 1``, which is complete."""
        self._graph.add_node(compose(self._graph.pose(n - 1), z))
        self._graph.add_edge(n - 1, n, z, info)
        if n >= 2:
            self._close_loops(n - 1)

    @property
    def graph(self) -> PoseGraph:
        """The pose graph of the keyframes (once the back end has caught up)."""
        self.sync()
        return self._graph

    @property
    def loops(self) -> list[LoopClosure]:
        """Every loop closure that entered the graph, in order (once the back end has caught
        up); see :attr:`accepted_loops`."""
        self.sync()
        return self._loops

    def _submap(self, frame: int, members, poses=None) -> tuple[NDArray, NDArray]:
        """Points and normals of keyframes ``members`` in keyframe ``frame``'s frame (at
        ``poses``, default the graph's)."""
        poses = self._graph.poses if poses is None else poses
        return self._in_frame(poses, members, poses[frame])

    def _looks(self, poses, i: int) -> NDArray[np.float64]:
        """Where keyframes ``0 .. i`` looked: their clouds' means placed at ``poses``."""
        return compose(poses[: i + 1], self._views[: i + 1])[:, :2]

    def _optimize(self) -> None:
        """Optimise; switch off loop edges that stay inconsistent, optimise again."""
        p = self.params
        self._graph.optimize(p.optimiser.iterations, p.optimiser.tol)
        active = [lc for lc in self._loops if self._graph.is_active(lc.edge)]
        if active:
            chi2 = self._graph.chi2(np.array([lc.edge for lc in active]))
            bad = [lc for lc, c in zip(active, chi2, strict=True) if c > p.loops.max_chi2]
            if bad:
                for lc in bad:
                    self._graph.set_active(lc.edge, False)
                self._graph.optimize(p.optimiser.iterations, p.optimiser.tol)
        self.loop_targets.drop_moved(self._graph.poses)

    # -- results ---------------------------------------------------------------------------
    @property
    def accepted_loops(self) -> list[LoopClosure]:
        """The loop closures still in the graph (not switched off as inconsistent)."""
        self.sync()
        return [lc for lc in self._loops if self._graph.is_active(lc.edge)]

    @property
    def poses(self) -> NDArray[np.float64]:
        """Every scan's pose so far: its keyframe's graph pose ⊕ its pose relative to it."""
        if not self._scan_kf:
            return np.zeros((0, 3))
        self.sync()
        local = compose(self._graph.poses[np.array(self._scan_kf)], np.array(self._scan_rel))
        return compose(self.origin, local)

    def finish(self) -> FinalEstimate:
        """Close the last keyframe (look for loops), optimise, and build the map from the
        keyframes at their optimised poses; every scan's pose is revised."""
        self.sync()
        if self._worker is not None:
            self._worker.close()
            self._worker = None
        n = len(self._graph)
        if n >= 2:
            self._complete(n - 1)
            self._close_loops(n - 1)
            self._optimize()
        return FinalEstimate(self.build_map(), self.poses)

    def build_map(self) -> list[Line]:
        """The map of reference lines from the keyframes' lines at their optimised poses
        (:meth:`fhslam.reference_map.ReferenceMap.update`: the front end's policy, applied
        keyframe by keyframe)."""
        fe = self.lines
        if self.origin is None:
            return []
        self.sync()
        refs = ReferenceMap(
            fe.matching, fe.min_reference_length, fe.min_reference_points, fe.max_merge_residual
        )
        for x, lines in zip(compose(self.origin, self._graph.poses), self._kf_lines, strict=True):
            world = transform_lines(lines, x)
            refs.update(world, refs.associate(world, x))
        return refs.lines
