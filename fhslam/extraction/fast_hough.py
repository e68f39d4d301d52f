"""Loop 1 of the paper: feature extraction with the fast Hough transform.

The paper ("Improved Fast Hough transform", "Feature extraction process", and steps 3-5 of the
simulation's step list) extracts wall lines from one laser scan in three moves:

1. :func:`cluster_scan` -- split the scan, in scan order, wherever two neighbouring points are
   farther apart than a threshold (Figs. 3-4);
2. :func:`densify` -- "extend" the points: add points between neighbours inside a cluster so
   that every stretch of wall votes in proportion to its length (Fig. 3);
3. per cluster, the fast Hough transform: a histogram of the angle of the line through point
   pairs (:func:`slope_histogram`), its dominant angle (:func:`dominant_angle`), a Hough vote
   for rho only in a small window around that angle (:func:`restricted_hough`), a least-squares
   refinement on the inliers, and then the next line ("sub-maximum") on the points that are
   left, until the support falls under a threshold.

Each step is a public function taking the scan's points and cluster labels, so a notebook
can show it on its own (a single cluster: give all its points label 0); each calls the same
compiled per-cluster kernel (:mod:`fhslam.extraction._kernels`) that :func:`extract_lines`,
the whole of Loop 1, runs on every cluster of a scan.

The entry point is :func:`extract_lines` (points in scan order, any frame) or
:func:`extract_lines_from_scan` (a :class:`fhslam.scan.Scan`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.extraction import _kernels as kernels
from fhslam.extraction.params import ExtractionParams
from fhslam.geometry import as_points, as_pose, observation
from fhslam.lines import Line
from fhslam.scan import Scan


@functools.lru_cache(maxsize=16)
def _pair_uniforms(seed: int, n_pairs: int) -> NDArray[np.float64]:
    """The seeded table of uniform numbers from which random point pairs are drawn."""
    u = np.random.default_rng(seed).random((n_pairs, 2))
    u.setflags(write=False)
    return u


# --------------------------------------------------------------------------- steps 1, 2


def lone_points(points: ArrayLike, gap: float) -> NDArray[np.bool_]:
    """Points farther than ``gap`` from both scan neighbours whose neighbours are within
    ``2 * gap`` of each other: lone returns in front of a surface (clutter).

    Parameters
    ----------
    points : array-like, shape (N, 2)
        Points in scan order.

    Returns
    -------
    ndarray of bool, shape (N,)
    """
    return kernels.lone_kernel(np.ascontiguousarray(as_points(points)), float(gap))


def cluster_scan(points: ArrayLike, gap: float) -> NDArray[np.intp]:
    """Cluster consecutive scan points by the distance between neighbours (paper Figs. 3-4).

    Parameters
    ----------
    points : array-like, shape (N, 2)
        Points in scan order.
    gap : float
        A new cluster starts where ``|p[i+1] - p[i]| > gap`` (metres).

    Returns
    -------
    labels : ndarray of int, shape (N,)
        Cluster label of each point, 0, 1, 2, ... in scan order.
    """
    return kernels.cluster_kernel(as_points(points), float(gap))


def densify(
    points: ArrayLike, labels: ArrayLike, step: float
) -> tuple[NDArray[np.float64], NDArray[np.intp], NDArray[np.intp]]:
    """Add points between neighbours of the same cluster ("extend laser scan points", Fig. 3).

    Between points ``p[i]`` and ``p[i+1]`` of one cluster, ``ceil(|p[i+1]-p[i]| / step) - 1``
    evenly spaced points are inserted, so no two consecutive points are more than ``step``
    apart.

    Parameters
    ----------
    points : array-like, shape (N, 2)
    labels : array-like of int, shape (N,)
        Cluster labels from :func:`cluster_scan`.
    step : float
        Largest spacing after densification, metres; ``0`` returns the input unchanged.

    Returns
    -------
    dense : ndarray, shape (M, 2)
    dense_labels : ndarray of int, shape (M,)
    source : ndarray of int, shape (M,)
        Index of the original point, or -1 for an added point.
    """
    p = as_points(points)
    lab = np.asarray(labels, dtype=np.intp)
    parts, labs, srcs = [], [], []
    for s, m in zip(*_segments(lab), strict=True):
        d, src = kernels.densify_kernel(p[s : s + m], float(step))
        parts.append(d)
        labs.append(np.full(len(d), lab[s]))
        srcs.append(np.where(src >= 0, src + s, -1))
    if not parts:
        return p.copy(), lab.copy(), np.arange(len(p))
    return np.concatenate(parts), np.concatenate(labs), np.concatenate(srcs)


# --------------------------------------------------------------------------- step 3


def _segments(labels: NDArray[np.intp]) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Starts and sizes of the runs of equal labels (clusters are contiguous in scan order)."""
    if len(labels) == 0:
        return np.zeros(0, np.intp), np.zeros(0, np.intp)
    starts = np.flatnonzero(np.r_[True, labels[1:] != labels[:-1]])
    return starts, np.diff(np.r_[starts, len(labels)])


