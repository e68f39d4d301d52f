"""Polygonal worlds: wall segments plus the route the simulated robot drives.

A world is stored as JSON::

    {"name": "office", "walls": [[x1, y1, x2, y2], ...], "route": [[x, y], ...],
     "start": [x, y, theta]}

in metres and radians; ``start`` is optional (default: the first waypoint, heading to the
second; a heading given is wrapped to (-pi, pi]). Every coordinate must be a JSON number
(``true``, ``"1"`` or ``null`` are refused, not read as 1, 1 or NaN); a key other than these
four is read as a misspelling: the world is used without it and an
:class:`~fhslam.errors.InputWarning` names the key and the known ones
(:meth:`World.from_dict`).

Built-in worlds: ``"paper"`` (:func:`paper_world`, the paper's 18.7 x 14.0 m office),
``"random:SEED"`` (:func:`random_world`, held-out worlds nothing was tuned on), and two small
worlds with walls through the origin, ``"hall"`` (:func:`hall_world`) and ``"corridor"``
(:func:`corridor_world`), a 150 m corridor ring, ``"ring"`` (:func:`ring_world`), an
office floor whose route drives its corridor both ways, ``"offices"`` (:func:`offices_world`),
and a kilometre of corridors round two blocks, ``"campus"`` (:func:`campus_world`).
:func:`transform_world` moves a world rigidly (to check that a
method does not depend on where the world frame lies).

The module gathers the names of its parts: :mod:`fhslam.sim.world_model` (the
:class:`World` type, its JSON structure and geometry), :mod:`fhslam.sim.builtin_worlds`,
:mod:`fhslam.sim.random_worlds` and :mod:`fhslam.sim.world_files` (:func:`load_world`).
"""

from fhslam.sim.builtin_worlds import (
    campus_world,
    corridor_world,
    hall_world,
    offices_world,
    paper_world,
    ring_world,
)
from fhslam.sim.random_worlds import random_world
from fhslam.sim.world_files import BUILTIN_WORLDS, load_world
from fhslam.sim.world_model import (
    WORLD_KEYS,
    World,
    WorldFormatError,
    box_walls,
    route_clearance,
    route_segments,
    transform_world,
)

__all__ = [
    "BUILTIN_WORLDS",
    "WORLD_KEYS",
    "World",
    "WorldFormatError",
    "box_walls",
    "campus_world",
    "corridor_world",
    "hall_world",
    "load_world",
    "offices_world",
    "paper_world",
    "random_world",
    "ring_world",
    "route_clearance",
    "route_segments",
    "transform_world",
]
