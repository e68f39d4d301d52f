"""Loop 3 of the paper: step-by-step self-calibration and map building (FH-SLAM).

Paper, "Self calibration and map building" and the simulation's step list:

1. receive the scan and the odometry; predict the pose from the odometry increment;
2. extract the scan's lines (Loop 1) and place them in the world at the predicted pose;
3. if there are no reference lines yet, the (longer) lines become the reference lines;
4. otherwise match them to the reference lines (Loop 2), compute the pose error from the
   matched pairs and calibrate the robot's pose (:func:`calibrate_pose`);
5. re-place the lines with the calibrated pose, merge the matched ones into their reference
   lines (Fig. 11) and add new long lines as reference lines;
6. the map is the list of reference lines.

A step without a scan (dropped), without lines or without a match keeps the odometry
prediction. Where the matched lines do not constrain a direction (a corridor: all lines
parallel) the pose is not corrected along it (see :func:`calibrate_pose`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray
from tqdm.auto import tqdm

from fhslam.extraction import ExtractionParams, extract_lines
from fhslam.geometry import (
    as_pose,
    compose,
    inverse,
    point_segment_distance,
    relative,
    signed_distance,
    wrap_angle,
)
from fhslam.io.log import scan_of
from fhslam.lines import Line, transform_lines
from fhslam.matching import MatchParams, match_lines, merge
from fhslam.scan import scan_to_points


@dataclass(frozen=True)
class SlamParams:
    """Parameters of FH-SLAM's Loop 3 (and the loops it calls).

    Attributes
    ----------
    extraction : ExtractionParams
        Loop 1.
    matching : MatchParams
        Loop 2, used to associate new lines with reference lines.
    min_reference_length : float
        New lines at least this long (metres) become reference lines ("generally speaking
        we choose one or several longer straight lines").
    min_reference_points : int
        ... and supported by at least this many scan points.
    iterations : int
        Rounds of "match, compute the pose error, correct" per step.
    min_eigen_ratio : float
        A direction is constrained by the matched lines only when the information in it is
        at least this fraction of the strongest direction's (corridor test).
    max_correction : float
        Largest accepted pose correction per step, metres; a bigger one is taken as a wrong
        association and the odometry prediction is kept.
    max_rotation_deg : float
        Largest accepted heading correction per step, degrees.
    robust_scale : float or None
        Huber scale of the calibration's endpoint residuals, metres (see
        :func:`calibrate_pose`).
    extractor : callable or None
        Loop 1 to use instead of the fast Hough transform: ``points (N, 2) -> list[Line]``
        (e.g. :func:`fhslam.baselines.hough_opencv_pointset`, to measure what the fast
        transform contributes). ``None``: :func:`fhslam.extraction.extract_lines` with
        ``extraction``.
    max_merge_residual : float
        After calibration, a matched line is merged into its reference line only if both of
        its endpoints lie within this distance of it, metres; a worse pair was a wrong match
        and would corrupt the map.
    """

    extraction: ExtractionParams = field(default_factory=ExtractionParams)
    matching: MatchParams = field(default_factory=MatchParams)
    min_reference_length: float = 0.6
    min_reference_points: int = 10
    iterations: int = 3
    min_eigen_ratio: float = 0.05
    max_correction: float = 0.5
    max_rotation_deg: float = 10.0
    robust_scale: float | None = 0.02
    max_merge_residual: float = 0.05
    extractor: Callable[[NDArray[np.float64]], list[Line]] | None = None


@dataclass(frozen=True)
class Calibration:
    """Result of :func:`calibrate_pose`."""

    pose: NDArray[np.float64]
    correction: NDArray[np.float64]
    constrained: tuple[bool, bool]
    n_pairs: int


def calibrate_pose(
    observed: Sequence[Line],
    references: Sequence[Line],
    pairs: Sequence[tuple[int, int]],
    pose: ArrayLike,
    iterations: int = 3,
    min_eigen_ratio: float = 0.05,
    robust_scale: float | None = 0.02,
) -> Calibration:
    """The robot pose that best lays the observed lines onto their reference lines.

    "Compute the deviation angle and distance between the new detecting line segment and the
    corresponding referenced one and calibrate the robot's pose." The deviation of a pair is
    measured where it is seen: the signed distances of the observed segment's two endpoints
    (placed in the world at the current pose) to the reference line. The pose correction
    ``(dx, dy, dtheta)``, rotating about the robot, minimises their support-weighted squares
    (Gauss-Newton, ``iterations`` rounds). Distances measured this way do not depend on where
    the world origin lies, unlike differences of the lines' Hessian ``rho``.

    Along an eigen-direction of the 3 x 3 normal matrix whose information is under
    ``min_eigen_ratio`` of the largest (all matched lines parallel: a corridor), the pose is
    not corrected: the odometry is kept there rather than a correction invented.

    Parameters
    ----------
    observed : sequence of Line
        Lines in the robot frame.
    references : sequence of Line
        Reference lines in the world frame.
    pairs : sequence of (int, int)
        ``(observed index, reference index)`` of the matched lines.
    pose : array-like, shape (3,)
        The predicted pose ``world_T_robot``.
    iterations : int
        Gauss-Newton rounds.
    min_eigen_ratio : float
        Corridor test threshold (see above).
    robust_scale : float or None
        Huber scale of the endpoint residuals, metres: a residual ``r`` beyond it is
        down-weighted by ``robust_scale / |r|`` (iteratively reweighted least squares), so one
        wrong pair (e.g. a line fitted across a shallow corner) cannot drag the pose. ``None``
        gives plain least squares.

    Returns
    -------
    Calibration
        The calibrated pose, the correction applied ``(dx, dy, dtheta)``, whether the
        position is constrained along its weakest / strongest directions, and the number of
        pairs.
    """
    pose0 = as_pose(pose)
    x = pose0.copy()
    if not pairs:
        return Calibration(x, np.zeros(3), (False, False), 0)
    obs = [observed[i] for i, _ in pairs]
    refs = [references[j] for _, j in pairs]
    # Each pair contributes its two endpoints; robot-frame points (2P, 2).
    q = np.array([[o.sp, o.ep] for o in obs]).reshape(-1, 2)
    th_r = np.repeat([r.theta for r in refs], 2)
    rho_r = np.repeat([r.rho for r in refs], 2)
    n_r = np.column_stack([np.cos(th_r), np.sin(th_r)])
    w0 = np.repeat([min(o.n, r.n) for o, r in zip(obs, refs, strict=True)], 2).astype(float)
    constrained = (False, False)
    for _ in range(iterations):
        c, s_ = np.cos(x[2]), np.sin(x[2])
        rel = q @ np.array([[c, s_], [-s_, c]])  # rotated into the world, relative to robot
        p_w = rel + x[:2]
        r = rho_r - np.einsum("ij,ij->i", n_r, p_w)  # signed distance to the reference
        jac = np.column_stack([n_r, n_r[:, 1] * rel[:, 0] - n_r[:, 0] * rel[:, 1]])
        w = (
            w0
            if robust_scale is None
            else w0 * np.minimum(1.0, robust_scale / np.maximum(np.abs(r), 1e-12))
        )
        h = (jac * w[:, None]).T @ jac
        # Position information left once the heading is free (Schur complement): its
        # weak eigen-direction, if any, is the corridor's axis.
        schur = h[:2, :2] - np.outer(h[:2, 2], h[2, :2]) / max(h[2, 2], 1e-12)
        evals, evecs = np.linalg.eigh(schur)
        ok = evals > min_eigen_ratio * max(evals[1], 1e-12)
        constrained = (bool(ok[0]), bool(ok[1]))
        basis = np.zeros((3, int(ok.sum()) + 1))  # constrained position directions + heading
        basis[:2, :-1] = evecs[:, ok]
        basis[2, -1] = 1.0
        jr = jac @ basis
        delta = (
            basis
            @ np.linalg.lstsq((jr * w[:, None]).T @ jr, (jr * w[:, None]).T @ r, rcond=None)[0]
        )
        x = x + delta
        x[2] = wrap_angle(x[2])
    correction = x - pose0
    correction[2] = wrap_angle(correction[2])
    return Calibration(x, correction, constrained, len(pairs))


@dataclass
class StepResult:
    """What one SLAM step did."""

    pose: NDArray[np.float64]
    n_lines: int
    n_matched: int
    n_added: int
    corrected: bool
    lines: list[Line] = field(default_factory=list, repr=False)
    """The scan's lines in the robot frame (Loop 1's output)."""


@dataclass
class SlamResult:
    """A whole run: one pose per scan, and the map."""

    timestamps: NDArray[np.float64]
    poses: NDArray[np.float64]
    map: list[Line]
    steps: list[StepResult] = field(repr=False)


class FastHoughSLAM:
    """The paper's step-by-step SLAM: fast Hough lines, four-condition matching, pose
    calibration from matched lines, merging into a map of reference lines.

    Parameters
    ----------
    params : SlamParams, optional
    initial_pose : array-like, shape (3,), optional
        The known pose of the first scan ("suppose the initial localization of mobile robot
        is correct"); default: the first odometry pose.

    Examples
    --------
    >>> slam = FastHoughSLAM()
    >>> for ranges, odo in zip(log.ranges, log.odometry):       # doctest: +SKIP
    ...     slam.step(ranges, log.angles, odo, max_range=log.max_range)
    >>> slam.references                                           # doctest: +SKIP
    """

    def __init__(self, params: SlamParams | None = None, initial_pose: ArrayLike | None = None):
        self.params = params or SlamParams()
        self.references: list[Line] = []
        self.pose: NDArray[np.float64] | None = (
            None if initial_pose is None else as_pose(initial_pose, "initial_pose")
        )
        self._last_odometry: NDArray[np.float64] | None = None
        self._ends_of: list[int] = []  # ids of the reference lines _end_array holds
        self._ends_keep: list[Line] = []
        self._end_array = np.zeros((0, 4))

    def predict(self, odometry: ArrayLike) -> NDArray[np.float64]:
        """Move the pose estimate by the odometry increment since the last step."""
        odo = as_pose(odometry, "odometry")
        if self.pose is None:
            self.pose = odo.copy()
        elif self._last_odometry is not None:
            self.pose = compose(self.pose, relative(self._last_odometry, odo))
        self._last_odometry = odo
        return self.pose

    def step(
        self,
        ranges: ArrayLike | None,
        angles: ArrayLike | None,
        odometry: ArrayLike,
        max_range: float | None = None,
    ) -> StepResult:
        """One step of the paper's procedure; ``ranges=None`` is a dropped scan."""
        p = self.params
        pose = self.predict(odometry)
        if ranges is None:
            return StepResult(pose.copy(), 0, 0, 0, False)
        points, _ = scan_to_points(ranges, angles, max_range=max_range)
        observed = p.extractor(points) if p.extractor else extract_lines(points, p.extraction)
        if not self.references:
            added = self._add_references(observed, pose, np.full(len(observed), -1))
            return StepResult(pose.copy(), len(observed), 0, added, False, observed)
        # Only reference lines within reach can pass conditions (c) and (d): preselect them.
        near = self._nearby(pose, observed)
        refs = [self.references[j] for j in near]
        corrected = False
        world = transform_lines(observed, pose)
        for _ in range(2):  # associate at the prediction, calibrate, re-associate
            match = match_lines(world, refs, p.matching, pose)
            pairs = [(i, int(j)) for i, j in enumerate(match) if j >= 0]
            cal = calibrate_pose(
                observed,
                refs,
                pairs,
                pose,
                p.iterations,
                p.min_eigen_ratio,
                p.robust_scale,
            )
            if (
                np.hypot(*cal.correction[:2]) > p.max_correction
                or abs(np.degrees(cal.correction[2])) > p.max_rotation_deg
            ):
                break  # implausible: a wrong association; keep the prediction
            corrected = corrected or cal.n_pairs > 0
            pose = cal.pose
            world = transform_lines(observed, pose)
        self.pose = pose
        # Re-place the lines with the calibrated pose; merge the matched ones into the map.
        match = match_lines(world, refs, p.matching, pose)
        match = np.where(match >= 0, near[np.maximum(match, 0)], -1) if len(near) else match
        for ln, j in zip(world, match, strict=True):
            if j >= 0:
                ref = self.references[j]
                off = np.abs(signed_distance(np.array([ln.sp, ln.ep]), ref.rho, ref.theta))
                if off.max() <= p.max_merge_residual:
                    self._set_reference(j, merge(ref, ln))
        added = self._add_references(observed, pose, match)
        n_matched = int((match >= 0).sum())
        return StepResult(pose.copy(), len(observed), n_matched, added, corrected, observed)

    def _ends(self) -> NDArray[np.float64]:
        """Endpoints (K, 4) of the reference lines, cached; rebuilt if the list was changed
        from outside (checked once per step, in :meth:`_nearby`)."""
        ids = [*map(id, self.references)]
        if ids != self._ends_of:
            self._ends_of = ids
            self._ends_keep = list(self.references)  # alive, so their ids stay unique
            self._end_array = np.array([[*ln.sp, *ln.ep] for ln in self.references]).reshape(-1, 4)
        return self._end_array

    def _set_reference(self, j: int, line: Line) -> None:
        self.references[j] = line
        self._ends_of[j] = id(line)
        self._ends_keep[j] = line
        self._end_array[j] = [*line.sp, *line.ep]

    def _nearby(self, pose: NDArray[np.float64], observed: Sequence[Line]) -> NDArray[np.intp]:
        """Indices of the reference lines that can match one of ``observed`` (robot frame):
        a matching reference has a point within ``max_distance`` (+ any allowed gap) of an
        observed segment, so within that of the farthest observed endpoint's range."""
        ends = self._ends()
        if not observed or len(ends) == 0:
            return np.zeros(0, dtype=np.intp)
        m = self.params.matching
        reach = max(max(np.hypot(*ln.sp), np.hypot(*ln.ep)) for ln in observed)
        reach += m.max_distance + max(0.0, -m.min_overlap) + 1e-6
        dist = point_segment_distance(pose[:2], ends[:, :2], ends[:, 2:])
        return np.flatnonzero(dist <= reach)

    def _add_references(self, observed: Sequence[Line], pose: NDArray, match: NDArray) -> int:
        p = self.params
        new = transform_lines(
            [
                ln
                for ln, j in zip(observed, match, strict=True)
                if j < 0 and ln.length >= p.min_reference_length and ln.n >= p.min_reference_points
            ],
            pose,
        )
        ends = self._ends()  # sync the cache, then extend both
        self.references.extend(new)
        self._ends_of.extend(map(id, new))
        self._ends_keep.extend(new)
        rows = np.array([[*ln.sp, *ln.ep] for ln in new]).reshape(-1, 4)
        self._end_array = np.vstack([ends, rows])
        return len(new)

    def run(self, log, progress: bool = False) -> SlamResult:
        """Run over a whole log (any object with ``timestamps``, ``ranges``, ``angles``,
        ``odometry`` and ``max_range``); scans whose ranges are all NaN count as dropped."""
        steps = []
        it = range(len(log.timestamps))
        for k in tqdm(
            it, desc=f"FH-SLAM {getattr(log, 'name', '')}", unit="scan", disable=not progress
        ):
            steps.append(self.step(*scan_of(log, k), log.odometry[k], log.max_range))
        poses = np.array([s.pose for s in steps]).reshape(-1, 3)
        return SlamResult(
            np.asarray(log.timestamps, dtype=float), poses, list(self.references), steps
        )


METHODS = ("fht", "graph", "classical", "ekf", "odometry")
"""SLAM methods: FH-SLAM (the paper's procedure), FH-SLAM on a pose graph with loop closures
(:mod:`fhslam.graphslam`, for long real logs), FH-SLAM with OpenCV's classical Hough as
Loop 1, the EKF line-SLAM baseline, and dead reckoning."""


def run_slam(
    log, method: str = "fht", params: SlamParams | None = None, progress: bool = False
) -> SlamResult:
    """Run a SLAM method (one of :data:`METHODS`) over a log.

    Every method starts at the first odometry pose, which a simulated log sets to the true
    start ("suppose the initial localization of mobile robot is correct").
    """
    offset = getattr(log, "laser_offset", None)
    if offset is not None and np.any(offset != 0) and method != "odometry":
        # The laser sits off the robot's origin: estimate laser poses, report robot poses.
        laser_log = replace(log, odometry=compose(log.odometry, offset), laser_offset=None)
        r = run_slam(laser_log, method, params, progress)
        return replace(r, poses=compose(r.poses, inverse(offset)))
    if method == "odometry":
        return SlamResult(
            np.asarray(log.timestamps, float), np.asarray(log.odometry, float), [], []
        )
    if method == "fht":
        return FastHoughSLAM(params).run(log, progress=progress)
    if method == "graph":
        from fhslam.graphslam import GraphFastHoughSLAM, GraphSlamParams

        gp = GraphSlamParams() if params is None else GraphSlamParams(front_end=params)
        return GraphFastHoughSLAM(gp).run(log, progress=progress)
    if method == "classical":
        from fhslam.baselines import hough_opencv_pointset

        p = replace(params or SlamParams(), extractor=hough_opencv_pointset)
        return FastHoughSLAM(p).run(log, progress=progress)
    if method == "ekf":
        from fhslam.baselines.ekf_slam import EKFLineSLAM

        return EKFLineSLAM().run(log, progress=progress)
    raise ValueError(f"unknown SLAM method {method!r}; choose one of {', '.join(METHODS)}")
