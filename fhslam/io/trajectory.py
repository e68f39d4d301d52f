"""Trajectory text files: one pose per line, ``timestamp x y theta``, ``#`` comments allowed;
one pose per timestamp (a timestamp repeated with another pose is an error).

Used for estimated trajectories (``fhslam slam --trajectory``) and for simulated ground truth.
Numbers are written with Python's shortest round-trip ``repr``, so a file reads back exactly.
"""

from __future__ import annotations

from collections.abc import Iterable
from os import PathLike

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.errors import InputError, InputWarning
from fhslam.geometry import wrap_angle
from fhslam.io.files import atomic_output
from fhslam.io.log import read_numeric_table
from fhslam.io.plausibility import check_sequence


class TrajectoryFormatError(InputError):
    """A malformed trajectory file. The message reads ``"{path}:{lineno}: {what is wrong}"``."""


class TrajectoryWarning(InputWarning):
    """A trajectory file whose time runs backwards or repeats (read as it is)."""


SAME_POSE = (1e-9, 1e-9)
"""How far (metres, radians) two poses of one timestamp may differ and still be one pose
(a file written by :func:`write_trajectory` repeats a pose exactly)."""


def write_trajectory(
    path: str | PathLike[str],
    timestamps: ArrayLike,
    poses: ArrayLike,
    header: str | Iterable[str] | None = None,
) -> None:
    """Write poses as ``timestamp x y theta`` lines.

    Parameters
    ----------
    path : str or path-like
        Output file, overwritten.
    timestamps : array-like, shape (T,)
        Seconds, e.g. the scans' own timestamps.
    poses : array-like, shape (T, 3)
        ``(x, y, theta)`` in metres and radians.
    header : str or iterable of str, optional
        Comment lines written first, each prefixed with ``"# "`` (a multi-line string is
        split at newlines).
    """
    t = np.asarray(timestamps, dtype=float)
    p = np.asarray(poses, dtype=float)
    if t.ndim != 1 or len(t) == 0:
        raise ValueError(f"timestamps must have shape (T,) with T >= 1, got {t.shape}")
    if p.shape != (len(t), 3):
        raise ValueError(f"poses must have shape ({len(t)}, 3) to match timestamps, got {p.shape}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(p))):
        raise ValueError("timestamps and poses must be finite")
    if header is None:
        comments: list[str] = []
    elif isinstance(header, str):
        comments = header.splitlines()
    else:
        comments = [c for h in header for c in str(h).splitlines()]
    rows = np.column_stack([t, p]).tolist()
    with atomic_output(path) as f:
        for c in comments:
            f.write(f"# {c}\n")
        for row in rows:
            f.write(" ".join(repr(v) for v in row) + "\n")


def read_trajectory(path: str | PathLike[str]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Read a ``timestamp x y theta`` file.

    Returns
    -------
    timestamps : ndarray, shape (T,)
    poses : ndarray, shape (T, 3)

    Raises
    ------
    MissingInputError
        If ``path`` does not exist.
    TrajectoryFormatError
        ``"{path}:{lineno}: ..."`` for a line without exactly 4 fields, a non-numeric or
        non-finite value, or two lines of one timestamp whose poses differ (by more than
        :data:`SAME_POSE`; naming both lines and the timestamp: which of them is the pose
        at that time cannot be told), or ``"{path}: ..."`` for a file without poses.

    Warns
    -----
    TrajectoryWarning
        Where the timestamps run backwards or repeat (naming the file and line): the file
        is read as it is. Poses are matched by timestamp in any order; a timestamp repeated
        with the same pose is read as it is (each line is a pose).
    """
    a, lines = read_numeric_table(
        path, "timestamp x y theta", TrajectoryFormatError, "poses", with_lines=True
    )
    _check_repeated_stamps(path, a[:, 0], a[:, 1:], lines)
    check_sequence(path, a[:, 0], None, lines, TrajectoryWarning, noun="pose")
    return a[:, 0], a[:, 1:]


def _check_repeated_stamps(
    path: str | PathLike[str], t: NDArray[np.float64], poses: NDArray[np.float64], lines
) -> None:
    """Refuse two poses of one timestamp (anywhere in the file) that differ by more than
    :data:`SAME_POSE`: a :class:`TrajectoryFormatError` naming the later line, the earlier
    one and the timestamp (the first such pair in the file, and how many more)."""
    order = np.argsort(t, kind="stable")
    ts = t[order]
    first = np.searchsorted(ts, ts, side="left")  # the first of each run of equal stamps
    k = np.flatnonzero(first != np.arange(len(ts)))
    if not len(k):
        return
    a, b = order[first[k]], order[k]  # a before b in the file (a stable sort)
    d = poses[b] - poses[a]
    d[:, 2] = wrap_angle(d[:, 2])
    tol_xy, tol_theta = SAME_POSE
    bad = (np.abs(d[:, :2]).max(axis=1) > tol_xy) | (np.abs(d[:, 2]) > tol_theta)
    if not bad.any():
        return
    a, b = a[bad], b[bad]
    j = int(np.argmin(b))
    i, k = int(a[j]), int(b[j])
    more = f" (and {len(b) - 1} more such lines)" if len(b) > 1 else ""
    raise TrajectoryFormatError(
        f"{path}:{lines[k]}: timestamp {float(t[k])!r} repeats that of line {lines[i]} with "
        f"another pose ({_pose(poses[k])} on line {lines[k]}, {_pose(poses[i])} on line "
        f"{lines[i]}){more}: a trajectory has one pose per timestamp"
    )


def _pose(p: NDArray[np.float64]) -> str:
    return f"x {p[0]:.6g} y {p[1]:.6g} theta {p[2]:.6g}"
