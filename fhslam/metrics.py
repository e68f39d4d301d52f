"""Measurement: line-detection scores, trajectory errors (ATE, RPE) and map errors.

Line detection (against the simulator's true walls) comes first; the trajectory metrics
(:func:`ate`, :func:`rpe`, after evo) and map metrics (:func:`map_error`,
:func:`map_coverage`) follow.

Line-detection scores
---------------------

After Nguyen, Gächter, Martinelli, Tomatis and Siegwart, "A comparison of line extraction
algorithms using 2D laser rangefinder for indoor mobile robotics", IROS 2005, Table II:

- **TruePos** = matched lines / true lines,
- **FalsePos** = (extracted lines - matched lines) / extracted lines,
- **rms Δρ**, **rms Δθ** over the matched pairs, in the sensor frame.

A *true line* is a run of consecutive beams that hit the same wall (a wall hidden in part by
an obstacle gives two true lines), with at least ``min_hits`` beams. Runs with fewer beams
are "don't care": a line on one of them counts neither as a hit nor as a false positive,
so extractors with a lower support threshold are not penalised for finding them.

An extracted line *matches* the true line that holds the majority of its supporting beams
(at least ``min_share``), if its (ρ, θ) lies within ``max_drho`` / ``max_dtheta_deg`` of
the true wall. Each true line matches at most one extracted line (the best supported);
further lines on it are false positives (a split wall).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.geometry import (
    distance_to_segments,
    inverse,
    line_through,
    ray_segment_intersection,
    relative,
    transform_points,
    wrap_angle,
)
from fhslam.lines import Line
from fhslam.scan import scan_to_points


@dataclass(frozen=True)
class TrueLine:
    """A wall as seen in one scan: a run of consecutive beams that hit it."""

    wall: int
    rho: float
    theta: float
    beams: NDArray[np.intp]


@dataclass(frozen=True)
class DetectionScores:
    """Nguyen et al. (2005) line-detection scores over a set of scans."""

    true_pos_rate: float
    false_pos_rate: float
    rms_drho: float
    rms_dtheta_deg: float
    n_true: int
    n_found: int
    n_matched: int
    n_ignored: int

    def as_dict(self) -> dict[str, float | int]:
        return dict(self.__dict__)


def line_difference(
    rho_a: float, theta_a: float, rho_b: float, theta_b: float
) -> tuple[float, float]:
    """Distance |Δρ| (m) and angle |Δθ| (rad, in [0, pi/2]) between two lines in Hessian form.

    Handles the ambiguity of a line through (or near) the origin, where ``(ρ, θ)`` and
    ``(-ρ, θ + pi)`` are the same line.
    """
    d = np.mod(theta_a - theta_b + np.pi, 2 * np.pi) - np.pi
    if abs(d) <= np.pi / 2:
        return abs(rho_a - rho_b), abs(d)
    return abs(rho_a + rho_b), np.pi - abs(d)


def true_lines(
    hits: ArrayLike, walls: ArrayLike, pose: ArrayLike, min_hits: int = 10
) -> tuple[list[TrueLine], NDArray[np.intp]]:
    """The walls seen in one scan, as beam runs, with (ρ, θ) in the laser frame.

    Parameters
    ----------
    hits : array-like of int, shape (B,)
        Wall index hit by each beam, -1 for no return (from the simulator).
    walls : array-like, shape (M, 4)
        Wall segments ``[x1, y1, x2, y2]`` in the world frame.
    pose : array-like, shape (3,)
        True ``world_T_laser`` pose of the scan.
    min_hits : int
        Shortest run that counts as a true line.

    Returns
    -------
    lines : list of TrueLine
        The runs with at least ``min_hits`` beams.
    run_of_beam : ndarray of int, shape (B,)
        Index into ``lines`` of each beam's run; -1 for no return, -2 for a short run.
    """
    h = np.asarray(hits, dtype=np.intp)
    w = np.asarray(walls, dtype=float)
    laser_T_world = inverse(pose)
    run_of_beam = np.full(len(h), -1, dtype=np.intp)
    brk = np.r_[True, h[1:] != h[:-1]]
    starts = np.flatnonzero(brk)
    stops = np.r_[starts[1:], len(h)]
    out: list[TrueLine] = []
    for a, b in zip(starts, stops, strict=True):
        wall = int(h[a])
        if wall < 0:
            continue
        if b - a < min_hits:
            run_of_beam[a:b] = -2
            continue
        p, q = transform_points(laser_T_world, w[wall].reshape(2, 2))
        rho, theta = line_through(p, q)
        run_of_beam[a:b] = len(out)
        out.append(TrueLine(wall, rho, theta, np.arange(a, b)))
    return out, run_of_beam


@dataclass
class _Tally:
    n_true: int = 0
    n_found: int = 0
    n_matched: int = 0
    n_ignored: int = 0

    def __post_init__(self) -> None:
        self.drho: list[float] = []
        self.dtheta: list[float] = []


def match_scan(
    lines: Sequence[Line],
    beams: ArrayLike,
    truth: Sequence[TrueLine],
    run_of_beam: ArrayLike,
    max_drho: float = 0.10,
    max_dtheta_deg: float = 5.0,
    min_share: float = 0.5,
) -> list[int | None]:
    """Match the lines extracted from one scan to its true lines.

    Parameters
    ----------
    lines : sequence of Line
        Extracted lines, in the laser frame, with ``inliers`` indexing the scan's points.
    beams : array-like of int, shape (N,)
        Beam index of every point (from :func:`fhslam.extraction.scan_to_points`).
    truth, run_of_beam
        From :func:`true_lines`.

    Returns
    -------
    list
        Per extracted line: the index of its true line, ``-1`` for "don't care" (a short
        run), or ``None`` for a false positive.
    """
    b = np.asarray(beams, dtype=np.intp)
    rob = np.asarray(run_of_beam, dtype=np.intp)
    result: list[int | None] = [None] * len(lines)
    candidates = []
    for i, line in enumerate(lines):
        runs = rob[b[line.inliers]]
        if len(runs) == 0:
            continue
        values, counts = np.unique(runs, return_counts=True)
        k = int(np.argmax(counts))
        run, share = int(values[k]), counts[k] / len(runs)
        if share < min_share or run == -1:
            continue
        if run == -2:
            result[i] = -1
            continue
        drho, dth = line_difference(line.rho, line.theta, truth[run].rho, truth[run].theta)
        if drho <= max_drho and np.degrees(dth) <= max_dtheta_deg:
            candidates.append((int(counts[k]), i, run))
    taken: set[int] = set()
    for _count, i, run in sorted(candidates, key=lambda c: (-c[0], c[1])):
        if run not in taken:
            taken.add(run)
            result[i] = run
    return result


def detection_scores(
    scans: Iterable[tuple[Sequence[Line], ArrayLike, Sequence[TrueLine], ArrayLike]],
    **match_kwargs: float,
) -> DetectionScores:
    """Nguyen et al. (2005) scores over scans given as ``(lines, beams, truth, run_of_beam)``."""
    t = _Tally()
    for lines, beams, truth, rob in scans:
        res = match_scan(lines, beams, truth, rob, **match_kwargs)
        t.n_true += len(truth)
        t.n_ignored += sum(r == -1 for r in res)
        t.n_found += sum(r != -1 for r in res)
        for line, r in zip(lines, res, strict=True):
            if r is not None and r >= 0:
                t.n_matched += 1
                drho, dth = line_difference(line.rho, line.theta, truth[r].rho, truth[r].theta)
                t.drho.append(drho)
                t.dtheta.append(dth)
    return DetectionScores(
        true_pos_rate=t.n_matched / t.n_true if t.n_true else float("nan"),
        false_pos_rate=(t.n_found - t.n_matched) / t.n_found if t.n_found else 0.0,
        rms_drho=float(np.sqrt(np.mean(np.square(t.drho)))) if t.drho else float("nan"),
        rms_dtheta_deg=float(np.degrees(np.sqrt(np.mean(np.square(t.dtheta)))))
        if t.dtheta
        else float("nan"),
        n_true=t.n_true,
        n_found=t.n_found,
        n_matched=t.n_matched,
        n_ignored=t.n_ignored,
    )


Extractor = Callable[[NDArray[np.float64]], list[Line]]


def score_extractor(
    extract: Extractor,
    log,
    scans: Iterable[int] | None = None,
    min_hits: int = 10,
    **match_kwargs: float,
) -> DetectionScores:
    """Run ``extract(points)`` on simulated scans and score it against the true walls.

    Parameters
    ----------
    extract : callable
        ``points (N, 2) in the laser frame -> list[Line]``.
    log : fhslam.io.Log
        A simulated log (it must carry ``truth``, ``hits`` and ``world``).
    scans : iterable of int, optional
        Scan indices to use (default: all).
    """
    if log.truth is None or log.hits is None or log.world is None:
        raise ValueError(
            f"log {log.name!r} has no ground truth (truth, hits, world): "
            "line-detection scores need a simulated log"
        )
    idx = range(len(log)) if scans is None else scans

    def per_scan():
        for k in idx:
            pts, beams = scan_to_points(log.ranges[k], log.angles, max_range=log.max_range)
            truth, rob = true_lines(log.hits[k], log.world.walls, log.truth[k], min_hits)
            yield extract(pts), beams, truth, rob

    return detection_scores(per_scan(), **match_kwargs)


# ==========================================================================================
# Trajectory metrics: absolute and relative pose error (after evo, github.com/MichaelGrupp/evo)
# ==========================================================================================
#
# Names and definitions follow evo (Grupp, "evo: Python package for the evaluation of
# odometry and SLAM", 2017): APE/ATE is the per-pose translation error, RPE the error of the
# relative motion between two poses, each summarised by rmse, mean, median, std, min, max.


@dataclass(frozen=True)
class ErrorStats:
    """Summary statistics of a set of errors, as evo reports them.

    Attributes
    ----------
    rmse : float
        ``sqrt(mean(e**2))``.
    mean, median : float
    std : float
        Population standard deviation (``numpy.std``, ``ddof=0``), as evo.
    min, max : float
    """

    rmse: float
    mean: float
    median: float
    std: float
    min: float
    max: float

    def as_dict(self) -> dict[str, float]:
        """``{"rmse": ..., "mean": ..., "median": ..., "std": ..., "min": ..., "max": ...}``."""
        return dict(self.__dict__)


def error_stats(errors: ArrayLike) -> ErrorStats:
    """Summarise errors by rmse, mean, median, std (population), min and max.

    Parameters
    ----------
    errors : array-like, shape (N,), N >= 1
        Finite error values (e.g. metres or degrees).

    Raises
    ------
    ValueError
        For no errors or a non-finite one.
    """
    e = np.asarray(errors, dtype=float).ravel()
    if e.size == 0:
        raise ValueError("error_stats needs at least one error value, got none")
    if not np.all(np.isfinite(e)):
        raise ValueError(f"error_stats got {int((~np.isfinite(e)).sum())} non-finite errors")
    return ErrorStats(
        rmse=float(np.sqrt(np.mean(e * e))),
        mean=float(np.mean(e)),
        median=float(np.median(e)),
        std=float(np.std(e)),
        min=float(np.min(e)),
        max=float(np.max(e)),
    )


def _stamps(t: ArrayLike, name: str) -> NDArray[np.float64]:
    a = np.asarray(t, dtype=float)
    if a.ndim != 1:
        raise ValueError(f"{name} must have shape (N,), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite")
    return a


def _nearest(query: NDArray[np.float64], stamps: NDArray[np.float64]) -> NDArray[np.intp]:
    """Index into ``stamps`` (any order) of the stamp nearest to each query, shape (Q,)."""
    order = np.argsort(stamps, kind="stable")
    s = stamps[order]
    pos = np.searchsorted(s, query)
    lo = np.clip(pos - 1, 0, len(s) - 1)
    hi = np.clip(pos, 0, len(s) - 1)
    take_hi = np.abs(s[hi] - query) < np.abs(s[lo] - query)
    return order[np.where(take_hi, hi, lo)]


def associate(
    t_est: ArrayLike, t_ref: ArrayLike, max_diff: float = 0.01
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Pair poses of two trajectories by timestamp, like evo's ``associate_trajectories``.

    Every stamp of the *shorter* trajectory (the reference on a tie) is paired with the
    nearest stamp of the other one, and the pair is kept if they differ by at most
    ``max_diff`` seconds. As in evo, a stamp of the longer trajectory may be used twice when
    the shorter one is sampled more densely than ``max_diff``.

    Parameters
    ----------
    t_est, t_ref : array-like, shape (N,) and (M,)
        Timestamps in seconds (any order).
    max_diff : float
        Largest accepted time difference, seconds (evo's default 0.01 s).

    Returns
    -------
    i_est, i_ref : ndarray of int, shape (K,)
        Indices of the matched poses, ``t_est[i_est[k]] ~ t_ref[i_ref[k]]``, in the order of
        the shorter trajectory.
    """
    te, tr = _stamps(t_est, "t_est"), _stamps(t_ref, "t_ref")
    if not max_diff >= 0:
        raise ValueError(f"max_diff must be >= 0 seconds, got {max_diff}")
    if len(te) == 0 or len(tr) == 0:
        return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
    if len(tr) > len(te):  # iterate over the shorter one, as evo does
        i_est = np.arange(len(te), dtype=np.intp)
        i_ref = _nearest(te, tr)
    else:
        i_ref = np.arange(len(tr), dtype=np.intp)
        i_est = _nearest(tr, te)
    keep = np.abs(te[i_est] - tr[i_ref]) <= max_diff
    return i_est[keep], i_ref[keep]


