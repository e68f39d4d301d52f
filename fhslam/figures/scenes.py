"""The scenes behind the paper's figures: the simulated logs and the worked examples.

Only data, no drawing (this module does not import Matplotlib): the run through the built-in
``paper`` world simulated with :data:`SEED` (:func:`paper_log`, and :func:`slam_log` with
drifting odometry for Fig. 14), the scan the Loop-1 figures show (:func:`figure_scan`), and
the small hand-made examples of Loop 2 -- the line AB of Fig. 6
(:func:`line_attributes_example`), the line pairs of Figs. 7-10 (:func:`similarity_examples`)
and the segments merged in Fig. 11 (:func:`merging_example`). :mod:`fhslam.figures.paper`
draws them.
"""

from __future__ import annotations

import numpy as np

from fhslam.extraction import ExtractionParams, cluster_scan
from fhslam.io import Log
from fhslam.lines import Line, line_from_points
from fhslam.scan import scan_to_points
from fhslam.sim import OdometryNoise, paper_world, simulate

SEED = 0
"""Seed of the simulation behind every reproduced figure."""


def paper_log(seed: int = SEED) -> Log:
    """The simulated run through the built-in paper world used by the figures."""
    return simulate(paper_world(), seed=seed)


def slam_log(seed: int = SEED) -> Log:
    """The paper world driven with drifting odometry (2-6 m), for the SLAM figures."""
    return simulate(paper_world(), seed=seed, odometry=OdometryNoise.drifting())


def figure_scan(log: Log, params: ExtractionParams | None = None, n_clusters: int = 5) -> int:
    """Index of the first scan whose points fall into ``n_clusters`` clusters (paper Fig. 4
    shows five), skipping the first ten scans; the middle scan if none does."""
    params = params or ExtractionParams()
    for k in range(10, len(log)):
        pts, _ = scan_to_points(log.ranges[k], log.angles, max_range=log.max_range)
        labels = cluster_scan(pts, params.cluster_gap)
        if np.count_nonzero(np.bincount(labels) >= params.min_points) == n_clusters:
            return k
    return len(log) // 2


Pose = tuple[float, float, float]


def _segment(p: tuple[float, float], q: tuple[float, float], n: int = 20) -> Line:
    """A line fitted to ``n`` points evenly spaced from ``p`` to ``q`` (so sp = p, ep = q)."""
    return line_from_points(np.linspace(p, q, n))


def line_attributes_example() -> tuple[Line, Pose]:
    """The line AB and robot pose of Fig. 6: nine slightly noisy scan points on a wall at
    ρ = 2.5 m, θ = 60°, seen from a robot on the origin's side (so ``dir`` = +1)."""
    pose = (1.3, 0.35, float(np.radians(70.0)))
    return line_from_points(_fig06_points(), pose=pose), pose


def _fig06_points() -> np.ndarray:
    rho0, theta0 = 2.5, np.radians(60.0)
    n = np.array([np.cos(theta0), np.sin(theta0)])
    u = np.array([-n[1], n[0]])
    t = np.linspace(-1.6, 1.4, 9)  # scan order: right (A) to left (B) as the robot sees it
    noise = np.random.default_rng(6).normal(0.0, 0.02, len(t))
    return rho0 * n + t[:, None] * u + noise[:, None] * n


SIMILARITY_POSE: Pose = (0.0, 1.0, float(np.pi / 2))
"""The robot pose from which every pair of Figs. 7-10 is seen (so condition (a) holds)."""


def similarity_examples() -> dict[int, tuple[Line, Line, Pose]]:
    """The line pairs of Figs. 7-10 as ``{figure: (reference, new, pose)}``.

    With :class:`~fhslam.matching.MatchParams` defaults (5°, 0.15 m, overlap >= 0) and seen
    from :data:`SIMILARITY_POSE` they reproduce the paper's verdicts: Fig. 7 satisfies all
    of (a)-(d); Fig. 8 satisfies (d) but not (c) (parallel, overlapping, 0.5 m apart);
    Fig. 9 fails (b) and (d) (12° apart, no common part, yet every endpoint within 0.15 m of
    the other line); Fig. 10 fails (b) and (c) (crossing at 60°, so the projections overlap).
    (a) holds in all four.
    """
    ref = _segment((-1.2, 2.0), (1.0, 2.0), 23)
    a9 = np.radians(12.0)
    d9 = np.array([np.cos(a9), np.sin(a9)])
    x9 = np.array([0.0, 2.0])
    a10 = np.radians(60.0)
    d10 = 0.7 * np.array([np.cos(a10), np.sin(a10)])
    x10 = np.array([0.1, 2.0])
    pose = SIMILARITY_POSE
    return {
        7: (ref, _segment((-0.4, 2.04), (1.5, 2.10)), pose),
        8: (ref, _segment((-0.5, 2.5), (1.5, 2.5)), pose),
        9: (
            _segment((-0.65, 2.0), (-0.1, 2.0), 12),
            _segment(tuple(x9 + 0.1 * d9), tuple(x9 + 0.65 * d9), 12),
            pose,
        ),
        10: (ref, _segment(tuple(x10 - d10), tuple(x10 + d10), 15), pose),
    }


def merging_example() -> tuple[Line, Line]:
    """The reference segment EF and the new segment AB of Fig. 11 (similar; AB overlaps EF
    and reaches beyond E, so EF is extended to C, the projection of A)."""
    ef = _segment((1.0, 1.0), (4.0, 1.0), 61)
    ab = _segment((-0.5, 1.03), (2.0, 1.06), 26)
    return ef, ab
