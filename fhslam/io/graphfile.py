"""Keyframe-graph files: the graph method's keyframes and loop closures as JSON
(``fhslam slam --method graph --graph G.json``).

::

    {"keyframes": [
      [timestamp, x, y, theta],
      ...],
     "loops": [
      {"old": i, "new": j, "active": true, "score": s},
      ...]}

One keyframe per text line, in the order the run started them: the timestamp of the scan
that started it (seconds) and its optimised pose, the robot's ``(x, y, theta)`` in the world
frame of the trajectory (metres, radians): the pose the trajectory file gives that scan. One
accepted loop closure per text line, in the order the run accepted them: keyframe ``new``
matched against the older keyframe ``old`` (indices into ``keyframes``, ``old < new``), its
match score, and whether it is still ``active`` in the end or was switched off as
inconsistent. Numbers are written as Python's shortest round-trip ``repr`` (what :mod:`json`
does), so a graph reads back exactly.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from os import PathLike
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fhslam.errors import InputError
from fhslam.io.files import atomic_output, input_path, reading
from fhslam.io.jsontext import parse_json

__all__ = ["GraphFormatError", "KeyframeGraph", "read_graph", "write_graph"]

_LOOP_KEYS = ("old", "new", "active", "score")


class GraphFormatError(InputError):
    """A malformed keyframe-graph file. The message names the file and, where it applies,
    the entry (``"{path}: keyframes[3]: ..."``, ``"{path}: loops[0]: ..."``) or the JSON text
    line (``"{path}:12: not valid JSON ..."``)."""


@dataclass(frozen=True, eq=False)
class KeyframeGraph:
    """A run's keyframes and loop closures (see the module docs).

    Attributes
    ----------
    timestamps : ndarray, shape (K,)
        The timestamp of the scan that started each keyframe, seconds.
    poses : ndarray, shape (K, 3)
        Each keyframe's optimised robot pose ``(x, y, theta)`` in the world frame.
    loops : ndarray of int, shape (L, 2)
        Each accepted loop closure's ``(old, new)`` keyframe indices, ``old < new``.
    active : ndarray of bool, shape (L,)
        Whether the closure is still in the graph at the end (not switched off).
    scores : ndarray, shape (L,)
        The closure's match score.
    """

    timestamps: NDArray[np.float64]
    poses: NDArray[np.float64]
    loops: NDArray[np.intp]
    active: NDArray[np.bool_]
    scores: NDArray[np.float64]

    def __post_init__(self) -> None:
        t = np.asarray(self.timestamps, dtype=float).reshape(-1)
        p = np.asarray(self.poses, dtype=float)
        loops = np.asarray(self.loops, dtype=np.intp).reshape(-1, 2)
        active = np.asarray(self.active, dtype=bool).reshape(-1)
        scores = np.asarray(self.scores, dtype=float).reshape(-1)
        if p.shape != (len(t), 3):
            raise ValueError(
                f"poses must have shape ({len(t)}, 3) to match timestamps, got {p.shape}"
            )
        if not len(active) == len(scores) == len(loops):
            raise ValueError(
                f"loops, active and scores must have the same length, got {len(loops)}, "
                f"{len(active)} and {len(scores)}"
            )
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(p)) and np.all(np.isfinite(scores))):
            raise ValueError("timestamps, poses and scores must be finite")
        bad = np.flatnonzero(
            (loops[:, 0] < 0) | (loops[:, 0] >= loops[:, 1]) | (loops[:, 1] >= len(t))
        )
        if len(bad):
            old, new = loops[bad[0]]
            raise ValueError(
                f"loops[{bad[0]}] = ({old}, {new}): need 0 <= old < new < {len(t)} keyframes"
            )
        for name, value in (
            ("timestamps", t),
            ("poses", p),
            ("loops", loops),
            ("active", active),
            ("scores", scores),
        ):
            object.__setattr__(self, name, value)

    def __len__(self) -> int:
        """The number of keyframes."""
        return len(self.timestamps)

    @property
    def n_active(self) -> int:
        """Loop closures still active at the end."""
        return int(self.active.sum())


def write_graph(path: str | PathLike[str], graph: KeyframeGraph) -> None:
    """Write a :class:`KeyframeGraph` as a keyframe-graph JSON file (atomically).

    Parameters
    ----------
    path : str or path-like
        Output file, overwritten.
    graph : KeyframeGraph
    """
    frames = [
        json.dumps([t, *pose])
        for t, pose in zip(graph.timestamps.tolist(), graph.poses.tolist(), strict=True)
    ]
    loops = [
        json.dumps({"old": old, "new": new, "active": on, "score": s})
        for (old, new), on, s in zip(
            graph.loops.tolist(), graph.active.tolist(), graph.scores.tolist(), strict=True
        )
    ]

    def block(items: list[str]) -> str:
        return "[\n  " + ",\n  ".join(items) + "]" if items else "[]"

    text = '{"keyframes": ' + block(frames) + ',\n "loops": ' + block(loops) + "}\n"
    with atomic_output(path) as f:
        f.write(text)


def _number(value: Any, what: str, where: str) -> float:
    """A finite JSON number (not a bool)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise GraphFormatError(f"{where}: {what} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise GraphFormatError(f"{where}: {what} is not finite: {value!r}")
    return float(value)


def _keyframe(row: Any, where: str) -> list[float]:
    if not isinstance(row, list) or len(row) != 4:
        raise GraphFormatError(f"{where}: expected [timestamp, x, y, theta], got {row!r}")
    names = ("timestamp", "x", "y", "theta")
    return [_number(v, name, where) for v, name in zip(row, names, strict=True)]


def _loop(d: Any, n_keyframes: int, where: str) -> tuple[int, int, bool, float]:
    if not isinstance(d, dict):
        raise GraphFormatError(
            f"{where}: expected an object with keys {', '.join(_LOOP_KEYS)}, got {type(d).__name__}"
        )
    missing = [k for k in _LOOP_KEYS if k not in d]
    if missing:
        raise GraphFormatError(f"{where}: missing key {missing[0]!r}")
    ends = []
    for key in ("old", "new"):
        v = d[key]
        if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v < n_keyframes:
            raise GraphFormatError(
                f"{where}: {key!r} must be a keyframe index 0 to {n_keyframes - 1}, got {v!r}"
            )
        ends.append(v)
    if ends[0] >= ends[1]:
        raise GraphFormatError(
            f"{where}: 'old' ({ends[0]}) must be an older keyframe than 'new' ({ends[1]})"
        )
    if not isinstance(d["active"], bool):
        raise GraphFormatError(f"{where}: 'active' must be true or false, got {d['active']!r}")
    return ends[0], ends[1], d["active"], _number(d["score"], "'score'", where)


def read_graph(path: str | PathLike[str]) -> KeyframeGraph:
    """Read a keyframe-graph JSON file (see the module docs).

    Returns
    -------
    KeyframeGraph

    Raises
    ------
    MissingInputError
        If ``path`` does not exist.
    GraphFormatError
        If the file is not JSON (naming the text line), lacks the ``"keyframes"`` or
        ``"loops"`` list, or an entry is malformed: a keyframe that is not four finite
        numbers, a loop closure without a key, with an index that is not a keyframe's or
        an ``old`` not older than its ``new``, a non-boolean ``active`` or a non-finite
        ``score`` (naming the entry, ``keyframes[i]`` or ``loops[i]``, and for ``NaN``,
        ``Infinity`` or a number beyond the largest float the text line too,
        :func:`fhslam.io.jsontext.parse_json`).
    """
    path = input_path(path, "keyframe-graph")
    try:
        with reading(path):
            text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as e:
        raise GraphFormatError(f"{path}: not a text file ({e.reason})") from None
    data = parse_json(text, path, GraphFormatError)
    if not isinstance(data, dict) or "keyframes" not in data or "loops" not in data:
        raise GraphFormatError(
            f'{path}: expected a JSON object {{"keyframes": [...], "loops": [...]}}'
        )
    for key in ("keyframes", "loops"):
        if not isinstance(data[key], list):
            raise GraphFormatError(
                f"{path}: {key!r} must be a list, got {type(data[key]).__name__}"
            )
    frames = [_keyframe(row, f"{path}: keyframes[{i}]") for i, row in enumerate(data["keyframes"])]
    loops = [_loop(d, len(frames), f"{path}: loops[{i}]") for i, d in enumerate(data["loops"])]
    a = np.array(frames, dtype=float).reshape(-1, 4)
    return KeyframeGraph(
        timestamps=a[:, 0],
        poses=a[:, 1:],
        loops=np.array([lp[:2] for lp in loops], dtype=np.intp).reshape(-1, 2),
        active=np.array([lp[2] for lp in loops], dtype=bool),
        scores=np.array([lp[3] for lp in loops], dtype=float),
    )
