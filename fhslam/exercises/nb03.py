"""Exercises of notebook 03, the fast Hough extraction step by step (paper Fig. 5): the slope
between every two points of a cluster, the vote restricted to a window, the support threshold."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.exercises import Feedback, Wrong, call, check_choice, exercise
from fhslam.extraction import (
    ExtractionParams,
    dominant_angle,
    extract_lines,
    restricted_hough,
    slope_histogram,
)

__all__ = [
    "ALL_PAIRS",
    "check_line_count",
    "check_pair_angles",
    "check_window_reading",
    "pair_angle_cases",
]

#: The slope histogram over every pair, none left out for being short: what
#: :func:`check_pair_angles` compares the student's directions with.
ALL_PAIRS = ExtractionParams(pairs="all", min_pair_dist=0.0)

_TOL = 1e-9  # radians; the cases' directions are far apart from each other and from 0 and π


def pair_angle_cases() -> list[tuple[str, np.ndarray]]:
    """The cases :func:`check_pair_angles` tries: (description, points (N, 2)).

    Coordinates are small integers or halves, exact in floating point, except the noisy wall.
    """
    rng = np.random.default_rng(3)
    t = np.arange(12) * 0.25
    direction = np.radians(120.0)
    noisy = np.column_stack([1 + t * np.cos(direction), 2 + t * np.sin(direction)])
    noisy += rng.normal(0.0, 0.01, noisy.shape)
    return [
        ("two points, the second 2 m right and 1 m up", np.array([[0.0, 0.0], [2, 1]])),
        ("two points of a horizontal wall, scanned right to left", np.array([[2.0, 1.0], [0, 1]])),
        ("three points of a corner", np.array([[0.0, 0.0], [2, 0], [2, 2]])),
        (
            "a wall going down to the left, in scan order",
            np.array([[3.0, 2.0], [2, 1.5], [1, 1], [0, 0.5]]),
        ),
        ("a vertical wall scanned top to bottom", np.array([[1.0, 3.0], [1, 2], [1, 1], [1, 0]])),
        ("12 points of a noisy wall at 120°", noisy),
    ]


def _reference(points: np.ndarray) -> NDArray[np.float64]:
    """Direction in [0, π) of the line through every pair i < j, as the slope histogram's
    kernel computes it (atan2, negative angles folded by + π)."""
    i, j = np.triu_indices(len(points), k=1)
    d = points[j] - points[i]
    return np.mod(np.arctan2(d[:, 1], d[:, 0]), np.pi)


def _canonical(a: np.ndarray) -> np.ndarray:
    """Sorted directions modulo π, with values a hair under π counted as 0."""
    a = np.mod(a, np.pi)
    return np.sort(np.where(a > np.pi - _TOL, 0.0, a))


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """The same directions (modulo π), in any order."""
    return bool(np.all(np.abs(_canonical(a) - _canonical(b)) <= _TOL))


def _degrees(a: np.ndarray) -> str:
    return ", ".join(f"{x:.1f}°" for x in np.degrees(a))


def _bins(a: np.ndarray, n_bins: int) -> np.ndarray:
    """The slope histogram's bins of directions in [0, π]."""
    k = np.minimum((a * n_bins / np.pi).astype(int), n_bins - 1)
    return np.bincount(k, minlength=n_bins)


def _edge_safe(a: np.ndarray, n_bins: int) -> bool:
    """No direction within 1e-6 of a bin edge (in bins) nor of 0 or π: binning is not a
    matter of the last bit there."""
    x = a * n_bins / np.pi
    return bool(np.all(np.abs(x - np.round(x)) > 1e-6))


def _angles(got: Any, what: str, n: int) -> np.ndarray:
    """The student's directions as a flat float array of one per pair, or :class:`Wrong`."""
    pairs = n * (n - 1) // 2
    give = f"{n} points give {pairs} pair{'s' if pairs > 1 else ''}"
    if got is None:
        raise Wrong(f"{what}: your function returned None; return one angle per pair of points")
    try:
        a = np.asarray(got, dtype=float)
    except (TypeError, ValueError):
        raise Wrong(
            f"{what}: return an array of angles (numbers), got {type(got).__name__}"
        ) from None
    if a.size == n * n and n > 1:
        raise Wrong(
            f"{what}: {give}, you returned {a.size} angles — an N × N "
            "table counts every pair twice and each point with itself; take each pair i < j once"
        )
    if a.size == n * (n - 1) and n > 1:
        raise Wrong(
            f"{what}: {give}, you returned {a.size} angles — (i, j) and "
            "(j, i) are the same line: take each pair i < j once"
        )
    if a.size == n - 1 and n > 2:
        raise Wrong(
            f"{what}: {give}, you returned {n - 1} — only neighbours? "
            "The paper takes the slope between every two points of the cluster"
        )
    if a.size != pairs:
        raise Wrong(f"{what}: {give} (i < j), you returned {a.size} angles (shape {a.shape})")
    a = a.ravel()
    if not np.all(np.isfinite(a)):
        raise Wrong(
            f"{what}: NaN or inf among your angles — a point paired with itself, or dy / dx "
            "with dx = 0? np.arctan2(dy, dx) needs no division"
        )
    return a


