"""The target clouds of the scan matcher, made ready for matching.

:class:`LikelihoodGrid`: the target rasterised into ``exp(-d²/2σ²)`` of each cell's
distance ``d`` to the nearest target point (an exact Euclidean distance transform,
compiled), with the zero padding and the max-pooled pyramid the correlative searches of
:mod:`fhslam.scanmatch.search` read. :class:`PointMap`: the target's points with normals,
bucketed for the nearest-neighbour queries of :func:`fhslam.scanmatch.refine`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from fhslam._numba import njit
from fhslam.geometry import as_points, as_pose, tls_normal_angle, transform_points
from fhslam.scanmatch.clouds import VOXEL_PHASE, _bounds

__all__ = ["BNB_LEVELS", "GRID_PAD", "LikelihoodGrid", "PointMap"]

BNB_LEVELS = 4
"""Levels of the branch-and-bound search: the coarsest blocks are 16 × 16 shifts."""

GRID_PAD = 1 << BNB_LEVELS
"""Cells of 0 around a grid's values (:attr:`LikelihoodGrid.padded`): the pyramid's
padding, and what lets the exhaustive search add a point's shifted cells without testing
each against the grid's edges."""


@dataclass(frozen=True)
class LikelihoodGrid:
    """``exp(-d²/2σ²)`` of the distance ``d`` to the nearest target point, per cell.

    ``values[row, col]`` covers ``x ∈ origin_x + col·resolution + [0, resolution)``,
    ``y`` likewise with ``row``.
    """

    values: NDArray[np.float32]
    origin: NDArray[np.float64]
    resolution: float

    @functools.cached_property
    def padded(self) -> NDArray[np.float32]:
        """:attr:`values` with ``GRID_PAD`` cells of 0 on every side (:meth:`build` makes the
        grid inside this array: :attr:`values` is a view of it)."""
        h, w = self.values.shape
        out = np.zeros((h + 2 * GRID_PAD, w + 2 * GRID_PAD), np.float32)
        out[GRID_PAD : GRID_PAD + h, GRID_PAD : GRID_PAD + w] = self.values
        return out

    @functools.cached_property
    def pyramid(self) -> NDArray[np.float32]:
        """Max-pooled copies of :attr:`values` for branch and bound, shape
        ``(BNB_LEVELS + 1, rows + 2 p, cols + 2 p)`` with ``p = 2**BNB_LEVELS``: level ``L`` at
        ``[L, p + r, p + c]`` holds the largest value of the ``2**L × 2**L`` cells from
        ``(r, c)`` upwards (cells off the grid count 0). Computed once per grid."""
        padded = self.padded
        out = np.empty((BNB_LEVELS + 1, *padded.shape), np.float32)
        out[0] = padded
        for level in range(1, BNB_LEVELS + 1):
            s = 1 << (level - 1)
            a, b = out[level - 1], out[level]
            b[:, :] = a
            np.maximum(b[:-s, :], a[s:, :], out=b[:-s, :])
            np.maximum(b[:, :-s], b[:, s:].copy(), out=b[:, :-s])
        return out

    @classmethod
    def build(
        cls, points: ArrayLike, resolution: float, sigma: float, margin: float
    ) -> LikelihoodGrid:
        """Rasterise ``points`` (N >= 1, 2) with at least ``margin`` metres of border, in
        cells whose corners lie at ``(k - VOXEL_PHASE) · resolution`` of the points' frame."""
        p = as_points(points, "target points")
        if len(p) == 0:
            raise ValueError("target points must not be empty")
        low, high = _bounds(p)
        # cell corners at (k - VOXEL_PHASE) · resolution of the points' frame, as the voxels':
        # anchored to the frame, and no point on a border by construction (the lowest point
        # sat exactly `margin` from the corner, a whole number of cells for some margins)
        lo = resolution * (np.floor((low - margin) / resolution + VOXEL_PHASE) - VOXEL_PHASE)
        shape = np.ceil((high + margin - lo) / resolution).astype(int) + 1
        # exp(-d²/2σ²) looked up by the exact integer d² (in cells²); the table runs to where
        # float32 underflows to 0, so the values are exactly those of the formula
        c2 = 0.5 * (resolution / sigma) ** 2
        table = np.exp(-c2 * np.arange(int(np.ceil(104.0 / c2)) + 2)).astype(np.float32)
        table[-1] = 0.0
        pad = GRID_PAD
        padded = _likelihood_grid(
            p, lo[0], lo[1], float(resolution), int(shape[1]), int(shape[0]), table, pad
        )
        grid = cls(padded[pad:-pad, pad:-pad], lo, float(resolution))
        grid.__dict__["padded"] = padded  # the cached property, computed already
        return grid

    def score(self, points: ArrayLike, pose: ArrayLike) -> float:
        """Mean likelihood of ``points`` placed at ``pose`` (points off the grid score 0)."""
        p = transform_points(as_pose(pose), as_points(points))
        c = np.floor((p - self.origin) / self.resolution).astype(int)
        h, w = self.values.shape
        ok = (c[:, 0] >= 0) & (c[:, 0] < w) & (c[:, 1] >= 0) & (c[:, 1] < h)
        return float(self.values[c[ok, 1], c[ok, 0]].sum() / max(len(p), 1))


