"""Scan-to-map tracking: the front end of :mod:`fhslam.slam.graph`.

Each scan is placed against a local map (the points of the last few keyframes) in two
stages: a correlative search (:func:`fhslam.scanmatch.correlative_search`) over a window
around the odometry prediction, which cannot be caught by a local minimum, then a
point-to-line refinement (:func:`fhslam.scanmatch.refine`) from its optimum, which reaches
millimetres and says how well each direction is constrained.

Real odometry glitches: a heading jump of 30-85° between two scans (MIT CSAIL, Intel), a
position jump of most of a metre. When the match at the prediction is not sure, or after a
doubtful scan, a second search with a wide window runs around the prediction. When the
odometry increment is larger than a robot moves between two scans at a laser's rate (a
glitch, or a sparse log's metre), a third one runs around the previous pose (the robot
stood still); it wins only by a clear margin (``STILL_MARGIN``: a metre along a corridor
looks like standing still). When nothing matches, the odometry prediction is kept: the
fallback.

Turning fast into space the local map has not seen (a 5 Hz laser turning 50° between two
scans), a scan scores low against the map although nothing is wrong. When the map gives no
sure match, the scan is also searched against the previous scan (densified, at its tracked
pose), which has seen most of that space; a sure match there places it. Only a previous scan
placed by a match counts: one left at the odometry's guess (after a glitch on ACES, 70° off)
would pass its error on. A scan placed
with a middling score (under ``sure_score``) by both is not trusted further: the graph
neither starts a keyframe on it nor adds its points to the map.

The local map's grids are built once per keyframe (:meth:`ScanTracker.set_map`), not per
scan.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from fhslam.errors import Range, Ranged
from fhslam.geometry import as_pose, transform_points
from fhslam.scanmatch import (
    LikelihoodGrid,
    PointMap,
    Refinement,
    correlative_search,
    densify,
    refine,
    scan_normals,
    voxel_downsample,
)

__all__ = ["ScanTracker", "Track", "TrackerParams", "is_glitch"]


# Fixed by the method (measured; not parameters):
SIGMA = 0.08
"""Width of the likelihood grid's ``exp(-d²/2σ²)``, metres."""
ANGLE_STEP_DEG = 0.5
"""Heading step of the correlative search, degrees."""
TURN_FRACTION = 0.3
"""The search's heading window grows by this fraction of the odometry's turn."""
SEARCH_PRIOR = (0.5, 0.05)
"""Score given up per metre and per radian from the prediction: of near-equal scores (along
a corridor's axis) the one nearest the prediction wins."""
MAX_STEP = 0.4
"""An odometry increment longer than this (metres)..."""
MAX_TURN_DEG = 25.0
"""... or turning more than this (degrees) is a glitch: the recovery search runs."""


def is_glitch(distance: float, turn_deg: float) -> bool:
    """Whether an odometry increment of ``distance`` metres turning ``turn_deg`` degrees is
    a glitch (longer than ``MAX_STEP`` or turning more than ``MAX_TURN_DEG``): more than a
    robot moves between two scans at a laser's rate (a glitch, or a sparse log's metre)."""
    return bool(distance > MAX_STEP or abs(turn_deg) > MAX_TURN_DEG)


STILL_PRIOR = (0.05, 0.05)
"""The search around the previous pose after a glitch gives up this much score per metre and
per radian: the odometry's increment says nothing then..."""
STILL_MARGIN = 0.05
"""... and it must score this much better than the best match around the prediction to win
(a sparse log's metre along a corridor looks like standing still)."""
QUERY_VOXEL = 0.05
"""The scan is thinned to one point per cell of this size (metres)..."""
MAX_POINTS = 250
"""... and to at most this many points."""
REFINE_DISTANCE = 0.15
"""Point-to-line pairs farther apart than this (metres) are not formed."""
PRIOR_SIGMA = (0.05, 10.0)
"""The odometry prediction enters the refinement as a prior of this standard deviation
(metres, degrees), relative to a point-to-line residual of ``RESIDUAL_SIGMA`` metres: where
the scan says nothing (a corridor's axis) the odometry is kept."""
RESIDUAL_SIGMA = 0.03


