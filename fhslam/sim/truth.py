"""Ground truth from the simulator, for the metrics: the true lines of a scan (the walls
it saw, as beam runs, for :mod:`fhslam.metrics.detection`) and the noise-free points where
the beams hit the walls (for :func:`fhslam.metrics.map_coverage`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.geometry import inverse, line_through, ray_segment_intersection, transform_points
from fhslam.sim.laser import cast_rays

__all__ = [
    "TrueLine",
    "beam_wall_points",
    "observed_wall_points",
    "true_lines",
    "visible_wall_points",
]


@dataclass(frozen=True)
class TrueLine:
    """A wall as seen in one scan: a run of consecutive beams that hit it."""

    wall: int
    rho: float
    theta: float
    beams: NDArray[np.intp]


def true_lines(
    hits: ArrayLike, walls: ArrayLike, pose: ArrayLike, min_hits: int = 10
) -> tuple[list[TrueLine], NDArray[np.intp]]:
    """The walls seen in one scan, as beam runs, with (ρ, θ) in the laser frame.

    Parameters
    ----------
    hits : array-like of int, shape (B,)
        Wall index hit by each beam, -1 for no return (from the simulator).
    walls : array-like, shape (M, 4)
        Wall segments ``[x1, y1, x2, y2]`` in the world frame.
    pose : array-like, shape (3,)
        True ``world_T_laser`` pose of the scan.
    min_hits : int
        Shortest run that counts as a true line.

    Returns
    -------
    lines : list of TrueLine
        The runs with at least ``min_hits`` beams.
    run_of_beam : ndarray of int, shape (B,)
        Index into ``lines`` of each beam's run; -1 for no return, -2 for a short run.
    """
    h = np.asarray(hits, dtype=np.intp)
    w = np.asarray(walls, dtype=float)
    laser_T_world = inverse(pose)
    run_of_beam = np.full(len(h), -1, dtype=np.intp)
    brk = np.r_[True, h[1:] != h[:-1]]
    starts = np.flatnonzero(brk)
    stops = np.r_[starts[1:], len(h)]
    out: list[TrueLine] = []
    for a, b in zip(starts, stops, strict=True):
        wall = int(h[a])
        if wall < 0:
            continue
        if b - a < min_hits:
            run_of_beam[a:b] = -2
            continue
        p, q = transform_points(laser_T_world, w[wall].reshape(2, 2))
        rho, theta = line_through(p, q)
        run_of_beam[a:b] = len(out)
        out.append(TrueLine(wall, rho, theta, np.arange(a, b)))
    return out, run_of_beam


def beam_wall_points(
    walls: NDArray, poses: NDArray, angles: NDArray, hits: NDArray
) -> NDArray[np.float64]:
    """Exact intersection of each beam with the wall it hit; poses (K, 3), hits (K, B)."""
    k, b = np.nonzero(hits >= 0)
    w = walls[hits[k, b]]
    o = poses[k, :2]
    a = angles[b] + poses[k, 2]
    d = np.column_stack([np.cos(a), np.sin(a)])
    t, _ = ray_segment_intersection(o, d, w[:, :2], w[:, 2:])
    return o + t[:, None] * d


def observed_wall_points(log, every: int = 5) -> NDArray[np.float64]:
    """The noise-free points where the beams of a simulated log hit the walls.

    For every ``every``-th scan, each beam with a return is intersected exactly with the wall
    it hit (``log.hits``), from the true pose (``log.truth``): the part of the world the
    robot actually saw, for :func:`fhslam.metrics.map_coverage`.

    Parameters
    ----------
    log : fhslam.io.Log
        A simulated log carrying ``truth``, ``hits`` and ``world``.
    every : int
        Use scans ``0, every, 2 every, ...``.

    Returns
    -------
    ndarray, shape (P, 2)
        World-frame points, metres.
    """
    if log.truth is None or log.hits is None or log.world is None:
        raise ValueError(
            f"log {log.name!r} has no ground truth (truth, hits, world): observed wall "
            "points need a simulated log"
        )
    if int(every) != every or every < 1:
        raise ValueError(f"every must be an integer >= 1, got {every}")
    walls = np.asarray(log.world.walls, dtype=float)
    return beam_wall_points(walls, log.truth[::every], log.angles, log.hits[::every])


def visible_wall_points(
    walls: ArrayLike,
    poses: ArrayLike,
    every: int = 5,
    n_beams: int = 181,
    fov_deg: float = 180.0,
    max_range: float = 8.0,
) -> NDArray[np.float64]:
    """Wall points a laser would hit from given poses: exact ray casting, no simulation.

    For when only the world and the true trajectory are at hand (``fhslam evaluate
    --world``): from every ``every``-th pose, ``n_beams`` beams spread over ``fov_deg``
    around the heading (default: the paper's SICK LMS200, 181 beams over 180 degrees, 8 m)
    are cast into the walls (:func:`fhslam.sim.cast_rays`) and the noise-free hit points
    returned. For a log simulated with that laser this equals :func:`observed_wall_points`.

    Parameters
    ----------
    walls : array-like, shape (W, 4)
    poses : array-like, shape (T, 3)
        True laser poses, world frame.
    every : int
    n_beams, fov_deg, max_range
        The laser (beams from ``-fov/2`` to ``+fov/2``, both included; metres).

    Returns
    -------
    ndarray, shape (P, 2)
    """
    if int(every) != every or every < 1:
        raise ValueError(f"every must be an integer >= 1, got {every}")
    w = np.asarray(walls, dtype=float).reshape(-1, 4)
    q = _poses(poses, "poses")[:: int(every)]
    half = np.radians(fov_deg) / 2
    angles = np.linspace(-half, half, int(n_beams))
    hits = np.array([cast_rays(w, pose, angles, max_range)[1] for pose in q], dtype=np.intp)
    return beam_wall_points(w, q, angles, hits.reshape(len(q), len(angles)))


def _poses(p: ArrayLike, name: str) -> NDArray[np.float64]:
    """``p`` as an (N, 3) array of finite poses (the check of :mod:`fhslam.metrics`)."""
    a = np.asarray(p, dtype=float)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name} must have shape (N, 3), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite")
    return a
