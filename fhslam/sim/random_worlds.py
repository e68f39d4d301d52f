"""Random worlds (``"random:SEED"``): polygonal worlds drawn from a seed, held out from
everything the methods were tuned on (:func:`random_world`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from fhslam.geometry import segment_distances
from fhslam.sim.world_model import World, box_walls


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