@njit(cache=True, nogil=True)
def _likelihood_grid(p, x0, y0, res, h, w, table, pad):  # pragma: no cover
    """The ``h`` × ``w`` grid of ``table[min(d², last)]``, ``d²`` the exact squared distance
    (in cells) of each cell to the nearest cell holding a point of ``p`` (cells of ``res``
    from ``(x0, y0)``), inside ``pad`` cells of 0 on every side.

    The exact Euclidean distance transform of Felzenszwalb and Huttenlocher (2012), in
    integers: per column the distance to the nearest occupied cell, then per row the lower
    envelope of the parabolas ``(x - q)² + g(q)²``. Only squares below the table's last
    entry (0) are needed, so a column distance ``g`` with ``g² > last`` counts as none: it
    cannot be part of a square below ``last``. The same values as OpenCV's exact transform
    (``cv2.DIST_MASK_PRECISE``) rounded back to integer squares, at half the time; and they
    depend on the cells alone (OpenCV's float32 distances varied in their last bit from one
    process to the next)."""
    last = table.shape[0] - 1
    none = 1
    while none * none <= last:
        none += 1
    g = np.full((h, w), none, np.int32)
    for k in range(p.shape[0]):
        g[int(np.floor((p[k, 1] - y0) / res)), int(np.floor((p[k, 0] - x0) / res))] = 0
    for y in range(1, h):
        for x in range(w):
            v = g[y - 1, x] + 1
            if v < g[y, x]:
                g[y, x] = v
    for y in range(h - 2, -1, -1):
        for x in range(w):
            v = g[y + 1, x] + 1
            if v < g[y, x]:
                g[y, x] = v
    out = np.zeros((h + 2 * pad, w + 2 * pad), np.float32)
    vv = np.empty(w, np.int64)  # the envelope's parabolas: apex column...
    ff = np.empty(w, np.int64)  # ... and height g²
    zz = np.empty(w + 1, np.float64)  # where each starts
    for y in range(h):
        row = out[pad + y, pad : pad + w]
        k = -1
        for q in range(w):
            if g[y, q] >= none:
                continue
            fq = np.int64(g[y, q]) * np.int64(g[y, q])
            s = -np.inf
            while k >= 0:
                s = ((fq + q * q) - (ff[k] + vv[k] * vv[k])) / (2.0 * (q - vv[k]))
                if s > zz[k]:
                    break
                k -= 1
            k += 1
            vv[k], ff[k], zz[k] = q, fq, s if k > 0 else -np.inf
        if k < 0:
            continue  # no point within reach: the row stays 0
        zz[k + 1] = np.inf
        j = 0
        # columns farther than `none` from every apex stay 0 as well
        for q in range(max(0, vv[0] - none + 1), min(w, vv[k] + none)):
            while zz[j + 1] < q:
                j += 1
            d2 = (q - vv[j]) * (q - vv[j]) + ff[j]
            if d2 < last:
                row[q] = table[d2]
    return out


