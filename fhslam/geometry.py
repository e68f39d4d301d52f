"""Planar geometry: SE(2) poses, angle wrapping, points and lines in Hessian normal form.

Conventions: metres and radians; a pose is ``(x, y, theta)`` and maps the
robot frame into the world frame (``world_T_robot``); angles are wrapped to (-pi, pi]; a
line is ``rho = x cos(theta) + y sin(theta)`` (paper eq. (1)) with ``rho >= 0`` and
``theta`` in [0, 2 pi).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam._numba import njit

TWO_PI = 2.0 * np.pi


def wrap_angle(a: ArrayLike) -> NDArray[np.float64] | float:
    """Wrap angles to (-pi, pi].

    Parameters
    ----------
    a : float or array-like
        Angles in radians.
    """
    w = np.pi - np.mod(np.pi - np.asarray(a, dtype=float), TWO_PI)
    # For a just above pi, np.mod rounds the tiny negative pi - a up to exactly 2 pi: -pi.
    w = np.where(w <= -np.pi, w + TWO_PI, w)
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
    if np.isfinite(p).all():  # one pass over the flat array: the common case
        return p
    bad = ~np.isfinite(p).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"{name} contains {int(bad.sum())} non-finite rows (first at index {i}: "
            f"{p[i].tolist()}); drop invalid beams first (fhslam.scan.scan_to_points)"
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
    if a.shape == b.shape == (3,):  # one pose each: the same arithmetic, without the arrays
        return _compose1(a, b)
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
    if a.shape == (3,):
        (a0, a1, a2), t = a, -a[2]
        c, s = np.cos(a2), np.sin(a2)
        return np.array([-c * a0 - s * a1, s * a0 - c * a1, _wrap1(t)])
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    x = -c * a[..., 0] - s * a[..., 1]
    y = s * a[..., 0] - c * a[..., 1]
    return np.stack([x, y, wrap_angle(-a[..., 2])], axis=-1)


def _wrap1(a: np.float64) -> np.float64:
    """:func:`wrap_angle` of one angle, with the same operations."""
    w = np.pi - np.mod(np.pi - a, TWO_PI)
    return w + TWO_PI if w <= -np.pi else w


def _compose1(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """:func:`compose` of two poses of shape (3,), with the same operations in the same
    order (bit for bit the same result) at a third of the cost: the SLAM front end composes
    a few poses per scan."""
    (a0, a1, a2), (b0, b1, b2) = a, b
    c, s = np.cos(a2), np.sin(a2)
    return np.array([a0 + c * b0 - s * b1, a1 + s * b0 + c * b1, _wrap1(a2 + b2)])


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
    if p.ndim == 2 and p.shape[1] >= 2:
        return _transform(p, float(x), float(y), float(c), float(s))
    return np.column_stack([x + c * p[:, 0] - s * p[:, 1], y + s * p[:, 0] + c * p[:, 1]])


@njit(cache=True, nogil=True)
def _transform(p, x, y, c, s):  # pragma: no cover
    """:func:`transform_points`' arithmetic, point by point in one pass (the same operations
    in the same order as the NumPy expression: the same bits)."""
    out = np.empty((p.shape[0], 2))
    for k in range(p.shape[0]):
        out[k, 0] = x + c * p[k, 0] - s * p[k, 1]
        out[k, 1] = y + s * p[k, 0] + c * p[k, 1]
    return out


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
    # np.mod rounds a tiny negative angle up to exactly 2 pi, which is 0.
    theta = np.where(theta >= TWO_PI, 0.0, theta)
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


def observation(
    rho: ArrayLike, theta: ArrayLike, x: ArrayLike, y: ArrayLike
) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """The paper's observation direction ``dir`` and distance ``d`` of lines seen from (x, y).

    ``dir = sign(rho - x cos(theta) - y sin(theta))`` (paper, "Match of feature lines",
    Fig. 6): +1 when the robot is on the origin's side of the line, -1 beyond it, 0 on it;
    ``d`` is the absolute value of the same expression, the robot's distance to the line.

    Parameters
    ----------
    rho, theta : float or array-like, shape (K,)
        Lines in Hessian normal form.
    x, y : float or array-like
        The robot's position, broadcast against the lines.

    Returns
    -------
    dir : ndarray of int
    d : ndarray of float
    """
    s = np.asarray(rho) - np.asarray(x) * np.cos(theta) - np.asarray(y) * np.sin(theta)
    return np.sign(s).astype(np.int64), np.abs(s)


def project_onto_line(points: ArrayLike, rho: float, theta: float) -> NDArray[np.float64]:
    """Orthogonal projection of points (N, 2) onto the line ``(rho, theta)``."""
    p = np.asarray(points, dtype=float)
    n = np.array([np.cos(theta), np.sin(theta)])
    return p - signed_distance(p, rho, theta)[..., None] * n


def position_on_line(points: ArrayLike, theta: ArrayLike) -> NDArray[np.float64]:
    """Coordinate of points (..., 2) along lines of normal angle ``theta``: their dot product
    with the direction ``u = (-sin(theta), cos(theta))`` (``u`` is the normal turned by +90°)."""
    p = np.asarray(points, dtype=float)
    return -p[..., 0] * np.sin(theta) + p[..., 1] * np.cos(theta)


def point_on_line(rho: ArrayLike, theta: ArrayLike, t: ArrayLike) -> NDArray[np.float64]:
    """The point at coordinate ``t`` along the line ``(rho, theta)``: ``rho n + t u`` with
    ``n = (cos(theta), sin(theta))`` and ``u = (-sin(theta), cos(theta))``; shape (..., 2)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.stack(np.broadcast_arrays(rho * c - t * s, rho * s + t * c), axis=-1)


