"""Trajectory text files: one pose per line, ``timestamp x y theta``, ``#`` comments allowed.

Used for estimated trajectories (``fhslam slam --trajectory``) and for simulated ground truth.
Numbers are written with Python's shortest round-trip ``repr``, so a file reads back exactly.
"""

from __future__ import annotations

from collections.abc import Iterable
from os import PathLike

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.errors import InputError, InputWarning
from fhslam.io.files import atomic_output
from fhslam.io.log import check_sequence, read_numeric_table


class TrajectoryFormatError(InputError):
    """A malformed trajectory file. The message reads ``"{path}:{lineno}: {what is wrong}"``."""


class TrajectoryWarning(InputWarning):
    """A trajectory file whose time runs backwards or repeats (read as it is)."""


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
        non-finite value, or ``"{path}: ..."`` for a file without poses.

    Warns
    -----
    TrajectoryWarning
        Where the timestamps run backwards or repeat (naming the file and line): the file
        is read as it is. Poses are matched by timestamp in any order; of poses that share
        a timestamp, the first in the file is the one matched.
    """
    a, lines = read_numeric_table(
        path, "timestamp x y theta", TrajectoryFormatError, "poses", with_lines=True
    )
    check_sequence(path, a[:, 0], None, lines, TrajectoryWarning, noun="pose")
    return a[:, 0], a[:, 1:]
