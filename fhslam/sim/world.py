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
"""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.errors import InputError, InputWarning
from fhslam.geometry import compose, segment_distances, transform_points, wrap_angle
from fhslam.io.files import input_path, reading
from fhslam.io.jsontext import parse_json
from fhslam.io.mapfile import MAX_COORDINATE

BUILTIN_WORLDS = ("paper", "hall", "corridor", "ring", "offices", "campus", "random:SEED")

WORLD_KEYS = ("name", "walls", "route", "start")
"""The keys of a world JSON object; any other is warned about and ignored."""


class WorldFormatError(InputError):
    """A world definition (dict or JSON file) that is malformed; the message names the field."""


def _json_text(value: Any) -> str:
    """How ``value`` is spelled in JSON (``true``, ``null``, ``"1"``), for error messages."""
    if isinstance(value, np.generic):
        value = value.item()
    try:
        return json.dumps(value)[:40]
    except (TypeError, ValueError):
        return repr(value)[:40]


def _not_a_number(value: Any) -> Any:
    """The first entry of the nested lists ``value`` that is not a number (a bool, a string,
    ``None``, ...), or ``None`` if every entry is one. NumPy number arrays pass at once."""
    if isinstance(value, np.ndarray) and value.dtype.kind in "iuf":
        return None
    if isinstance(value, list | tuple | np.ndarray):
        for v in value:
            bad = _not_a_number(v)
            if bad is not None:
                return bad
        return None
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | float | np.number):
        return (value,)  # a tuple, so that a bad None is told from "all numbers"
    return None


def _array(value: Any, field: str, cols: int, min_rows: int) -> NDArray[np.float64]:
    """Validate a list of rows of ``cols`` finite numbers, at least ``min_rows`` rows."""
    numeric = isinstance(value, np.ndarray) and value.dtype.kind in "iuf"
    if not numeric and (
        not isinstance(value, list | tuple | np.ndarray)
        or (isinstance(value, np.ndarray) and value.ndim == 0)
    ):
        raise WorldFormatError(
            f"field {field!r} must be a list of [{', '.join(['number'] * cols)}] rows, got "
            f"{_json_text(value)}"
        )
    for i, row in enumerate([] if numeric else value):
        bad = _not_a_number(row)
        if bad is not None:
            raise WorldFormatError(
                f"field {field!r} must be a list of [{', '.join(['number'] * cols)}] rows: row "
                f"{i} holds {_json_text(bad[0])}, which is not a number"
            )
    try:
        a = np.array(value, dtype=float)  # a copy: the world makes it read-only
    except (TypeError, ValueError):
        raise WorldFormatError(
            f"field {field!r} must be a list of [{', '.join(['number'] * cols)}] rows"
        ) from None
    if a.ndim != 2 or a.shape[1] != cols:
        raise WorldFormatError(f"field {field!r} must have shape (N, {cols}), got shape {a.shape}")
    if len(a) < min_rows:
        raise WorldFormatError(f"field {field!r} needs at least {min_rows} rows, got {len(a)}")
    bad = ~np.isfinite(a).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise WorldFormatError(f"field {field!r} row {i} is not finite: {a[i].tolist()}")
    far = np.abs(a[:, : min(cols, 4)]).max(axis=1) > MAX_COORDINATE
    if far.any():
        i = int(np.flatnonzero(far)[0])
        raise WorldFormatError(
            f"field {field!r} row {i} lies beyond the plausible {MAX_COORDINATE:g} m: "
            f"{a[i].tolist()}"
        )
    return a


@dataclass(frozen=True, eq=False)
class World:
    """A polygonal environment and the route through it.

    Attributes
    ----------
    name : str
    walls : ndarray, shape (M, 4)
        Wall segments ``[x1, y1, x2, y2]``, metres, each of non-zero length.
    route : ndarray, shape (K, 2), K >= 2
        Waypoints the robot drives through in order, metres.
    start : ndarray, shape (3,)
        Initial pose ``(x, y, theta)``; by default the first waypoint, facing the second.
        ``theta`` is wrapped to (-pi, pi] (a heading already in it is kept as given).

    Raises
    ------
    WorldFormatError
        On wrong shapes, non-finite numbers, zero-length walls or a route of < 2 points.
    """

    name: str
    walls: NDArray[np.float64]
    route: NDArray[np.float64]
    start: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str):
            raise WorldFormatError(f"field 'name' must be a string, got {self.name!r}")
        walls = _array(self.walls, "walls", 4, 1)
        short = np.hypot(walls[:, 2] - walls[:, 0], walls[:, 3] - walls[:, 1]) < 1e-9
        if short.any():
            i = int(np.flatnonzero(short)[0])
            raise WorldFormatError(f"field 'walls' row {i} has zero length: {walls[i].tolist()}")
        route = _array(self.route, "route", 2, 2)
        if self.start is None:
            d = route[1] - route[0]
            if np.hypot(*d) == 0:
                raise WorldFormatError(
                    "field 'route': the first two waypoints coincide, so the start heading is "
                    "undefined; give 'start' explicitly"
                )
            start = np.array([*route[0], np.arctan2(d[1], d[0])])
        else:
            bad = _not_a_number(self.start)
            if bad is not None:
                raise WorldFormatError(
                    f"field 'start' must be [x, y, theta] numbers: {_json_text(bad[0])} is not a "
                    "number"
                )
            try:
                start = np.asarray(self.start, dtype=float)
            except (TypeError, ValueError):
                raise WorldFormatError("field 'start' must be [x, y, theta] numbers") from None
            if start.shape != (3,):
                raise WorldFormatError(
                    f"field 'start' must be [x, y, theta] (shape (3,)), got shape {start.shape}"
                )
            if not np.isfinite(start).all():
                raise WorldFormatError(f"field 'start' is not finite: {start.tolist()}")
            if np.abs(start[:2]).max() > MAX_COORDINATE:
                raise WorldFormatError(
                    f"field 'start' lies beyond the plausible {MAX_COORDINATE:g} m: "
                    f"{start.tolist()}"
                )
        if not -np.pi < start[2] <= np.pi:  # 7.0 is 7.0 - 2 pi; only such a heading changes
            start = start.copy()  # never the caller's array
            start[2] = wrap_angle(start[2])
        # The robot drives from the start to the first waypoint, then along the route: a
        # leg through a wall would put it on the far side of it without a word.
        legs = np.vstack([start[:2], route])
        legs = np.hstack([legs[:-1], legs[1:]])
        legs = legs[np.hypot(legs[:, 2] - legs[:, 0], legs[:, 3] - legs[:, 1]) > 0]
        if len(legs):
            hit = segment_distances(legs, walls) < 1e-9
            if hit.any():
                k, j = (int(v[0]) for v in np.nonzero(hit))
                a, b = legs[k, :2].tolist(), legs[k, 2:].tolist()
                first = k == 0 and self.start is not None
                leg = "start to first waypoint" if first else "a leg of the route"
                raise WorldFormatError(
                    f"field 'route': the robot's way from {a} to {b} ({leg}) meets wall row "
                    f"{j} {walls[j].tolist()}; a robot cannot drive through walls"
                )
        for attr, value in (("walls", walls), ("route", route), ("start", start)):
            value.flags.writeable = False
            object.__setattr__(self, attr, value)

    @classmethod
    def from_dict(cls, d: dict[str, Any], source: str = "world") -> World:
        """Build a world from the JSON structure; errors are prefixed with ``source``.

        A key other than :data:`WORLD_KEYS` (a misspelled ``"strat"``, an editor's comment)
        is ignored with one :class:`~fhslam.errors.InputWarning` naming it and the known
        keys: the world is well defined without it, but what it was meant to say is not used.
        """
        try:
            if not isinstance(d, dict):
                raise WorldFormatError(
                    f"expected a JSON object with 'name', 'walls', 'route', got {type(d).__name__}"
                )
            missing = [k for k in ("walls", "route") if k not in d]
            if missing:
                raise WorldFormatError(f"missing field {missing[0]!r}")
            unknown = [str(k) for k in d if k not in WORLD_KEYS]
            if unknown:
                warnings.warn(
                    f"{source}: unknown key{'s' if len(unknown) > 1 else ''} "
                    f"{', '.join(repr(k) for k in unknown)} ignored; a world has "
                    f"{', '.join(repr(k) for k in WORLD_KEYS)}",
                    InputWarning,
                    stacklevel=2,
                )
            return cls(
                name=d.get("name", Path(source).stem),
                walls=d["walls"],
                route=d["route"],
                start=d.get("start"),
            )
        except WorldFormatError as e:
            raise WorldFormatError(f"{source}: {e}") from None

    def to_dict(self) -> dict[str, Any]:
        """The JSON structure (plain lists), so that ``World.from_dict(w.to_dict())`` == ``w``."""
        return {
            "name": self.name,
            "walls": self.walls.tolist(),
            "route": self.route.tolist(),
            "start": self.start.tolist(),
        }

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` of all walls and waypoints, metres."""
        pts = np.vstack([self.walls[:, :2], self.walls[:, 2:], self.route])
        (xmin, ymin), (xmax, ymax) = pts.min(axis=0), pts.max(axis=0)
        return float(xmin), float(ymin), float(xmax), float(ymax)

    @property
    def route_length(self) -> float:
        """Length of the route polyline, metres."""
        return float(np.hypot(*np.diff(self.route, axis=0).T).sum())

    def __repr__(self) -> str:
        xmin, ymin, xmax, ymax = self.bounds
        return (
            f"World({self.name!r}: {len(self.walls)} walls, {len(self.route)} waypoints, "
            f"route {self.route_length:.1f} m, {xmax - xmin:.1f} x {ymax - ymin:.1f} m)"
        )


# ----------------------------------------------------------------------------- geometry


def route_segments(world: World) -> NDArray[np.float64]:
    """The route as segments ``[x1, y1, x2, y2]``, shape (K-1, 4)."""
    return np.hstack([world.route[:-1], world.route[1:]])


def route_clearance(world: World) -> float:
    """Smallest distance between the route polyline and any wall, metres."""
    return float(segment_distances(route_segments(world), world.walls).min())


def box_walls(cx: float, cy: float, w: float, h: float, angle_deg: float = 0.0) -> NDArray:
    """The 4 walls (4, 4) of a ``w`` x ``h`` rectangle centred at ``(cx, cy)``, rotated."""
    corners = np.array([[-w, -h], [w, -h], [w, h], [-w, h]]) / 2
    c = transform_points([cx, cy, np.radians(angle_deg)], corners)
    return np.hstack([c, np.roll(c, -1, axis=0)])


def _polyline(*points: tuple[float, float]) -> NDArray:
    """Walls along a polyline through ``points``."""
    p = np.asarray(points, dtype=float)
    return np.hstack([p[:-1], p[1:]])


def transform_world(world: World, pose: ArrayLike) -> World:
    """The same world moved rigidly: walls, route and start mapped by ``pose``.

    Parameters
    ----------
    world : World
    pose : array-like, shape (3,)
        ``new_T_old`` as ``(x, y, theta)``: where the world's old frame lies in the new one.

    Returns
    -------
    World
        Same name; a robot driving it sees exactly the same scans (up to rounding).
    """
    p = np.asarray(pose, dtype=float)
    walls = np.hstack(
        [transform_points(p, world.walls[:, :2]), transform_points(p, world.walls[:, 2:])]
    )
    return World(
        name=world.name,
        walls=walls,
        route=transform_points(p, world.route),
        start=compose(p, world.start),
    )


# ---------------------------------------------------------------------------- built-ins


def paper_world() -> World:
    """An 18.7 x 14.0 m office in the spirit of the paper's Fig. 13 (origin: lower-left corner).

    A 2 m wide east-west corridor (y 6-8 m) with three rooms below (A, B, C) and three above
    (D, E, F), doorways 1.0-1.2 m wide, box-shaped furniture (one rotated by 30 degrees, one
    by 20), diagonal walls cutting the corners of rooms A and F, and two partial walls. The
    route starts at S in room A, takes the corridor east, loops through room B, then room F,
    and ends at E at the east end of the corridor; it keeps at least 0.5 m from every wall.
    """
    walls = [
        # Outer rectangle.
        _polyline((0, 0), (18.7, 0), (18.7, 14.0), (0, 14.0), (0, 0)),
        # Corridor, south side (y = 6) with doors into A, B, C.
        _polyline((0, 6), (3.0, 6)),
        _polyline((4.1, 6), (9.0, 6)),
        _polyline((10.2, 6), (15.0, 6)),
        _polyline((16.0, 6), (18.7, 6)),
        # Corridor, north side (y = 8) with doors into D, E, F.
        _polyline((0, 8), (2.2, 8)),
        _polyline((3.2, 8), (7.4, 8)),
        _polyline((8.4, 8), (14.4, 8)),
        _polyline((15.6, 8), (18.7, 8)),
        # Partitions between rooms.
        _polyline((6.0, 0), (6.0, 6)),
        _polyline((12.2, 0), (12.2, 6)),
        _polyline((5.5, 8), (5.5, 14)),
        _polyline((11.5, 8), (11.5, 14)),
        # Non-Manhattan: diagonal walls across the SW corner of A and the NE corner of F.
        _polyline((0, 1.2), (1.2, 0)),
        _polyline((16.6, 14.0), (18.7, 11.9)),
        # Partial walls: an alcove in C, a half wall in E.
        _polyline((17.0, 0), (17.0, 1.8), (18.0, 1.8)),
        _polyline((5.5, 11.5), (7.5, 11.5)),
        # Furniture.
        box_walls(1.6, 4.4, 0.8, 0.6),  # A
        box_walls(5.0, 1.1, 0.6, 0.5, 20.0),  # A, rotated
        box_walls(9.2, 3.0, 1.0, 0.7, 30.0),  # B, rotated, inside the route's loop
        box_walls(15.8, 3.2, 1.2, 0.8),  # C
        box_walls(2.6, 11.4, 1.0, 1.0),  # D
        box_walls(9.2, 11.0, 0.9, 0.6),  # E
        box_walls(14.8, 10.75, 0.7, 0.5),  # F, inside the route's loop
    ]
    route = [
        (1.5, 2.2),  # S, room A
        (3.55, 2.2),
        (3.55, 7.0),  # through A's door into the corridor
        (9.6, 7.0),
        (9.6, 4.5),  # through B's door
        (7.3, 4.5),
        (7.3, 1.5),
        (11.0, 1.5),
        (11.0, 4.5),
        (9.6, 4.5),
        (9.6, 7.0),  # back in the corridor
        (15.0, 7.0),
        (15.0, 9.6),  # through F's door
        (17.4, 9.6),
        (17.4, 11.0),
        (12.8, 12.6),
        (12.8, 9.6),
        (15.0, 9.6),
        (15.0, 7.0),  # back in the corridor
        (17.6, 7.0),  # E
    ]
    return World(name="paper", walls=np.vstack(walls), route=np.array(route, dtype=float))


def hall_world() -> World:
    """A 15 x 15 m pillared hall whose walls run along the axes (origin: south-west corner).

    Sixteen 0.8 m square pillars stand on a 3 m grid (centres 3, 6, 9 and 12 m). The route
    starts at (1.5, 1.5), a metre and a half from the walls ``y = 0`` and ``x = 0``, which
    pass through the origin (lines with ``rho = 0``), and drives once round the four
    south-western pillars (24 m), between the pillars on its north and east legs, keeping at
    least 1.1 m from every wall. The start heading is 0.05 rad, not the first leg's 0, so
    that the path's coordinates are not round numbers: from round ones some beams pass
    exactly through a pillar's corner, and grazing or missing it is then decided by
    rounding, differently in a moved frame (:func:`transform_world`).
    """
    walls = [_polyline((0, 0), (15, 0), (15, 15), (0, 15), (0, 0))]
    walls += [box_walls(cx, cy, 0.8, 0.8) for cx in (3, 6, 9, 12) for cy in (3, 6, 9, 12)]
    route = [(1.5, 1.5), (7.5, 1.5), (7.5, 7.5), (1.5, 7.5), (1.5, 1.5)]
    return World(
        name="hall", walls=np.vstack(walls), route=np.array(route, dtype=float),
        start=np.array([1.5, 1.5, 0.05]),
    )  # fmt: skip


def corridor_world() -> World:
    """A corridor 2 m wide round a 6 x 2 m block, outer walls along the axes (origin: the
    south-west corner).

    The outer wall is the 10 x 6 m rectangle from the origin, the block spans (2, 2)-(8, 4),
    and a 0.6 m deep alcove is cut into the outer wall halfway along each long side. The route
    runs along the corridor's centre line once round the block (24 m), starting at (1, 1)
    (heading 0.05 rad, for the reason given in :func:`hall_world`): the walls ``y = 0`` and
    ``x = 0`` pass through the origin.
    """
    walls = [
        _polyline((0, 0), (4.5, 0), (4.5, -0.6), (5.5, -0.6), (5.5, 0), (10, 0), (10, 6)),
        _polyline((10, 6), (5.5, 6), (5.5, 6.6), (4.5, 6.6), (4.5, 6), (0, 6), (0, 0)),
        box_walls(5.0, 3.0, 6.0, 2.0),
    ]
    route = [(1, 1), (9, 1), (9, 5), (1, 5), (1, 1)]
    return World(
        name="corridor", walls=np.vstack(walls), route=np.array(route, dtype=float),
        start=np.array([1.0, 1.0, 0.05]),
    )  # fmt: skip


def _alcoved(p0, p1, outward, spacing=10.0, width=1.0, depth=0.8) -> NDArray:
    """The wall from ``p0`` to ``p1`` with alcoves ``width`` wide and ``depth`` deep cut
    towards ``outward``, the first ``spacing / 2`` from ``p0``, then 7-13 m apart for
    ``spacing`` 10 (deterministic, irregular: no two stretches of wall look alike)."""
    p0, p1, out = np.array(p0, float), np.array(p1, float), np.array(outward, float)
    length = float(np.hypot(*(p1 - p0)))
    u = (p1 - p0) / length
    pts, s = [p0], spacing / 2
    while s + width < length - 1.0:
        a, b = p0 + u * s, p0 + u * (s + width)
        pts += [a, a + out * depth, b + out * depth, b]
        s += spacing * (0.7 + 0.6 * ((s * 7.3) % 1.0))
    pts.append(p1)
    return np.array([[*pts[k], *pts[k + 1]] for k in range(len(pts) - 1)])


def ring_world() -> World:
    """A corridor 2.5 m wide round a 45 x 25 m block: 150 m a lap (origin: the south-west
    corner).

    The outer wall is the 50 x 30 m rectangle from the origin, the block spans (2.5, 2.5) -
    (47.5, 27.5); both sides of the corridor have alcoves 1 m wide and 0.8 m deep, 7-13 m
    apart. With the default 8 m laser there are stretches where no alcove is in reach, and
    along them only the odometry says where along the corridor the robot is. The route runs
    along the corridor's centre line once round the block, counter-clockwise from (1.25, 1.25)
    (heading 0.02 rad, for the reason given in :func:`hall_world`).

    Coming back to its start, the robot faces south while the first keyframes faced east:
    the right match overlaps little, and one a corridor's width off (the outer corner laid on
    the block's corner) scores as well. The graph method must not take it
    (``tests/test_graphslam.py``).
    """
    w, h, c = 50.0, 30.0, 2.5
    walls = [
        _alcoved((0, 0), (w, 0), (0, -1)),
        _alcoved((w, 0), (w, h), (1, 0)),
        _alcoved((w, h), (0, h), (0, 1)),
        _alcoved((0, h), (0, 0), (-1, 0)),
        _alcoved((c, c), (c, h - c), (1, 0)),
        _alcoved((c, h - c), (w - c, h - c), (0, -1)),
        _alcoved((w - c, h - c), (w - c, c), (-1, 0)),
        _alcoved((w - c, c), (c, c), (0, 1)),
    ]
    m = c / 2
    route = [(m, m), (w - m, m), (w - m, h - m), (m, h - m), (m, m)]
    return World(
        name="ring", walls=np.vstack(walls), route=np.array(route, dtype=float),
        start=np.array([m, m, 0.02]),
    )  # fmt: skip


def campus_world() -> World:
    """Corridors 2.5 m wide round two 97.5 x 115 m blocks side by side, with a corridor
    between them: a 200 x 120 m floor whose route runs 1,062 m (origin: the south-west
    corner), the scale of the long indoor logs (MIT's Killian Court, whose relations span
    2.1 hours).

    Built as the ``ring`` is (both sides of every corridor with alcoves 1 m wide and 0.8 m
    deep, 7-13 m apart). The route starts at (1.25, 1.25) heading east (0.02 rad), goes
    round the east block and down the middle corridor (531 m), back west along the south
    corridor it started in, now facing the other way; then round the west block and down
    the middle corridor again, and east along the south corridor as at the start. Coming
    down the middle corridor onto the south one, the robot looks along a corridor it drove
    430 m earlier facing the other way: the two views overlap little, and most where the
    corridors cross.
    """
    w, h, c = 200.0, 120.0, 2.5
    m, x = c / 2, w / 2

    def block(x0, y0, x1, y1):
        return [
            _alcoved((x0, y0), (x0, y1), (1, 0)),
            _alcoved((x0, y1), (x1, y1), (0, -1)),
            _alcoved((x1, y1), (x1, y0), (-1, 0)),
            _alcoved((x1, y0), (x0, y0), (0, 1)),
        ]

    walls = [
        _alcoved((0, 0), (w, 0), (0, -1)),
        _alcoved((w, 0), (w, h), (1, 0)),
        _alcoved((w, h), (0, h), (0, 1)),
        _alcoved((0, h), (0, 0), (-1, 0)),
        *block(c, c, x - m, h - c),
        *block(x + m, c, w - c, h - c),
    ]
    route = [
        (m, m), (w - m, m), (w - m, h - m), (x, h - m), (x, m),  # round the east block
        (m, m), (m, h - m), (x, h - m), (x, m), (w - m, m),  # the west block, then east
    ]  # fmt: skip
    return World(
        name="campus", walls=np.vstack(walls), route=np.array(route, dtype=float),
        start=np.array([m, m, 0.02]),
    )  # fmt: skip


def offices_world() -> World:
    """A 20 x 12 m office floor (origin: the south-west corner): an east-west corridor 2 m
    wide (y 5-7 m) between four rooms 5 m wide on each side, doors 1 m wide, three boxes
    (two turned by 15 and -20 degrees).

    The route starts at the corridor's west end, goes east, loops through the second room on
    the south side and the third on the north side, turns at the corridor's east end and
    drives the corridor back west to the start (64 m; a closed route). On the way back its
    180-degree laser looks the other way: what it sees, the keyframes a few metres ahead of it
    saw on the way out, not the ones where it stands. The start heading is 0.03 rad, for the
    reason given in :func:`hall_world`.
    """
    w, h = 20.0, 12.0
    walls = [_polyline((0, 0), (w, 0), (w, h), (0, h), (0, 0))]
    for y, side, door in ((5.0, -1.0, 2.0), (7.0, 1.0, 2.5)):  # corridor walls, room walls
        x = 0.0
        for k in range(4):
            walls.append(np.array([[x, y, 5.0 * k + door, y]]))
            x = 5.0 * k + door + 1.0
        walls.append(np.array([[x, y, w, y]]))
        walls += [np.array([[5.0 * k, y, 5.0 * k, y + 5.0 * side]]) for k in (1, 2, 3)]
    walls += [
        box_walls(3.0, 2.0, 1.2, 0.6, 15.0),
        box_walls(12.4, 9.6, 0.6, 0.6),
        box_walls(17.0, 2.5, 1.6, 0.8, -20.0),
    ]
    route = [
        (1.0, 6.0),
        (7.5, 6.0),  # the corridor east
        (7.5, 3.5),
        (9.0, 2.0),
        (6.0, 1.5),
        (6.5, 4.0),
        (7.5, 4.0),
        (7.5, 6.0),  # a south room
        (13.0, 6.0),
        (13.0, 8.5),
        (14.0, 10.5),
        (11.0, 10.8),
        (11.5, 8.5),
        (13.0, 8.5),
        (13.0, 6.0),  # north
        (19.0, 6.0),
        (19.0, 6.2),
        (1.0, 6.2),
        (1.0, 6.0),  # the east end, and back west
    ]
    return World(
        name="offices", walls=np.vstack(walls), route=np.array(route, dtype=float),
        start=np.array([1.0, 6.0, 0.03]),
    )  # fmt: skip


def _inside_polygon(p: NDArray, poly: NDArray) -> NDArray[np.bool_]:
    """Even-odd rule: which points ``p`` (N, 2) lie inside the closed polygon ``poly`` (V, 2)."""
    a, b = poly, np.roll(poly, -1, axis=0)
    x, y = p[:, None, 0], p[:, None, 1]
    straddle = (a[:, 1] > y) != (b[:, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return (straddle & (x < x_cross)).sum(axis=1) % 2 == 1


def random_world(seed: int) -> World:
    """A random polygonal world for held-out evaluation, deterministic for a given ``seed``.

    The outer wall is a star-shaped polygon of 6-9 vertices at random angles and radii of
    5-9 m around a centre at (9, 9), so walls meet at arbitrary angles. The route is the
    same polygon shrunk by half toward the centre, driven once round as a closed loop. A few
    spur walls stick in from the outer wall, stopping at least 1 m short of the route, and
    3-6 boxes (0.4-1.2 m sides, random rotation) stand at least 0.6 m from the route and from
    every other wall.
    """
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ValueError(f"random_world seed must be a non-negative integer, got {seed!r}")
    rng = np.random.default_rng(int(seed))
    centre = np.array([9.0, 9.0])
    for _ in range(100):  # redraw the outline until the route is well clear of it
        n = int(rng.integers(6, 10))
        gaps = rng.uniform(0.6, 1.4, n)
        phi = rng.uniform(0, 2 * np.pi) + np.cumsum(gaps * (2 * np.pi / gaps.sum()))
        radius = rng.uniform(5.0, 9.0, n)
        outline = centre + radius[:, None] * np.column_stack([np.cos(phi), np.sin(phi)])
        walls = np.hstack([outline, np.roll(outline, -1, axis=0)])
        loop = centre + 0.5 * (outline - centre)
        route = np.vstack([loop, loop[:1]])
        route_segs = np.hstack([route[:-1], route[1:]])
        if segment_distances(route_segs, walls).min() >= 1.5:
            break
    else:  # pragma: no cover (never happens for radii 5-9 m)
        raise RuntimeError(f"random_world({seed}): could not draw a valid outline")

    def clear(new: NDArray, margin: float) -> bool:
        return bool(
            segment_distances(new, route_segs).min() >= margin
            and segment_distances(new, walls).min() >= margin
        )

    spurs = []
    for _ in range(int(rng.integers(1, 4))):  # spur walls from the outline, pointing inward
        i, t, length = int(rng.integers(n)), rng.uniform(0.25, 0.75), rng.uniform(0.6, 1.8)
        a, b = outline[i], outline[(i + 1) % n]
        foot = a + t * (b - a)
        inward = np.array([a[1] - b[1], b[0] - a[0]]) / np.hypot(*(b - a))  # left normal
        if np.dot(centre - foot, inward) < 0:
            inward = -inward
        spur = np.hstack([foot, foot + length * inward])[None]
        if segment_distances(spur, route_segs).min() >= 1.0:
            spurs.append(spur)
    walls = np.vstack([walls, *spurs])

    lo, hi = outline.min(axis=0), outline.max(axis=0)
    for _ in range(int(rng.integers(3, 7))):  # boxes, by rejection sampling
        for _ in range(200):
            c = rng.uniform(lo, hi)
            w, h = rng.uniform(0.4, 1.2, 2)
            box = box_walls(c[0], c[1], w, h, rng.uniform(0.0, 180.0))
            if _inside_polygon(c[None], outline)[0] and clear(box, 0.6):
                walls = np.vstack([walls, box])
                break
    return World(name=f"random:{seed}", walls=walls, route=route)


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
