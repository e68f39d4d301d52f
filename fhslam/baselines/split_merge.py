"""Split-and-merge line extraction (iterative end-point fit), a classical non-Hough baseline.

Reference: V. Nguyen, A. Martinelli, N. Tomatis, R. Siegwart, "A comparison of line
extraction algorithms using 2D laser rangefinder for indoor mobile robotics", IEEE/RSJ
IROS 2005. There split-and-merge (with the iterative end-point fit split test) is among
the fastest and most accurate of the compared methods.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.geometry import angle_difference_lines, as_points, signed_distance
from fhslam.lines import Line, fit_line, line_from_points, split_runs


@dataclass(frozen=True)
class SplitMergeParams:
    """Parameters of :func:`split_and_merge`.

    Attributes
    ----------
    split_dist : float
        A segment is split while its point farthest from the chord (the straight line between
        its first and last point) is more than this far from it, metres.
    max_gap : float
        Consecutive points further apart than this start a new cluster, metres.
    min_points : int
        Fewest points in a segment (>= 2).
    min_length : float
        Shortest line returned, metres.
    merge_angle_deg : float
        Neighbouring segments merge only if the line fitted to both turns by at most this from
        the longer segment's line, degrees ...
    merge_dist : float
        ... and passes within this of each segment's centroid, metres.
    """

    split_dist: float = 0.03
    max_gap: float = 0.3
    min_points: int = 6
    min_length: float = 0.3
    merge_angle_deg: float = 2.0
    merge_dist: float = 0.03

    def __post_init__(self) -> None:
        for name in ("split_dist", "max_gap", "merge_dist"):
            if not getattr(self, name) > 0:
                raise ValueError(f"SplitMergeParams.{name} must be > 0, got {getattr(self, name)}")
        if not (self.min_length >= 0 and self.merge_angle_deg >= 0):
            raise ValueError("SplitMergeParams.min_length and merge_angle_deg must be >= 0")
        if self.min_points < 2:
            raise ValueError(f"SplitMergeParams.min_points must be >= 2, got {self.min_points}")


def _chord_distances(q: NDArray[np.float64]) -> NDArray[np.float64]:
    """Distances of points q (K, 2) to the line through q[0] and q[-1] (to q[0] if equal)."""
    d = q[-1] - q[0]
    r = q - q[0]
    norm = np.hypot(*d)
    if norm == 0.0:
        return np.hypot(r[:, 0], r[:, 1])
    return np.abs(d[0] * r[:, 1] - d[1] * r[:, 0]) / norm


def _split(
    p: NDArray[np.float64], idx: NDArray[np.intp], params: SplitMergeParams
) -> list[NDArray[np.intp]]:
    """Iterative end-point fit of one cluster ``idx``; returns segments (index arrays) in order."""
    segments: list[NDArray[np.intp]] = []
    stack = [idx]
    while stack:
        seg = stack.pop()
        if len(seg) < params.min_points:
            continue
        dist = _chord_distances(p[seg])
        k = int(np.argmax(dist))
        if dist[k] > params.split_dist:
            stack += [seg[k + 1 :], seg[: k + 1]]  # left half popped first: scan order kept
        else:
            segments.append(seg)
    return segments


def _collinear(p: NDArray[np.float64], a: NDArray, b: NDArray, params: SplitMergeParams) -> bool:
    """The merge test for neighbouring segments ``a`` and ``b`` (index arrays).

    The line fitted to both must turn by at most ``merge_angle_deg`` from the longer
    segment's own line and pass within ``merge_dist`` of both segments' centroids. (Comparing
    the two segments' own angles instead fails on the short noisy pieces that noise splits off
    a long wall: their fitted angle is uncertain by degrees.)
    """
    longer = a if len(a) >= len(b) else b
    _, theta_long, _ = fit_line(p[longer])
    rho, theta, _ = fit_line(p[np.concatenate([a, b])])
    if angle_difference_lines(theta, theta_long) > np.radians(params.merge_angle_deg):
        return False
    centroids = np.vstack([p[a].mean(axis=0), p[b].mean(axis=0)])
    return bool(np.all(np.abs(signed_distance(centroids, rho, theta)) <= params.merge_dist))


def split_and_merge(
    points: ArrayLike, params: SplitMergeParams | None = None, pose: ArrayLike | None = None
) -> list[Line]:
    """Split-and-merge line extraction (Nguyen et al., IROS 2005).

    1. Cluster: break the scan where consecutive points are more than ``max_gap`` apart.
    2. Split (iterative end-point fit): split a segment after its point farthest from the
       chord between its end points while that distance exceeds ``split_dist``; segments of
       fewer than ``min_points`` points are dropped.
    3. Merge neighbouring segments of one cluster that are collinear (angle and distance
       tests of :class:`SplitMergeParams`).
    4. Fit each segment by least squares; keep those at least ``min_length`` long.

    Parameters
    ----------
    points : array-like, shape (N, 2)
        Finite scan points in scan order, metres (any frame).
    params : SplitMergeParams, optional
    pose : array-like, shape (3,), optional
        Robot pose in the points' frame, for ``Line.dir`` and ``Line.d``.

    Returns
    -------
    list of Line
        In scan order; ``inliers`` index ``points``; ``[]`` for fewer than 2 points.
    """
    p = as_points(points)
    params = params or SplitMergeParams()
    if len(p) < 2:
        return []
    lines = []
    for cluster in split_runs(p, np.arange(len(p)), params.max_gap):
        merged: list[NDArray[np.intp]] = []
        for seg in _split(p, cluster, params):
            if merged and _collinear(p, merged[-1], seg, params):
                merged[-1] = np.concatenate([merged[-1], seg])
            else:
                merged.append(seg)
        lines += [line_from_points(p, seg, pose=pose) for seg in merged]
    return [line for line in lines if line.length >= params.min_length]
