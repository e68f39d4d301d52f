"""The thresholds of Loop 1 (:class:`ExtractionParams`), with the paper's values."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Literal

from fhslam.errors import ParameterError, Range, check_ranges

__all__ = ["ExtractionParams"]

MAX_DENSIFY = 1000
"""Most points :attr:`ExtractionParams.densify_step` may fill into one gap between
neighbouring scan points (the gap is at most ``cluster_gap``)."""


@dataclass(frozen=True)
class ExtractionParams:
    """Thresholds of the fast Hough line extraction (paper: "Improved Fast Hough transform").

    Attributes
    ----------
    cluster_gap : float
        Largest distance between neighbouring scan points inside one cluster, metres
        (paper Figs. 3-4: "if the distance between p_{i+1} and p_i is bigger than a threshold,
        p_{i+1} belongs to the other class"). Also the largest gap inside one line segment.
    densify_step : float
        Spacing of the points added between neighbours inside a cluster ("extend laser scan
        points"), metres; 0 turns densification off. Added points only vote; lines are fitted
        to real scan points.
    pairs : {"random", "all"}
        Point pairs whose slope enters the histogram: ``n_pairs`` seeded random pairs per
        cluster (the paper's step list: "select two points randomly") or every pair in the
        cluster ("the slope between every two points"; O(n^2), for teaching).
    n_pairs : int
        Random pairs drawn per cluster and round.
    min_pair_dist : float
        Pairs closer than this (metres) do not vote: their slope is dominated by range noise.
    angle_bin_deg : float
        Width of a slope-histogram bin ("if the slope is in the setting range"), degrees.
    window_deg : float
        Half-width of the angle window around the dominant angle in which rho is voted,
        degrees. The classical transform votes over the full 0-180°.
    theta_step_deg : float
        Angle step of the restricted Hough accumulator, degrees.
    rho_step : float
        Distance step of the restricted Hough accumulator, metres.
    inlier_dist : float
        A point supports a line when it lies within this distance of it, metres (about four
        times the range noise; chosen on the paper world: 2 cm splits walls).
    refine_iterations : int
        Least-squares refinements of each Hough peak on its inliers (0: report the peak).
    min_points : int
        Support threshold: a line needs at least this many scan points; a cluster is finished
        when its best line has fewer ("until the number ... is lower than the threshold").
    min_length : float
        Shortest segment reported, metres.
    max_lines_per_cluster : int
        Upper bound on the "sub-maximum" rounds per cluster.
    drop_lone_points : bool
        Before clustering, drop a point farther than ``cluster_gap`` from both its neighbours
        while those neighbours are within ``2 * cluster_gap`` of each other: a lone return in
        front of a surface (a chair leg, a person, a spurious echo). The paper's clustering
        would split the surface there; ``False`` keeps the paper's rule exactly.
    max_peaks : int
        Histogram peaks tried per round before a cluster is finished: when the best slope
        holds no line with ``min_points`` support (its pairs straddled two walls), the next
        peak outside its window is tried.
    seed : int
        Seed of the random pair sampling: the same seed gives the same lines.
    """

    cluster_gap: float = 0.3
    densify_step: float = 0.05
    pairs: Literal["random", "all"] = "random"
    n_pairs: int = 128
    min_pair_dist: float = 0.2
    angle_bin_deg: float = 1.0
    window_deg: float = 3.0
    theta_step_deg: float = 0.5
    rho_step: float = 0.02
    inlier_dist: float = 0.04
    refine_iterations: int = 2
    min_points: int = 6
    min_length: float = 0.3
    max_lines_per_cluster: int = 12
    max_peaks: int = 3
    drop_lone_points: bool = True
    seed: int = 0

    RANGES: ClassVar[dict[str, Range]] = {
        "cluster_gap": Range(0.0, 10.0, open_low=True, unit="m"),
        "densify_step": Range(0.0, 10.0, unit="m"),
        "n_pairs": Range(1, 100_000, integer=True),
        "min_pair_dist": Range(0.0, 100.0, unit="m"),
        "angle_bin_deg": Range(0.01, 90.0, unit="degrees"),
        "window_deg": Range(0.0, 90.0, cap=False, unit="degrees"),
        "theta_step_deg": Range(0.01, 90.0, unit="degrees"),
        "rho_step": Range(0.001, 10.0, unit="m"),
        "inlier_dist": Range(0.0, 10.0, open_low=True, unit="m"),
        "refine_iterations": Range(0, 100, integer=True),
        "min_points": Range(2, 1_000_000, integer=True),
        "min_length": Range(0.0, 1000.0, unit="m"),
        "max_lines_per_cluster": Range(1, 10_000, integer=True),
        "max_peaks": Range(1, 1000, integer=True),
        "seed": Range(0, 2**63 - 1, integer=True),
    }
    """The range of each number (:class:`fhslam.errors.Range`), checked when the parameters
    are made. "At most" is a limit of plausibility, and so are the smallest steps: a
    histogram bin or accumulator step finer than that holds millions of cells. Besides,
    ``densify_step`` is 0 (off) or at least ``cluster_gap`` / :data:`MAX_DENSIFY` (the
    points filled into one gap)."""

    def __post_init__(self) -> None:
        if self.pairs not in ("random", "all"):
            raise ParameterError("ExtractionParams", "pairs", self.pairs, "'random' or 'all'")
        check_ranges(self, self.RANGES)
        if 0 < self.densify_step < self.cluster_gap / MAX_DENSIFY:
            raise ParameterError(
                "ExtractionParams",
                "densify_step",
                self.densify_step,
                f"0 (off) or at least cluster_gap / {MAX_DENSIFY} = "
                f"{self.cluster_gap / MAX_DENSIFY:g} m",
            )