@dataclass(frozen=True)
class TrackerParams(Ranged):
    """Parameters of :class:`ScanTracker`.

    Attributes
    ----------
    resolution : float
        Cell of the correlative search's likelihood grid (its translation step), metres.
    window : float
        Search ``± window`` metres around the odometry prediction...
    window_deg : float
        ... and ``± window_deg`` degrees (plus a share of the odometry's turn).
    recovery_window : float
        The search around the previous pose (see the module docs), ± metres...
    recovery_window_deg : float
        ... and ± degrees.
    min_score : float
        A match scoring less (mean likelihood of the scan's points, 0..1) is not used.
    sure_score : float
        A match scoring less is used but not *sure* (:attr:`Track.sure`): the next scan
        searches widely again, and the graph builds nothing on it.
    refine_iterations : int
        Rounds of the point-to-line refinement (each pairs the points anew and takes a
        Gauss-Newton step; the last only measures).
    """

    resolution: float = 0.05
    window: float = 0.2
    window_deg: float = 3.0
    recovery_window: float = 0.6
    recovery_window_deg: float = 45.0
    min_score: float = 0.45
    sure_score: float = 0.6
    refine_iterations: int = 6

    RANGES: ClassVar[dict[str, Range]] = {
        "resolution": Range(0.01, 1.0, unit="m"),
        "window": Range(0.0, 10.0, unit="m"),
        "window_deg": Range(0.0, 180.0, cap=False, unit="degrees"),
        "recovery_window": Range(0.0, 20.0, unit="m"),
        "recovery_window_deg": Range(0.0, 180.0, cap=False, unit="degrees"),
        "min_score": Range(0.0, 1.0, cap=False),
        "sure_score": Range(0.0, 1.0, cap=False),
        "refine_iterations": Range(1, 100, integer=True),
    }
    """The range of each number (:class:`fhslam.errors.Range`), checked when the parameters
    are made. The upper bounds of lengths and counts are limits of plausibility: past them a
    search's grid or loop outgrows any machine; so is the lower bound of ``resolution`` (a
    grid finer than 1 cm over a local map of 50 m holds more than 25 million cells)."""


@dataclass(frozen=True)
class Track:
    """Where :meth:`ScanTracker.track` placed a scan."""

    pose: NDArray[np.float64]
    score: float
    """The correlative score at the chosen pose (0 when nothing matched)."""
    matched: bool
    """Whether the pose comes from the map (else: the odometry prediction)."""
    recovered: bool
    """Whether the recovery search (around the previous pose) won."""
    sure: bool
    """Whether the match scored at least ``sure_score``."""
    refinement: Refinement | None


def _thin(points: NDArray[np.float64], n: int) -> NDArray[np.float64]:
    if len(points) <= n:
        return points
    return points[np.linspace(0, len(points) - 1, n).astype(np.intp)]


