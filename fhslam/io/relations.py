"""Relations files of the Freiburg SLAM benchmark (Kümmerle et al. 2009).

One relation per line, ``timestamp1 timestamp2 x y z roll pitch yaw``: the true relative
motion from the robot's pose at ``timestamp1`` to its pose at ``timestamp2``, expressed in
the frame of the first pose (metres, radians). The timestamps are the logs' scan stamps
(CARMEN ``ipc_timestamp``). ``#`` comments and blank lines are skipped. See
``data/SOURCES.md`` and :func:`fhslam.metrics.relations_error`.

R. Kümmerle, B. Steder, C. Dornhege, M. Ruhnke, G. Grisetti, C. Stachniss, A. Kleiner,
"On measuring the accuracy of SLAM algorithms", Autonomous Robots 27(4):387-407, 2009.
"""

from __future__ import annotations

from os import PathLike

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.errors import InputError
from fhslam.io.files import atomic_output
from fhslam.io.log import read_numeric_table

PLANAR_TOL = 1e-6
"""Largest ``|z|``, ``|roll|``, ``|pitch|`` accepted: the relations metric here is 2-D."""

_FIELDS = "timestamp1 timestamp2 x y z roll pitch yaw"


class RelationsFormatError(InputError):
    """A malformed relations file. The message reads ``"{path}:{lineno}: {what is wrong}"``."""


def read_relations(
    path: str | PathLike[str],
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Read a ``.relations`` file (``timestamp1 timestamp2 x y z roll pitch yaw`` lines).

    Parameters
    ----------
    path : str or path-like
        The relations file.

    Returns
    -------
    t1, t2 : ndarray, shape (R,)
        Timestamps of the first and second pose of each relation, seconds.
    rel : ndarray, shape (R, 3)
        True relative motion ``(x, y, yaw)`` from the pose at ``t1`` to the pose at ``t2``,
        in the frame of the pose at ``t1`` (metres, radians), in file order.

    Raises
    ------
    MissingInputError
        If ``path`` does not exist.
    RelationsFormatError
        ``"{path}:{lineno}: ..."`` for a line without exactly 8 fields, a non-numeric or
        non-finite value, or a non-planar relation (``|z|``, ``|roll|`` or ``|pitch|``
        above 1e-6); ``"{path}: ..."`` for a file without relations or not text.
    """

    def planar(row: list[float], where: str) -> None:
        for name, value in zip(("z", "roll", "pitch"), row[4:7], strict=True):
            if abs(value) > PLANAR_TOL:
                raise RelationsFormatError(
                    f"{where}: {name} = {value:g} is not 0: only planar (2-D) "
                    "relations are supported (|z|, |roll|, |pitch| <= 1e-6)"
                )

    a = read_numeric_table(path, _FIELDS, RelationsFormatError, "relations", planar)
    return a[:, 0], a[:, 1], a[:, [2, 3, 7]]


def write_relations(
    path: str | PathLike[str],
    t1: ArrayLike,
    t2: ArrayLike,
    rel: ArrayLike,
    header: str | None = None,
) -> None:
    """Write planar relations as ``timestamp1 timestamp2 x y z roll pitch yaw`` lines, the
    format :func:`read_relations` reads (``z``, ``roll`` and ``pitch`` written as 0).

    Parameters
    ----------
    path : str or path-like
        Output file, overwritten.
    t1, t2 : array-like, shape (R,)
        Timestamps of each relation's first and second pose, seconds.
    rel : array-like, shape (R, 3)
        ``(x, y, yaw)`` of each relation (metres, radians).
    header : str, optional
        Comment lines written first, each prefixed with ``"# "``.

    Raises
    ------
    ValueError
        For inputs of wrong shape, none, or non-finite values.
    """
    a, b = np.asarray(t1, dtype=float), np.asarray(t2, dtype=float)
    r = np.asarray(rel, dtype=float)
    if a.ndim != 1 or len(a) == 0 or b.shape != a.shape or r.shape != (len(a), 3):
        raise ValueError(
            f"t1, t2 and rel must have shapes (R,), (R,), (R, 3) with R >= 1, got "
            f"{a.shape}, {b.shape}, {r.shape}"
        )
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b)) and np.all(np.isfinite(r))):
        raise ValueError("relations must be finite")
    zeros = np.zeros(len(a))
    rows = np.column_stack([a, b, r[:, 0], r[:, 1], zeros, zeros, zeros, r[:, 2]]).tolist()
    with atomic_output(path) as f:
        for c in (header or "").splitlines():
            f.write(f"# {c}\n")
        for row in rows:
            f.write(" ".join(repr(v) for v in row) + "\n")