def slope_histogram(
    points: ArrayLike,
    labels: ArrayLike,
    params: ExtractionParams | None = None,
    rng: np.random.Generator | None = None,
) -> NDArray[np.int64]:
    """Histogram of the direction of the line through point pairs, per cluster.

    The paper's "compute respectively the slope between every two points. Setting up a
    counter, if the slope is in the setting range, we add one on the counter". Slopes are
    direction angles in [0, pi) so vertical walls are no special case.

    Parameters
    ----------
    points : array-like, shape (N, 2)
    labels : array-like of int, shape (N,)
        Cluster labels (clusters contiguous in scan order).
    params : ExtractionParams, optional
    rng : numpy.random.Generator, optional
        Source of the random pairs; default: the table seeded by ``params.seed`` that
        :func:`extract_lines` uses.

    Returns
    -------
    hist : ndarray of int, shape (C, n_bins)
        Votes per cluster and direction bin; bin ``k`` covers
        ``[k, k+1) * angle_bin_deg`` degrees.
    """
    params = params or ExtractionParams()
    p = as_points(points)
    n_bins = round(180.0 / params.angle_bin_deg)
    out = []
    for s, m in zip(*_segments(np.asarray(labels)), strict=True):
        u = (
            rng.random((params.n_pairs, 2))
            if rng is not None
            else _pair_uniforms(params.seed, params.n_pairs)
        )
        out.append(
            kernels.slope_histogram_kernel(
                p[s : s + m], u, n_bins, params.min_pair_dist, params.pairs == "all"
            )
        )
    return np.array(out, dtype=np.int64).reshape(len(out), n_bins)


