"""Planar geometry: SE(2) poses, angle wrapping, points and lines in Hessian normal form.

Conventions (see DESIGN.md): metres and radians; a pose is ``(x, y, theta)`` and maps the
robot frame into the world frame (``world_T_robot``); angles are wrapped to (-pi, pi]; a
line is ``rho = x cos(theta) + y sin(theta)`` (paper eq. (1)) with ``rho >= 0`` and
``theta`` in [0, 2 pi).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

TWO_PI = 2.0 * np.pi


def wrap_angle(a: ArrayLike) -> NDArray[np.float64] | float:
    """Wrap angles to (-pi, pi].

    Parameters
    ----------
    a : float or array-like
        Angles in radians.
    """
    w = np.pi - np.mod(np.pi - np.asarray(a, dtype=float), TWO_PI)
    return float(w) if np.ndim(w) == 0 else w


def as_pose(pose: ArrayLike, name: str = "pose") -> NDArray[np.float64]:
    """Validate a pose ``(x, y, theta)`` and return it as a float array of shape (3,)."""
    p = np.asarray(pose, dtype=float)
    if p.shape != (3,):
        raise ValueError(f"{name} must have shape (3,) as (x, y, theta), got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError(f"{name} must be finite, got {p.tolist()}")
    return p


def as_points(points: ArrayLike, name: str = "points") -> NDArray[np.float64]:
    """Validate an (N, 2) array of finite points and return it as float64."""
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"{name} must have shape (N, 2), got shape {p.shape}")
    bad = ~np.isfinite(p).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"{name} contains {int(bad.sum())} non-finite rows (first at index {i}: "
            f"{p[i].tolist()}); drop invalid beams first (fhslam.extraction.scan_to_points)"
        )
    return p


def compose(a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """SE(2) composition ``a ⊕ b``: the pose ``b`` (given in frame ``a``) in a's parent frame.

    Parameters
    ----------
    a, b : array-like, shape (3,) or (N, 3)
        Poses ``(x, y, theta)``; broadcast against each other.
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    x = a[..., 0] + c * b[..., 0] - s * b[..., 1]
    y = a[..., 1] + s * b[..., 0] + c * b[..., 1]
    return np.stack([x, y, wrap_angle(a[..., 2] + b[..., 2])], axis=-1)


def inverse(a: ArrayLike) -> NDArray[np.float64]:
    """SE(2) inverse ``⊖a``, so that ``compose(a, inverse(a)) == 0``.

    Parameters
    ----------
    a : array-like, shape (3,) or (N, 3)
    """
    a = np.asarray(a, dtype=float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    x = -c * a[..., 0] - s * a[..., 1]
    y = s * a[..., 0] - c * a[..., 1]
    return np.stack([x, y, wrap_angle(-a[..., 2])], axis=-1)


def relative(a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """The motion from pose ``a`` to pose ``b`` expressed in frame ``a``: ``⊖a ⊕ b``."""
    return compose(inverse(a), b)


def transform_points(pose: ArrayLike, points: ArrayLike) -> NDArray[np.float64]:
    """Map points from a frame into its parent frame: ``world_p = world_T_robot * robot_p``.

    Parameters
    ----------
    pose : array-like, shape (3,)
        ``world_T_robot`` as ``(x, y, theta)``.
    points : array-like, shape (N, 2)
        Points in the robot frame.

    Returns
    -------
    ndarray, shape (N, 2)
    """
    x, y, th = np.asarray(pose, dtype=float)
    p = np.asarray(points, dtype=float)
    c, s = np.cos(th), np.sin(th)
    return np.column_stack([x + c * p[:, 0] - s * p[:, 1], y + s * p[:, 0] + c * p[:, 1]])


def polar_to_points(ranges: ArrayLike, angles: ArrayLike) -> NDArray[np.float64]:
    """Convert beams (range, bearing) in the laser frame to Cartesian points, shape (N, 2)."""
    r = np.asarray(ranges, dtype=float)
    a = np.asarray(angles, dtype=float)
    return np.column_stack([r * np.cos(a), r * np.sin(a)])


def normalize_line(rho: ArrayLike, theta: ArrayLike) -> tuple[NDArray, NDArray]:
    """Bring lines to the paper's form: ``rho >= 0`` and ``theta`` in [0, 2 pi).

    A line with negative ``rho`` is the same line as ``(-rho, theta + pi)``.
    """
    rho = np.asarray(rho, dtype=float)
    theta = np.asarray(theta, dtype=float)
    neg = rho < 0
    rho = np.where(neg, -rho, rho)
    theta = np.mod(np.where(neg, theta + np.pi, theta), TWO_PI)
    return rho, theta


def line_through(p: ArrayLike, q: ArrayLike) -> tuple[float, float]:
    """Hessian form ``(rho, theta)`` of the infinite line through two distinct points."""
    p = np.asarray(p, dtype=float)
    q = np.asarray(q, dtype=float)
    d = q - p
    if np.hypot(*d) == 0.0:
        raise ValueError(f"line_through needs two distinct points, got {p.tolist()} twice")
    theta = np.arctan2(d[1], d[0]) + np.pi / 2
    rho = p[0] * np.cos(theta) + p[1] * np.sin(theta)
    r, t = normalize_line(rho, theta)
    return float(r), float(t)


def signed_distance(points: ArrayLike, rho: float, theta: float) -> NDArray[np.float64]:
    """Signed distance ``x cos(theta) + y sin(theta) - rho`` of points (N, 2) to a line."""
    p = np.asarray(points, dtype=float)
    return p[..., 0] * np.cos(theta) + p[..., 1] * np.sin(theta) - rho


def project_onto_line(points: ArrayLike, rho: float, theta: float) -> NDArray[np.float64]:
    """Orthogonal projection of points (N, 2) onto the line ``(rho, theta)``."""
    p = np.asarray(points, dtype=float)
    n = np.array([np.cos(theta), np.sin(theta)])
    return p - signed_distance(p, rho, theta)[..., None] * n


def point_segment_distance(points: ArrayLike, a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """Euclidean distance of points (N, 2) to the segment from ``a`` to ``b``."""
    p = np.asarray(points, dtype=float)
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    ab = b - a
    denom = float(ab @ ab)
    t = np.zeros(len(p)) if denom == 0.0 else np.clip((p - a) @ ab / denom, 0.0, 1.0)
    return np.hypot(*(p - (a + t[:, None] * ab)).T)


def angle_difference_lines(theta_a: ArrayLike, theta_b: ArrayLike) -> NDArray | float:
    """Unsigned angle in [0, pi/2] between two undirected lines with normal angles a, b."""
    d = np.abs(np.mod(np.asarray(theta_a) - np.asarray(theta_b), np.pi))
    d = np.minimum(d, np.pi - d)
    return float(d) if np.ndim(d) == 0 else d