def tls_normal_angle(sxx: float, syy: float, sxy: float) -> float:
    """Normal angle of the total-least-squares line through points with centred second
    moments ``sxx = Σ(x - x̄)²``, ``syy``, ``sxy`` (any weights): the line's direction is the
    principal axis ``0.5 atan2(2 sxy, sxx - syy)``, the normal is 90° further.

    Plain scalar arithmetic, so :mod:`fhslam.extraction` compiles this very function into its
    kernels (numba) and every least-squares line in the package is fitted by one formula.
    """
    return 0.5 * np.arctan2(2.0 * sxy, sxx - syy) + 0.5 * np.pi


def point_segment_distance(points: ArrayLike, a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """Euclidean distance of points to segments from ``a`` to ``b``; all (..., 2), broadcast.

    A degenerate segment (``a == b``) is the point ``a``.
    """
    p = np.asarray(points, dtype=float)
    a = np.asarray(a, dtype=float)
    ab = np.asarray(b, dtype=float) - a
    denom = np.maximum((ab * ab).sum(-1), 1e-300)
    t = np.clip(((p - a) * ab).sum(-1) / denom, 0.0, 1.0)
    return np.linalg.norm(p - (a + t[..., None] * ab), axis=-1)


_CHUNK = 1 << 20  # elements of a (points x segments) block


def distance_to_segments(points: ArrayLike, segments: ArrayLike) -> NDArray[np.float64]:
    """Distance from each point to the nearest of the segments, metres.

    Broadcasts points against segments in blocks of about a million pairs.

    Parameters
    ----------
    points : array-like, shape (P, 2)
    segments : array-like, shape (M, 4), M >= 1
        Rows ``[x1, y1, x2, y2]``.

    Returns
    -------
    ndarray, shape (P,)
    """
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    s = np.asarray(segments, dtype=float).reshape(-1, 4)
    if len(s) == 0:
        raise ValueError("distance_to_segments needs at least one segment")
    out = np.empty(len(p))
    rows = max(1, _CHUNK // len(s))
    for lo in range(0, len(p), rows):
        d = point_segment_distance(p[lo : lo + rows, None, :], s[:, :2], s[:, 2:])
        out[lo : lo + rows] = d.min(axis=1)
    return out


def segment_distances(s: ArrayLike, t: ArrayLike) -> NDArray[np.float64]:
    """Shortest distance between every segment of ``s`` (N, 4) and of ``t`` (M, 4): (N, M).

    Zero where two segments cross; otherwise the smallest endpoint-to-segment distance.
    """
    s = np.asarray(s, dtype=float).reshape(-1, 4)
    t = np.asarray(t, dtype=float).reshape(-1, 4)
    a, b = s[:, None, :2], s[:, None, 2:]
    c, d = t[None, :, :2], t[None, :, 2:]
    dist = np.minimum.reduce(
        [point_segment_distance(a, c, d), point_segment_distance(b, c, d),
         point_segment_distance(c, a, b), point_segment_distance(d, a, b)]
    )  # fmt: skip

    def cross(u: NDArray, v: NDArray) -> NDArray:
        return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]

    crossing = (cross(b - a, c - a) * cross(b - a, d - a) < 0) & (
        cross(d - c, a - c) * cross(d - c, b - c) < 0
    )
    return np.where(crossing, 0.0, dist)


def ray_segment_intersection(
    origin: ArrayLike, direction: ArrayLike, a: ArrayLike, b: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Where rays ``origin + t direction`` meet the lines through segments ``a``-``b``.

    Solves ``o + t d = a + s (b - a)`` with 2D cross products: ``t = (a - o) × (b - a) /
    d × (b - a)``, ``s = (a - o) × d / d × (b - a)``. The ray hits the segment when ``t > 0``
    and ``0 <= s <= 1``; a ray parallel to the segment gives ``inf`` or ``nan`` (no warning).

    Parameters
    ----------
    origin, direction, a, b : array-like, shape (..., 2)
        Broadcast against each other (e.g. one origin, beams (B, 1, 2), walls (M, 2)).

    Returns
    -------
    t, s : ndarray
        Range along the ray (in units of ``|direction|``) and position along the segment.
    """
    o, d = np.asarray(origin, dtype=float), np.asarray(direction, dtype=float)
    a = np.asarray(a, dtype=float)
    p, e = a - o, np.asarray(b, dtype=float) - a
    denom = d[..., 0] * e[..., 1] - d[..., 1] * e[..., 0]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        t = (p[..., 0] * e[..., 1] - p[..., 1] * e[..., 0]) / denom
        s = (p[..., 0] * d[..., 1] - p[..., 1] * d[..., 0]) / denom
    return t, s


def angle_difference_lines(theta_a: ArrayLike, theta_b: ArrayLike) -> NDArray | float:
    """Unsigned angle in [0, pi/2] between two undirected lines with normal angles a, b."""
    d = np.abs(np.mod(np.asarray(theta_a) - np.asarray(theta_b), np.pi))
    d = np.minimum(d, np.pi - d)
    return float(d) if np.ndim(d) == 0 else d