def _poses(p: ArrayLike, name: str, cols: tuple[int, ...] = (3,)) -> NDArray[np.float64]:
    a = np.asarray(p, dtype=float)
    if a.ndim != 2 or a.shape[1] not in cols:
        shapes = " or ".join(f"(N, {c})" for c in cols)
        raise ValueError(f"{name} must have shape {shapes}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite")
    return a


def _pair(est: ArrayLike, ref: ArrayLike, cols: tuple[int, ...]) -> tuple[NDArray, NDArray]:
    e, r = _poses(est, "est_poses", cols), _poses(ref, "ref_poses", cols)
    if len(e) != len(r):
        raise ValueError(
            f"est_poses and ref_poses must be associated pose by pose (fhslam.metrics."
            f"associate), got {len(e)} and {len(r)} poses"
        )
    if len(e) == 0:
        raise ValueError("no poses to compare")
    return e, r


def align_se2(src: ArrayLike, dst: ArrayLike) -> NDArray[np.float64]:
    """Rigid SE(2) least-squares alignment of point sets (Umeyama 1991 without scale).

    Finds the rotation ``R(theta)`` and translation ``t`` minimising
    ``sum_i |dst_i - (R src_i + t)|**2``. In 2D Umeyama's SVD solution has the closed form
    ``theta = atan2(sum cross(a_i, b_i), sum dot(a_i, b_i))`` for the centred points
    ``a = src - mean(src)``, ``b = dst - mean(dst)`` (a proper rotation, never a reflection),
    and ``t = mean(dst) - R mean(src)``.

    Parameters
    ----------
    src, dst : array-like, shape (N, 2) or (N, 3)
        Corresponding positions (only x, y are used), e.g. estimated and true poses.

    Returns
    -------
    ndarray, shape (3,)
        The transform as a pose ``(x, y, theta)``: ``transform_points(T, src) ~ dst``.
        With all ``src`` points identical the rotation is undetermined and 0 is returned.
    """
    s, d = _pair(src, dst, (2, 3))
    s, d = s[:, :2], d[:, :2]
    ms, md = s.mean(axis=0), d.mean(axis=0)
    a, b = s - ms, d - md
    theta = float(
        np.arctan2(
            np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]),
            np.sum(a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1]),
        )
    )
    c, sn = np.cos(theta), np.sin(theta)
    t = md - np.array([c * ms[0] - sn * ms[1], sn * ms[0] + c * ms[1]])
    return np.array([t[0], t[1], theta])


