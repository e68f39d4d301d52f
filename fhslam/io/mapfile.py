"""Map files: the SLAM map's feature lines as JSON.

::

    {"lines": [{"sp": [x, y], "ep": [x, y], "rho": ρ, "theta": θ, "n": n}, ...]}

in metres and radians, in the map (world) frame; ``sp``/``ep`` are the segment's end points,
``(rho, theta)`` its line in the paper's Hessian form (``rho >= 0``, ``theta`` in [0, 2 pi)),
``n`` the number of scan points merged into it. Numbers are written as Python's shortest
round-trip ``repr`` (what :mod:`json` does), so a map reads back exactly.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from os import PathLike
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from fhslam.errors import InputError
from fhslam.geometry import line_through
from fhslam.io.files import atomic_output, input_path, reading
from fhslam.io.jsontext import parse_json
from fhslam.lines import Line

_KEYS = ("sp", "ep", "rho", "theta", "n")

MAX_COORDINATE = 1e6
"""Largest ``|x|``, ``|y|`` or ``rho`` a map file may hold, metres: a thousand kilometres is
no building, and a coordinate near the float limit (``1e308``) overflows any length or
distance computed from it (the map error came out ``inf``)."""


MAX_POINTS = 2**63 - 1
"""Largest ``n`` a map file may hold: what a 64-bit integer holds."""


class MapFormatError(InputError):
    """A malformed map file. The message names the file and, where it applies, the line index
    (``"{path}: lines[3]: ..."``) or the JSON text line (``"{path}:12: not valid JSON ..."``).
    """


def _entry(line: Line, i: int) -> dict[str, Any]:
    sp = np.asarray(line.sp, dtype=float).ravel()
    ep = np.asarray(line.ep, dtype=float).ravel()
    if sp.shape != (2,) or ep.shape != (2,):
        raise ValueError(f"write_map: lines[{i}]: sp and ep must have shape (2,)")
    values = [*sp, *ep, float(line.rho), float(line.theta)]
    if not all(math.isfinite(v) for v in values):
        raise ValueError(f"write_map: lines[{i}] has a non-finite value: {line!r}")
    return {
        "sp": [float(sp[0]), float(sp[1])],
        "ep": [float(ep[0]), float(ep[1])],
        "rho": float(line.rho),
        "theta": float(line.theta),
        "n": int(line.n),
    }


def write_map(path: str | PathLike[str], lines: Sequence[Line]) -> None:
    """Write feature lines as a map JSON file, one line object per text line.

    Parameters
    ----------
    path : str or path-like
        Output file, overwritten.
    lines : sequence of Line
        The map's lines in the map frame (e.g. ``FastHoughSLAM``'s reference lines). Only
        ``sp``, ``ep``, ``rho``, ``theta`` and ``n`` are stored.

    Raises
    ------
    ValueError
        If a line has a non-finite coordinate (naming its index); nothing is written then.
    """
    entries = [json.dumps(_entry(line, i)) for i, line in enumerate(lines)]
    body = ",\n  ".join(entries)
    text = '{"lines": [\n  ' + body + "\n]}\n" if entries else '{"lines": []}\n'
    with atomic_output(path) as f:
        f.write(text)


def _number(value: Any, what: str, where: str) -> float:
    """A finite JSON number (not a bool)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise MapFormatError(f"{where}: {what} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise MapFormatError(f"{where}: {what} is not finite: {value!r}")
    return float(value)


def _point(value: Any, key: str, where: str) -> np.ndarray:
    if not isinstance(value, list) or len(value) != 2:
        raise MapFormatError(f"{where}: {key!r} must be a list [x, y], got {value!r}")
    xy = np.array([_number(v, f"{key!r} coordinate", where) for v in value])
    if np.abs(xy).max() > MAX_COORDINATE:
        raise MapFormatError(
            f"{where}: {key!r} coordinate {np.abs(xy).max():g} m is beyond the plausible "
            f"{MAX_COORDINATE:g} m"
        )
    return xy


def _line(d: Any, where: str) -> Line:
    if not isinstance(d, dict):
        raise MapFormatError(
            f"{where}: expected an object with keys {', '.join(_KEYS)}, got {type(d).__name__}"
        )
    missing = [k for k in _KEYS if k not in d]
    if missing:
        raise MapFormatError(f"{where}: missing key {missing[0]!r}")
    sp, ep = _point(d["sp"], "sp", where), _point(d["ep"], "ep", where)
    rho = _number(d["rho"], "'rho'", where)
    theta = _number(d["theta"], "'theta'", where)
    n = d["n"]
    if (
        isinstance(n, bool)
        or not isinstance(n, int | float)
        or not math.isfinite(n)
        or n != int(n)
        or not 0 <= n <= MAX_POINTS
    ):
        raise MapFormatError(
            f"{where}: 'n' must be a whole number from 0 to {MAX_POINTS}, got {n!r}"
        )
    if rho < 0:
        raise MapFormatError(f"{where}: 'rho' must be >= 0 (Hessian normal form), got {rho!r}")
    if rho > MAX_COORDINATE:
        raise MapFormatError(
            f"{where}: 'rho' {rho:g} m is beyond the plausible {MAX_COORDINATE:g} m"
        )
    return Line(
        rho=rho,
        theta=float(np.mod(theta, 2 * np.pi)),
        n=int(n),
        length=float(np.hypot(*(ep - sp))),
        sp=sp,
        ep=ep,
    )


def read_map(path: str | PathLike[str]) -> list[Line]:
    """Read a map JSON file into :class:`~fhslam.lines.Line` objects.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    list of Line
        In file order, with ``length = |ep - sp|``; no ``inliers``, ``dir`` or ``d``.

    Raises
    ------
    MissingInputError
        If ``path`` does not exist.
    MapFormatError
        If the file is not JSON (naming the text line), has no ``"lines"`` list, or a line
        object lacks a key or holds a non-number, ``NaN``, ``Infinity`` or a number beyond
        the largest float (naming the text line too, :func:`fhslam.io.jsontext.parse_json`),
        a negative ``rho``, an ``n`` that is no whole number from 0 to :data:`MAX_POINTS`, or
        a coordinate or ``rho`` beyond :data:`MAX_COORDINATE` (naming the index,
        ``lines[i]``). A ``theta`` outside
        [0, 2 pi) is wrapped into it.
    """
    path = input_path(path, "map")
    try:
        with reading(path):
            text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as e:
        raise MapFormatError(f"{path}: not a text file ({e.reason})") from None
    data = parse_json(text, path, MapFormatError)
    if not isinstance(data, dict) or "lines" not in data:
        raise MapFormatError(f'{path}: expected a JSON object {{"lines": [...]}}')
    if not isinstance(data["lines"], list):
        raise MapFormatError(f"{path}: 'lines' must be a list, got {type(data['lines']).__name__}")
    return [_line(d, f"{path}: lines[{i}]") for i, d in enumerate(data["lines"])]


def lines_from_segments(segments: ArrayLike, n: int = 0) -> list[Line]:
    """Feature lines for wall segments, e.g. to write a world's true walls as a map.

    Parameters
    ----------
    segments : array-like, shape (M, 4)
        ``[x1, y1, x2, y2]`` per segment, metres, each of non-zero length.
    n : int
        Support count given to every line.

    Returns
    -------
    list of Line
        ``sp = (x1, y1)``, ``ep = (x2, y2)``, ``(rho, theta)`` of the line through them.
    """
    s = np.asarray(segments, dtype=float).reshape(-1, 4)
    out = []
    for x1, y1, x2, y2 in s:
        rho, theta = line_through((x1, y1), (x2, y2))
        sp, ep = np.array([x1, y1]), np.array([x2, y2])
        length = float(np.hypot(x2 - x1, y2 - y1))
        out.append(Line(rho=rho, theta=theta, n=int(n), length=length, sp=sp, ep=ep))
    return out
