"""The built-in worlds: the paper's office (:func:`paper_world`), two small worlds with
walls through the origin (:func:`hall_world`, :func:`corridor_world`), a 150 m corridor ring
(:func:`ring_world`), a kilometre of corridors round two blocks (:func:`campus_world`) and an
office floor whose route drives its corridor both ways (:func:`offices_world`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from fhslam.sim.world_model import World, box_walls


def _polyline(*points: tuple[float, float]) -> NDArray:
    """Walls along a polyline through ``points``."""
    p = np.asarray(points, dtype=float)
    return np.hstack([p[:-1], p[1:]])


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
