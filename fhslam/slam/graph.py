"""FH-SLAM on a pose graph: the paper's method made to survive long real logs.

On a simulated world the paper's step-by-step calibration keeps the pose within centimetres
(:mod:`fhslam.slam.fht`). On the Intel Research Lab log (45 minutes, 600 m, the same rooms
visited again and again) it drifts by metres: every reference line is placed with the pose
of its time, and nothing ever corrects a line placed wrongly, so the errors stay in the map
and feed back into the pose. What the real logs need, and this module adds:

1. **The paper's loops as the front end.** :class:`fhslam.slam.FastHoughSLAM` runs scan by
   scan (Loops 1-3), giving smooth, locally accurate poses (a few centimetres between
   scans seconds apart on Intel).
2. **Keyframes.** Every ``keyframe_distance`` metres or ``keyframe_angle_deg`` degrees of
   travel a keyframe starts; the scans until the next one are attached to it with their
   front-end poses relative to it, and their points form its cloud.
3. **Odometry edges by scan-to-submap matching.** When a keyframe is complete, its cloud
   is matched (:func:`fhslam.scanmatch.match_clouds`, a small window) against the clouds of
   the previous ``submap_keyframes`` keyframes, refining the front end's relative motion.
4. **Loop closures.** The completed keyframe is matched against up to ``loop_candidates``
   old keyframes within ``loop_radius`` of it (a large window, exhaustive search); a match
   scoring at least ``loop_min_score`` adds a loop edge with a Cauchy kernel, and the graph
   is re-optimised (:mod:`fhslam.posegraph`).
5. **The map of reference lines** is built at the end by Loop 2 itself: each keyframe's fast
   Hough lines, placed at its optimised pose, are matched with and merged into the map
   (Fig. 11), and long unmatched lines are added - the paper's map, from better poses.

Each scan's pose is its keyframe's optimised pose composed with the scan's front-end pose
relative to the keyframe.

Optionally (``GraphSlamParams(predict=True)``) each scan is first matched against the recent
keyframe clouds and the match replaces a clearly worse odometry increment before the front
end sees it. This rescues MIT CSAIL (whose odometry heading is poor: 1.40 m → 0.040 m mean
relation error) but derails Intel at an odometry glitch (0.041 m → 2.1 m), so it is off by
default: an open problem, shown in notebook 08.

``method="graph"`` in :func:`fhslam.pipeline.run_slam` and ``fhslam slam --method graph`` run it;
``method="fht"`` stays the paper's procedure.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.geometry import as_pose, compose, relative, transform_points
from fhslam.lines import Line, transform_lines
from fhslam.posegraph import PoseGraph
from fhslam.reference_map import ReferenceMap
from fhslam.scan import Scan
from fhslam.scanmatch import match_clouds, voxel_downsample
from fhslam.slam.base import FinalEstimate, StepResult
from fhslam.slam.fht import FastHoughSLAM, SlamParams

__all__ = ["GraphFastHoughSLAM", "GraphSlamParams", "LoopClosure"]


@dataclass(frozen=True)
class GraphSlamParams:
    """Parameters of :class:`GraphFastHoughSLAM`.

    Attributes
    ----------
    front_end : SlamParams
        The paper's loops, run scan by scan.
    keyframe_distance : float
        Start a keyframe after this much travel, metres...
    keyframe_angle_deg : float
        ... or this much turning, degrees.
    cloud_max_range : float
        Points farther than this from the laser (metres) stay out of the clouds.
    cloud_voxel : float
        A keyframe's cloud keeps one point per cell of this size, metres.
    submap_keyframes : int
        Keyframes in the local submap an odometry edge is matched against.
    predict : bool
        Whether to correct the odometry by scan matching before the front end (below).
    predict_window : float
        Each scan is first matched against the last two keyframes' clouds (in the front
        end's frame) within ± this many metres of the odometry prediction...
    predict_window_deg : float
        ... and ± this many degrees plus ``predict_turn_fraction`` of the odometry's turn
        since the last scan; a good match replaces the odometry increment the front end
        sees (see :meth:`GraphFastHoughSLAM._matched_odometry`).
    predict_turn_fraction : float
        See ``predict_window_deg``.
    predict_min_gain : float
        The match replaces the odometry only if it raises the coarse score by at least
        this much over the odometry's own pose: odometry that already fits is kept, and a
        match that is not clearly better cannot lead the front end astray.
    odometry_window : float
        Search window of odometry edges, ± metres...
    odometry_window_deg : float
        ... and ± degrees.
    odometry_min_score : float
        Below this match score an odometry edge keeps the front end's relative motion.
    odometry_sigma : (float, float)
        Standard deviation of an odometry edge: metres, degrees.
    loop_radius : float
        Old keyframes within this distance (at the current estimate) are loop candidates.
    loop_min_gap : int
        ... if at least this many keyframes older.
    loop_candidates : int
        Nearest candidates tried per keyframe.
    loop_window : float
        Search window of a loop closure, ± metres...
    loop_window_deg : float
        ... and ± degrees.
    loop_min_score : float
        Smallest fine-grid score (mean likelihood of the query points, 0..1) accepted.
    loop_sigma : (float, float)
        Standard deviation of a loop edge: metres, degrees.
    loop_kernel : float
        Cauchy kernel scale of loop edges (Mahalanobis units).
    optimize_iterations : int
        Largest number of Gauss-Newton rounds after a keyframe that closed a loop...
    optimize_tol : float
        ... which stop once no pose moves more than this (metres, radians).
    """

    front_end: SlamParams = field(default_factory=SlamParams)
    keyframe_distance: float = 0.5
    keyframe_angle_deg: float = 20.0
    cloud_max_range: float = 20.0
    cloud_voxel: float = 0.02
    submap_keyframes: int = 5
    predict: bool = False
    predict_window: float = 0.2
    predict_window_deg: float = 8.0
    predict_turn_fraction: float = 0.2
    predict_min_gain: float = 0.2
    odometry_window: float = 0.3
    odometry_window_deg: float = 5.0
    odometry_min_score: float = 0.2
    odometry_sigma: tuple[float, float] = (0.02, 0.5)
    loop_radius: float = 2.5
    loop_min_gap: int = 20
    loop_candidates: int = 2
    loop_window: float = 1.5
    loop_window_deg: float = 15.0
    loop_min_score: float = 0.6
    loop_sigma: tuple[float, float] = (0.05, 1.0)
    loop_kernel: float = 1.0
    optimize_iterations: int = 5
    optimize_tol: float = 1e-4

    def __post_init__(self) -> None:
        for name in ("keyframe_distance", "keyframe_angle_deg", "cloud_max_range", "cloud_voxel"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)}")
        if self.submap_keyframes < 1 or self.loop_candidates < 0 or self.loop_min_gap < 1:
            raise ValueError(
                "submap_keyframes and loop_min_gap must be >= 1 and loop_candidates >= 0"
            )
        if not 0 <= self.loop_min_score <= 1:
            raise ValueError(f"loop_min_score must be in [0, 1], got {self.loop_min_score}")


@dataclass(frozen=True)
class LoopClosure:
    """An accepted loop closure: keyframe ``new`` seen from the older keyframe ``old``."""

    old: int
    new: int
    pose: NDArray[np.float64]
    score: float


def _information(sigma: tuple[float, float]) -> NDArray[np.float64]:
    s_xy, s_deg = sigma
    return np.array([1 / s_xy**2, 1 / s_xy**2, 1 / np.radians(s_deg) ** 2])


class GraphFastHoughSLAM:
    """FH-SLAM with keyframes, scan-to-submap odometry edges and loop closures (see the
    module docs).

    Parameters
    ----------
    params : GraphSlamParams, optional
    initial_pose : array-like, shape (3,), optional
        The pose of the first scan; default: the first odometry pose.
    """

    def __init__(
        self, params: GraphSlamParams | None = None, initial_pose: ArrayLike | None = None
    ):
        self.params = params or GraphSlamParams()
        self.front_end = FastHoughSLAM(self.params.front_end, initial_pose)
        self.graph = PoseGraph()
        self.loops: list[LoopClosure] = []
        self._kf_front: list[NDArray[np.float64]] = []  # keyframe poses in the front end's frame
        self._clouds: list[NDArray[np.float64]] = []
        self._kf_lines: list[list[Line]] = []
        self._odometry_edge: list[int] = [-1]  # per keyframe: the edge from its predecessor
        self._scan_kf: list[int] = []
        self._scan_rel: list[NDArray[np.float64]] = []
        self._last_odometry: NDArray[np.float64] | None = None
        self._corrected: NDArray[np.float64] | None = None

    # -- keyframes -------------------------------------------------------------------------
    def _new_keyframe(self, front_pose: NDArray[np.float64], lines: list[Line]) -> None:
        p = self.params
        n = len(self.graph)
        if n == 0:
            self.graph.add_node(front_pose)
        else:
            if n >= 2:
                self._refine_odometry_edge(n - 1)
            z = relative(self._kf_front[-1], front_pose)
            self.graph.add_node(compose(self.graph.pose(n - 1), z))
            self._odometry_edge.append(
                self.graph.add_edge(n - 1, n, z, _information(p.odometry_sigma))
            )
            if n >= 2:
                self._close_loops(n - 1)
        self._kf_front.append(front_pose.copy())
        self._clouds.append(np.zeros((0, 2)))
        self._kf_lines.append(lines)

    def _submap(self, frame: int, members) -> NDArray[np.float64]:
        x = self.graph.pose(frame)
        return np.vstack(
            [transform_points(relative(x, self.graph.pose(m)), self._clouds[m]) for m in members]
        )

    def _refine_odometry_edge(self, i: int) -> None:
        """Match the completed keyframe ``i`` against its predecessors; refine edge i-1 -> i."""
        p = self.params
        target = self._submap(i - 1, range(max(0, i - p.submap_keyframes), i))
        guess = relative(self.graph.pose(i - 1), self.graph.pose(i))
        m = match_clouds(target, self._clouds[i], guess, p.odometry_window, p.odometry_window_deg)
        if m.score >= p.odometry_min_score:
            self.graph.set_measurement(self._odometry_edge[i], m.pose)
            self.graph.set_pose(i, compose(self.graph.pose(i - 1), m.pose))

    def _close_loops(self, i: int) -> None:
        p = self.params
        if p.loop_candidates == 0 or i <= p.loop_min_gap:
            return
        poses = self.graph.poses
        old = poses[: i - p.loop_min_gap + 1]
        d = np.hypot(old[:, 0] - poses[i, 0], old[:, 1] - poses[i, 1])
        cands = [
            int(j)
            for j in np.argsort(d, kind="stable")[: p.loop_candidates]
            if d[j] <= p.loop_radius
        ]
        if not cands:
            return
        query = self._submap(i, range(max(0, i - 2), i + 1))
        # Right after a loop closure the pose is known well: search a small window only.
        tracking = bool(self.loops) and self.loops[-1].new == i - 1
        win, win_deg = (
            (p.odometry_window, p.odometry_window_deg)
            if tracking
            else (p.loop_window, p.loop_window_deg)
        )
        closed = False
        for j in cands[:1] if tracking else cands:
            target = self._submap(j, range(max(0, j - 3), min(j + 4, i - p.loop_min_gap + 1)))
            m = match_clouds(target, query, relative(poses[j], poses[i]), win, win_deg)
            if m.score >= p.loop_min_score:
                self.graph.add_edge(
                    j, i, m.pose, _information(p.loop_sigma), p.loop_kernel, kind="loop"
                )
                self.loops.append(LoopClosure(j, i, m.pose, m.score))
                closed = True
        if closed:
            self.graph.optimize(p.optimize_iterations, p.optimize_tol)

    # -- the per-scan step -----------------------------------------------------------------
    def step(self, scan: Scan | None, odometry: ArrayLike) -> StepResult:
        """Run the front end on one scan, start a keyframe when due, attach the scan to it;
        returns the front end's step (its pose in the front end's frame)."""
        p = self.params
        odometry = as_pose(odometry, "odometry")
        pts = None if scan is None else scan.points(max_range=p.cloud_max_range)[0]
        res = self.front_end.step(scan, self._matched_odometry(odometry, pts))
        pose = res.pose
        if not self._kf_front or self._keyframe_due(pose):
            self._new_keyframe(pose, res.lines)
        k = len(self.graph) - 1
        rel = relative(self._kf_front[k], pose)
        self._scan_kf.append(k)
        self._scan_rel.append(rel)
        if pts is not None and len(pts):
            cloud = np.vstack([self._clouds[k], transform_points(rel, pts)])
            self._clouds[k] = voxel_downsample(cloud, p.cloud_voxel)
        return res

    def _matched_odometry(
        self, odometry: NDArray[np.float64], pts: NDArray[np.float64] | None
    ) -> NDArray[np.float64]:
        """The odometry stream the front end sees: each increment of the wheel odometry
        replaced by the scan's match against the recent keyframe clouds, when it matches.

        Between two scans a real robot may turn by 10-25° (mit-csail at 5 Hz), and wheel
        odometry gets turns wrong by several per cent; the front end's line matching only
        tolerates ``max_angle_deg`` (5°). Matching the points first gives it a prediction
        within a fraction of a degree.
        """
        p = self.params
        last, self._last_odometry = self._last_odometry, odometry
        if last is None or self._corrected is None:
            self._corrected = odometry.copy()
            return self._corrected
        inc = relative(last, odometry)
        fe_pose = self.front_end.pose
        moved = np.hypot(inc[0], inc[1]) > 1e-3 or abs(inc[2]) > np.radians(0.05)
        if p.predict and moved and pts is not None and len(pts) >= 10 and self._kf_front:
            k = len(self._kf_front) - 1
            target = np.vstack(
                [
                    transform_points(self._kf_front[m], self._clouds[m])
                    for m in range(max(0, k - 1), k + 1)
                ]
            )
            if len(target) >= 10:
                guess = compose(fe_pose, inc)
                turn = abs(np.degrees(inc[2]))
                m = match_clouds(
                    target,
                    pts,
                    guess,
                    p.predict_window,
                    p.predict_window_deg + p.predict_turn_fraction * turn,
                )
                if (
                    m.score >= p.odometry_min_score
                    and m.coarse_score - m.guess_score >= p.predict_min_gain
                ):
                    inc = relative(fe_pose, m.pose)
        self._corrected = compose(self._corrected, inc)
        return self._corrected

    def _keyframe_due(self, pose: NDArray[np.float64]) -> bool:
        rel = relative(self._kf_front[-1], pose)
        return bool(
            np.hypot(rel[0], rel[1]) >= self.params.keyframe_distance
            or abs(np.degrees(rel[2])) >= self.params.keyframe_angle_deg
        )

    # -- results ---------------------------------------------------------------------------
    @property
    def poses(self) -> NDArray[np.float64]:
        """Every scan's pose so far: its keyframe's graph pose ⊕ its pose relative to it."""
        if not self._scan_kf:
            return np.zeros((0, 3))
        return compose(self.graph.poses[np.array(self._scan_kf)], np.array(self._scan_rel))

    def finish(self) -> FinalEstimate:
        """Close the last keyframe (refine its edge, look for loops), optimise, and build the
        map from the keyframes at their optimised poses; every scan's pose is revised."""
        n = len(self.graph)
        if n >= 2:
            self._refine_odometry_edge(n - 1)
            self._close_loops(n - 1)
            self.graph.optimize(self.params.optimize_iterations, self.params.optimize_tol)
        return FinalEstimate(self.build_map(), self.poses)

    def build_map(self) -> list[Line]:
        """The map of reference lines from the keyframes' lines at their optimised poses
        (:meth:`fhslam.reference_map.ReferenceMap.update`: the front end's policy, applied
        keyframe by keyframe)."""
        fe = self.params.front_end
        refs = ReferenceMap(
            fe.matching, fe.min_reference_length, fe.min_reference_points, fe.max_merge_residual
        )
        for x, lines in zip(self.graph.poses, self._kf_lines, strict=True):
            world = transform_lines(lines, x)
            refs.update(world, refs.associate(world, x))
        return refs.lines