def ate_errors(est_poses: ArrayLike, ref_poses: ArrayLike, align: bool = False) -> NDArray:
    """Per-pose translation error ``|p_est - p_ref|`` (evo's APE, translation part), metres.

    Parameters
    ----------
    est_poses, ref_poses : array-like, shape (N, 3) or (N, 2)
        Associated poses (see :func:`associate`); only x, y are used.
    align : bool
        First move the estimate rigidly onto the reference (:func:`align_se2`).

    Returns
    -------
    ndarray, shape (N,)
    """
    e, r = _pair(est_poses, ref_poses, (2, 3))
    p = e[:, :2]
    if align:
        p = transform_points(align_se2(p, r), p)
    return np.hypot(*(p - r[:, :2]).T)


def ate(est_poses: ArrayLike, ref_poses: ArrayLike, align: bool = False) -> ErrorStats:
    """Absolute trajectory error (evo's APE, translation part), metres.

    By default **no alignment**: the SLAM starts at the known first true pose, so its map
    frame is the world frame and any offset is a real error (evo ``evo_ape`` without ``-a``).
    ``align=True`` first applies the SE(2) least-squares alignment (Umeyama without scale,
    evo ``-a``), which measures only the shape of the trajectory.

    Parameters
    ----------
    est_poses, ref_poses : array-like, shape (N, 3) or (N, 2)
        Associated estimated and true poses (see :func:`associate`).
    align : bool

    Returns
    -------
    ErrorStats
    """
    return error_stats(ate_errors(est_poses, ref_poses, align=align))