@dataclass(frozen=True)
class PointMap:
    """A target cloud ready for point-to-line matching: the points that have a normal,
    bucketed in square cells of ``cell`` metres for nearest-neighbour queries (each cell's
    points are ``order[starts[c]:starts[c + 1]]``, cell ``c = ix · ny + iy`` from ``origin``).
    Normals are given (e.g. :func:`fhslam.scanmatch.scan_normals`; NaN: none) or come from
    the principal axis of each point's ``k`` nearest neighbours. Points without a normal
    (clutter, corners: the smaller spread over 1/4 of the larger) are left out, so every
    query point's nearest neighbour has one."""

    points: NDArray[np.float64]
    normals: NDArray[np.float64]
    origin: NDArray[np.float64]
    cell: float
    shape: tuple[int, int]
    starts: NDArray[np.int64]
    order: NDArray[np.int64]

    @classmethod
    def build(
        cls, points: ArrayLike, normals: ArrayLike | None = None, k: int = 6, cell: float = 0.15
    ) -> PointMap:
        """From points and, if known, their normals (:func:`fhslam.scanmatch.scan_normals`,
        NaN: none)."""
        p = as_points(points, "target points")
        if normals is not None:
            nrm = np.asarray(normals, dtype=float).reshape(-1, 2)
            if len(nrm) != len(p):
                raise ValueError(f"{len(nrm)} normals for {len(p)} points")
            ok = np.isfinite(nrm[:, 0])
            return cls._bucketed(p[ok], nrm[ok], cell)
        if len(p) < k:
            raise ValueError(f"a point map needs at least {k} points, got {len(p)}")
        _, nb = cKDTree(p).query(p, k=k)
        q = p[nb] - p[nb].mean(axis=1, keepdims=True)
        sxx, syy, sxy = (
            (q[..., 0] ** 2).sum(1),
            (q[..., 1] ** 2).sum(1),
            (q[..., 0] * q[..., 1]).sum(1),
        )
        theta = tls_normal_angle(sxx, syy, sxy)
        normals = np.column_stack([np.cos(theta), np.sin(theta)])
        # eigenvalues of the 2x2 scatter: spread across / along the local line
        half, mean = np.hypot(0.5 * (sxx - syy), sxy), 0.5 * (sxx + syy)
        ok = mean - half <= 0.25**2 * (mean + half)
        return cls._bucketed(p[ok], normals[ok], cell)

    @classmethod
    def _bucketed(cls, p, normals, cell) -> PointMap:
        if not cell > 0:
            raise ValueError(f"cell must be > 0, got {cell}")
        lo, high = _bounds(p) if len(p) else (np.zeros(2), np.zeros(2))
        extent = high - lo
        cell = max(cell, float(np.sqrt(np.prod(extent + cell) / 4e6)))  # at most ~4e6 cells
        p = np.ascontiguousarray(p)
        if len(p):
            nx, ny, starts, order = _bucket(p, lo[0], lo[1], float(cell))
        else:
            nx, ny, starts, order = 1, 1, np.zeros(2, np.int64), np.zeros(0, np.int64)
        return cls(p, np.ascontiguousarray(normals), lo, float(cell), (int(nx), int(ny)),
                   starts, order)  # fmt: skip


@njit(cache=True, nogil=True)
def _bucket(p, x0, y0, cell):  # pragma: no cover
    """:class:`PointMap`'s buckets of the points ``p`` (N >= 1) in cells of ``cell`` from
    ``(x0, y0)``: ``(nx, ny, starts, order)``, ``order`` the points sorted stably by cell
    ``ix · ny + iy`` (a counting sort: the same order as NumPy's stable argsort) and
    ``starts[c]`` the number of points in cells before ``c``."""
    n = p.shape[0]
    ix = np.empty(n, np.int64)
    iy = np.empty(n, np.int64)
    for k in range(n):
        ix[k] = int(np.floor((p[k, 0] - x0) / cell))
        iy[k] = int(np.floor((p[k, 1] - y0) / cell))
    nx, ny = ix.max() + 1, iy.max() + 1
    starts = np.zeros(nx * ny + 1, np.int64)
    for k in range(n):
        starts[ix[k] * ny + iy[k] + 1] += 1
    for c in range(nx * ny):
        starts[c + 1] += starts[c]
    fill = starts[:-1].copy()
    order = np.empty(n, np.int64)
    for k in range(n):
        c = ix[k] * ny + iy[k]
        order[fill[c]] = k
        fill[c] += 1
    return nx, ny, starts, order
