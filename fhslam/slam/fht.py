"""Loop 3 of the paper: step-by-step self-calibration and map building (FH-SLAM).

Paper, "Self calibration and map building" and the simulation's step list:

1. receive the scan and the odometry; predict the pose from the odometry increment;
2. extract the scan's lines (Loop 1) and place them in the world at the predicted pose;
3. if there are no reference lines yet, the (longer) lines become the reference lines;
4. otherwise match them to the reference lines (Loop 2), compute the pose error from the
   matched pairs and calibrate the robot's pose (:func:`fhslam.calibration.calibrate_pose`);
5. re-place the lines with the calibrated pose, merge the matched ones into their reference
   lines (Fig. 11) and add new long lines as reference lines
   (:class:`fhslam.reference_map.ReferenceMap`);
6. the map is the list of reference lines.

A step without a scan (dropped), without lines or without a match keeps the odometry
prediction. Where the matched lines do not constrain a direction (a corridor: all lines
parallel) the pose is not corrected along it (see :func:`fhslam.calibration.calibrate_pose`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.calibration import calibrate_pose
from fhslam.errors import ParameterError, Range, check_ranges
from fhslam.extraction import ExtractionParams, extract_lines
from fhslam.geometry import as_pose, compose, relative
from fhslam.lines import Line, transform_lines
from fhslam.matching import MatchParams
from fhslam.reference_map import ReferenceMap
from fhslam.scan import Scan
from fhslam.slam.base import FinalEstimate, StepResult

__all__ = ["FastHoughSLAM", "SlamParams"]


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

    RANGES: ClassVar[dict[str, Range]] = {
        "min_reference_length": Range(0.0, 1000.0, unit="m"),
        "min_reference_points": Range(0, 1_000_000, integer=True),
        "iterations": Range(1, 100, integer=True),
        "min_eigen_ratio": Range(0.0, 1.0, cap=False),
        "max_correction": Range(0.0, 100.0, unit="m"),
        "max_rotation_deg": Range(0.0, 180.0, cap=False, unit="degrees"),
        "robust_scale": Range(0.0, 10.0, open_low=True, optional=True, unit="m"),
        "max_merge_residual": Range(0.0, 10.0, unit="m"),
    }
    """The range of each number (:class:`fhslam.errors.Range`), checked when the parameters
    are made (``extraction`` and ``matching`` check their own); "at most": a limit of
    plausibility."""

    def __post_init__(self) -> None:
        for name, kind in (("extraction", ExtractionParams), ("matching", MatchParams)):
            if not isinstance(getattr(self, name), kind):
                raise ParameterError("SlamParams", name, getattr(self, name), f"a {kind.__name__}")
        if not (self.extractor is None or callable(self.extractor)):
            raise ParameterError("SlamParams", "extractor", self.extractor, "callable or None")
        check_ranges(self, self.RANGES)


class FastHoughSLAM:
    """The paper's step-by-step SLAM: fast Hough lines, four-condition matching, pose
    calibration from matched lines, merging into a map of reference lines.

    A SLAM back end (:class:`fhslam.slam.Backend`): :func:`fhslam.run_slam` drives it over a
    log, or call :meth:`step` yourself.

    Parameters
    ----------
    params : SlamParams, optional
    initial_pose : array-like, shape (3,), optional
        The known pose of the first scan ("suppose the initial localization of mobile robot
        is correct"); default: the first odometry pose.

    Examples
    --------
    >>> slam = FastHoughSLAM()
    >>> for k in range(len(log)):                                  # doctest: +SKIP
    ...     slam.step(log.scan(k), log.odometry[k])
    >>> slam.references                                           # doctest: +SKIP
    """

    def __init__(self, params: SlamParams | None = None, initial_pose: ArrayLike | None = None):
        self.params = params or SlamParams()
        p = self.params
        self.map = ReferenceMap(
            p.matching, p.min_reference_length, p.min_reference_points, p.max_merge_residual
        )
        self.pose: NDArray[np.float64] | None = (
            None if initial_pose is None else as_pose(initial_pose, "initial_pose")
        )
        self._last_odometry: NDArray[np.float64] | None = None

    @property
    def references(self) -> list[Line]:
        """The reference lines (the map) so far, world frame."""
        return self.map.lines

    def predict(self, odometry: ArrayLike) -> NDArray[np.float64]:
        """Move the pose estimate by the odometry increment since the last step."""
        odo = as_pose(odometry, "odometry")
        if self.pose is None:
            self.pose = odo.copy()
        elif self._last_odometry is not None:
            self.pose = compose(self.pose, relative(self._last_odometry, odo))
        self._last_odometry = odo
        return self.pose

    def extract(self, scan: Scan) -> list[Line]:
        """Loop 1 on a scan: its lines in the laser frame."""
        p = self.params
        points, _ = scan.points()
        return p.extractor(points) if p.extractor else extract_lines(points, p.extraction)

    def step(self, scan: Scan | None, odometry: ArrayLike) -> StepResult:
        """One step of the paper's procedure (see the module docs); ``scan=None`` is a
        dropped scan."""
        p = self.params
        pose = self.predict(odometry)
        if scan is None:
            return StepResult(pose.copy(), 0, 0, 0, False)
        observed = self.extract(scan)
        if not len(self.map):
            world = transform_lines(observed, pose)
            added = self.map.update(world, np.full(len(observed), -1))
            return StepResult(pose.copy(), len(observed), 0, added, False, observed)
        # Only reference lines within reach can pass conditions (c) and (d): preselect them.
        near = self.map.nearby(pose, self._reach(observed)) if observed else np.zeros(0, np.intp)
        refs = self.map.lines
        corrected = False
        world = transform_lines(observed, pose)
        for _ in range(2):  # associate at the prediction, calibrate, re-associate
            match = self.map.associate(world, pose, near)
            pairs = [(i, int(j)) for i, j in enumerate(match) if j >= 0]
            cal = calibrate_pose(
                observed, refs, pairs, pose, p.iterations, p.min_eigen_ratio, p.robust_scale
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
        match = self.map.associate(world, pose, near)
        added = self.map.update(world, match)
        n_matched = int((match >= 0).sum())
        return StepResult(pose.copy(), len(observed), n_matched, added, corrected, observed)

    def _reach(self, observed: Sequence[Line]) -> float:
        """How far from the robot a reference line matching one of ``observed`` (robot frame)
        can lie: a matching reference has a point within ``max_distance`` (+ any allowed gap)
        of an observed segment, so within that of the farthest observed endpoint's range."""
        m = self.params.matching
        reach = max(max(np.hypot(*ln.sp), np.hypot(*ln.ep)) for ln in observed)
        return reach + m.max_distance + max(0.0, -m.min_overlap) + 1e-6

    def finish(self) -> FinalEstimate:
        """The map; the steps' poses stand."""
        return FinalEstimate(self.map.lines)
