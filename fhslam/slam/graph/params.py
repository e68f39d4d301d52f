"""The parameters of the default SLAM (:class:`~fhslam.slam.GraphFastHoughSLAM`), in groups.

Every field can be set, for one run, with ``fhslam slam LOG --set GROUP.NAME=VALUE`` (e.g.
``--set loops.min_score=0.6``) or in Python::

    from dataclasses import replace
    params = GraphSlamParams(loops=replace(LoopParams(), min_score=0.6))

Each number has a range (:class:`fhslam.errors.Range`) checked when its group is made: a
value out of it raises :class:`fhslam.errors.ParameterError` naming the group, the field,
the range and the value. Units: metres, degrees (fields ending in ``_deg``), counts of
keyframes. The constants the method fixes (not parameters: their values were measured and
nobody needs to touch them) sit beside the code that uses them, in
:mod:`fhslam.slam.graph.tracker`, :mod:`~fhslam.slam.graph.closure`,
:mod:`~fhslam.slam.graph.search` and :mod:`~fhslam.slam.graph.slam`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, is_dataclass
from typing import ClassVar

from fhslam.errors import ParameterError, Range, Ranged
from fhslam.slam.graph.tracker import TrackerParams

__all__ = [
    "EdgeParams",
    "GlobalSearchParams",
    "GraphSlamParams",
    "KeyframeParams",
    "LoopParams",
    "OptimiserParams",
    "TrackerParams",
    "count_parameters",
]


@dataclass(frozen=True)
class KeyframeParams(Ranged):
    """When a keyframe starts, and what its cloud of points keeps.

    Attributes
    ----------
    distance : float
        A keyframe starts after this much travel, metres...
    angle_deg : float
        ... or this much turning, degrees.
    max_range : float
        Points farther than this from the laser enter no cloud, metres.
    voxel : float
        A keyframe's cloud keeps one point per cell of this size, metres.
    submap : int
        Keyframes in the local map a scan is tracked against.
    """

    distance: float = 0.5
    angle_deg: float = 20.0
    max_range: float = 20.0
    voxel: float = 0.02
    submap: int = 5

    RANGES: ClassVar[dict[str, Range]] = {
        "distance": Range(0.0, 100.0, open_low=True, unit="m"),
        "angle_deg": Range(0.0, 360.0, open_low=True, cap=False, unit="degrees"),
        "max_range": Range(0.0, 1000.0, open_low=True, unit="m"),
        "voxel": Range(0.0, 1.0, open_low=True, unit="m"),
        "submap": Range(1, 1000, integer=True),
    }


@dataclass(frozen=True)
class EdgeParams(Ranged):
    """The information of an edge between consecutive keyframes.

    Attributes
    ----------
    sigma : float
        Standard deviation of a point-to-line distance, metres...
    points : float
        ... counted as this many independent points: the refinement's Hessian is scaled to
        ``points / (n · sigma²)`` (``n``: the points it paired).
    odometry_sigma : (float, float)
        The odometry prior each edge also carries: metres, degrees.
    """

    sigma: float = 0.03
    points: float = 25.0
    odometry_sigma: tuple[float, float] = (0.1, 2.0)

    RANGES: ClassVar[dict[str, Range]] = {
        "sigma": Range(0.0, 10.0, open_low=True, unit="m"),
        "points": Range(0.0, 1e6, open_low=True),
        "odometry_sigma": Range(0.0, 1000.0, open_low=True, items=2),
    }


@dataclass(frozen=True)
class LoopParams(Ranged):
    """The local loop-closure search (:mod:`fhslam.slam.graph.closure`).

    Attributes
    ----------
    candidates : int
        Old keyframes tried per keyframe, those that looked nearest where it looks; 0: none.
    min_gap : int
        Candidates are at least this many keyframes older.
    radius : float
        Candidates looked within this distance of where the keyframe looks, metres...
    growth : float
        ... plus this fraction of the travel since the last closure (the drift since)...
    max_radius : float
        ... up to this, metres.
    target_keyframes : int
        A candidate's target is its cloud and this many keyframes' on either side.
    window : float
        The match's search window, ± metres (grows like ``radius``, to at most 3 m)...
    window_deg : float
        ... and ± degrees.
    min_score : float
        Smallest fine-grid score (mean likelihood of the query's points, 0..1) accepted.
    max_chi2 : float
        After an optimisation, a loop edge whose squared Mahalanobis error is above this is
        switched off.
    confirm_distance : float
        A closure that would move its keyframe more than this (metres) waits until an
        independent closure agrees with it...
    consistency : float
        ... placing the keyframe within this many metres of it.
    """

    candidates: int = 2
    min_gap: int = 20
    radius: float = 2.5
    growth: float = 0.05
    max_radius: float = 8.0
    target_keyframes: int = 6
    window: float = 1.0
    window_deg: float = 15.0
    min_score: float = 0.55
    max_chi2: float = 25.0
    confirm_distance: float = 0.1
    consistency: float = 0.15

    RANGES: ClassVar[dict[str, Range]] = {
        "candidates": Range(0, 1000, integer=True),
        "min_gap": Range(1, 1_000_000, integer=True),
        "radius": Range(0.0, 1000.0, unit="m"),
        "growth": Range(0.0, 10.0, open_low=True),
        "max_radius": Range(0.0, 1000.0, unit="m"),
        "target_keyframes": Range(0, 1000, integer=True),
        "window": Range(0.0, 100.0, unit="m"),
        "window_deg": Range(0.0, 180.0, cap=False, unit="degrees"),
        "min_score": Range(0.0, 1.0, cap=False),
        "max_chi2": Range(0.0, 1e9),
        "confirm_distance": Range(0.0, 100.0, open_low=True, unit="m"),
        "consistency": Range(0.0, 100.0, open_low=True, unit="m"),
    }


@dataclass(frozen=True)
class GlobalSearchParams(Ranged):
    """The global search for a place seen long ago (:mod:`fhslam.slam.graph.search`).

    Attributes
    ----------
    every : int
        Once ``after`` metres passed without a closure, the search runs every this many
        keyframes; 0: never.
    after : float
        Metres of travel without a closure before it starts; its targets are this much older.
    keyframes : int
        The query: the clouds of this many last keyframes.
    min_score : float
        The score (0..1) a unique match needs to be held as a hypothesis...
    confirm_score : float
        ... and the score of the independent match that confirms it (at most ``min_score``).
    window_deg : float
        ± degrees searched around each guess.
    max_window : float
        ± metres searched at most (the window grows with the travel since the last closure).
    """

    every: int = 20
    after: float = 10.0
    keyframes: int = 9
    min_score: float = 0.55
    confirm_score: float = 0.5
    window_deg: float = 30.0
    max_window: float = 50.0

    RANGES: ClassVar[dict[str, Range]] = {
        "every": Range(0, 1_000_000, integer=True),
        "after": Range(0.0, 1e6, unit="m"),
        "keyframes": Range(1, 1000, integer=True),
        "min_score": Range(0.0, 1.0, cap=False),
        "confirm_score": Range(0.0, 1.0, cap=False),
        "window_deg": Range(0.0, 180.0, open_low=True, cap=False, unit="degrees"),
        "max_window": Range(0.0, 500.0, open_low=True, unit="m"),
    }


@dataclass(frozen=True)
class OptimiserParams(Ranged):
    """The Gauss-Newton optimisation of the pose graph (:class:`fhslam.posegraph.PoseGraph`).

    Attributes
    ----------
    iterations : int
        Largest number of rounds after a keyframe that closed a loop...
    tol : float
        ... which stop once no pose moves more than this (metres, radians).
    """

    iterations: int = 10
    tol: float = 1e-4

    RANGES: ClassVar[dict[str, Range]] = {
        "iterations": Range(1, 1000, integer=True),
        "tol": Range(0.0, 1.0),
    }


@dataclass(frozen=True)
class GraphSlamParams:
    """Parameters of :class:`~fhslam.slam.GraphFastHoughSLAM`, one group per job.

    Attributes
    ----------
    keyframes : KeyframeParams
        When keyframes start, what their clouds keep.
    tracker : TrackerParams
        Scan-to-map tracking (:mod:`fhslam.slam.graph.tracker`).
    edges : EdgeParams
        The information of the edges between consecutive keyframes.
    loops : LoopParams
        The local loop-closure search.
    search : GlobalSearchParams
        The global search after a long stretch without a closure.
    optimiser : OptimiserParams
        The pose graph's Gauss-Newton rounds.

    These are all the parameters of the estimate. The map of fast Hough lines drawn from the
    keyframes takes the paper's own (the ``fht`` method's :class:`~fhslam.slam.SlamParams`,
    :class:`~fhslam.slam.GraphFastHoughSLAM`'s ``lines``): they move no pose.
    """

    keyframes: KeyframeParams = field(default_factory=KeyframeParams)
    tracker: TrackerParams = field(default_factory=TrackerParams)
    edges: EdgeParams = field(default_factory=EdgeParams)
    loops: LoopParams = field(default_factory=LoopParams)
    search: GlobalSearchParams = field(default_factory=GlobalSearchParams)
    optimiser: OptimiserParams = field(default_factory=OptimiserParams)

    def __post_init__(self) -> None:
        for f in fields(self):
            kind = f.default_factory  # each group's class
            if not isinstance(getattr(self, f.name), kind):
                raise ParameterError(
                    "GraphSlamParams", f.name, getattr(self, f.name), f"a {kind.__name__}"
                )


def count_parameters(params: object) -> int:
    """The number of leaf fields of a dataclass of parameters, its groups opened:
    ``count_parameters(GraphSlamParams())`` is the default method's parameters."""
    n = 0
    for f in fields(params):
        value = getattr(params, f.name)
        n += count_parameters(value) if is_dataclass(value) else 1
    return n
