"""The paper's feature line and least-squares line fitting.

Paper, "Match of feature lines" (Fig. 6): a line carries ``(rho, theta, n, l, sp, ep, dir, d)``:

- ``rho``   distance OP from the origin O to the line (``rho >= 0``), metres;
- ``theta`` angle of the perpendicular OP to the positive x axis, in [0, 2 pi), radians;
- ``n``     number of scan points fitted to the line;
- ``l``     length of the segment from ``sp`` to ``ep`` (here ``length``), metres;
- ``sp``, ``ep`` start and end point of the segment (in scan order);
- ``dir``   observation direction ``sign(rho - x cos(theta) - y sin(theta))`` for a robot at
  ``(x, y)``: +1 when the robot is on the origin's side of the line, -1 beyond it, 0 on it;
- ``d``     distance from the robot to the line, metres.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.geometry import (
    as_pose,
    normalize_line,
    observation,
    point_on_line,
    position_on_line,
    signed_distance,
    tls_normal_angle,
    transform_points,
)


@dataclass(frozen=True, eq=False)
class Line:
    """A feature line segment (paper Fig. 6). Build one with :func:`line_from_points`.

    Attributes
    ----------
    rho, theta : float
        Hessian normal form, ``rho >= 0``, ``theta`` in [0, 2 pi).
    n : int
        Number of scan points supporting the line.
    length : float
        Segment length ``|ep - sp|`` (the paper's ``l``).
    sp, ep : ndarray, shape (2,)
        Start and end point: the inliers' extreme projections on the line, ``sp`` on the side
        of the first inlier in scan order.
    dir : int or None
        Observation direction relative to ``pose`` (None when no pose was given).
    d : float or None
        Distance from ``pose`` to the line (None when no pose was given).
    inliers : ndarray of int, shape (n,)
        Indices of the supporting points in the array the line was extracted from.
    rms : float
        Root mean square orthogonal distance of the inliers to the line.
    """

    rho: float
    theta: float
    n: int
    length: float
    sp: NDArray[np.float64]
    ep: NDArray[np.float64]
    dir: int | None = None
    d: float | None = None
    inliers: NDArray[np.intp] = field(default_factory=lambda: np.zeros(0, dtype=np.intp))
    rms: float = 0.0

    @property
    def normal(self) -> NDArray[np.float64]:
        """Unit normal ``(cos theta, sin theta)`` pointing from the origin to the line."""
        return np.array([np.cos(self.theta), np.sin(self.theta)])

    @property
    def midpoint(self) -> NDArray[np.float64]:
        return 0.5 * (self.sp + self.ep)

    def observed_from(self, pose: ArrayLike) -> Line:
        """The same line with ``dir`` and ``d`` computed for a robot at ``pose``."""
        p = as_pose(pose)
        side, d = observation(self.rho, self.theta, p[0], p[1])
        return replace(self, dir=int(side), d=float(d))

    def transformed(self, pose: ArrayLike) -> Line:
        """The line mapped by the rigid motion ``pose`` (e.g. from robot to world frame).

        ``dir`` and ``d`` are dropped (they refer to a robot pose in the old frame).
        """
        p = as_pose(pose)
        sp, ep = transform_points(p, np.vstack([self.sp, self.ep]))
        theta = self.theta + p[2]
        rho = self.rho + p[0] * np.cos(theta) + p[1] * np.sin(theta)
        r, t = normalize_line(rho, theta)
        return replace(self, rho=float(r), theta=float(t), sp=sp, ep=ep, dir=None, d=None)

    def __repr__(self) -> str:
        pose_part = "" if self.dir is None else f", dir={self.dir:+d}, d={self.d:.3f}"
        return (
            f"Line(rho={self.rho:.3f}, theta={np.degrees(self.theta):.2f}°, n={self.n}, "
            f"l={self.length:.3f}, sp=({self.sp[0]:.3f}, {self.sp[1]:.3f}), "
            f"ep=({self.ep[0]:.3f}, {self.ep[1]:.3f}){pose_part})"
        )


def fit_line(points: ArrayLike) -> tuple[float, float, float]:
    """Total-least-squares line through points: minimises the orthogonal distances.

    Parameters
    ----------
    points : array-like, shape (N, 2), N >= 2, not all identical

    Returns
    -------
    rho, theta, rms : float
        The line in the paper's Hessian form and the rms orthogonal residual.
    """
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 2:
        raise ValueError(f"fit_line needs an (N, 2) array with N >= 2, got shape {p.shape}")
    c = p.mean(axis=0)
    q = p - c
    sxx, syy, sxy = (q[:, 0] ** 2).sum(), (q[:, 1] ** 2).sum(), (q[:, 0] * q[:, 1]).sum()
    if sxx + syy == 0.0:
        raise ValueError("fit_line got identical points: the line direction is undefined")
    theta = tls_normal_angle(sxx, syy, sxy)
    rho = c[0] * np.cos(theta) + c[1] * np.sin(theta)
    r, t = normalize_line(rho, theta)
    rms = float(np.sqrt(np.mean(signed_distance(p, float(r), float(t)) ** 2)))
    return float(r), float(t), rms


def line_from_points(
    points: ArrayLike,
    inliers: ArrayLike | None = None,
    pose: ArrayLike | None = None,
    rho_theta: tuple[float, float] | None = None,
) -> Line:
    """Build a :class:`Line` from its supporting points (given in scan order).

    Parameters
    ----------
    points : array-like, shape (N, 2)
        All points of the scan.
    inliers : array-like of int, optional
        Indices of the supporting points, in scan order (default: all points).
    pose : array-like, shape (3,), optional
        Robot pose in the points' frame, for ``dir`` and ``d``.
    rho_theta : (float, float), optional
        Use this line instead of the least-squares fit (e.g. a classical Hough peak).
    """
    p = np.asarray(points, dtype=float)
    idx = np.arange(len(p)) if inliers is None else np.asarray(inliers, dtype=np.intp)
    q = p[idx]
    if rho_theta is None:
        rho, theta, rms = fit_line(q)
    else:
        rho, theta = (float(v) for v in normalize_line(*rho_theta))
        rms = float(np.sqrt(np.mean(signed_distance(q, rho, theta) ** 2))) if len(q) else 0.0
    t = position_on_line(q, theta)
    # Extreme projections, oriented so that sp lies on the side of the first point in scan order.
    lo, hi = (t.min(), t.max()) if t[0] <= t[-1] else (t.max(), t.min())
    sp, ep = point_on_line(rho, theta, np.array([lo, hi]))
    line = Line(
        rho=rho,
        theta=theta,
        n=len(idx),
        length=float(abs(hi - lo)),
        sp=sp,
        ep=ep,
        inliers=idx,
        rms=rms,
    )
    return line if pose is None else line.observed_from(pose)


def split_runs(points: ArrayLike, idx: ArrayLike, max_gap: float) -> list[NDArray[np.intp]]:
    """Split a line's inliers (indices in scan order) where neighbours are over ``max_gap`` apart.

    A straight wall seen from one viewpoint is ordered along the line as the beams are, so a
    gap between consecutive inliers means two separate segments on the same infinite line
    (e.g. two walls either side of a doorway).

    Parameters
    ----------
    points : array-like, shape (N, 2)
    idx : array-like of int, shape (K,)
        Inlier indices into ``points``, increasing.
    max_gap : float
        Largest distance between consecutive inliers inside one segment, metres.

    Returns
    -------
    list of ndarray of int
        The runs, in scan order.
    """
    idx = np.asarray(idx, dtype=np.intp)
    if len(idx) < 2:
        return [idx] if len(idx) else []
    p = np.asarray(points, dtype=float)[idx]
    gaps = np.hypot(*np.diff(p, axis=0).T)
    cuts = np.flatnonzero(gaps > max_gap) + 1
    return np.split(idx, cuts)


def transform_lines(lines: list[Line], pose: ArrayLike) -> list[Line]:
    """:meth:`Line.transformed` for many lines at once (the same numbers, vectorised)."""
    if not lines:
        return []
    x, y, th = as_pose(pose)
    c, s = np.cos(th), np.sin(th)
    ends = np.array([[ln.sp, ln.ep] for ln in lines]).reshape(-1, 2)
    ends = np.column_stack(
        [x + c * ends[:, 0] - s * ends[:, 1], y + s * ends[:, 0] + c * ends[:, 1]]
    )
    theta = np.array([ln.theta for ln in lines]) + th
    rho = np.array([ln.rho for ln in lines]) + x * np.cos(theta) + y * np.sin(theta)
    rho, theta = normalize_line(rho, theta)
    return [
        Line(
            rho=float(r),
            theta=float(t),
            n=ln.n,
            length=ln.length,
            sp=ends[2 * k],
            ep=ends[2 * k + 1],
            inliers=ln.inliers,
            rms=ln.rms,
        )
        for k, (ln, r, t) in enumerate(zip(lines, rho, theta, strict=True))
    ]
