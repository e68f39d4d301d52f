"""Checks for the notebooks' exercises: each receives the student's function and either
returns a short success message or raises ``AssertionError`` saying what went wrong."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from fhslam.extraction import cluster_scan


def _same_partition(a: np.ndarray, b: np.ndarray) -> bool:
    """Two labelings describe the same clusters (label values may differ)."""
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape:
        return False
    return bool(np.array_equal(np.diff(a) != 0, np.diff(b) != 0))


def clustering_cases() -> list[tuple[str, np.ndarray, float]]:
    """The cases :func:`check_clustering` tries: (description, points, gap)."""
    rng = np.random.default_rng(7)
    t = np.linspace(0, 4, 41)
    wall = np.column_stack([t, np.full_like(t, 2.0)])
    door = np.vstack([wall[:15], wall[25:]])  # a 1.0 m gap in the wall
    scan = np.cumsum(rng.normal(0, 0.15, (120, 2)), axis=0)  # random steps, some over the gap
    return [
        ("one straight wall", wall, 0.3),
        ("a wall with a doorway", door, 0.3),
        ("a random walk of points", scan, 0.2),
        ("a single point", wall[:1], 0.3),
        ("points exactly gap apart (not a break: the rule is 'bigger than')", wall, 0.1),
    ]


def check_clustering(fn: Callable[[np.ndarray, float], np.ndarray]) -> str:
    """Check a student's clustering ``fn(points, gap) -> labels`` against paper Figs. 3-4.

    The rule: a new cluster starts at point ``i+1`` when ``|p[i+1] - p[i]| > gap``.
    """
    for what, pts, gap in clustering_cases():
        got = fn(pts.copy(), gap)
        if got is None:
            raise AssertionError(f"{what}: your function returned None; return the labels")
        want = cluster_scan(pts, gap)
        if not _same_partition(got, want):
            raise AssertionError(
                f"{what} (gap {gap} m): expected {len(np.unique(want))} clusters with breaks "
                f"after points {np.flatnonzero(np.diff(want)).tolist()}, got labels "
                f"{np.asarray(got).tolist()[:20]}..."
            )
    return f"correct on all {len(clustering_cases())} cases"