def rpe_pairs(n: int, delta: int = 1, all_pairs: bool = False) -> NDArray[np.intp]:
    """Index pairs ``(i, j)`` ``delta`` frames apart, as evo's ``filter_pairs_by_index``.

    Parameters
    ----------
    n : int
        Number of poses.
    delta : int
        Frame distance, >= 1.
    all_pairs : bool
        False (evo's default): consecutive, non-overlapping pairs ``(0, d), (d, 2d), ...``;
        True: every ``(i, i + d)``.

    Returns
    -------
    ndarray of int, shape (K, 2)
    """
    if int(delta) != delta or delta < 1:
        raise ValueError(f"delta must be an integer >= 1 (frames), got {delta}")
    delta = int(delta)
    if all_pairs:
        i = np.arange(max(n - delta, 0), dtype=np.intp)
        return np.column_stack([i, i + delta])
    ids = np.arange(0, n, delta, dtype=np.intp)
    return np.column_stack([ids[:-1], ids[1:]])


def rpe_errors(
    est_poses: ArrayLike, ref_poses: ArrayLike, delta: int = 1, all_pairs: bool = False
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Relative pose errors between poses ``delta`` frames apart (evo's RPE).

    For each pair ``(i, j)`` (:func:`rpe_pairs`) the error is the SE(2) pose
    ``E = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j)`` with true poses ``Q`` and estimates ``P``; the
    translation error is ``|t(E)|`` and the rotation error ``|angle(E)|``.

    Parameters
    ----------
    est_poses, ref_poses : array-like, shape (N, 3)
        Associated poses ``(x, y, theta)``.
    delta : int
        Frame distance of the pairs.
    all_pairs : bool
        Use every pair ``(i, i + delta)`` instead of evo's default consecutive pairs.

    Returns
    -------
    trans : ndarray, shape (K,)
        Translation errors, metres.
    rot : ndarray, shape (K,)
        Rotation errors, radians, in [0, pi].
    """
    e, r = _pair(est_poses, ref_poses, (3,))
    ij = rpe_pairs(len(e), delta, all_pairs)
    if len(ij) == 0:
        raise ValueError(f"RPE with delta={delta} needs at least {delta + 1} poses, got {len(e)}")
    i, j = ij[:, 0], ij[:, 1]
    err = relative(relative(r[i], r[j]), relative(e[i], e[j]))
    return np.hypot(err[:, 0], err[:, 1]), np.abs(wrap_angle(err[:, 2]))


def rpe(
    est_poses: ArrayLike, ref_poses: ArrayLike, delta: int = 1, all_pairs: bool = False
) -> ErrorStats:
    """Relative pose error, translation part, metres (see :func:`rpe_errors`)."""
    return error_stats(rpe_errors(est_poses, ref_poses, delta, all_pairs)[0])


def rpe_rot_deg(
    est_poses: ArrayLike, ref_poses: ArrayLike, delta: int = 1, all_pairs: bool = False
) -> ErrorStats:
    """Relative pose error, rotation part, degrees (see :func:`rpe_errors`)."""
    return error_stats(np.degrees(rpe_errors(est_poses, ref_poses, delta, all_pairs)[1]))


# ==========================================================================================
# Map metrics: the SLAM map's line segments against the world's true walls
# ==========================================================================================


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
        :func:`observed_wall_points` or :func:`visible_wall_points`.
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


def _beam_wall_points(
    walls: NDArray, poses: NDArray, angles: NDArray, hits: NDArray
) -> NDArray[np.float64]:
    """Exact intersection of each beam with the wall it hit; poses (K, 3), hits (K, B)."""
    k, b = np.nonzero(hits >= 0)
    w = walls[hits[k, b]]
    o = poses[k, :2]
    a = angles[b] + poses[k, 2]
    d = np.column_stack([np.cos(a), np.sin(a)])
    t, _ = ray_segment_intersection(o, d, w[:, :2], w[:, 2:])
    return o + t[:, None] * d


def observed_wall_points(log, every: int = 5) -> NDArray[np.float64]:
    """The noise-free points where the beams of a simulated log hit the walls.

    For every ``every``-th scan, each beam with a return is intersected exactly with the wall
    it hit (``log.hits``), from the true pose (``log.truth``): the part of the world the
    robot actually saw, for :func:`map_coverage`.

    Parameters
    ----------
    log : fhslam.io.Log
        A simulated log carrying ``truth``, ``hits`` and ``world``.
    every : int
        Use scans ``0, every, 2 every, ...``.

    Returns
    -------
    ndarray, shape (P, 2)
        World-frame points, metres.
    """
    if log.truth is None or log.hits is None or log.world is None:
        raise ValueError(
            f"log {log.name!r} has no ground truth (truth, hits, world): observed wall "
            "points need a simulated log"
        )
    if int(every) != every or every < 1:
        raise ValueError(f"every must be an integer >= 1, got {every}")
    walls = np.asarray(log.world.walls, dtype=float)
    return _beam_wall_points(walls, log.truth[::every], log.angles, log.hits[::every])


def visible_wall_points(
    walls: ArrayLike,
    poses: ArrayLike,
    every: int = 5,
    n_beams: int = 181,
    fov_deg: float = 180.0,
    max_range: float = 8.0,
) -> NDArray[np.float64]:
    """Wall points a laser would hit from given poses: exact ray casting, no simulation.

    For when only the world and the true trajectory are at hand (``fhslam evaluate
    --world``): from every ``every``-th pose, ``n_beams`` beams spread over ``fov_deg``
    around the heading (default: the paper's SICK LMS200, 181 beams over 180 degrees, 8 m)
    are cast into the walls (:func:`fhslam.sim.cast_rays`) and the noise-free hit points
    returned. For a log simulated with that laser this equals :func:`observed_wall_points`.

    Parameters
    ----------
    walls : array-like, shape (W, 4)
    poses : array-like, shape (T, 3)
        True laser poses, world frame.
    every : int
    n_beams, fov_deg, max_range
        The laser (beams from ``-fov/2`` to ``+fov/2``, both included; metres).

    Returns
    -------
    ndarray, shape (P, 2)
    """
    from fhslam.sim.laser import cast_rays  # metrics sits above sim; import on use

    if int(every) != every or every < 1:
        raise ValueError(f"every must be an integer >= 1, got {every}")
    w = np.asarray(walls, dtype=float).reshape(-1, 4)
    q = _poses(poses, "poses")[:: int(every)]
    half = np.radians(fov_deg) / 2
    angles = np.linspace(-half, half, int(n_beams))
    hits = np.array([cast_rays(w, pose, angles, max_range)[1] for pose in q], dtype=np.intp)
    return _beam_wall_points(w, q, angles, hits.reshape(len(q), len(angles)))


# ==========================================================================================
# The relations metric of the Freiburg SLAM benchmark (Kümmerle et al. 2009)
# ==========================================================================================
#
# R. Kümmerle, B. Steder, C. Dornhege, M. Ruhnke, G. Grisetti, C. Stachniss, A. Kleiner,
# "On measuring the accuracy of SLAM algorithms", Autonomous Robots 27(4):387-407, 2009.
# Reported as in W. Hess, D. Kohler, H. Rapp, D. Andor, "Real-time loop closure in 2D LIDAR
# SLAM", ICRA 2016, Table II: mean ± std of the absolute and of the squared error.


@dataclass(frozen=True)
class RelationsError:
    """The Kümmerle et al. (2009) relations error, summarised as in Hess et al. (2016).

    Attributes
    ----------
    trans_mean, trans_std : float
        Mean and population standard deviation of the translational errors, metres.
    trans_sq_mean, trans_sq_std : float
        The same of the squared translational errors, m².
    rot_mean_deg, rot_std_deg : float
        Mean and population standard deviation of the rotational errors, degrees.
    rot_sq_mean_deg, rot_sq_std_deg : float
        The same of the squared rotational errors, deg².
    n_used : int
        Relations whose two timestamps were both found in the trajectory.
    n_total : int
        All relations given.
    """

    trans_mean: float
    trans_std: float
    trans_sq_mean: float
    trans_sq_std: float
    rot_mean_deg: float
    rot_std_deg: float
    rot_sq_mean_deg: float
    rot_sq_std_deg: float
    n_used: int
    n_total: int

    def as_dict(self) -> dict[str, float | int]:
        """All fields by name, e.g. ``{"trans_mean": ..., ..., "n_total": ...}``."""
        return dict(self.__dict__)


def relations_errors(
    timestamps: ArrayLike,
    poses: ArrayLike,
    t1: ArrayLike,
    t2: ArrayLike,
    rel: ArrayLike,
    max_diff: float = 0.001,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """Per-relation errors of a trajectory against true relative motions (Kümmerle 2009).

    For relation ``k`` the poses at ``t1[k]`` and ``t2[k]`` are the trajectory's poses with
    the nearest timestamps, if these lie within ``max_diff`` seconds (no interpolation: a
    trajectory has one pose per scan and the relations are given between scans). With the
    estimated motion ``δ = ⊖pose(t1) ⊕ pose(t2)`` and the true one ``δ* = rel[k]``, the error
    is Kümmerle's ``δ ⊖ δ* = ⊖δ* ⊕ δ`` (``relative(δ*, δ)``), of which the translational
    error is ``|(x, y)|`` and the rotational error ``|wrap(θ)|``.

    (Cartographer's ``compute_relations_metrics`` composes the other way round,
    ``δ ⊕ ⊖δ*``, whose translation also picks up the rotational error; the two agree
    when the estimated rotation is right.)

    Parameters
    ----------
    timestamps : array-like, shape (N,)
        Timestamps of the trajectory's poses, seconds (any order).
    poses : array-like, shape (N, 3)
        Trajectory ``(x, y, theta)``, metres and radians, in any fixed frame.
    t1, t2 : array-like, shape (R,)
        Relation timestamps (see :func:`fhslam.io.read_relations`).
    rel : array-like, shape (R, 3)
        True relative motions ``(x, y, yaw)`` from the pose at ``t1`` to the pose at ``t2``,
        in the frame of the pose at ``t1``.
    max_diff : float
        Largest accepted difference between a relation timestamp and a pose timestamp,
        seconds. The default 1 ms absorbs the rounding of mit-csail's relations (5 decimals)
        against its log (6 decimals).

    Returns
    -------
    trans : ndarray, shape (K,)
        Translational errors of the used relations, metres.
    rot : ndarray, shape (K,)
        Rotational errors of the used relations, radians, in [0, pi].
    used : ndarray of bool, shape (R,)
        Which relations were used (``K = used.sum()``); the others have a timestamp not in
        the trajectory.
    """
    ts = _stamps(timestamps, "timestamps")
    p = _poses(poses, "poses")
    if len(p) != len(ts):
        raise ValueError(
            f"timestamps and poses must have the same length, got {len(ts)} and {len(p)}"
        )
    a, b = _stamps(t1, "t1"), _stamps(t2, "t2")
    r = _poses(rel, "rel")
    if not len(a) == len(b) == len(r):
        raise ValueError(
            f"t1, t2 and rel must have the same length, got {len(a)}, {len(b)} and {len(r)}"
        )
    if not max_diff >= 0:
        raise ValueError(f"max_diff must be >= 0 seconds, got {max_diff}")
    if len(ts) == 0 or len(a) == 0:
        empty = np.zeros(0)
        return empty, empty.copy(), np.zeros(len(a), dtype=bool)
    i1, i2 = _nearest(a, ts), _nearest(b, ts)
    used = (np.abs(ts[i1] - a) <= max_diff) & (np.abs(ts[i2] - b) <= max_diff)
    est = relative(p[i1[used]], p[i2[used]])
    err = relative(r[used], est)
    return np.hypot(err[:, 0], err[:, 1]), np.abs(wrap_angle(err[:, 2])), used


def relations_error(
    timestamps: ArrayLike,
    poses: ArrayLike,
    t1: ArrayLike,
    t2: ArrayLike,
    rel: ArrayLike,
    max_diff: float = 0.001,
) -> RelationsError:
    """Kümmerle et al. (2009) relations error of a trajectory, as Hess et al. (2016) Table II.

    The per-relation translational and rotational errors (:func:`relations_errors`) are
    summarised by the mean and standard deviation of the absolute error and of the squared
    error: metres and m², degrees and deg². Relations with a timestamp not found in the
    trajectory (within ``max_diff`` seconds) are skipped and counted: ``n_used`` of
    ``n_total``.

    The standard deviations are population ones (``numpy.std``, ``ddof=0``, as the other
    metrics here); Cartographer's tool divides by ``n - 1``, a relative difference of
    ``1/(2n)``, 0.04 % for a thousand relations.

    Parameters
    ----------
    timestamps, poses, t1, t2, rel, max_diff
        As in :func:`relations_errors`.

    Returns
    -------
    RelationsError

    Raises
    ------
    ValueError
        If no relation can be used (the message says how many relation timestamps matched
        a pose), or for inputs of wrong shape or non-finite values.
    """
    trans, rot, used = relations_errors(timestamps, poses, t1, t2, rel, max_diff)
    if not used.any():
        ts = _stamps(timestamps, "timestamps")
        stamps = np.concatenate([_stamps(t1, "t1"), _stamps(t2, "t2")])
        found = 0
        if len(ts) and len(stamps):
            found = int(np.sum(np.abs(ts[_nearest(stamps, ts)] - stamps) <= max_diff))
        raise ValueError(
            f"no relation can be used: {found} of the {len(stamps)} relation timestamps "
            f"match a pose of the trajectory within {max_diff:g} s, and a relation needs "
            "both of its two; are the trajectory's timestamps the scans' own?"
        )
    rot_deg = np.degrees(rot)
    sq_t, sq_r = trans * trans, rot_deg * rot_deg
    return RelationsError(
        trans_mean=float(np.mean(trans)),
        trans_std=float(np.std(trans)),
        trans_sq_mean=float(np.mean(sq_t)),
        trans_sq_std=float(np.std(sq_t)),
        rot_mean_deg=float(np.mean(rot_deg)),
        rot_std_deg=float(np.std(rot_deg)),
        rot_sq_mean_deg=float(np.mean(sq_r)),
        rot_sq_std_deg=float(np.std(sq_r)),
        n_used=int(used.sum()),
        n_total=len(used),
    )
