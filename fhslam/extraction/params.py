"""The thresholds of Loop 1 (:class:`ExtractionParams`), with the paper's values."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

__all__ = ["ExtractionParams"]


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

    def __post_init__(self) -> None:
        positive = ("cluster_gap", "angle_bin_deg", "theta_step_deg", "rho_step", "inlier_dist")
        for name in positive:
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"ExtractionParams.{name} must be a positive number, got {v!r}")
        if not (np.isfinite(self.densify_step) and self.densify_step >= 0):
            raise ValueError(f"ExtractionParams.densify_step must be >= 0, got {self.densify_step}")
        if self.pairs not in ("random", "all"):
            raise ValueError(
                f"ExtractionParams.pairs must be 'random' or 'all', got {self.pairs!r}"
            )
        if self.min_points < 2:
            raise ValueError(f"ExtractionParams.min_points must be >= 2, got {self.min_points}")
        if (
            self.window_deg < 0
            or self.n_pairs < 1
            or self.refine_iterations < 0
            or self.max_peaks < 1
        ):
            raise ValueError(
                "ExtractionParams: window_deg, n_pairs, refine_iterations out of range"
            )
