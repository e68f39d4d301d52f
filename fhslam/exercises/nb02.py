"""Exercises of notebook 02, the scan and its clusters (paper Figs. 2-4)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from fhslam.exercises import Feedback, Wrong, call, check_choice, check_value, exercise
from fhslam.extraction import cluster_scan

__all__ = [
    "check_clustering",
    "check_point_spacing",
    "check_small_gap_reading",
    "clustering_cases",
]


def check_point_spacing(answer: Any, distance: float = 4.0, step_deg: float = 1.0) -> Feedback:
    """Exercise 2.1 (predict): the distance between the two points that beams ``step_deg``
    apart, either side of the perpendicular, make on a wall ``distance`` metres away:
    ``2 distance tan(step / 2)`` (about ``distance * step`` in radians)."""
    expected = 2 * distance * np.tan(np.radians(step_deg) / 2)
    return check_value(
        answer,
        expected,
        tolerance=0.005,
        what="my_spacing",
        unit=" m",
        hint=f"Two beams {step_deg:g}° apart diverge by about distance × angle in radians.",
    )


def clustering_cases() -> list[tuple[str, np.ndarray, float]]:
    """The cases :func:`check_clustering` tries: (description, points, gap).

    Spacings are multiples of 1/8 m, exact in binary floating point, so that the case of
    neighbours exactly ``gap`` apart is exact and not decided by the last bit.
    """
    rng = np.random.default_rng(7)
    t = np.arange(33) * 0.125  # 0 .. 4 m in exact steps of 1/8 m
    wall = np.column_stack([t, np.full_like(t, 2.0)])
    door = np.vstack([wall[:12], wall[20:]])  # a 1.0 m gap in the wall
    walk = np.cumsum(rng.normal(0, 0.15, (120, 2)), axis=0)  # random steps, some over the gap
    return [
        ("one straight wall", wall, 0.3),
        ("a wall with a doorway", door, 0.3),
        ("a random walk of points", walk, 0.2),
        ("a single point", wall[:1], 0.3),
        ("neighbours exactly gap apart (no break: the rule is 'farther than')", wall, 0.125),
        ("neighbours just over gap apart (every point its own cluster)", wall, 0.12),
    ]


def _breaks(labels: np.ndarray) -> list[int]:
    return (np.flatnonzero(np.diff(labels) != 0) + 1).tolist()


def _short(items: list[int], n: int = 8) -> str:
    return (
        str(items) if len(items) <= n else f"[{', '.join(map(str, items[:n]))}, ...] ({len(items)})"
    )


@exercise("my_cluster")
def check_clustering(fn: Callable[[np.ndarray, float], Any]) -> str:
    """Exercise 2.3 (implement): ``fn(points, gap) -> labels``, one integer per point, a new
    cluster starting at point ``i+1`` exactly when ``|p[i+1] - p[i]| > gap`` (Figs. 3-4).
    Label values may differ from the package's; the clusters must be the same."""
    cases = clustering_cases()
    for what, pts, gap in cases:
        got = call(fn, pts.copy(), gap)
        if got is None:
            raise Wrong(f"{what}: your function returned None; return the labels")
        got = np.asarray(got)
        if got.shape != (len(pts),):
            raise Wrong(
                f"{what}: expected {len(pts)} labels (one per point), got shape {got.shape}"
            )
        want = cluster_scan(pts, gap)
        if _breaks(got) != _breaks(want):
            want_at, got_at = _short(_breaks(want)), _short(_breaks(got))
            raise Wrong(
                f"{what} (gap {gap} m): a new cluster should start at points {want_at}, "
                f"yours start at {got_at}"
            )
    return f"the same clusters as fhslam.extraction.cluster_scan in all {len(cases)} cases"


def check_small_gap_reading(answer: Any) -> Feedback:
    """Exercise 2.2 (interpret): why a 5 cm gap cuts scan ``k`` into about 150 clusters."""
    return check_choice(
        answer,
        right="b",
        why={
            "a": "the simulated range noise is 1 cm (standard deviation), far below 5 cm; "
            "noise alone breaks few neighbours.",
            "b": "beams 1° apart land about 1.7 cm apart per metre of range, so every wall "
            "farther than about 3 m is more than 5 cm between points and falls apart.",
            "c": "clustering runs before densification, and the added points never create "
            "clusters: they are inserted inside clusters only.",
        },
    )
