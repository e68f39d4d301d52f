"""Map metrics: the SLAM map's line segments against the world's true walls."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.geometry import distance_to_segments
from fhslam.lines import Line


def as_segments(lines: Sequence[Line] | ArrayLike) -> NDArray[np.float64]:
    """Segments ``[x1, y1, x2, y2]`` (M, 4) from Lines (``sp``, ``ep``) or an (M, 4) array."""
    if isinstance(lines, Sequence) and len(lines) and isinstance(lines[0], Line):
        return np.array([[*ln.sp, *ln.ep] for ln in lines], dtype=float).reshape(-1, 4)
    s = np.asarray(lines, dtype=float)
    if s.size == 0:
        return np.zeros((0, 4))
    if s.ndim != 2 or s.shape[1] != 4:
        raise ValueError(f"segments must be Lines or an (M, 4) array, got shape {s.shape}")
    return s


def sample_segments(segments: ArrayLike, step: float = 0.05) -> NDArray[np.float64]:
    """Points along segments, evenly spaced at most ``step`` apart, both ends included.

    Parameters
    ----------
    segments : array-like, shape (M, 4)
    step : float
        Largest spacing, metres. A segment of length ``L`` gets ``ceil(L / step) + 1``
        points (at least 2).

    Returns
    -------
    ndarray, shape (P, 2)
    """
    if not step > 0:
        raise ValueError(f"step must be positive (metres), got {step}")
    s = as_segments(segments)
    a, b = s[:, :2], s[:, 2:]
    length = np.hypot(*(b - a).T)
    n = np.maximum(np.ceil(length / step).astype(np.intp), 1)  # intervals per segment
    seg = np.repeat(np.arange(len(s)), n + 1)
    first = np.cumsum(n + 1) - (n + 1)
    k = np.arange(len(seg)) - first[seg]
    t = (k / n[seg])[:, None]
    return a[seg] + t * (b[seg] - a[seg])


def map_error(lines: Sequence[Line] | ArrayLike, walls: ArrayLike, step: float = 0.05) -> float:
    """Mean distance from the map's segments to the true walls, metres.

    Points are sampled every ``step`` metres along each map segment (:func:`sample_segments`,
    so long lines weigh more), and each point's distance to the nearest true wall segment is
    averaged. 0 for a map drawn exactly on the walls; it does not see walls the map misses
    (that is :func:`map_coverage`).

    Parameters
    ----------
    lines : sequence of Line, or array-like (M, 4)
        The map, in the world frame (the SLAM starts at the true first pose).
    walls : array-like, shape (W, 4)
        True wall segments.
    step : float
        Sampling step along the map segments, metres.

    Returns
    -------
    float
        NaN for an empty map.
    """
    pts = sample_segments(as_segments(lines), step)
    if len(pts) == 0:
        return float("nan")
    return float(np.mean(distance_to_segments(pts, walls)))


def map_coverage(
    lines: Sequence[Line] | ArrayLike, observed_points: ArrayLike, tol: float = 0.05
) -> float:
    """Share of the observed wall points that lie within ``tol`` of a map segment.

    Parameters
    ----------
    lines : sequence of Line, or array-like (M, 4)
        The map, in the world frame.
    observed_points : array-like, shape (P, 2), P >= 1
        Points on the true walls that the laser hit during the run (noise-free), e.g. from
        :func:`fhslam.sim.observed_wall_points` or :func:`fhslam.sim.visible_wall_points`.
    tol : float
        Distance within which a wall point counts as mapped, metres.

    Returns
    -------
    float
        In [0, 1]; 0 for an empty map.
    """
    p = np.asarray(observed_points, dtype=float).reshape(-1, 2)
    if len(p) == 0:
        raise ValueError("map_coverage needs at least one observed wall point")
    if not tol >= 0:
        raise ValueError(f"tol must be >= 0 (metres), got {tol}")
    s = as_segments(lines)
    if len(s) == 0:
        return 0.0
    return float(np.mean(distance_to_segments(p, s) <= tol))