def _diagnose(a: np.ndarray, want: np.ndarray, what: str) -> str:
    """Why directions ``a`` are not ``want``: the usual mistakes first."""
    if np.abs(a).max() > np.pi + _TOL and _same(np.radians(a), want):
        return f"{what}: your angles are in degrees (up to {np.abs(a).max():.0f}); return radians"
    if _same(a, want):  # the right directions, not folded
        bad = a[(a < -_TOL) | (a > np.pi + _TOL)]
        return (
            f"{what}: the right directions, but {_degrees(bad[:1])} is not in [0, π): fold it "
            f"(it is the same line as {_degrees(np.mod(bad[:1], np.pi))}); atan2 gives (−180°, "
            "180°], atan (−90°, 90°): add π to the negative ones"
        )
    if _same(a - np.pi / 2, want):
        return (
            f"{what}: those are the normals' angles (direction + 90°), the θ of eq. (1); the "
            "histogram counts the direction of the line itself"
        )
    if _same(np.arctan(a), want):
        return f"{what}: those look like slopes dy / dx; return the angle, np.arctan2(dy, dx)"
    if len(want) <= 6:
        return (
            f"{what}: expected the directions {_degrees(_canonical(want))} (any order), "
            f"got {_degrees(np.sort(a))}"
        )
    ref = _canonical(want)
    mine = _canonical(a)
    k = np.clip(np.searchsorted(ref, mine), 1, len(ref) - 1)
    # distance modulo π to the nearest expected direction (either neighbour, or across 0/π)
    gaps = np.abs(mine - ref[np.stack([k - 1, k, np.zeros_like(k), np.full_like(k, -1)])])
    near = np.minimum(gaps, np.pi - gaps).min(axis=0)
    off = int(np.sum(near > _TOL))
    return (
        f"{what}: {off} of {len(want)} directions differ from the line's angle "
        "np.arctan2(dy, dx) folded into [0, π)"
    )


@exercise("my_pair_angles")
def check_pair_angles(fn: Callable[[np.ndarray], Any], cluster: ArrayLike | None = None) -> str:
    """Exercise 3.1 (implement): ``fn(points (N, 2)) -> angles (N (N-1) / 2,)``, the direction
    in [0, π) of the line through every pair of points, each pair once, in any order — what
    :func:`fhslam.extraction.slope_histogram` counts with ``pairs="all"``.

    Any representation equal modulo π is accepted (π for 0, say); directions outside [0, π],
    degrees, normal angles and slopes are refused with a hint. Tried on
    :func:`pair_angle_cases`, then on ``cluster`` (the notebook's), whose dominant slope the
    success message gives."""
    cases = pair_angle_cases()
    if cluster is not None:
        pts = np.asarray(cluster, dtype=float)
        cases.append((f"the notebook's cluster ({len(pts)} points)", pts))
    n_bins = round(180.0 / ALL_PAIRS.angle_bin_deg)
    pairs = 0
    for what, pts in cases:
        a = _angles(call(fn, pts.copy()), what, len(pts))
        want = _reference(pts)
        inside = np.all((a >= -_TOL) & (a <= np.pi + _TOL))
        if not (inside and _same(a, want)):
            raise Wrong(_diagnose(a, want, what))
        hist = slope_histogram(pts, np.zeros(len(pts), int), ALL_PAIRS)[0]
        if _edge_safe(want, n_bins) and not np.array_equal(_bins(np.mod(a, np.pi), n_bins), hist):
            raise Wrong(f"{what}: binned by 1°, your directions differ from slope_histogram's")
        pairs += len(want)
    done = (
        f"the same directions as the pairs fhslam.extraction.slope_histogram counts "
        f"(pairs='all') in all {len(cases)} cases, {pairs} pairs"
    )
    if cluster is not None:
        pts = np.asarray(cluster, dtype=float)
        phi, _ = dominant_angle(slope_histogram(pts, np.zeros(len(pts), int), ALL_PAIRS))
        done += (
            f"; on the notebook's cluster their histogram peaks at {np.degrees(phi[0]):.1f}°, "
            "the direction of its longest wall"
        )
    return done


