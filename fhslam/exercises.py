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


def check_observation(fn: Callable[[float, float, np.ndarray], tuple[int, float]]) -> str:
    """Check ``fn(rho, theta, pose) -> (dir, d)``: the paper's observation direction
    ``dir = sign(rho - x cos(theta) - y sin(theta))`` and distance ``d`` (Fig. 6)."""
    from fhslam.lines import line_from_points

    rng = np.random.default_rng(3)
    for _ in range(50):
        a, b = rng.uniform(-5, 5, 2), rng.uniform(-5, 5, 2)
        line = line_from_points(np.array([a, b]))
        pose = np.array([*rng.uniform(-6, 6, 2), rng.uniform(-np.pi, np.pi)])
        want = line.observed_from(pose)
        got = fn(line.rho, line.theta, pose)
        if got is None or len(got) != 2:
            raise AssertionError("return a pair (dir, d)")
        if int(got[0]) != want.dir or not np.isclose(got[1], want.d, atol=1e-9):
            raise AssertionError(
                f"line rho={line.rho:.3f} theta={line.theta:.3f}, robot at {pose.round(3)}: "
                f"expected dir={want.dir}, d={want.d:.4f}, got {got}"
            )
    return "correct on 50 random lines and robot poses"


def check_heading_correction(fn: Callable[[np.ndarray, np.ndarray, np.ndarray], float]) -> str:
    """Check ``fn(theta_observed, theta_reference, weights) -> dtheta``: the support-weighted
    mean of the wrapped angle differences ``reference - observed`` (radians)."""
    rng = np.random.default_rng(5)
    for _ in range(50):
        k = rng.integers(1, 8)
        ref = rng.uniform(0, 2 * np.pi, k)
        true = rng.normal(0, 0.05)
        obs = np.mod(ref - true + rng.normal(0, 0.002, k), 2 * np.pi)
        w = rng.integers(5, 200, k).astype(float)
        diff = np.pi - np.mod(np.pi - (ref - obs), 2 * np.pi)
        want = float(np.sum(w * diff) / w.sum())
        got = fn(obs, ref, w)
        if got is None or not np.isclose(got, want, atol=1e-9):
            raise AssertionError(
                f"expected {want:.6f} rad, got {got}; did you wrap the differences to "
                "(-pi, pi] before averaging (0.01 and 6.27 rad are 0.023 rad apart)?"
            )
    return "correct on 50 random sets of matched lines"


def check_ate(fn: Callable[[np.ndarray, np.ndarray], float]) -> str:
    """Check ``fn(estimate (T, 3), truth (T, 3)) -> float``: the ATE rmse (metres) as
    :func:`fhslam.metrics.ate` computes it (translation only, no alignment)."""
    from fhslam.metrics import ate

    rng = np.random.default_rng(11)
    for _ in range(20):
        truth = np.cumsum(rng.normal(0, 0.1, (100, 3)), axis=0)
        est = truth + rng.normal(0, 0.05, (100, 3))
        want = ate(est, truth).rmse
        got = fn(est, truth)
        if got is None or not np.isclose(got, want, rtol=1e-9):
            raise AssertionError(
                f"expected {want:.6f} m, got {got}: the rmse of the position errors "
                "sqrt(mean(dx^2 + dy^2)), ignoring theta"
            )
    return "correct on 20 random trajectories"
