"""A simulated 2D laser range finder (SICK LMS200-like): exact ray casting against wall segments.

The laser sits at the robot's centre, looking along the robot's x axis. Beam bearings are
measured counter-clockwise from straight ahead, so the paper's scan "0-180 degrees with 90
degrees straight ahead" is the bearing range -90..+90 degrees here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.geometry import as_pose, ray_segment_intersection


@dataclass(frozen=True)
class LaserParams:
    """Parameters of the simulated laser (defaults: the paper's SICK LMS200 on a Pioneer II).

    Attributes
    ----------
    n_beams : int
        Number of beams per scan (181: one per degree over 180 degrees).
    fov_deg : float
        Field of view in degrees; beams are spread evenly from ``-fov/2`` to ``+fov/2``
        (both ends included) around the robot's heading.
    max_range : float
        Largest measurable range, metres. A beam that hits nothing closer reads exactly
        ``max_range`` ("no return").
    range_noise_std : float
        Standard deviation of the zero-mean Gaussian range noise, metres.
    resolution : float
        Ranges are rounded to multiples of this, metres (the LMS200 reports millimetres);
        0 disables the rounding.
    """

    n_beams: int = 181
    fov_deg: float = 180.0
    max_range: float = 8.0
    range_noise_std: float = 0.01
    resolution: float = 0.001

    def __post_init__(self) -> None:
        if int(self.n_beams) != self.n_beams or self.n_beams < 2:
            raise ValueError(f"LaserParams.n_beams must be an integer >= 2, got {self.n_beams}")
        if not 0 < self.fov_deg <= 360:
            raise ValueError(f"LaserParams.fov_deg must be in (0, 360], got {self.fov_deg}")
        if not self.max_range > 0:
            raise ValueError(f"LaserParams.max_range must be positive, got {self.max_range}")
        if not self.range_noise_std >= 0:
            raise ValueError(
                f"LaserParams.range_noise_std must be >= 0, got {self.range_noise_std}"
            )
        if not 0 <= self.resolution < self.max_range:
            raise ValueError(
                f"LaserParams.resolution must be in [0, max_range), got {self.resolution}"
            )


def beam_angles(params: LaserParams) -> NDArray[np.float64]:
    """Beam bearings in the laser frame, radians, shape (n_beams,), from -fov/2 to +fov/2."""
    half = np.radians(params.fov_deg / 2)
    return np.linspace(-half, half, params.n_beams)


def cast_rays(
    walls: ArrayLike, pose: ArrayLike, angles: ArrayLike, max_range: float
) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """Exact ranges from ``pose`` along each beam to the nearest wall.

    :func:`fhslam.geometry.ray_segment_intersection` of every beam with every wall at once,
    as a (B, M) array: ``t`` is the range, and the hit is valid when ``t > 0`` and
    ``0 <= s <= 1``. Beams parallel to a wall never hit it.

    Parameters
    ----------
    walls : array-like, shape (M, 4)
        Wall segments ``[x1, y1, x2, y2]``, metres.
    pose : array-like, shape (3,)
        Laser pose ``(x, y, theta)`` in the world frame.
    angles : array-like, shape (B,)
        Beam bearings in the laser frame, radians.
    max_range : float
        Hits at ``max_range`` or farther count as "no return".

    Returns
    -------
    ranges : ndarray, shape (B,)
        Noise-free range of each beam, metres; exactly ``max_range`` for no return.
    hit_wall : ndarray of int, shape (B,)
        Row of ``walls`` hit by each beam, -1 for no return.
    """
    w = np.asarray(walls, dtype=float).reshape(-1, 4)
    x, y, th = as_pose(pose)
    a = np.asarray(angles, dtype=float) + th
    d = np.stack([np.cos(a), np.sin(a)], axis=-1)[:, None, :]  # (B, 1, 2) beam directions
    t, s = ray_segment_intersection((x, y), d, w[:, :2], w[:, 2:])  # (B, M) each
    valid = np.isfinite(t) & (t > 0) & (s >= 0) & (s <= 1) & (t < max_range)
    t = np.where(valid, t, np.inf)
    if w.shape[0] == 0:  # no walls: nothing to hit
        return np.full(len(a), float(max_range)), np.full(len(a), -1, dtype=np.intp)
    hit = np.argmin(t, axis=1)
    ranges = t[np.arange(len(a)), hit]
    none = ~np.isfinite(ranges)
    return np.where(none, float(max_range), ranges), np.where(none, -1, hit).astype(np.intp)


def add_range_noise(
    ranges: ArrayLike, hit_wall: ArrayLike, params: LaserParams, rng: np.random.Generator
) -> NDArray[np.float64]:
    """Measured ranges: Gaussian noise, rounding to ``params.resolution``, clipping.

    Beams that hit a wall get ``N(0, range_noise_std)`` noise, are rounded to the sensor
    resolution and clipped into the open interval (0, max_range) (to
    ``[resolution, max_range - resolution]``, or a 1 µm margin without rounding) so a real
    return is never mistaken for "no return". Beams with no return stay exactly ``max_range``.

    Parameters
    ----------
    ranges : array-like, shape (B,) or (T, B)
        Noise-free ranges from :func:`cast_rays`.
    hit_wall : array-like of int, same shape
        Wall index per beam, -1 for no return.
    params : LaserParams
    rng : numpy.random.Generator

    Returns
    -------
    ndarray, same shape as ``ranges``
    """
    r = np.asarray(ranges, dtype=float)
    hit = np.asarray(hit_wall) >= 0
    noisy = r + rng.normal(0.0, params.range_noise_std, size=r.shape)
    step = params.resolution
    if step > 0:
        # Round to the sensor's step; the second rounding removes float dust (2.0010000000000003).
        noisy = np.round(np.round(noisy / step) * step, 9)
    margin = step if step > 0 else 1e-6
    noisy = np.clip(noisy, margin, params.max_range - margin)
    return np.where(hit, noisy, params.max_range)
