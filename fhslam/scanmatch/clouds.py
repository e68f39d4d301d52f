"""Point clouds of scans for the scan matcher: thinned, smoothed, filled in, with normals.

A scan's points (laser frame, metres, in beam order) become a matcher's cloud here:
:func:`voxel_downsample` / :func:`voxel_index` keep the first point of each square cell;
:func:`scan_normals` gives each point the unit normal of its beam neighbours' line (NaN at
edges, jumps and clutter); :func:`smooth_scan` moves the points of straight surfaces onto
their windows' lines; :func:`densify` fills in points between beams on one surface. Each is
a compiled kernel that returns the numbers of its NumPy reference (``_*_numpy``, kept for
the tests) bit for bit.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam._numba import njit
from fhslam.geometry import as_points, tls_normal_angle

__all__ = [
    "VOXEL_PHASE",
    "densify",
    "scan_normals",
    "smooth_scan",
    "voxel_downsample",
    "voxel_index",
]


VOXEL_PHASE = (3 - 5**0.5) / 2
"""The cells' corners lie this fraction of a cell (0.382) off the frame's axes and round
coordinates: a point on an axis (a laser's beam straight ahead, ``y = 0`` in its frame) or at
a quantised range (whole centimetres or millimetres) sits a tenth of a millimetre or more
inside a cell of 1-10 cm, not on a border where the last bit of its pose picks the cell."""


def voxel_downsample(points: ArrayLike, size: float) -> NDArray[np.float64]:
    """Keep the first point of each ``size`` × ``size`` cell (order preserved; the cells'
    corners at ``(k - VOXEL_PHASE) · size``)."""
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    return p[voxel_index(p, size)]


def voxel_index(points: ArrayLike, size: float) -> NDArray[np.intp]:
    """Indices of the first point of each ``size`` × ``size`` cell (corners at
    ``(k - VOXEL_PHASE) · size``), increasing.

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
    k = np.floor(p / size + VOXEL_PHASE).astype(np.int64)
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
        fx = np.floor(p[i, 0] / size + VOXEL_PHASE)
        fy = np.floor(p[i, 1] / size + VOXEL_PHASE)
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


def densify(
    points: ArrayLike,
    normals: ArrayLike,
    step: float = 0.02,
    max_gap: float = 0.1,
    max_gap_per_metre: float = 0.03,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A scan (laser frame, beam order) with points filled in every ``step`` metres between
    consecutive beams that lie on one surface (closer than ``max_gap + max_gap_per_metre ×
    range``, as in :func:`scan_normals`); a filled point's normal is its pair's.

    A wall 15 m away is seen by beams 26 cm apart (1° resolution): as points it is a dotted
    line that a likelihood grid scores low wherever a query point falls between the dots;
    filled in, it scores as the wall it is.

    Compiled (:func:`_densify`), with NumPy's operations in its order: the same points and
    normals, bit for bit.
    """
    p = as_points(points, "points")
    nrm = np.asarray(normals, dtype=float).reshape(-1, 2)
    if len(nrm) != len(p):
        raise ValueError(f"{len(nrm)} normals for {len(p)} points")
    if len(p) < 2:
        return p, nrm
    dense, dense_normals, _, _ = _densify(
        p, nrm, float(step), float(max_gap), float(max_gap_per_metre)
    )
    if len(dense) == len(p):
        return p, nrm
    return dense, dense_normals


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


def _densify_numpy(points, normals, step=0.02, max_gap=0.1, max_gap_per_metre=0.03):
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
    return np.vstack([p, fill]), np.vstack([nrm, fill_normals])
