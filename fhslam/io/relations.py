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

import errno
from os import PathLike
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from fhslam.io.log import is_number

PLANAR_TOL = 1e-6
"""Largest ``|z|``, ``|roll|``, ``|pitch|`` accepted: the relations metric here is 2-D."""

_FIELDS = "timestamp1 timestamp2 x y z roll pitch yaw"


class RelationsFormatError(ValueError):
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
    FileNotFoundError
        If ``path`` does not exist.
    RelationsFormatError
        ``"{path}:{lineno}: ..."`` for a line without exactly 8 fields, a non-numeric or
        non-finite value, or a non-planar relation (``|z|``, ``|roll|`` or ``|pitch|``
        above 1e-6); ``"{path}: ..."`` for a file without relations or not text.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(errno.ENOENT, "relations file not found", str(path))
    rows: list[list[float]] = []
    try:
        with path.open(encoding="utf-8") as f:
            for lineno, line in enumerate(f, start=1):
                fields = line.split()
                if not fields or fields[0].startswith("#"):
                    continue
                where = f"{path}:{lineno}"
                if len(fields) != 8:
                    raise RelationsFormatError(
                        f"{where}: expected 8 fields '{_FIELDS}', found {len(fields)}"
                    )
                try:
                    row = [float(v) for v in fields]
                except ValueError:
                    bad = next(v for v in fields if not is_number(v))
                    raise RelationsFormatError(f"{where}: non-numeric value {bad!r}") from None
                if not all(np.isfinite(row)):
                    raise RelationsFormatError(f"{where}: non-finite value in {fields}")
                for name, value in zip(("z", "roll", "pitch"), row[4:7], strict=True):
                    if abs(value) > PLANAR_TOL:
                        raise RelationsFormatError(
                            f"{where}: {name} = {value:g} is not 0: only planar (2-D) "
                            "relations are supported (|z|, |roll|, |pitch| <= 1e-6)"
                        )
                rows.append(row)
    except UnicodeDecodeError as e:
        raise RelationsFormatError(f"{path}: not a text file ({e.reason})") from None
    if not rows:
        raise RelationsFormatError(f"{path}: no relations found")
    a = np.array(rows)
    return a[:, 0], a[:, 1], a[:, [2, 3, 7]]