def _full_peak(points: np.ndarray, params: ExtractionParams) -> tuple[float, int, float, int]:
    """The full 0-180° accumulator of ``points`` at the restricted vote's resolution, rho from
    their centroid: (theta of its best cell, its votes, theta of the best cell at least 45°
    from it, its votes)."""
    from fhslam.baselines import hough_accumulator

    q = points - points.mean(axis=0)
    reach = float(np.hypot(q[:, 0], q[:, 1]).max()) + params.rho_step
    acc, thetas, _ = hough_accumulator(q, params.rho_step, np.radians(params.theta_step_deg), reach)
    best = acc.max(axis=1)
    i = int(np.argmax(best))
    apart = np.abs(np.mod(thetas - thetas[i] + np.pi / 2, np.pi) - np.pi / 2) >= np.pi / 4
    j = int(np.flatnonzero(apart)[np.argmax(best[apart])])
    return float(thetas[i]), int(best[i]), float(thetas[j]), int(best[j])


def check_window_reading(
    answer: Any,
    points: ArrayLike | None = None,
    phi: ArrayLike | None = None,
    params: ExtractionParams | None = None,
) -> Feedback:
    """Exercise 3.2 (interpret): why voting only in a window of a few degrees around the
    dominant slope loses nothing against the full 0-180° accumulator, on one cluster.

    With ``points`` (the notebook's densified cluster) and ``phi`` (its dominant slope), the
    explanations quote that cluster's restricted and full accumulators."""
    params = params or ExtractionParams()
    rows = 2 * round(params.window_deg / params.theta_step_deg) + 1
    full_rows = round(180.0 / params.theta_step_deg)
    here = second = ""
    if points is not None and phi is not None:
        p = np.asarray(points, dtype=float)
        peak = restricted_hough(p, np.zeros(len(p), int), np.atleast_1d(phi)[:1], params)
        t_full, v_full, t_other, v_other = _full_peak(p, params)
        t_win = np.degrees(peak.theta[0]) % 360
        here = (
            f" Here the full accumulator's best cell, θ = {np.degrees(t_full):.1f}° with "
            f"{v_full} votes, is the line the window found (θ = {t_win:.1f}°, "
            f"{peak.votes[0]} votes; θ and θ + 180° with −ρ are one line), with {rows} of its "
            f"{full_rows} rows."
        )
        second = (
            f" (In the full accumulator the second wall is a peak of {v_other} votes at "
            f"θ = {np.degrees(t_other):.1f}°, far outside the window.)"
        )
    return check_choice(
        answer,
        right="a",
        why={
            "a": "pairs of points on one straight wall all have the wall's direction, so the "
            "slope histogram's peak is the direction of the cluster's best-supported wall and "
            "the full accumulator's highest cell lies in the window around it; the other "
            f"walls are found in the next rounds, once this line's points are removed.{here}",
            "b": f"the window is ±{params.window_deg:g}° wide; the cluster's two walls are 90° "
            "apart. The points of the wall across the window's angles spread over many ρ cells "
            "and make no peak in it: that wall is found in the next round, around its own "
            f"dominant slope, after the first line's points are removed.{second}",
            "c": f"the cells are the same ({params.theta_step_deg:g}° × "
            f"{100 * params.rho_step:g} cm) as a full accumulator at this resolution would "
            f"have; the window only votes {rows} of its {full_rows} rows.",
            "d": "the second wall of the cluster is not lost: the sub-maximum search takes the "
            "next line from the points left once the first line's are removed, with a slope "
            "histogram and a window of its own (l5 in the table of lines, from the same "
            "cluster as l4).",
        },
    )


@exercise("my_count")
def check_line_count(answer: Any, points: ArrayLike, min_points: int = 12) -> str:
    """Exercise 3.3 (predict): how many lines :func:`fhslam.extraction.extract_lines` keeps on
    the scan ``points`` with a support threshold ``min_points`` (the other thresholds at their
    defaults), computed here."""
    p = np.asarray(points, dtype=float)
    try:
        value = float(answer)
    except (TypeError, ValueError):
        raise Wrong(f"my_count should be a number of lines, got {answer!r}") from None
    if not (np.isfinite(value) and value == round(value)):
        raise Wrong(f"my_count = {answer!r}: a number of lines is a whole number")
    default = extract_lines(p)
    kept = extract_lines(p, ExtractionParams(min_points=min_points))
    n = len(kept)
    supports = ", ".join(str(line.n) for line in kept)
    gone = ", ".join(str(line.n) for line in default if line.n < min_points)
    if int(value) == n:
        return (
            f"my_count = {n}: {n} lines have at least {min_points} supporting scan points "
            f"({supports}); the lines of {gone} points are gone"
        )
    if int(value) == len(default):
        raise Wrong(
            f"{int(value)} is the count at the default min_points = "
            f"{ExtractionParams().min_points}; at {min_points}, a line needs {min_points} scan "
            "points within the inlier distance: read the n column of the table of lines"
        )
    raise Wrong(
        f"my_count = {value:g} lines; a line is kept when at least min_points = {min_points} "
        "scan points support it: count the lines of the table above with n ≥ "
        f"{min_points}"
    )
