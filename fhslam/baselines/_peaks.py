"""Shared post-processing for the Hough baselines: from accumulator peaks to feature lines.

A Hough transform only says "many points lie near the infinite line (rho, theta)". To turn
its peaks into the paper's line segments every Hough baseline in :mod:`fhslam.baselines`
uses the same greedy walk, so that they differ only in how the peaks are found.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from fhslam.geometry import signed_distance
from fhslam.lines import Line, line_from_points, split_runs


def lines_from_peaks(
    points: ArrayLike,
    peaks: ArrayLike,
    *,
    inlier_dist: float,
    max_gap: float,
    min_points: int,
    min_length: float,
    max_lines: int,
    refine: bool = False,
    pose: ArrayLike | None = None,
) -> list[Line]:
    """Turn Hough peaks, best first, into feature lines that do not share points.

    For each peak in order: its inliers are the still-unassigned points within
    ``inlier_dist`` of the peak's line; they are split into runs at gaps over ``max_gap``
    (:func:`fhslam.lines.split_runs`); every run with at least ``min_points`` points and at
    least ``min_length`` long becomes a line and its points become assigned. The walk stops
    when the peaks run out, ``max_lines`` lines were found, or fewer than ``min_points``
    points are left.

    Parameters
    ----------
    points : array-like, shape (N, 2)
        Scan points in scan order, metres (already validated).
    peaks : array-like, shape (K, 2)
        Candidate lines ``(rho, theta)`` (metres, radians; ``rho`` may be negative),
        ordered by votes, best first.
    inlier_dist : float
        Largest orthogonal distance of an inlier from the peak's line, metres.
    max_gap : float
        Largest distance between consecutive inliers inside one segment, metres.
    min_points : int
        Fewest points in a segment.
    min_length : float
        Shortest segment, metres.
    max_lines : int
        Most lines returned.
    refine : bool
        False (classical Hough): report the peak's own ``(rho, theta)``. True: least-squares
        refit of each segment to its inliers.
    pose : array-like, shape (3,), optional
        Robot pose in the points' frame, for ``Line.dir`` and ``Line.d``.

    Returns
    -------
    list of Line
        In the order found; ``inliers`` index ``points`` and increase.
    """
    p = np.asarray(points, dtype=float)
    peaks = np.asarray(peaks, dtype=float).reshape(-1, 2)
    free = np.ones(len(p), dtype=bool)
    lines: list[Line] = []
    for rho, theta in peaks:
        if len(lines) >= max_lines or free.sum() < min_points:
            break
        near = np.flatnonzero(free & (np.abs(signed_distance(p, rho, theta)) <= inlier_dist))
        for run in split_runs(p, near, max_gap):
            if len(run) < min_points:
                continue
            line = line_from_points(p, run, pose=pose, rho_theta=(rho, theta))
            if line.length < min_length:
                continue
            if refine:
                line = line_from_points(p, run, pose=pose)
            lines.append(line)
            free[run] = False
            if len(lines) >= max_lines:
                break
    return lines
