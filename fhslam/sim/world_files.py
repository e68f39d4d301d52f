"""Reading worlds: :func:`load_world` gives a built-in world by name (:data:`BUILTIN_WORLDS`)
or reads a world JSON file (the format is described in :mod:`fhslam.sim.world`).
"""

from __future__ import annotations

from os import PathLike
from pathlib import Path

from fhslam.errors import InputError
from fhslam.io.files import input_path, reading
from fhslam.io.jsontext import parse_json
from fhslam.sim.builtin_worlds import (
    campus_world,
    corridor_world,
    hall_world,
    offices_world,
    paper_world,
    ring_world,
)
from fhslam.sim.random_worlds import random_world
from fhslam.sim.world_model import World, WorldFormatError

BUILTIN_WORLDS = ("paper", "hall", "corridor", "ring", "offices", "campus", "random:SEED")
"""The names :func:`load_world` takes besides a file's path."""


def load_world(name_or_path: str | PathLike[str]) -> World:
    """A built-in world by name, or a world JSON file.

    Parameters
    ----------
    name_or_path : str or path-like
        ``"paper"``, ``"hall"``, ``"corridor"``, ``"ring"``, ``"offices"``, ``"random:SEED"``
        (e.g. ``"random:3"``),
        or the path of a JSON file
        ``{"name": ..., "walls": [[x1, y1, x2, y2], ...], "route": [[x, y], ...],
        "start": [x, y, theta]}`` (``start`` optional).

    Raises
    ------
    InputError
        For an unknown built-in name (the message lists the built-ins).
    MissingInputError
        For a path (ends in ``.json`` or contains a directory separator) that does not exist.
    WorldFormatError
        For a file that is not valid JSON (also one nested too deeply to read) or has a
        malformed field (a coordinate that is not a JSON number: ``true`` is not 1); names
        the file and field.

    Warns
    -----
    InputWarning
        For a key other than ``name``, ``walls``, ``route`` and ``start`` (ignored).
    """
    text = str(name_or_path)
    if not isinstance(name_or_path, PathLike):
        builtin = {
            "paper": paper_world,
            "hall": hall_world,
            "corridor": corridor_world,
            "ring": ring_world,
            "offices": offices_world,
            "campus": campus_world,
        }
        if text in builtin:
            return builtin[text]()
        if text.startswith("random:"):
            seed = text.removeprefix("random:")
            if not seed.isdigit():
                raise InputError(
                    f"world {text!r}: the seed after 'random:' must be a non-negative integer"
                )
            return random_world(int(seed))
    path = Path(name_or_path)
    if not path.is_file():
        if isinstance(name_or_path, PathLike) or path.suffix or len(path.parts) > 1:
            input_path(path, "world")  # raises
        raise InputError(
            f"unknown world {text!r}: built-in worlds are {', '.join(BUILTIN_WORLDS)}; "
            "or give the path of a world JSON file"
        )
    try:
        with reading(path):
            text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as e:
        raise WorldFormatError(f"{path}: not valid JSON ({e})") from None
    data = parse_json(text, path, WorldFormatError)  # NaN / Infinity: refused as not finite
    return World.from_dict(data, source=str(path))
