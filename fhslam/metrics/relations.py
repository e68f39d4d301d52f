"""The relations metric of the Freiburg SLAM benchmark (Kümmerle et al. 2009).

R. Kümmerle, B. Steder, C. Dornhege, M. Ruhnke, G. Grisetti, C. Stachniss, A. Kleiner,
"On measuring the accuracy of SLAM algorithms", Autonomous Robots 27(4):387-407, 2009.
Reported as in W. Hess, D. Kohler, H. Rapp, D. Andor, "Real-time loop closure in 2D LIDAR
SLAM", ICRA 2016, Table II: mean ± std of the absolute and of the squared error.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from fhslam.geometry import compose, relative, wrap_angle
from fhslam.metrics._arrays import _nearest, _poses, _stamps


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


def sample_relations(
    timestamps: ArrayLike,
    truth: ArrayLike,
    step: float = 0.5,
    revisit_radius: float = 1.0,
    revisit_gap: float = 60.0,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Relations in the manner of the Freiburg benchmark's, taken from a known truth.

    So that a simulated run is measured as a real log is (:func:`relations_error`): the
    benchmark's relations join poses about half a metre of travel apart (median 0.28–0.51 m
    on Intel, ACES, MIT CSAIL, Freiburg 079 and MIT Killian) and, for 6–41 % of them, poses
    of one place visited again a minute or more later. Here, deterministically:

    - *anchors*: the first pose, then each pose ``step`` metres of travel or 10 degrees of
      turning on from the anchor before it; one relation from each anchor to the next;
    - *revisits*: for each anchor, the nearest earlier anchor within ``revisit_radius``
      metres that lies ``revisit_gap`` seconds or more before it (none if there is none).

    Parameters
    ----------
    timestamps : array-like, shape (T,)
        Seconds, increasing.
    truth : array-like, shape (T, 3)
        True poses ``(x, y, theta)``, metres and radians.
    step, revisit_radius, revisit_gap : float
        As above: metres, metres, seconds (all positive).

    Returns
    -------
    t1, t2 : ndarray, shape (R,)
        Timestamps of each relation's first and second pose (sequential relations first).
    rel : ndarray, shape (R, 3)
        The true motion from the first pose to the second, in the first's frame.

    Raises
    ------
    ValueError
        For inputs of wrong shape, non-finite or non-increasing timestamps, non-positive
        parameters, or a truth too short to give one relation.
    """
    ts = _stamps(timestamps, "timestamps")
    p = _poses(truth, "truth")
    if len(p) != len(ts):
        raise ValueError(
            f"truth must have one pose per timestamp: {len(p)} poses, {len(ts)} stamps"
        )
    given = {"step": step, "revisit_radius": revisit_radius, "revisit_gap": revisit_gap}
    for name, v in given.items():
        if not (np.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be a positive number, got {v!r}")
    if len(ts) > 1 and not np.all(np.diff(ts) > 0):
        raise ValueError("timestamps must be strictly increasing")
    travel = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p[:, :2], axis=0).T))])
    heading = np.concatenate([[0.0], np.cumsum(np.abs(wrap_angle(np.diff(p[:, 2]))))])
    # A simulated robot moves in equal steps, so travel often lands on a multiple of `step`
    # itself; a threshold a hair below it keeps the last bit from choosing the anchors.
    reach, turn = step * (1.0 - 1e-9), np.radians(10.0) * (1.0 - 1e-9)
    anchors = [0]
    for k in range(1, len(ts)):  # one pass; the thresholds need the anchor before
        a = anchors[-1]
        if travel[k] - travel[a] >= reach or heading[k] - heading[a] >= turn:
            anchors.append(k)
    idx = np.asarray(anchors)
    if len(idx) < 2:
        raise ValueError(
            f"the truth travels {travel[-1]:.3g} m and turns {np.degrees(heading[-1]):.3g} "
            f"degrees: too little for one relation of {step:g} m or 10 degrees"
        )
    first, second = list(idx[:-1]), list(idx[1:])
    xy = p[idx, :2]
    for b, near in enumerate(cKDTree(xy).query_ball_point(xy, revisit_radius)):
        old = [a for a in near if ts[idx[b]] - ts[idx[a]] >= revisit_gap]
        if old:
            d = np.hypot(*(xy[old] - xy[b]).T)
            first.append(idx[old[int(np.argmin(d))]])
            second.append(idx[b])
    i1, i2 = np.asarray(first), np.asarray(second)
    return ts[i1], ts[i2], relative(p[i1], p[i2])


def extend_by_odometry(
    timestamps: ArrayLike,
    poses: ArrayLike,
    all_timestamps: ArrayLike,
    odometry: ArrayLike,
) -> NDArray[np.float64]:
    """A trajectory over some of a log's scans (a sparse copy's, :func:`fhslam.sim.sparsify`)
    extended to every scan of the log by its odometry, so that it meets the log's relations.

    Scan ``j`` gets the pose of the latest trajectory scan ``k`` at or before it, moved by
    the odometry from ``k`` to ``j``: ``poses[k] ⊕ (⊖odometry[k] ⊕ odometry[j])``. What the
    odometry adds between two kept scans (under a metre) is a floor of the relations error
    the extended trajectory can reach.

    Parameters
    ----------
    timestamps : array-like, shape (N,)
        The trajectory's timestamps, increasing, each one of ``all_timestamps``.
    poses : array-like, shape (N, 3)
        Its poses (robot frame, as the odometry).
    all_timestamps : array-like, shape (T,)
        Every scan's timestamp, increasing; the first is the trajectory's first.
    odometry : array-like, shape (T, 3)
        The odometry pose at every scan.

    Returns
    -------
    ndarray, shape (T, 3)

    Raises
    ------
    ValueError
        For shapes that do not match, or a trajectory timestamp that is not a scan's, or a
        trajectory that does not start at the first scan.
    """
    ts, p = _stamps(timestamps, "timestamps"), _poses(poses, "poses")
    every, odo = _stamps(all_timestamps, "all_timestamps"), _poses(odometry, "odometry")
    if len(ts) != len(p) or len(every) != len(odo):
        raise ValueError(
            "timestamps and poses, all_timestamps and odometry must have the same lengths, "
            f"got {len(ts)}, {len(p)}, {len(every)} and {len(odo)}"
        )
    idx = np.minimum(np.searchsorted(every, ts), max(len(every) - 1, 0))
    if not (len(ts) and np.array_equal(every[idx], ts) and idx[0] == 0) or np.any(
        np.diff(idx) <= 0
    ):
        raise ValueError(
            "the trajectory's timestamps must be increasing scan timestamps of the log, "
            "starting at its first scan"
        )
    k = np.searchsorted(idx, np.arange(len(every)), side="right") - 1
    return compose(p[k], relative(odo[idx[k]], odo))