class ScanTracker:
    """Places scans in a local map (see the module docs)."""

    def __init__(self, params: TrackerParams | None = None):
        self.params = params or TrackerParams()
        self._grid: LikelihoodGrid | None = None
        self._points: PointMap | None = None
        self._doubt = False  # the last scan was not placed surely
        self._last: NDArray[np.float64] | None = None  # the last matched scan's points

    def set_map(self, points: NDArray[np.float64], normals: NDArray[np.float64]) -> None:
        """Use ``points`` (in the tracking frame) with their ``normals`` (NaN: none; see
        :func:`fhslam.scanmatch.scan_normals`) as the local map from now on."""
        p = self.params
        margin = p.recovery_window + 3 * SIGMA
        pts = voxel_downsample(points, p.resolution / 2)
        if len(pts) < 10:
            self._grid = self._points = None
            return
        self._grid = LikelihoodGrid.build(pts, p.resolution, SIGMA, margin)
        self._points = PointMap.build(points, normals)

    def _wide_search(
        self, grid: LikelihoodGrid, q: NDArray[np.float64], centre: NDArray[np.float64], still: bool
    ) -> tuple[float, NDArray[np.float64]]:
        """The recovery search around ``centre``; ``still``: the previous pose (after a
        glitch), with the weaker prior."""
        p = self.params
        return correlative_search(
            grid,
            q,
            centre,
            p.recovery_window,
            np.radians(p.recovery_window_deg),
            np.radians(ANGLE_STEP_DEG),
            STILL_PRIOR if still else SEARCH_PRIOR,
        )

    def track(
        self,
        points: NDArray[np.float64],
        predicted: NDArray[np.float64],
        previous: NDArray[np.float64],
    ) -> Track:
        """Place a scan (``points`` in the laser frame) near ``predicted`` (the previous pose
        moved by the odometry increment); ``previous`` is the previous scan's pose."""
        p = self.params
        predicted = as_pose(predicted, "predicted")
        last, self._last = self._last, None
        q = _thin(voxel_downsample(points, QUERY_VOXEL), MAX_POINTS)
        if self._grid is None or len(q) < 10:
            self._doubt = True
            return Track(predicted, 0.0, False, False, False, None)
        step = previous[:2] - predicted[:2]
        turn = abs(np.degrees(np.angle(np.exp(1j * (predicted[2] - previous[2])))))
        da = np.radians(ANGLE_STEP_DEG)
        score, pose = correlative_search(
            self._grid,
            q,
            predicted,
            p.window,
            np.radians(p.window_deg + TURN_FRACTION * turn),
            da,
            SEARCH_PRIOR,
        )
        recovered = False
        doubt, self._doubt = self._doubt, True
        glitch = is_glitch(np.hypot(*step), turn)
        if doubt or score < p.sure_score or glitch:
            # Widely around the prediction; after a glitch also around the previous pose (the
            # robot stood still), which must score clearly better to win.
            for still in (False, True) if glitch else (False,):
                centre = as_pose(previous, "previous") if still else predicted
                s2, pose2 = self._wide_search(self._grid, q, centre, still)
                if s2 > score + (STILL_MARGIN if still else 0.02):
                    score, pose, recovered = s2, pose2, still
        target = self._points
        if score < p.sure_score and last is not None and len(last) >= 10:
            # Turning fast into space the map has not seen: the previous scan has seen it.
            centre = as_pose(previous, "previous")
            cloud, normals = densify(last, scan_normals(last))
            c, s = np.cos(centre[2]), np.sin(centre[2])
            cloud, normals = transform_points(centre, cloud), normals @ [[c, s], [-s, c]]
            grid = LikelihoodGrid.build(
                voxel_downsample(cloud, p.resolution / 2),
                p.resolution,
                SIGMA,
                p.recovery_window + 3 * SIGMA,
            )
            s3, pose3 = self._wide_search(grid, q, centre if glitch else predicted, glitch)
            if s3 >= p.sure_score and s3 > score:
                score, pose, recovered = s3, pose3, glitch
                target = PointMap.build(cloud, normals)
        if score < p.min_score:
            return Track(predicted, score, False, False, False, None)
        s_xy, s_deg = PRIOR_SIGMA
        info = RESIDUAL_SIGMA**2 * np.diag([1 / s_xy**2, 1 / s_xy**2, 1 / np.radians(s_deg) ** 2])
        # after a glitch (recovered) the prediction is wrong: no prior then
        prior = None if recovered else (predicted, info)
        ref = refine(target, points, pose, REFINE_DISTANCE, p.refine_iterations, prior=prior)
        if ref.n_matched >= 10 and np.hypot(*(ref.pose[:2] - pose[:2])) <= p.window:
            pose = ref.pose
        self._doubt = score < p.sure_score
        self._last = points  # placed by a match: the next scan may chain on it
        return Track(pose, score, True, recovered, not self._doubt, ref)
