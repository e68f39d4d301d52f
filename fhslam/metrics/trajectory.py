"""Trajectory metrics: absolute and relative pose error (after evo, github.com/MichaelGrupp/evo).

Names and definitions follow evo (Grupp, "evo: Python package for the evaluation of
odometry and SLAM", 2017): APE/ATE is the per-pose translation error, RPE the error of the
relative motion between two poses, each summarised by rmse, mean, median, std, min, max.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.geometry import relative, transform_points, wrap_angle
from fhslam.metrics._arrays import _nearest, _pair, _stamps


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
