"""The world type: :class:`World` (wall segments, the route the simulated robot drives and
its start, validated when made), its JSON structure (:meth:`World.from_dict`,
:meth:`World.to_dict`), and the geometry of a world: the route's segments and clearance,
rectangular walls (:func:`box_walls`) and rigid moves (:func:`transform_world`).

The JSON format and the built-in worlds are described in :mod:`fhslam.sim.world`.
"""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.errors import InputError, InputWarning
from fhslam.geometry import compose, segment_distances, transform_points, wrap_angle
from fhslam.io.mapfile import MAX_COORDINATE

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
