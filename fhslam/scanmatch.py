"""Correlative scan matching (Olson 2009): the pose of one point cloud in another's frame.

The target cloud is rasterised into a *likelihood grid*: each cell holds
``exp(-d² / 2σ²)`` of its distance ``d`` to the nearest target point (an exact Euclidean
distance transform, compiled). A candidate pose scores the mean likelihood of the query
points it places in the grid. :func:`match_clouds` searches exhaustively, first on a coarse
grid (10 cm, 1° steps) over the whole search window, then on a fine grid (2 cm, 0.1°) around
the coarse optimum. An exhaustive search cannot be caught by a local minimum, which is what a
loop closure after a long drift needs; the score says how well the clouds agree, which is
what decides whether to trust the match.

Used by :mod:`fhslam.slam.graph`; depends only on :mod:`fhslam.geometry`. The inner loop is a
``numba`` kernel (one pass over angles × shifts × points).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from llvmlite import ir
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from fhslam._numba import intrinsic, njit, types
from fhslam.geometry import as_points, as_pose, tls_normal_angle, transform_points

__all__ = [
    "LikelihoodGrid",
    "MatchResult",
    "PointMap",
    "Refinement",
    "correlative_search",
    "densify",
    "match_clouds",
    "refine",
    "scan_normals",
    "smooth_scan",
    "voxel_downsample",
    "voxel_index",
]


def voxel_downsample(points: ArrayLike, size: float) -> NDArray[np.float64]:
    """Keep the first point of each ``size`` × ``size`` cell (order preserved)."""
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    return p[voxel_index(p, size)]


def voxel_index(points: ArrayLike, size: float) -> NDArray[np.intp]:
    """Indices of the first point of each ``size`` × ``size`` cell, increasing.

    Compiled (:func:`_first_per_cell`): the same indices as NumPy's ``np.unique`` on the
    cells (:func:`_voxel_index_numpy`), a tenth of the time on a scan."""
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(p) == 0:
        return np.zeros(0, dtype=np.intp)
    if not size > 0:
        raise ValueError(f"size must be > 0, got {size}")
    first = _first_per_cell(p, float(size))
    return _voxel_index_numpy(p, size) if first is None else first


def _voxel_index_numpy(points: ArrayLike, size: float) -> NDArray[np.intp]:
    """:func:`voxel_index` by ``np.unique`` (the kernel's reference in the tests, and the
    way for points whose cells an int64 does not hold)."""
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    k = np.floor(p / size).astype(np.int64)
    k -= k.min(axis=0)
    _, first = np.unique(k[:, 0] * (int(k[:, 1].max()) + 1) + k[:, 1], return_index=True)
    return np.sort(first)


@njit(cache=True, nogil=True)
def _first_per_cell(p, size):  # pragma: no cover
    """:func:`voxel_index` of ``p`` (N >= 1): one pass marking the cells seen where the
    cells' box is small against N (a scan's, a submap's), else the first of each run of
    equal cells in a stable sort; ``None`` if a cell index would not fit an int64."""
    n = p.shape[0]
    kx = np.empty(n, np.int64)
    ky = np.empty(n, np.int64)
    for i in range(n):
        fx, fy = np.floor(p[i, 0] / size), np.floor(p[i, 1] / size)
        if not (abs(fx) < 2.0**52 and abs(fy) < 2.0**52):
            return None
        kx[i], ky[i] = np.int64(fx), np.int64(fy)
    x0, y0 = kx.min(), ky.min()
    nx, ny = kx.max() - x0 + 1, ky.max() - y0 + 1
    out = np.empty(n, np.intp)
    m = 0
    if float(nx) * float(ny) <= 256.0 * n + 65536.0:
        seen = np.zeros(nx * ny, np.bool_)
        for i in range(n):
            key = (kx[i] - x0) * ny + (ky[i] - y0)
            if not seen[key]:
                seen[key] = True
                out[m] = i
                m += 1
        return out[:m]
    key = (kx - x0) * ny + (ky - y0)
    order = np.argsort(key, kind="mergesort")
    out[0] = order[0]
    m = 1
    for t in range(1, n):
        if key[order[t]] != key[order[t - 1]]:
            out[m] = order[t]
            m += 1
    return np.sort(out[:m])


def scan_normals(
    points: ArrayLike, half_window: int = 3, max_gap: float = 0.1, max_gap_per_metre: float = 0.03
) -> NDArray:
    """Unit normals of a scan's points (laser frame, beam order) from their beam neighbours.

    Each point's normal is the principal axis of the ``2 half_window + 1`` consecutive points
    around it, when each lies within ``max_gap + max_gap_per_metre × range`` metres per index
    step of the point; else
    (an edge, a jump, clutter) the normal is NaN. Neighbours in beam order lie on the same
    surface, so a scan's normals stay sharp where a cloud merged from many scans is blurred.

    Windows of up to 7 points are summed by a compiled kernel (:func:`_window_moments`),
    value after value as NumPy sums them: the same normals, bit for bit, at a fifth of the
    time (``tests/test_scanmatch.py``); wider windows, whose sums NumPy pairs up, take the
    NumPy path (:func:`_scan_normals_numpy`).
    """
    p = as_points(points, "points")
    n = len(p)
    w = 2 * half_window + 1
    if not 1 <= w <= 7 or n < w:
        return _scan_normals_numpy(p, half_window, max_gap, max_gap_per_metre)
    ok, sxx, syy, sxy = _window_moments(p, half_window, float(max_gap), float(max_gap_per_metre))
    theta = tls_normal_angle(sxx, syy, sxy)  # NumPy's arctan2: numba's differs in last bits
    out = np.full((n, 2), np.nan)
    out[half_window : n - half_window][ok] = np.column_stack([np.cos(theta), np.sin(theta)])[ok]
    return out


def _scan_normals_numpy(points, half_window=3, max_gap=0.1, max_gap_per_metre=0.03):
    """:func:`scan_normals` in NumPy (any window; the kernel's reference in the tests)."""
    p = as_points(points, "points")
    n = len(p)
    out = np.full((n, 2), np.nan)
    w = 2 * half_window + 1
    if n < w:
        return out
    idx = np.arange(n - w + 1)[:, None] + np.arange(w)  # windows, centre at half_window
    win = p[idx]
    centre = win[:, half_window]
    far = np.hypot(*(win - centre[:, None]).transpose(2, 0, 1))
    gap = max_gap + max_gap_per_metre * np.hypot(*centre.T)
    ok = np.all(far <= gap[:, None] * np.abs(np.arange(w) - half_window), axis=1)
    q = win - win.mean(axis=1, keepdims=True)
    sxx, syy = (q[..., 0] ** 2).sum(1), (q[..., 1] ** 2).sum(1)
    sxy = (q[..., 0] * q[..., 1]).sum(1)
    theta = tls_normal_angle(sxx, syy, sxy)
    half, mean = np.hypot(0.5 * (sxx - syy), sxy), 0.5 * (sxx + syy)
    ok &= mean - half <= 0.25**2 * (mean + half)  # spread across under 1/4 of along
    nrm = np.column_stack([np.cos(theta), np.sin(theta)])
    out[half_window : n - half_window][ok] = nrm[ok]
    return out


def smooth_scan(
    points: ArrayLike,
    normals: ArrayLike,
    half_window: int = 3,
    max_turn_deg: float = 10.0,
    max_spread: float = 2.0,
) -> NDArray[np.float64]:
    """A scan's points (laser frame, beam order) with their range noise across the surface
    averaged out: each point whose :func:`scan_normals` normal exists (``normals``, computed
    with the same ``half_window``) is moved onto the total-least-squares line of its window
    (the ``2 half_window + 1`` consecutive points through their mean, along that normal).

    Only where the surface is straight over more than the window: the normals
    ``half_window`` beams before and after must lie within ``max_turn_deg`` of the point's
    own, so that corners (a window straddling two walls at an obtuse angle can still pass
    :func:`scan_normals`' straightness test) keep their points; and the window's points
    must lie within ``max_spread`` times the scan's median rms distance of a window to
    its line (the range noise, as this scan shows it), so that a step or a recess smaller
    than the window (a door frame) is not ironed out. Other points are returned as they
    are. Along a wall the points stay where they were; what the window removes is
    the noise that moves them off it (1 cm in the simulated laser), which a keyframe cloud
    otherwise carries into every scan matched against it.
    """
    return _smooth(points, normals, half_window, max_turn_deg, max_spread, _smooth_windows)


def _smooth_scan_numpy(
    points: ArrayLike,
    normals: ArrayLike,
    half_window: int = 3,
    max_turn_deg: float = 10.0,
    max_spread: float = 2.0,
) -> NDArray[np.float64]:
    """The NumPy reference of :func:`smooth_scan` (tests/test_kernels.py)."""
    return _smooth(points, normals, half_window, max_turn_deg, max_spread, _smooth_windows_numpy)


def _smooth(points, normals, half_window, max_turn_deg, max_spread, windows):
    """:func:`smooth_scan` with ``windows(p, normals, h, cos)`` giving each window's mean,
    whether it passes the turn tests and its rms across (compiled, or NumPy's)."""
    p = as_points(points, "points")
    nrm = np.asarray(normals, dtype=float).reshape(-1, 2)
    if len(nrm) != len(p):
        raise ValueError(f"{len(nrm)} normals for {len(p)} points")
    if half_window < 1:
        raise ValueError(f"half_window must be >= 1, got {half_window}")
    h, n = half_window, len(p)
    out = p.copy()
    if n < 2 * h + 1:
        return out
    inner = np.arange(h, n - h)
    own = nrm[inner]
    mean, ok, rms = windows(p, np.ascontiguousarray(nrm), h, np.cos(np.radians(max_turn_deg)))
    if not ok.any():
        return out
    ok &= rms <= max_spread * np.median(rms[ok])
    k = inner[ok]
    off = ((p[k] - mean[ok]) * own[ok]).sum(1)
    out[k] -= off[:, None] * own[ok]
    return out


def _smooth_windows_numpy(p, nrm, h, cos):
    """:func:`_smooth_windows` in NumPy: the reference its operations follow."""
    inner = np.arange(h, len(p) - h)
    window = np.lib.stride_tricks.sliding_window_view(p, 2 * h + 1, axis=0)  # (m, 2, w)
    mean = window.mean(axis=2)
    own, before, after = nrm[inner], nrm[inner - h], nrm[inner + h]
    with np.errstate(invalid="ignore"):  # NaN normals compare False
        ok = (np.abs((own * before).sum(1)) >= cos) & (np.abs((own * after).sum(1)) >= cos)
    across = ((window - mean[:, :, None]) * np.nan_to_num(own)[:, :, None]).sum(axis=1)
    return mean, ok, np.sqrt((across**2).mean(axis=1))


@njit(cache=True, nogil=True)
def _smooth_windows(p, nrm, h, cos):  # pragma: no cover
    """For :func:`smooth_scan`, each window of ``2 h + 1`` points: its mean, whether its
    normals pass the turn tests, and the rms of its points across the middle normal (0.31
    ms a scan in NumPy, 0.08 ms in all compiled); the operations of
    :func:`_smooth_windows_numpy` in its order (sums from +0.0, one term after
    the other, as NumPy sums fewer than 8 values; NaN normals fail the tests, and count
    as 0 across)."""
    w = 2 * h + 1
    m = p.shape[0] - w + 1
    mean = np.empty((m, 2))
    ok = np.empty(m, np.bool_)
    rms = np.empty(m)
    for i in range(m):
        sx = 0.0
        sy = 0.0
        for j in range(w):
            sx += p[i + j, 0]
            sy += p[i + j, 1]
        mx = sx / w
        my = sy / w
        mean[i, 0] = mx
        mean[i, 1] = my
        k = i + h
        ox, oy = nrm[k, 0], nrm[k, 1]
        tb = 0.0 + ox * nrm[k - h, 0]
        tb += oy * nrm[k - h, 1]
        ta = 0.0 + ox * nrm[k + h, 0]
        ta += oy * nrm[k + h, 1]
        ok[i] = (abs(tb) >= cos) and (abs(ta) >= cos)
        if ox != ox:  # NaN: np.nan_to_num
            ox = 0.0
        if oy != oy:
            oy = 0.0
        s2 = 0.0
        for j in range(w):
            a = 0.0 + (p[i + j, 0] - mx) * ox
            a += (p[i + j, 1] - my) * oy
            s2 += a * a
        rms[i] = np.sqrt(s2 / w)
    return mean, ok, rms


@njit(cache=True, nogil=True)
def _window_moments(p, half_window, max_gap, max_gap_per_metre):  # pragma: no cover
    """For each window of :func:`scan_normals`: whether it passes the gap and the spread
    tests, and its centred second moments; the operations of the NumPy version in its
    order (NumPy sums fewer than 8 values one after the other, from +0.0)."""
    w = 2 * half_window + 1
    m = p.shape[0] - w + 1
    ok = np.empty(m, np.bool_)
    sxx, syy, sxy = np.empty(m), np.empty(m), np.empty(m)
    for i in range(m):
        cx, cy = p[i + half_window, 0], p[i + half_window, 1]
        gap = max_gap + max_gap_per_metre * np.hypot(cx, cy)
        good = True
        for j in range(w):
            good &= np.hypot(p[i + j, 0] - cx, p[i + j, 1] - cy) <= gap * abs(j - half_window)
        mx, my = 0.0, 0.0  # from +0.0, as NumPy: a sum of -0.0 terms is +0.0
        for j in range(w):
            mx += p[i + j, 0]
            my += p[i + j, 1]
        mx, my = mx / w, my / w
        xx, yy, xy = 0.0, 0.0, 0.0
        for j in range(w):
            a, b = p[i + j, 0] - mx, p[i + j, 1] - my
            xx += a * a
            yy += b * b
            xy += a * b
        half, mean = np.hypot(0.5 * (xx - yy), xy), 0.5 * (xx + yy)
        ok[i] = good and mean - half <= 0.25**2 * (mean + half)
        sxx[i], syy[i], sxy[i] = xx, yy, xy
    return ok, sxx, syy, sxy


@njit(cache=True, nogil=True)
def _bounds(p):  # pragma: no cover
    """``(p.min(axis=0), p.max(axis=0))`` of finite points (N >= 1, 2) in one pass: the same
    numbers (a minimum is exact), without NumPy's slow column reductions."""
    low, high = p[0].copy(), p[0].copy()
    for k in range(1, p.shape[0]):
        for d in range(2):
            if p[k, d] < low[d]:
                low[d] = p[k, d]
            elif p[k, d] > high[d]:
                high[d] = p[k, d]
    return low, high


BNB_LEVELS = 4
"""Levels of the branch-and-bound search: the coarsest blocks are 16 × 16 shifts."""

BNB_MIN_SHIFTS = 8
"""Windows of fewer than this many shifts either side are searched exhaustively."""

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
        """Rasterise ``points`` (N >= 1, 2) with ``margin`` metres of border."""
        p = as_points(points, "target points")
        if len(p) == 0:
            raise ValueError("target points must not be empty")
        low, high = _bounds(p)
        lo = low - margin
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


@njit(cache=True, nogil=True)
def _search(lik, ox, oy, res, px, py, x0, y0, th0, n_t, n_a, da, w_t, w_r):  # pragma: no cover
    h, w = lik.shape
    n = px.shape[0]
    best, bx, by, bt, best_acc = -np.inf, x0, y0, th0, 0.0
    ix = np.empty(n, np.int64)
    iy = np.empty(n, np.int64)
    for ka in range(-n_a, n_a + 1):
        th = th0 + ka * da
        c, s = np.cos(th), np.sin(th)
        for k in range(n):
            ix[k] = int(np.floor((c * px[k] - s * py[k] + x0 - ox) / res))
            iy[k] = int(np.floor((s * px[k] + c * py[k] + y0 - oy) / res))
        for sx in range(-n_t, n_t + 1):
            for sy in range(-n_t, n_t + 1):
                acc = 0.0
                for k in range(n):
                    u = ix[k] + sx
                    v = iy[k] + sy
                    if 0 <= u < w and 0 <= v < h:
                        acc += lik[v, u]
                # the prior: of equal scores (a corridor's axis) the nearest to the guess wins
                sc = acc / max(n, 1) - w_t * res * np.sqrt(sx * sx + sy * sy) - w_r * abs(ka * da)
                if sc > best:
                    best, bx, by, bt = sc, x0 + sx * res, y0 + sy * res, th
                    best_acc = acc
    return best_acc / max(n, 1), bx, by, bt


@njit(cache=True, nogil=True)
def _search_padded(
    padded, pad, ox, oy, res, px, py, x0, y0, th0, n_t, n_a, da, w_t, w_r
):  # pragma: no cover
    """:func:`_search` on the grid inside ``pad`` cells of 0 (:attr:`LikelihoodGrid.padded`),
    point by point: each point adds its cell's (2 n_t + 1)² shifted neighbours to the
    shifts' sums, without testing each against the grid's edges where the whole block lies
    within the padding. Every sum adds the same values in the same order as :func:`_search`
    (a cell in the padding adds 0.0, which leaves a sum of non-negative values as it is), so
    the result is the same bit for bit, ties included."""
    hp, wp = padded.shape
    h, w = hp - 2 * pad, wp - 2 * pad
    n = px.shape[0]
    m = 2 * n_t + 1
    best, bx, by, bt, best_acc = -np.inf, x0, y0, th0, 0.0
    acc = np.empty((m, m))  # [x shift, y shift]
    for ka in range(-n_a, n_a + 1):
        th = th0 + ka * da
        c, s = np.cos(th), np.sin(th)
        acc[:, :] = 0.0
        for k in range(n):
            ix = int(np.floor((c * px[k] - s * py[k] + x0 - ox) / res))
            iy = int(np.floor((s * px[k] + c * py[k] + y0 - oy) / res))
            u0, v0 = ix - n_t + pad, iy - n_t + pad
            if u0 >= 0 and v0 >= 0 and u0 + m <= wp and v0 + m <= hp:
                for a in range(m):
                    for b in range(m):
                        acc[a, b] += padded[v0 + b, u0 + a]
            else:
                for a in range(m):
                    u = ix - n_t + a
                    for b in range(m):
                        v = iy - n_t + b
                        if 0 <= u < w and 0 <= v < h:
                            acc[a, b] += padded[v + pad, u + pad]
        for a in range(m):
            sx = a - n_t
            for b in range(m):
                sy = b - n_t
                sc = (
                    acc[a, b] / max(n, 1)
                    - w_t * res * np.sqrt(sx * sx + sy * sy)
                    - w_r * abs(ka * da)
                )
                if sc > best:
                    best, bx, by, bt = sc, x0 + sx * res, y0 + sy * res, th
                    best_acc = acc[a, b]
    return best_acc / max(n, 1), bx, by, bt


@njit(cache=True, nogil=True)
def _bound(pyr, level, pad, ix, iy, sx, sy):  # pragma: no cover
    """Sum over the points of the level's pooled value at their cell + (sx, sy)."""
    h, w = pyr.shape[1], pyr.shape[2]
    acc = 0.0
    for k in range(ix.shape[0]):
        u = ix[k] + sx + pad
        v = iy[k] + sy + pad
        if 0 <= u < w and 0 <= v < h:
            acc += pyr[level, v, u]
    return acc


@njit(cache=True, nogil=True)
def _search_bnb(
    pyr, ox, oy, res, px, py, x0, y0, th0, n_t, n_a, da, w_t, w_r, ex, ey, er, floor
):  # pragma: no cover
    """:func:`_search` by branch and bound over the max-pooled grids ``pyr``
    (:attr:`LikelihoodGrid.pyramid`): the same optimum, ties broken the same way (the first
    of equal scores in the order angle, x shift, y shift). With ``er >= 0`` the shifts within
    ``er`` of ``(ex, ey)`` in x and in y (every angle) are left out: the best pose elsewhere.
    Only poses scoring (with the prior) above ``floor`` are looked for: if there is none,
    the score is 0 and the pose the guess."""
    n = px.shape[0]
    pad = 1 << BNB_LEVELS
    na = 2 * n_a + 1
    ixs = np.empty((na, n), np.int64)
    iys = np.empty((na, n), np.int64)
    for a in range(na):
        th = th0 + (a - n_a) * da
        c, s = np.cos(th), np.sin(th)
        for k in range(n):
            ixs[a, k] = int(np.floor((c * px[k] - s * py[k] + x0 - ox) / res))
            iys[a, k] = int(np.floor((s * px[k] + c * py[k] + y0 - oy) / res))
    nn = max(n, 1)
    top = BNB_LEVELS
    # stack of (level, angle, sx, sy) with their bounds
    cap = 64 + na * ((2 * n_t) // (1 << top) + 2) ** 2 + 4 * top * 64
    st_l = np.empty(cap, np.int64)
    st_a = np.empty(cap, np.int64)
    st_x = np.empty(cap, np.int64)
    st_y = np.empty(cap, np.int64)
    st_b = np.empty(cap, np.float64)
    sp = 0
    # the coarsest blocks, pushed in increasing order of their bound (best popped first)
    nb = ((2 * n_t) >> top) + 1
    m = na * nb * nb
    cb = np.empty(m)
    ca = np.empty(m, np.int64)
    cx = np.empty(m, np.int64)
    cy = np.empty(m, np.int64)
    i = 0
    for a in range(na):
        for bx in range(nb):
            for by in range(nb):
                sx, sy = -n_t + (bx << top), -n_t + (by << top)
                ca[i], cx[i], cy[i] = a, sx, sy
                cb[i] = _block_score(
                    pyr, top, pad, ixs[a], iys[a], sx, sy, n_t, a - n_a, nn, res, da, w_t, w_r
                )
                i += 1
    order = np.argsort(cb)
    for t in range(m):
        q = order[t]
        st_l[sp], st_a[sp], st_x[sp], st_y[sp], st_b[sp] = top, ca[q], cx[q], cy[q], cb[q]
        sp += 1
    best, best_acc = floor, 0.0
    ba, bx_, by_ = 0, 0, 0
    cb4 = np.empty(4)
    cx4 = np.empty(4, np.int64)
    cy4 = np.empty(4, np.int64)
    while sp > 0:
        sp -= 1
        lv, a, sx, sy, bnd = st_l[sp], st_a[sp], st_x[sp], st_y[sp], st_b[sp]
        if bnd < best:
            continue
        if lv == 0:
            if er >= 0 and abs(sx - ex) <= er and abs(sy - ey) <= er:
                continue
            acc = _bound(pyr, 0, pad, ixs[a], iys[a], sx, sy)
            sc = acc / nn - w_t * res * np.sqrt(sx * sx + sy * sy) - w_r * abs((a - n_a) * da)
            if sc > best or (sc == best and (a, sx, sy) < (ba, bx_, by_)):
                best, best_acc, ba, bx_, by_ = sc, acc, a, sx, sy
            continue
        half = 1 << (lv - 1)
        nc = 0
        for dx in range(2):
            for dy in range(2):
                x, y = sx + dx * half, sy + dy * half
                if x > n_t or y > n_t:
                    continue
                cx4[nc], cy4[nc] = x, y
                cb4[nc] = _block_score(
                    pyr, lv - 1, pad, ixs[a], iys[a], x, y, n_t, a - n_a, nn, res, da, w_t, w_r
                )
                nc += 1
        o = np.argsort(cb4[:nc])
        for t in range(nc):
            q = o[t]
            if cb4[q] >= best:
                st_l[sp], st_a[sp], st_x[sp], st_y[sp], st_b[sp] = lv - 1, a, cx4[q], cy4[q], cb4[q]
                sp += 1
    return best_acc / nn, x0 + bx_ * res, y0 + by_ * res, th0 + (ba - n_a) * da


@njit(cache=True, nogil=True)
def _block_score(
    pyr, level, pad, ix, iy, sx, sy, n_t, ka, nn, res, da, w_t, w_r
):  # pragma: no cover
    """An upper bound of the score of every shift in the block of ``2**level`` shifts from
    ``(sx, sy)`` (clipped at ``n_t``): pooled likelihoods minus the smallest prior."""
    size = (1 << level) - 1
    hx, hy = min(sx + size, n_t), min(sy + size, n_t)
    mx = 0 if sx <= 0 <= hx else min(abs(sx), abs(hx))
    my = 0 if sy <= 0 <= hy else min(abs(sy), abs(hy))
    acc = _bound(pyr, level, pad, ix, iy, sx, sy)
    return acc / nn - w_t * res * np.sqrt(mx * mx + my * my) - w_r * abs(ka * da)


def correlative_search(
    grid: LikelihoodGrid,
    points: NDArray[np.float64],
    guess: NDArray[np.float64],
    window: float,
    window_angle: float,
    angle_step: float,
    prior: tuple[float, float] = (0.0, 0.0),
    exclude: tuple[ArrayLike, float] | None = None,
    floor: float = -np.inf,
) -> tuple[float, NDArray[np.float64]]:
    """Best ``(score, pose)`` over ``guess ± window`` (in steps of the grid's resolution)
    and ``± window_angle`` (in steps of ``angle_step``, radians).

    The search maximises the score minus ``prior[0]`` per metre and ``prior[1]`` per
    radian of distance from the guess; the score returned is the plain one. Windows of
    ``BNB_MIN_SHIFTS`` shifts or more are searched by branch and bound, smaller ones
    exhaustively: the same optimum either way, bit for bit.

    ``exclude=(pose, radius)`` leaves out the positions within ``radius`` metres of
    ``pose`` in x and in y (at every heading): the best pose elsewhere, e.g. to tell
    whether a match is unique (searched by branch and bound whatever the window). With a
    ``floor``, only poses whose score less the prior exceeds it are looked for (branch and
    bound prunes the rest at once): if there is none, ``(0.0, guess)`` is returned."""
    n_t = round(window / grid.resolution)
    n_a = int(np.ceil(window_angle / angle_step - 1e-9))
    ex = ey = 0
    er = -1
    if exclude is not None:
        centre = as_pose(exclude[0], "excluded pose")
        ex = round((centre[0] - guess[0]) / grid.resolution)
        ey = round((centre[1] - guess[1]) / grid.resolution)
        er = round(float(exclude[1]) / grid.resolution)
    if n_t >= BNB_MIN_SHIFTS or exclude is not None or floor > -np.inf:
        kernel, table, extra = _search_bnb, (grid.pyramid,), (ex, ey, er, float(floor))
    else:
        kernel, table, extra = _search_padded, (grid.padded, GRID_PAD), ()
    s, x, y, t = kernel(
        *table, float(grid.origin[0]), float(grid.origin[1]), grid.resolution,
        np.ascontiguousarray(points[:, 0]), np.ascontiguousarray(points[:, 1]),
        float(guess[0]), float(guess[1]), float(guess[2]), n_t, n_a, float(angle_step),
        float(prior[0]), float(prior[1]), *extra,
    )  # fmt: skip
    return float(s), np.array([x, y, t])


@dataclass(frozen=True)
class MatchResult:
    """Result of :func:`match_clouds`: the query's pose in the target frame and its scores
    (mean likelihood of the query points, 0..1) on the fine and the coarse grid; how much
    ``coarse_score`` exceeds ``guess_score`` says how much the match improved on the guess."""

    pose: NDArray[np.float64]
    score: float
    coarse_score: float
    guess_score: float = 0.0
    """The coarse grid's score at the guess (0 without a coarse stage)."""
    runner_up: float = 0.0
    """The best coarse score more than ``exclude[0]`` metres from the coarse optimum if it is
    more than ``exclude[1]`` times the coarse score, else 0 (0 unless :func:`match_clouds`
    was asked for it)."""


def _thin(points, n):
    """At most ``n`` points, evenly spaced along the array (deterministic)."""
    if len(points) <= n:
        return points
    return points[np.linspace(0, len(points) - 1, n).astype(np.intp)]


def _crop(target, query, pose, margin):
    """The ``target`` points (in order) within ``margin`` of the box around ``query`` placed
    at ``pose``."""
    q = transform_points(pose, query)
    low, high = _bounds(q)
    lo, hi = low - margin, high + margin
    return _in_box(target, lo[0], lo[1], hi[0], hi[1])


@njit(cache=True, nogil=True)
def _in_box(p, x0, y0, x1, y1):  # pragma: no cover
    """The points of ``p`` with ``x0 <= x <= x1`` and ``y0 <= y <= y1``, in order."""
    n = 0
    for k in range(p.shape[0]):
        if x0 <= p[k, 0] <= x1 and y0 <= p[k, 1] <= y1:
            n += 1
    out = np.empty((n, 2))
    n = 0
    for k in range(p.shape[0]):
        if x0 <= p[k, 0] <= x1 and y0 <= p[k, 1] <= y1:
            out[n, 0], out[n, 1] = p[k, 0], p[k, 1]
            n += 1
    return out


def match_clouds(
    target: ArrayLike,
    query: ArrayLike,
    guess: ArrayLike,
    window: float = 1.0,
    window_deg: float = 15.0,
    coarse: tuple[float, float, float] = (0.10, 0.15, 1.0),
    fine: tuple[float, float, float] = (0.02, 0.04, 0.1),
    max_points: tuple[int, int] = (200, 500),
    prior: tuple[float, float] = (0.05, 0.05),
    exclude: tuple[float, float] | None = None,
    min_coarse: float = -np.inf,
    exclude_min_score: float = -np.inf,
) -> MatchResult:
    """The pose of the ``query`` cloud's frame in the ``target`` cloud's frame.

    Parameters
    ----------
    target, query : array-like, shape (N, 2)
        Points, each in its own frame.
    guess : array-like, shape (3,)
        Predicted pose of the query frame in the target frame.
    window : float
        Search ``± window`` metres in x and y around the guess (coarse stage).
    window_deg : float
        ... and ``± window_deg`` degrees in heading.
    coarse, fine : (resolution m, sigma m, angle step deg)
        The two stages' grid cell, likelihood width and angular step. The fine stage
        searches ``± 6`` cells and ``± 1.5`` coarse angle steps around the coarse optimum.
        With ``window=0`` only the fine stage runs, over ``± window_deg`` around the guess.
    max_points : (int, int)
        The query is thinned to one point per cell and then to at most this many points
        (evenly along the cloud) for the coarse and the fine stage: the cost of a search is
        points × shifts × angles.
    prior : (float, float)
        Score given up per metre and per radian of distance from the guess (coarse stage)
        and from the coarse optimum (fine stage): where the clouds cannot tell positions
        apart (along a corridor), the guess wins instead of the window's corner.
    exclude : (float, float), optional
        ``(radius, fraction)``: also look for the best coarse score more than ``radius``
        metres (in x or y) from the coarse optimum, above ``fraction`` of the coarse score
        (:attr:`MatchResult.runner_up`): a match is unique only if nothing elsewhere scores
        nearly as well (a corridor with doors every few metres). Branch and bound looks only
        where that is possible, so an answer of "none" is cheap.
    min_coarse : float
        The coarse stage looks only for poses scoring (less the prior) above this: if there
        is none, the result has scores 0 and the guess as its pose, and the fine stage does
        not run. Cheap where most searches find nothing (a global search over a large
        window). The coarse grid's wider likelihood scores a pose about as high as the fine
        grid or higher, so a floor at the fine score wanted should lose little (the Freiburg
        hospital's global matches are the same with and without it).
    exclude_min_score : float
        With ``exclude``: look for the runner-up only if the (fine) score reaches this;
        otherwise ``runner_up`` is 0. A caller that drops matches under a score anyway
        saves the second coarse search for them (most loop searches fail); where it is
        looked for, the runner-up is the same as without this.

    Returns
    -------
    MatchResult
        Scores are 0 when the query or the target (near the guess) has fewer than 10
        points; the pose is then the guess.
    """
    tg = as_points(target, "target")
    q = as_points(query, "query")
    g = as_pose(guess, "guess")
    (rc, sc, ac), (rf, sf, af) = coarse, fine
    if len(q) < 10:
        return MatchResult(g, 0.0, 0.0)
    s_c = s_g = 0.0
    rival = None  # where exclude's runner-up is looked for: (coarse grid, points, guess, search)
    if window > 0:
        near = _crop(tg, q, g, window + 3 * sc)
        if len(near) < 10:
            return MatchResult(g, 0.0, 0.0)
        grid = LikelihoodGrid.build(near, rc, sc, window + 3 * sc)
        qc = _thin(voxel_downsample(q, rc), max_points[0])
        s_g = grid.score(qc, g)
        search = (window, np.radians(window_deg), np.radians(ac), prior)
        s_c, best = correlative_search(grid, qc, g, *search, floor=min_coarse)
        if s_c == 0.0 and min_coarse > -np.inf:
            return MatchResult(g, 0.0, 0.0, s_g)  # nothing above the floor
        if exclude is not None:
            rival = (grid, qc, g, search)
        g = best

    def runner_up(score: float) -> float:
        """The runner-up's coarse score, looked for once the match is worth it."""
        if rival is None or not score >= exclude_min_score:
            return 0.0
        grid_c, points, guess_c, search_c = rival
        return correlative_search(
            grid_c, points, guess_c, *search_c, exclude=(best, exclude[0]), floor=exclude[1] * s_c
        )[0]

    qf = _thin(voxel_downsample(q, 1.5 * rf), max_points[1])
    fw = 6 * rf
    near = _crop(tg, q, g, fw + 3 * sf)
    if len(near) < 10:
        return MatchResult(g, 0.0, s_c, s_g, runner_up(0.0))
    grid = LikelihoodGrid.build(near, rf, sf, fw + 3 * sf)
    s_f, pose = correlative_search(
        grid, qf, g, fw, np.radians(ac if window > 0 else window_deg), np.radians(af), prior
    )
    return MatchResult(pose, s_f, s_c, s_g, runner_up(s_f))


def densify(
    points: ArrayLike,
    normals: ArrayLike,
    step: float = 0.02,
    max_gap: float = 0.1,
    max_gap_per_metre: float = 0.03,
    corner_deg: float | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A scan (laser frame, beam order) with points filled in every ``step`` metres between
    consecutive beams that lie on one surface (closer than ``max_gap + max_gap_per_metre ×
    range``, as in :func:`scan_normals`); a filled point's normal is its pair's.

    A wall 15 m away is seen by beams 26 cm apart (1° resolution): as points it is a dotted
    line that a likelihood grid scores low wherever a query point falls between the dots;
    filled in, it scores as the wall it is.

    With ``corner_deg``, the points filled in across a chord that turns by more than
    ``corner_deg`` from both neighbouring chords (or has none) get no normal (NaN): such a
    chord joins two surfaces, cutting a corner, and its points lie off both (behind a
    convex corner, in front of a concave one), by centimetres where the beams are far
    apart. They are still points (a likelihood grid scores them); a point-to-line match
    (:class:`PointMap`) leaves them out.

    Compiled (:func:`_densify`), with NumPy's operations in its order: the same points and
    normals, bit for bit.
    """
    p = as_points(points, "points")
    nrm = np.asarray(normals, dtype=float).reshape(-1, 2)
    if len(nrm) != len(p):
        raise ValueError(f"{len(nrm)} normals for {len(p)} points")
    if corner_deg is not None and not 0 < corner_deg <= 90:
        raise ValueError(f"corner_deg must be in (0, 90] degrees, got {corner_deg}")
    if len(p) < 2:
        return p, nrm
    dense, dense_normals, k, linked = _densify(
        p, nrm, float(step), float(max_gap), float(max_gap_per_metre)
    )
    if len(dense) == len(p):
        return p, nrm
    if corner_deg is not None:
        corner = _corner_chords(p, linked, corner_deg) & (k > 0)
        dense_normals[len(p) :][np.repeat(corner, k)] = np.nan
    return dense, dense_normals


def _corner_chords(p, linked, corner_deg):
    """Which chords between consecutive points ``p`` turn by more than ``corner_deg`` from
    each neighbour on the same surface (``linked``: closer than :func:`densify`'s gap), or
    have no such neighbour."""
    d = np.diff(p, axis=0)
    u = d / np.maximum(np.hypot(*d.T), 1e-300)[:, None]
    straight = linked[1:] & linked[:-1]
    straight &= np.abs((u[1:] * u[:-1]).sum(1)) >= np.cos(np.radians(corner_deg))
    along = np.zeros(len(d), bool)
    along[:-1] |= straight
    along[1:] |= straight
    return ~along


@njit(cache=True, nogil=True)
def _densify(p, nrm, step, max_gap, max_gap_per_metre):  # pragma: no cover
    """:func:`densify`: the filled points follow the scan's, pair by pair, each at
    ``(j + 1) / (k + 1)`` of its pair's gap; also ``k``, the points filled in each gap, and
    which gaps passed the test (``linked``; ``k`` is 0 in those shorter than ``step``)."""
    n = p.shape[0]
    k = np.zeros(n - 1, np.int64)
    linked = np.zeros(n - 1, np.bool_)
    for i in range(n - 1):
        gap = np.hypot(p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1])
        if gap <= max_gap + max_gap_per_metre * np.hypot(p[i, 0], p[i, 1]):
            k[i] = int(np.floor(gap / step))
            linked[i] = True
    total = n + k.sum()
    out_p, out_n = np.empty((total, 2)), np.empty((total, 2))
    out_p[:n], out_n[:n] = p, nrm
    r = n
    for i in range(n - 1):
        dx, dy = p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1]
        gap = np.hypot(dx, dy)
        for j in range(k[i]):
            t = (j + 1) / (k[i] + 1)
            out_p[r, 0], out_p[r, 1] = p[i, 0] + t * dx, p[i, 1] + t * dy
            out_n[r, 0], out_n[r, 1] = -(dy / gap), dx / gap
            r += 1
    return out_p, out_n, k, linked


def _densify_numpy(
    points, normals, step=0.02, max_gap=0.1, max_gap_per_metre=0.03, corner_deg=None
):
    """:func:`densify` in NumPy (the kernel's reference in the tests)."""
    p = as_points(points, "points")
    nrm = np.asarray(normals, dtype=float).reshape(-1, 2)
    if len(p) < 2:
        return p, nrm
    d = np.diff(p, axis=0)
    gap = np.hypot(*d.T)
    limit = max_gap + max_gap_per_metre * np.hypot(*p[:-1].T)
    linked = gap <= limit
    k = np.where(linked, np.floor(gap / step).astype(np.intp), 0)
    pair = np.repeat(np.arange(len(d)), k)
    if len(pair) == 0:
        return p, nrm
    t = (np.arange(len(pair)) - np.repeat(np.cumsum(k) - k, k) + 1) / np.repeat(k + 1, k)
    fill = p[pair] + t[:, None] * d[pair]
    u = d[pair] / gap[pair, None]
    fill_normals = np.column_stack([-u[:, 1], u[:, 0]])
    if corner_deg is not None:
        fill_normals[_corner_chords(p, linked, corner_deg)[pair]] = np.nan
    return np.vstack([p, fill]), np.vstack([nrm, fill_normals])


# -- point-to-line refinement ---------------------------------------------------------------


@dataclass(frozen=True)
class PointMap:
    """A target cloud ready for point-to-line matching: the points that have a normal,
    bucketed in square cells of ``cell`` metres for nearest-neighbour queries (each cell's
    points are ``order[starts[c]:starts[c + 1]]``, cell ``c = ix · ny + iy`` from ``origin``).
    Normals are given (e.g. :func:`scan_normals`; NaN: none) or come from the principal axis
    of each point's ``k`` nearest neighbours. Points without a normal (clutter, corners: the
    smaller spread over 1/4 of the larger) are left out, so every query point's nearest
    neighbour has one."""

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
        """From points and, if known, their normals (:func:`scan_normals`, NaN: none)."""
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


@njit(cache=True, nogil=True)
def _accumulate(
    q0, x, y, th, pts, nrm, lo, cell, nx, ny, starts, order, max_d, huber
):  # pragma: no cover
    """One Gauss-Newton round of :func:`refine`: each query point at the pose ``(x, y, th)``
    paired with its nearest map point closer than ``max_d``; returns the weighted normal
    equations ``(H, g)``, the number of pairs and the sum of squared residuals."""
    h = np.zeros((3, 3))
    g = np.zeros(3)
    c, s = np.cos(th), np.sin(th)
    reach = int(np.ceil(max_d / cell))
    n_ok, ss = 0, 0.0
    jac = np.empty(3)
    for k in range(q0.shape[0]):
        qx = c * q0[k, 0] - s * q0[k, 1] + x
        qy = s * q0[k, 0] + c * q0[k, 1] + y
        ix = int(np.floor((qx - lo[0]) / cell))
        iy = int(np.floor((qy - lo[1]) / cell))
        best, bj = max_d * max_d, -1
        # cells in rings around the point's own; a cell (or a ring) whose nearest edge is
        # farther than the best pair so far cannot hold a nearer point (the margin covers
        # rounding in the cell index)
        ax, ay = qx - lo[0] - ix * cell, qy - lo[1] - iy * cell
        for r in range(reach + 1):
            if r >= 2 and ((r - 1) * cell) ** 2 > best * (1 + 1e-9) + 1e-18:
                break
            for u in range(ix - r, ix + r + 1):
                if u < 0 or u >= nx:
                    continue
                gx = (
                    0.0
                    if u == ix
                    else ((u - ix) * cell - ax if u > ix else ax + (ix - u - 1) * cell)
                )
                step = 1 if abs(u - ix) == r else 2 * r
                for v in range(iy - r, iy + r + 1, max(step, 1)):
                    if v < 0 or v >= ny:
                        continue
                    gy = (
                        0.0
                        if v == iy
                        else ((v - iy) * cell - ay if v > iy else ay + (iy - v - 1) * cell)
                    )
                    if gx * gx + gy * gy > best * (1 + 1e-9) + 1e-18:
                        continue
                    cc = u * ny + v
                    for t in range(starts[cc], starts[cc + 1]):
                        j = order[t]
                        dx, dy = qx - pts[j, 0], qy - pts[j, 1]
                        d2 = dx * dx + dy * dy
                        if d2 < best or (d2 == best and bj >= 0 and j < bj):
                            best, bj = d2, j
        if bj < 0:
            continue
        nx_, ny_ = nrm[bj, 0], nrm[bj, 1]
        r = nx_ * (qx - pts[bj, 0]) + ny_ * (qy - pts[bj, 1])
        jac[0], jac[1] = nx_, ny_
        jac[2] = ny_ * (qx - x) - nx_ * (qy - y)
        # Huber on the residual, tapered to 0 at max_d: a pair forming or breaking at the
        # cut-off changes nothing abruptly
        w = min(1.0, huber / max(abs(r), 1e-12)) * (1.0 - best / (max_d * max_d)) ** 2
        for a in range(3):
            g[a] += w * jac[a] * r
            for b in range(3):
                h[a, b] += w * jac[a] * jac[b]
        n_ok += 1
        ss += r * r
    return h, g, n_ok, ss


@dataclass(frozen=True)
class Refinement:
    """Result of :func:`refine`: the pose, the information of the point-to-line residuals
    about it (3 x 3, per squared metre of residual; units 1/m², 1/(m·rad), 1/rad²), the
    number of query points that found a line and their rms distance to it (metres)."""

    pose: NDArray[np.float64]
    hessian: NDArray[np.float64]
    n_matched: int
    rms: float


def refine(
    target: PointMap,
    query: ArrayLike,
    guess: ArrayLike,
    max_distance: float = 0.1,
    iterations: int = 10,
    huber: float = 0.02,
    min_eigen_ratio: float = 1e-3,
    prior: tuple[ArrayLike, ArrayLike] | None = None,
) -> Refinement:
    """Point-to-line ICP: the pose of ``query`` in ``target``'s frame near ``guess``.

    Each query point is paired with its nearest target point within ``max_distance``; the
    pose minimises the weighted squared distances of the query points to those points'
    tangent lines (Gauss-Newton, a fixed number of rounds: Huber weights, tapered to zero at
    ``max_distance``). Along a direction the pairs do
    not constrain (a corridor's axis: eigenvalue under ``min_eigen_ratio`` of the largest)
    the guess is kept; :attr:`Refinement.hessian` tells the caller how little is known
    there.

    ``prior=(pose, information)`` adds ``(x - pose)ᵀ information (x - pose)`` to the cost
    (information in the residuals' units, 1/m² per squared metre of residual): where the
    pairs say nothing, ``pose`` (e.g. the odometry's prediction) is kept instead of the
    guess. :attr:`Refinement.hessian` holds the pairs' information only.
    """
    q0 = as_points(query, "query")
    x = as_pose(guess, "guess").copy()
    if prior is not None:
        prior_pose = as_pose(prior[0], "prior pose")
        prior_info = np.asarray(prior[1], dtype=float).reshape(3, 3)
    if not max_distance > 0:
        raise ValueError(f"max_distance must be > 0, got {max_distance}")
    if len(target.points) == 0 or iterations < 1:
        return Refinement(x, np.zeros((3, 3)), 0, 0.0)
    nx, ny = target.shape
    if prior is None:
        prior_pose, prior_info = np.zeros(3), np.zeros((3, 3))
    x, h, n_ok, rms = _gauss_newton(
        np.ascontiguousarray(q0), x, target.points, target.normals, target.origin,
        target.cell, nx, ny, target.starts, target.order, float(max_distance), float(huber),
        int(iterations), float(min_eigen_ratio), prior is not None,
        np.ascontiguousarray(prior_pose), np.ascontiguousarray(prior_info),
    )  # fmt: skip
    return Refinement(x, h, int(n_ok), float(rms))


@intrinsic
def _fma(typingctx, a, b, c):  # pragma: no cover (compiled)
    """``a * b + c`` rounded once (LLVM's ``llvm.fma``: one instruction where the CPU has
    it, else a correctly rounded library call)."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        d = ir.DoubleType()
        fn = builder.module.declare_intrinsic("llvm.fma", [d], ir.FunctionType(d, [d, d, d]))
        return builder.call(fn, args)

    return sig, codegen


@njit(cache=True, nogil=True)
def _dot_rows(a, x):  # pragma: no cover
    """``a @ x`` rounded as NumPy's ``@`` is for a C-ordered ``a``: OpenBLAS's transposed
    matrix-vector kernel (x86-64) forms each row's dot product as the second product, then
    fused multiply-adds of the first, the third, ..."""
    out = np.empty(a.shape[0])
    for i in range(a.shape[0]):
        if a.shape[1] == 1:
            out[i] = a[i, 0] * x[0]
            continue
        s = _fma(a[i, 0], x[0], a[i, 1] * x[1])
        for j in range(2, a.shape[1]):
            s = _fma(a[i, j], x[j], s)
        out[i] = s
    return out


@njit(cache=True, nogil=True)
def _dot_columns(a, x):  # pragma: no cover
    """``a @ x`` rounded as NumPy's ``@`` is for a Fortran-ordered ``a`` (what a boolean
    selection of columns gives): OpenBLAS's kernel adds column after column, each by a fused
    multiply-add."""
    out = np.empty(a.shape[0])
    for i in range(a.shape[0]):
        s = a[i, 0] * x[0]
        for j in range(1, a.shape[1]):
            s = _fma(a[i, j], x[j], s)
        out[i] = s
    return out


@njit(cache=True, nogil=True)
def _gauss_newton(
    q0,
    x,
    pts,
    nrm,
    lo,
    cell,
    nx,
    ny,
    starts,
    order,
    max_d,
    huber,
    iterations,
    min_eigen_ratio,
    use_prior,
    prior_pose,
    prior_info,
):  # pragma: no cover
    """The rounds of :func:`refine`, compiled: each pairs the points (:func:`_accumulate`)
    and takes a Gauss-Newton step, rounded as the NumPy code it replaces, bit for bit
    (LAPACK's solve and symmetric eigensolver; the products as :func:`_dot_rows` and
    :func:`_dot_columns`). Returns
    ``(pose, H, pairs, rms)``."""
    h, n_ok, rms = np.zeros((3, 3)), 0, 0.0
    for it in range(iterations):
        h, g, n_ok, ss = _accumulate(
            q0, x[0], x[1], x[2], pts, nrm, lo, cell, nx, ny, starts, order, max_d, huber
        )
        if n_ok < 10:
            return x, np.zeros((3, 3)), n_ok, 0.0
        rms = np.sqrt(ss / n_ok)
        if it == iterations - 1:
            break
        if use_prior:
            dp = x - prior_pose
            dp[2] = np.arctan2(np.sin(dp[2]), np.cos(dp[2]))
            delta = -np.linalg.solve(h + prior_info, g + _dot_rows(prior_info, dp))
        else:
            evals, evecs = np.linalg.eigh(h)
            keep = evals > min_eigen_ratio * max(evals[-1], 1e-12)
            v = evecs[:, keep]  # NumPy's is Fortran-ordered, its transpose C-ordered
            delta = -_dot_columns(v, _dot_rows(np.ascontiguousarray(v.T), g) / evals[keep])
        x = x + delta  # no early stop: runs that differ in the last bit stay that close
    return x, h, n_ok, rms