def dominant_angle(hist: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The most supported line direction of each cluster ("the maximum number to support a
    certain slope").

    The histogram is smoothed with a circular [1, 2, 1] / 4 kernel (so a direction split over
    two bins is not lost) before taking the peak.

    Parameters
    ----------
    hist : array-like, shape (C, n_bins)

    Returns
    -------
    phi : ndarray, shape (C,)
        Dominant direction (angle of the line itself, not its normal) in [0, pi), radians,
        at the centre of the peak bin.
    support : ndarray, shape (C,)
        Smoothed vote count at the peak; 0 for a cluster without any valid pair.
    """
    h = np.atleast_2d(np.asarray(hist, dtype=np.int64))
    res = np.array([kernels.dominant_kernel(row) for row in h]).reshape(-1, 2)
    return res[:, 0], res[:, 1]


@dataclass(frozen=True)
class HoughPeaks:
    """Result of :func:`restricted_hough`, one entry per cluster.

    ``rho``/``theta`` are the peak line in Hessian form (``theta`` is the normal angle, not
    yet normalised to ``rho >= 0``), ``votes`` its count, ``centroid`` the local origin of
    the cluster's accumulator, ``accumulators[c]`` = ``(votes (W, R), thetas (W,), rhos (R,))``
    with ``rhos`` measured from the centroid.
    """

    rho: NDArray[np.float64]
    theta: NDArray[np.float64]
    votes: NDArray[np.int64]
    centroid: NDArray[np.float64]
    accumulators: list[tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]]


def restricted_hough(
    points: ArrayLike,
    labels: ArrayLike,
    phi: ArrayLike,
    params: ExtractionParams | None = None,
) -> HoughPeaks:
    """Hough vote for rho only in an angle window around each cluster's dominant direction.

    Paper eq. (1), ``rho = x cos(theta) + y sin(theta)``, but with ``theta`` restricted to
    ``phi + 90° ± window_deg`` instead of 0-180°: "Fast Hough transform searches feature
    lines ... in a certain angle range". ``rho`` is measured from the cluster's centroid, so
    the accumulator spans only the cluster's extent and the result does not depend on where
    the frame's origin lies.

    Parameters
    ----------
    points : array-like, shape (N, 2)
    labels : array-like of int, shape (N,)
        Cluster labels (clusters contiguous in scan order).
    phi : array-like, shape (C,)
        Dominant line direction of each cluster (from :func:`dominant_angle`), radians.
    params : ExtractionParams, optional

    Returns
    -------
    HoughPeaks
    """
    params = params or ExtractionParams()
    p = as_points(points)
    phi = np.atleast_1d(np.asarray(phi, dtype=float))
    half = round(params.window_deg / params.theta_step_deg)
    rows, accs = [], []
    for c, (s, m) in enumerate(zip(*_segments(np.asarray(labels)), strict=True)):
        rho, theta, votes, acc, thetas, rho0, cx, cy = kernels.window_hough_kernel(
            p[s : s + m], phi[c], half, np.radians(params.theta_step_deg), params.rho_step
        )
        rows.append((rho, theta, votes, cx, cy))
        accs.append((acc, thetas, rho0 + params.rho_step * np.arange(acc.shape[1])))
    r = np.array(rows, dtype=float).reshape(-1, 5)
    return HoughPeaks(r[:, 0], r[:, 1], r[:, 2].astype(np.int64), r[:, 3:5], accs)


# --------------------------------------------------------------------------- the pipeline


def extract_lines(
    points: ArrayLike,
    params: ExtractionParams | None = None,
    pose: ArrayLike | None = None,
) -> list[Line]:
    """Extract straight wall lines from one scan with the paper's fast Hough transform.

    Per cluster (:func:`cluster_scan`), on the densified points (:func:`densify`): the slope
    histogram (:func:`slope_histogram`) gives the dominant direction
    (:func:`dominant_angle`), a Hough vote restricted to a window around it
    (:func:`restricted_hough`) gives the best line, which is refined by total least squares on
    its inliers; the inliers are split at gaps into segments, removed, and the next line is
    sought on what is left, until the best line has fewer than ``min_points`` supporting
    points.

    Parameters
    ----------
    points : array-like, shape (N, 2)
        Finite scan points in scan order, in any frame (laser frame, or world frame at the
        robot's pose). Use :func:`scan_to_points` to drop invalid beams first.
    params : ExtractionParams, optional
    pose : array-like, shape (3,), optional
        The robot pose in the points' frame; fills each line's ``dir`` and ``d``.

    Returns
    -------
    list of Line
        By cluster in scan order, then in the order found (strongest first).
        ``Line.inliers`` index into ``points``. Fewer than ``min_points`` points, or points
        that are all identical, give ``[]``.

    Raises
    ------
    ValueError
        If ``points`` is not (N, 2) or contains NaN/inf.
    """
    params = params or ExtractionParams()
    p = np.ascontiguousarray(as_points(points))
    if pose is not None:
        pose = as_pose(pose)
    if len(p) < params.min_points:
        return []
    kept = None
    if params.drop_lone_points:
        lone = kernels.lone_kernel(p, params.cluster_gap)
        if lone.any():
            kept = np.flatnonzero(~lone)
            p = np.ascontiguousarray(p[kept])
    seg, offsets, flat = kernels.extract_kernel(
        p,
        _pair_uniforms(params.seed, params.n_pairs),
        params.cluster_gap,
        params.densify_step,
        round(180.0 / params.angle_bin_deg),
        params.min_pair_dist,
        params.pairs == "all",
        round(params.window_deg / params.theta_step_deg),
        np.radians(params.theta_step_deg),
        params.rho_step,
        params.inlier_dist,
        params.refine_iterations,
        params.min_points,
        params.min_length,
        params.max_lines_per_cluster,
        params.max_peaks,
    )
    if kept is not None:
        flat = kept[flat]  # indices into the caller's points
    n_in = np.diff(offsets)
    length = np.hypot(seg[:, 5] - seg[:, 3], seg[:, 6] - seg[:, 4])
    if pose is not None:
        side, dist = observation(seg[:, 0], seg[:, 1], pose[0], pose[1])
    lines = []
    for k, (rho, theta, rms, *_ends) in enumerate(seg.tolist()):
        lines.append(
            Line(
                rho=rho,
                theta=theta,
                n=int(n_in[k]),
                length=float(length[k]),
                sp=seg[k, 3:5],
                ep=seg[k, 5:7],
                dir=None if pose is None else int(side[k]),
                d=None if pose is None else float(dist[k]),
                inliers=flat[offsets[k] : offsets[k + 1]],
                rms=rms,
            )
        )
    return lines


def extract_lines_from_scan(
    scan: Scan, params: ExtractionParams | None = None, pose: ArrayLike | None = None
) -> tuple[list[Line], NDArray[np.intp]]:
    """:func:`extract_lines` on a raw scan, in the laser frame (invalid beams dropped by
    :meth:`fhslam.scan.Scan.points`).

    Returns the lines and the beam index of every point (``beams[line.inliers]`` are the
    beams supporting a line).
    """
    pts, beams = scan.points()
    return extract_lines(pts, params, pose=pose), beams


__all__ = [
    "ExtractionParams",
    "HoughPeaks",
    "cluster_scan",
    "densify",
    "dominant_angle",
    "extract_lines",
    "extract_lines_from_scan",
    "lone_points",
    "restricted_hough",
    "slope_histogram",
]
