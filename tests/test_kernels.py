"""Compiled kernels and the loop-target cache against the code they replace, bit for bit.

Each numba kernel of :mod:`fhslam.scanmatch` claims the same result as the NumPy / OpenCV
code before it (kept as ``_*_numpy`` references, or re-implemented here from the previous
commit); :meth:`fhslam.posegraph.PoseGraph.chi2` of a few edges claims the numbers of the
whole-graph computation; :class:`fhslam.slam.graph.LoopTargetCache` claims to change no pose.
Exact claims are checked exactly: same shape, dtype and bytes (NaN where NaN).
"""

from __future__ import annotations

import itertools

import cv2
import numpy as np
import pytest

from fhslam.geometry import transform_points
from fhslam.posegraph import PoseGraph, _chi2, edge_errors
from fhslam.scanmatch import (
    LikelihoodGrid,
    PointMap,
    densify,
    refine,
    scan_normals,
    smooth_scan,
    voxel_index,
)
from fhslam.scanmatch.clouds import (
    VOXEL_PHASE,
    _bounds,
    _densify_numpy,
    _first_per_cell,
    _scan_normals_numpy,
    _smooth_scan_numpy,
    _voxel_index_numpy,
)
from fhslam.scanmatch.grids import GRID_PAD
from fhslam.scanmatch.refinement import _accumulate, _dot_columns, _dot_rows, _fma
from fhslam.scanmatch.search import _crop, _in_box, _search, _search_padded
from fhslam.sim import load_world, simulate
from fhslam.slam.graph import LoopTargetCache
from fhslam.slam.graph import worker as worker_module


def assert_identical(a, b):
    """``a`` and ``b`` are the same array bit for bit: shape, dtype and bytes (NaN where
    NaN, and of the same sign for zeros)."""
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape, (a.shape, b.shape)
    assert a.dtype == b.dtype, (a.dtype, b.dtype)
    assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f")
    assert np.ascontiguousarray(a).tobytes() == np.ascontiguousarray(b).tobytes()


@pytest.fixture(scope="module")
def paper_scans():
    """Laser-frame points of the first 40 scans of the simulated paper world (as
    :meth:`fhslam.scan.Scan.points` gives them to the SLAM)."""
    log = simulate(load_world("paper"), seed=0, max_scans=40)
    return [log.scan(k).points()[0] for k in range(len(log))]


def _room(step=0.02):
    """A 6 x 4 m room with a 1 x 0.5 m box, points every ``step`` metres."""
    corners = [(0, 0), (6, 0), (6, 4), (0, 4), (0, 0)]
    box = [(2, 1), (3, 1), (3, 1.5), (2, 1.5), (2, 1)]
    segs = []
    for poly in (corners, box):
        for a, b in itertools.pairwise(poly):
            n = int(np.hypot(*np.subtract(b, a)) / step) + 1
            segs.append(np.linspace(a, b, n))
    return np.vstack(segs)


def _clouds(rng):
    """Point clouds for the kernels: random, with duplicates, on cell boundaries, tiny."""
    uniform = rng.uniform(-3, 5, (400, 2))
    dup = np.repeat(rng.uniform(0, 2, (50, 2)), rng.integers(1, 4, 50), axis=0)
    dup = dup[rng.permutation(len(dup))]
    # multiples of 0.05 and 0.1: exactly on (or one rounding off) the cell boundaries
    boundary = rng.integers(-40, 40, (300, 2)) * 0.05
    boundary[::7] = boundary[::7].round(1)
    return {
        "uniform": uniform,
        "duplicates": dup,
        "boundary": boundary,
        "negative": rng.normal(-7, 0.5, (200, 2)),
        "one": np.array([[0.37, -1.2]]),
        "two": np.array([[0.0, 0.0], [0.05, 0.1]]),
        "two equal": np.array([[0.3, 0.3], [0.3, 0.3]]),
        "room": _room(),
    }


# ------------------------------------------------------------------- 1. voxel_index


def _cells_box(p, size):
    """``nx · ny`` of the cells' bounding box, and the bound of :func:`_first_per_cell`'s
    one-pass branch."""
    k = np.floor(p / size).astype(np.int64)
    nx, ny = k.max(axis=0) - k.min(axis=0) + 1
    return float(nx) * float(ny), 256.0 * len(p) + 65536.0


@pytest.mark.parametrize("size", [0.05, 0.1, 0.3])
def test_voxel_index_in_a_small_box_equals_np_unique(size, paper_scans):
    """Claim 1, one-pass branch (cells' box <= 256 N + 65536): :func:`voxel_index` gives the
    indices of ``np.unique`` (:func:`_voxel_index_numpy`), for random clouds, duplicates,
    points on cell boundaries, 1 and 2 points, and real scans."""
    clouds = _clouds(np.random.default_rng(1))
    clouds.update({f"scan {k}": s for k, s in enumerate(paper_scans[::5])})
    for name, p in clouds.items():
        cells, bound = _cells_box(p, size)
        assert cells <= bound, name  # the branch this test is about
        assert_identical(voxel_index(p, size), _voxel_index_numpy(p, size))


def test_voxel_index_in_a_sparse_huge_box_equals_np_unique(paper_scans):
    """Claim 1, sorting branch (cells' box > 256 N + 65536): points spread over 1e5 m in
    5 cm cells, with repeated cells scattered through the cloud; a scan with one far point;
    and a box just past the branches' bound next to one just within it."""
    rng = np.random.default_rng(2)
    spread = rng.uniform(-5e4, 5e4, (300, 2))
    repeated = np.vstack([spread, spread[rng.integers(0, 300, 200)] + 0.001])
    repeated = repeated[rng.permutation(len(repeated))]
    outlier = np.vstack([paper_scans[3], [[4e4, -3e4]], paper_scans[4]])
    cases = [(spread, 0.05), (repeated, 0.05), (outlier, 0.05), (outlier, 0.01)]
    for p, size in cases:
        cells, bound = _cells_box(p, size)
        assert cells > bound
        assert _first_per_cell(p, size) is not None
        assert_identical(voxel_index(p, size), _voxel_index_numpy(p, size))
    assert len(voxel_index(repeated, 0.05)) < len(repeated) - 150  # runs of equal cells
    # 2 points: the bound is 66048 = 512 x 129 cells; 512 x 130 is past it
    for ny, within in [(129, True), (130, False)]:
        p = np.array([[0.5, 0.5], [511.5, ny - 0.5]])
        cells, bound = _cells_box(p, 1.0)
        assert (cells <= bound) == within
        assert_identical(voxel_index(p, 1.0), _voxel_index_numpy(p, 1.0))


def test_voxel_index_beyond_2_52_cells_falls_back_to_numpy():
    """Claim 1, fallback: cells past 2**52 make the kernel return ``None`` and
    :func:`voxel_index` takes the NumPy path (cells that still fit an int64)."""
    rng = np.random.default_rng(3)
    size = 1e-10  # x near 1e6 m: about 1e16 cells (> 2**52 ~ 4.5e15); y a few cells
    p = np.column_stack([1e6 + rng.integers(0, 5, 50) * 2.5e-10, rng.integers(0, 4, 50) * size])
    assert np.abs(np.floor(p / size)).max() >= 2.0**52
    assert _first_per_cell(p, size) is None
    got = voxel_index(p, size)
    assert_identical(got, _voxel_index_numpy(p, size))
    assert 1 < len(got) < len(p)  # the reference is not degenerate here


# ------------------------------------------------------------------- 2. scan_normals


@pytest.mark.parametrize("half_window", [0, 1, 2, 3, 4])
def test_scan_normals_equal_numpy_bit_for_bit(half_window, paper_scans):
    """Claim 2: :func:`scan_normals` (the compiled window sums for windows of up to 7
    points, h <= 3; the NumPy path for h = 4) equals :func:`_scan_normals_numpy` bit for
    bit, NaN where NaN: real scans, a room seen in beam order, random walks with jumps,
    points repeated twice, and scans shorter than, equal to and one longer than the window.
    (Windows of 2h + 1 *identical* points: see the next test.)"""
    rng = np.random.default_rng(4)
    w = 2 * half_window + 1
    walk = np.cumsum(rng.normal(0, 0.03, (300, 2)), axis=0) + np.array([2.0, 0.0])
    walk[::37] += 0.8  # jumps: windows that fail the gap test
    flat = np.column_stack([np.linspace(1, 3, 40), np.full(40, 1.5)])  # exactly collinear
    scans = [
        *paper_scans,
        walk,
        flat,
        np.repeat(walk[:60], 2, axis=0),  # each point twice
        walk[: w - 1] if w > 1 else walk[:0],
        walk[:w],
        walk[: w + 1],
        walk[:1],
        walk[:2],
    ]
    params = [(0.1, 0.03), (0.05, 0.0), (1.0, 0.1)]
    for k, p in enumerate(scans):
        max_gap, per_metre = params[k % len(params)]
        got = scan_normals(p, half_window, max_gap, per_metre)
        assert_identical(got, _scan_normals_numpy(p, half_window, max_gap, per_metre))
    if half_window > 0:  # not vacuous: real scans have normals and NaNs both
        n = scan_normals(paper_scans[0], half_window)
        assert np.isnan(n[:, 0]).any() and np.isfinite(n[:, 0]).sum() > 50


@pytest.mark.parametrize("half_window", [1, 2, 3, 4])
def test_smooth_scan_equals_numpy_bit_for_bit(half_window, paper_scans):
    """:func:`smooth_scan` (the window sums, turn tests and spreads compiled)
    equals :func:`_smooth_scan_numpy` bit for bit: real scans (the paper world's and a noisy
    walk along walls with corners), NaN normals, identical points, windows that fail every
    test, and scans shorter than, equal to and one longer than the window."""
    rng = np.random.default_rng(7)
    w = 2 * half_window + 1
    walk = np.cumsum(rng.normal(0, 0.03, (300, 2)), axis=0) + np.array([2.0, 0.0])
    walk[::37] += 0.8
    t = np.linspace(0.0, 1.0, 120)
    room = np.vstack(
        [np.column_stack([t, np.zeros_like(t)]), np.column_stack([np.ones_like(t), t])]
    )
    room += rng.normal(0, 0.01, room.shape)
    scans = [*paper_scans, walk, room, np.repeat(walk[:60], 2, axis=0), np.zeros((12, 2))]
    scans += [walk[: w - 1], walk[:w], walk[: w + 1]]
    smoothed = 0
    for p in scans:
        nrm = scan_normals(p, half_window) if len(p) else np.zeros((0, 2))
        for kw in ({}, {"max_turn_deg": 30.0, "max_spread": 1.0}, {"max_turn_deg": 0.0}):
            got = smooth_scan(p, nrm, half_window, **kw)
            assert_identical(got, _smooth_scan_numpy(p, nrm, half_window, **kw))
            smoothed += int((got != p).any())
    assert smoothed > len(paper_scans)  # not vacuous: most scans have points moved


@pytest.mark.parametrize(("half_window", "y"), [(1, 0.1), (2, 0.11), (3, 0.7)])
def test_scan_normals_of_identical_points_equal_numpy(half_window, y):
    """Claim 2 on degenerate windows: 2h + 1 identical consecutive points (a beam
    repeated), alone and as runs of 7 within a random walk, for each compiled window. Every
    x deviation is +0.0 and every y deviation -ε, so each product is -0.0: a sum started
    from the first term is -0.0, NumPy's (from +0.0) is +0.0, and atan2 turned the normal
    around ((1, 0) against (-1, 1.2e-16)) until the kernel's sums started from +0.0."""
    w = 2 * half_window + 1
    same = np.tile([1.0, y], (w, 1))
    assert same.reshape(1, w, 2).mean(axis=1)[0, 1] > y  # the y deviations are -ε
    steps = np.random.default_rng(4).normal(0, 0.03, (300, 2))
    walk = np.cumsum(steps, axis=0) + np.array([2.0, 0.0])
    for p in (same, np.repeat(walk[:30], 7, axis=0), np.vstack([walk[:10], same, walk[10:20]])):
        assert_identical(scan_normals(p, half_window), _scan_normals_numpy(p, half_window))


# ------------------------------------------------------------------- 3. densify


def test_densify_equals_numpy_bit_for_bit(paper_scans):
    """Claim 3: :func:`densify` equals :func:`_densify_numpy` bit for bit, points and
    normals: real scans (some gaps filled, wider ones left open), a gap exactly at the
    limit, a zero gap, other steps and limits, a scan where no gap is filled (both return
    the input), scans of 0, 1 and 2 points."""
    rng = np.random.default_rng(5)
    walk = np.cumsum(rng.normal(0, 0.06, (200, 2)), axis=0) + np.array([3.0, -1.0])
    at_limit = np.array([[0.0, 0.0], [0.1, 0.0], [0.1, 0.0], [0.3, 0.0]])  # gaps 0.1, 0, 0.2
    cases = [(s, scan_normals(s), {}) for s in paper_scans]
    cases += [
        (walk, rng.normal(size=(200, 2)), {}),
        (walk, rng.normal(size=(200, 2)), {"step": 0.007, "max_gap": 0.05}),
        (walk, rng.normal(size=(200, 2)), {"step": 0.1, "max_gap_per_metre": 0.0}),
        (at_limit, np.full((4, 2), np.nan), {}),
        (at_limit[:2], [[0.0, 1.0], [0.0, 1.0]], {"step": 0.03}),
    ]
    for p, nrm, kw in cases:
        got, want = densify(p, nrm, **kw), _densify_numpy(p, nrm, **kw)
        assert_identical(got[0], want[0])
        assert_identical(got[1], want[1])
    # real scans: some pairs filled, and some gaps over the limit left open
    p = paper_scans[0]
    dense, _ = densify(p, scan_normals(p))
    gaps = np.hypot(*np.diff(p, axis=0).T)
    assert len(dense) > len(p) and (gaps > 0.1 + 0.03 * np.hypot(*p[:-1].T)).any()
    # nothing to fill, fewer than 2 points: the input itself, as before
    sparse = np.array([[0.0, 0.0], [5.0, 0.0], [5.0, 5.0]])
    for q in (sparse, sparse[:1], sparse[:0]):
        n = np.ones_like(q)
        got, want = densify(q, n), _densify_numpy(q, n)
        assert got[0] is q and want[0] is q
        assert_identical(got[1], want[1])


# ------------------------------------------------------------------- 4. LikelihoodGrid


def _opencv_grid(points, resolution, sigma, margin):
    """The reference grid: OpenCV's exact distance transform, its float32 distances squared
    and rounded to integers, looked up in the ``exp`` table; cell corners at
    ``(k - VOXEL_PHASE) · resolution``."""
    p = np.asarray(points, dtype=float)
    lo = resolution * (np.floor((p.min(axis=0) - margin) / resolution + VOXEL_PHASE) - VOXEL_PHASE)
    shape = np.ceil((p.max(axis=0) + margin - lo) / resolution).astype(int) + 1
    img = np.full((shape[1], shape[0]), 255, np.uint8)
    c = np.floor((p - lo) / resolution).astype(int)
    img[c[:, 1], c[:, 0]] = 0
    d = cv2.distanceTransform(img, cv2.DIST_L2, cv2.DIST_MASK_PRECISE).astype(np.float64)
    c2 = 0.5 * (resolution / sigma) ** 2
    table = np.exp(-c2 * np.arange(int(np.ceil(104.0 / c2)) + 2)).astype(np.float32)
    table[-1] = 0.0
    d2 = np.minimum(np.rint(d * d), len(table) - 1).astype(np.intp)
    return table[d2], lo


def test_likelihood_grid_equals_opencv_construction(paper_scans):
    """Claim 4: :meth:`LikelihoodGrid.build` gives the OpenCV reference grid,
    values and origin exactly: several resolutions, sigmas (tables from 2 to 187 000
    entries) and margins (0 included), duplicates, cell boundaries, 1 and 2 points, a
    sparse 30 m cloud, real scans and merged real scans."""
    rng = np.random.default_rng(6)
    clouds = list(_clouds(rng).values())
    clouds += [rng.uniform(0, 30, (60, 2)), paper_scans[0], np.vstack(paper_scans[::4])]
    settings = [(0.05, 0.1, 0.5), (0.1, 0.15, 0.0), (0.02, 0.05, 0.3), (0.05, 0.03, 0.05)]
    settings += [(0.01, 0.3, 0.2), (0.2, 0.05, 1.0)]
    for k, p in enumerate(clouds):
        for res, sigma, margin in settings[k % 3 :: 3] if len(p) > 1000 else settings:
            grid = LikelihoodGrid.build(p, res, sigma, margin)
            values, origin = _opencv_grid(p, res, sigma, margin)
            assert_identical(grid.values, values)
            assert_identical(grid.origin, origin)
            assert grid.resolution == res
    # the single point with no margin: a grid of at most 2 x 2 cells, 1.0 at the point
    grid = LikelihoodGrid.build([[0.3, 0.4]], 0.05, 0.1, 0.0)
    assert max(grid.values.shape) <= 2 and grid.score([[0.3, 0.4]], [0.0, 0.0, 0.0]) == 1.0


def test_likelihood_grid_values_are_a_view_of_the_zero_padded_grid(paper_scans):
    """Claim 4: :attr:`LikelihoodGrid.padded` holds :attr:`values` with ``GRID_PAD`` cells
    of 0 on each side, :attr:`values` is a view of it, and a grid made from its values
    alone pads the same."""
    for p, res in [(paper_scans[2], 0.05), ([[1.0, 2.0]], 0.1), (_room(), 0.1)]:
        grid = LikelihoodGrid.build(p, res, 0.1, 0.3)
        h, w = grid.values.shape
        padded = grid.padded
        assert padded.dtype == np.float32 and padded.shape == (h + 2 * GRID_PAD, w + 2 * GRID_PAD)
        assert grid.values.base is padded and np.shares_memory(grid.values, padded)
        inner = np.zeros(padded.shape, bool)
        inner[GRID_PAD:-GRID_PAD, GRID_PAD:-GRID_PAD] = True
        assert_identical(padded[inner].reshape(h, w), grid.values)
        assert not padded[~inner].any()
        assert not np.signbit(padded[~inner]).any()  # +0.0: a sum plus it stays the sum
        fresh = LikelihoodGrid(np.array(grid.values), grid.origin, grid.resolution)
        assert_identical(fresh.padded, padded)


# ------------------------------------------------------------------- 5. _search_padded


@pytest.mark.parametrize("prior", [(0.0, 0.0), (0.05, 0.05), (0.5, 0.05), (3.0, 0.0)])
def test_padded_search_returns_exactly_the_plain_search(prior, paper_scans):
    """Claim 5: ``_search_padded(grid.padded, GRID_PAD, ...)`` returns ``_search(grid.values,
    ...)`` bit for bit (score, x, y, theta), for windows ``n_t`` of 0 to 7 shifts, 0 to 12
    angle steps, with and without the prior; query points on the grid, at its very edge
    (margin 0: the padding is added), far off it (the edge branch), all of them off it
    (every shift ties at 0) and none."""
    rng = np.random.default_rng(8)
    targets = [_room(), paper_scans[1], paper_scans[20]]
    for trial in range(24):
        n_t, n_a = trial % 8, [0, 1, 5, 12][trial % 4]
        res, sigma = [(0.05, 0.08), (0.1, 0.15), (0.02, 0.05)][trial % 3]
        target = targets[trial % 3]
        margin = [0.0, n_t * res, 3 * sigma][trial % 3]
        grid = LikelihoodGrid.build(target, res, sigma, margin)
        query = transform_points(rng.normal(0, [0.1, 0.1, 0.05]), target[::2])
        if trial % 4 == 1:
            query[::5] += rng.normal(0, 30.0, 2)  # a fifth far off the grid
        elif trial % 4 == 2:
            query = query + 500.0  # all off the grid: ties
        elif trial % 4 == 3 and trial > 12:
            query = query[:0]
        guess = rng.normal(0, [0.05, 0.05, 0.02])
        qx, qy = np.ascontiguousarray(query.T)
        args = (*grid.origin, res, qx, qy, *guess, n_t, n_a, np.radians(0.7), *prior)
        got = _search_padded(grid.padded, GRID_PAD, *args)
        want = _search(grid.values, *args)
        assert got == want, (trial, got, want)
        assert all(type(v) is type(u) for v, u in zip(got, want, strict=True))


# ------------------------------------------------------------------- 6. PointMap buckets


def _old_bucketed(p, normals, cell):
    """``PointMap._bucketed`` of the previous commit: its origin, cell, shape, starts and
    order."""
    lo = p.min(axis=0) if len(p) else np.zeros(2)
    extent = (p.max(axis=0) - lo) if len(p) else np.zeros(2)
    cell = max(cell, float(np.sqrt(np.prod(extent + cell) / 4e6)))
    ij = np.floor((p - lo) / cell).astype(np.int64)
    nx, ny = (ij.max(axis=0) + 1) if len(p) else (1, 1)
    c = ij[:, 0] * ny + ij[:, 1]
    order = np.argsort(c, kind="stable")
    starts = np.searchsorted(c[order], np.arange(nx * ny + 1)).astype(np.int64)
    return lo, float(cell), (int(nx), int(ny)), starts, order.astype(np.int64)


def test_point_map_buckets_equal_stable_argsort(paper_scans):
    """Claim 6: :meth:`PointMap.build`'s counting sort (``_bucket``) gives the previous
    commit's ``order`` (``np.argsort(ix · ny + iy, kind="stable")``) and ``starts``
    (``np.searchsorted`` of the sorted cells), and the same origin, cell and shape: given
    normals (NaN ones left out) and normals from neighbours, duplicates, cell boundaries,
    1 and 2 points, none left, real scans, and a 1e4 m cloud whose cell is enlarged."""
    rng = np.random.default_rng(9)
    cases = [(p, rng.normal(size=p.shape), 0.15) for p in _clouds(rng).values()]
    cases += [(p, scan_normals(p), 0.15) for p in paper_scans[::6]]
    merged = np.vstack(paper_scans[::3])
    cases += [(merged, scan_normals(merged), c) for c in (0.15, 0.05, 1.0)]
    cases += [(rng.uniform(-5e3, 5e3, (500, 2)), rng.normal(size=(500, 2)), 0.15)]
    cases += [(merged[:5], np.full((5, 2), np.nan), 0.15)]  # no normal: an empty map
    cases += [(merged, None, 0.15), (_room(), None, 0.1)]  # normals from 6 neighbours
    for p, normals, cell in cases:
        m = PointMap.build(p, normals, cell=cell)
        lo, cell2, shape, starts, order = _old_bucketed(m.points, m.normals, cell)
        if normals is not None:
            keep = np.isfinite(np.asarray(normals)[:, 0])
            assert_identical(m.points, p[keep])
        assert_identical(m.origin, lo)
        assert m.cell == cell2 and m.shape == shape
        assert_identical(m.starts, starts)
        assert_identical(m.order, order)
    assert PointMap.build(cases[-4][0], cases[-4][1]).cell > 0.15  # the enlarged cell


# ------------------------------------------------------------------- 7. _bounds, _crop


def test_bounds_equal_numpy_min_and_max(paper_scans):
    """Claim 7: ``_bounds(p)`` equals ``(p.min(axis=0), p.max(axis=0))`` bit for bit
    (random, sorted either way, duplicates, 1 and 2 points, real scans); with both 0.0 and
    -0.0 in a column the zeros compare equal, though their sign may differ from NumPy's
    (harmless: ``x - 0.0`` and ``x - -0.0`` floor to the same cell)."""
    rng = np.random.default_rng(10)
    clouds = list(_clouds(rng).values()) + list(paper_scans[::7])
    line = np.column_stack([np.arange(20.0), -np.arange(20.0)])
    clouds += [line, line[::-1], np.zeros((3, 2)), np.array([[-0.0, -0.0]])]
    for p in clouds:
        low, high = _bounds(np.ascontiguousarray(p))
        assert_identical(low, p.min(axis=0))
        assert_identical(high, p.max(axis=0))
    mixed = np.array([[0.0, 1.0], [-0.0, 2.0], [0.0, -0.0], [0.3, 0.0], [-0.0, 0.5]])
    for p in (mixed, mixed[::-1].copy()):
        low, high = _bounds(p)
        assert np.array_equal(low, p.min(axis=0)) and np.array_equal(high, p.max(axis=0))
        # downstream, with no margin to absorb the sign: the same grid and buckets
        grid = LikelihoodGrid.build(p, 0.05, 0.1, 0.0)
        values, origin = _opencv_grid(p, 0.05, 0.1, 0.0)
        assert_identical(grid.values, values)
        assert np.array_equal(grid.origin, origin)
        m = PointMap.build(p, np.ones_like(p))
        _, _, shape, starts, order = _old_bucketed(p, None, 0.15)
        assert m.shape == shape
        assert_identical(m.starts, starts)
        assert_identical(m.order, order)


def _old_crop(target, query, pose, margin):
    """``_crop`` of the previous commit: a boolean mask over the target's columns."""
    q = transform_points(pose, query)
    lo, hi = q.min(axis=0) - margin, q.max(axis=0) + margin
    x, y = target[:, 0], target[:, 1]
    return target[(x >= lo[0]) & (x <= hi[0]) & (y >= lo[1]) & (y <= hi[1])]


def test_crop_equals_the_boolean_mask(paper_scans):
    """Claim 7: ``_crop`` (``_bounds`` and ``_in_box``) keeps exactly the target points,
    in order, that the previous commit's boolean mask kept: real scans, points exactly on
    the box's edges and one rounding step outside, an empty result, a one-point query."""
    rng = np.random.default_rng(11)
    target = np.vstack(paper_scans[::4])
    for k in range(12):
        query = paper_scans[(5 * k + 1) % len(paper_scans)][:: 1 + k % 3]
        pose = rng.normal(0, [1.0, 1.0, 0.5])
        margin = [0.0, 0.3, 2.0][k % 3]
        assert_identical(_crop(target, query, pose, margin), _old_crop(target, query, pose, margin))
    # points on the box's edges, and just outside them
    query, pose, margin = paper_scans[0][::10], np.array([0.3, -0.2, 0.4]), 0.25
    q = transform_points(pose, query)
    lo, hi = q.min(axis=0) - margin, q.max(axis=0) + margin
    edges = np.array(
        [[lo[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]], [hi[0], 0.5 * (lo[1] + hi[1])]]
    )
    outside = np.array([np.nextafter(lo, -np.inf), np.nextafter(hi, np.inf)])
    cases = [np.vstack([edges, outside, edges[::-1]])[rng.permutation(10)], outside, target[:1]]
    cases.append(np.vstack([target, edges]))
    for t in cases:
        assert_identical(_crop(t, query, pose, margin), _old_crop(t, query, pose, margin))
    assert len(_crop(cases[0], query, pose, margin)) == 8
    assert _crop(outside, query, pose, margin).shape == (0, 2)
    one = query[:1]
    assert_identical(_crop(target, one, pose, 1.0), _old_crop(target, one, pose, 1.0))
    box = _in_box(target, *lo, *hi)
    inside = (target >= lo).all(axis=1) & (target <= hi).all(axis=1)
    assert_identical(box, target[inside])


# ------------------------------------------------------------------- 8. PoseGraph.chi2


def _old_chi2(graph, info, edges):
    """``PoseGraph.chi2`` of the previous commit: index arrays of the whole graph."""
    k = np.asarray(edges, dtype=np.intp).reshape(-1)
    i_all, j_all, z_all, _ = graph.edges
    return _chi2(edge_errors(graph.poses, i_all[k], j_all[k], z_all[k]), np.array(info)[k])


def test_pose_graph_chi2_of_some_edges_equals_the_whole_graph_computation():
    """Claim 8: :meth:`PoseGraph.chi2` of a subset of edges (one, several in any order,
    repeated, all, none; as arrays or lists) equals the previous commit's computation over
    the whole graph's arrays bit for bit, before and after :meth:`PoseGraph.optimize`, with
    diagonal and full information and angles that wrap."""
    rng = np.random.default_rng(12)
    g, info = PoseGraph(), []
    truth = np.column_stack([np.cumsum(rng.uniform(0.5, 1, 12)), rng.normal(0, 1, 12)])
    truth = np.column_stack([truth, rng.uniform(-np.pi, np.pi, 12)])
    for x in truth:
        g.add_node(x + rng.normal(0, [0.1, 0.1, 0.05]))

    def add(i, j, z, om):
        g.add_edge(i, j, z, om)
        om = np.asarray(om, dtype=float)
        info.append(om[:, None] * np.eye(3) if om.ndim == 1 else om)

    for i in range(11):
        add(i, i + 1, rng.normal(0, [1, 1, 3]), rng.uniform(10, 1000, 3))
    for _ in range(8):
        i, j = rng.choice(12, 2, replace=False)
        a = rng.normal(size=(3, 3))
        add(int(i), int(j), rng.normal(0, [1, 1, 3]), a @ a.T + np.eye(3))
    subsets = [[3], [0, 1, 2], [18, 4, 11, 0], [5, 5, 2, 5], np.arange(19), np.array([17, 12])]
    subsets += [np.arange(19)[::-1], np.array([], dtype=int)]
    for _ in range(2):
        for edges in subsets:
            assert_identical(g.chi2(edges), _old_chi2(g, info, edges))
        g.optimize(3)
    assert g.chi2([0, 11]).min() > 0  # not trivially zero


# ------------------------------------------------------------------- 9. LoopTargetCache


class _Builds:
    """``build`` callbacks for :meth:`LoopTargetCache.get` that count their calls."""

    def __init__(self, seed=13):
        self.calls = 0
        self.rng = np.random.default_rng(seed)

    def __call__(self, n=100):
        def build():
            self.calls += 1
            p = self.rng.uniform(0, 5, (n, 2))
            return p, self.rng.normal(size=(n, 2))

        return build


def _consistent(cache):
    """The cache's byte count is that of its targets, within its bound."""
    assert cache.nbytes == sum(t.nbytes for t in cache._targets.values())
    assert cache.nbytes <= cache.max_bytes


def test_loop_target_cache_hits_misses_and_drops_moved_targets():
    """Claim 9: a second ``get`` with the same poses and members is a hit returning the
    same object without building; other members, or one member's pose changed in its last
    bit (or 0.0 to -0.0), miss; a pose outside the members changes nothing;
    ``drop_moved`` forgets exactly the targets whose members' poses changed."""
    poses = np.random.default_rng(14).normal(size=(12, 3))
    cache, build = LoopTargetCache(), _Builds()
    a = cache.get(poses, range(0, 4), build())
    assert (cache.hits, cache.misses, build.calls, len(cache)) == (0, 1, 1, 1)
    assert cache.get(poses.copy(), range(0, 4), build()) is a
    assert (cache.hits, cache.misses, build.calls) == (1, 1, 1)
    b = cache.get(poses, range(2, 6), build())
    c = cache.get(poses, range(7, 9), build())
    assert len({id(a), id(b), id(c)}) == 3 and build.calls == 3
    moved = poses.copy()
    moved[3, 2] = np.nextafter(moved[3, 2], np.inf)  # in a's and b's members
    assert cache.get(moved, range(0, 4), build()) is not a
    assert build.calls == 4 and cache.misses == 4
    assert cache.get(moved, range(7, 9), build()) is c  # c's poses did not change
    outside = poses.copy()
    outside[11] += 1.0
    assert cache.get(outside, range(2, 6), build()) is b
    zero = poses.copy()
    zero[8, 0] = 0.0
    cache.get(zero, range(7, 9), build())
    zero[8, 0] = -0.0
    cache.get(zero, range(7, 9), build())
    assert build.calls == 6
    _consistent(cache)
    # drop_moved: exactly the targets whose members' poses are not their key's
    cache = LoopTargetCache()
    for members in (range(0, 4), range(2, 6), range(7, 9), range(9, 12)):
        cache.get(poses, members, build())
    cache.drop_moved(poses)
    assert len(cache) == 4
    cache.drop_moved(outside)  # pose 11 moved: range(9, 12) only
    assert [k[:2] for k in cache._targets] == [(0, 4), (2, 6), (7, 9)]
    cache.drop_moved(moved)  # pose 3 moved: (0, 4) and (2, 6)
    assert [k[:2] for k in cache._targets] == [(7, 9)]
    _consistent(cache)
    cache.drop_moved(poses + 1.0)
    assert len(cache) == 0 and cache.nbytes == 0


def test_loop_target_cache_evicts_least_recently_used_and_builds_point_maps_once(monkeypatch):
    """Claim 9: beyond ``max_bytes`` the least recently used targets go first (a hit counts
    as a use) and ``nbytes`` stays within the bound and equal to the targets' bytes; the
    point map of a target is built once (and counted); ``max_bytes=0`` keeps nothing."""
    built = []

    class CountingPointMap:
        @staticmethod
        def build(points, normals):
            built.append(1)
            return PointMap.build(points, normals)

    monkeypatch.setattr(worker_module, "PointMap", CountingPointMap)
    poses = np.random.default_rng(15).normal(size=(20, 3))
    build = _Builds()
    one = 100 * 2 * 8 * 2  # points and normals of a 100-point target
    cache = LoopTargetCache(max_bytes=3 * one + 10)
    ranges = [range(k, k + 2) for k in range(0, 20, 2)]
    for r in ranges[:3]:
        cache.get(poses, r, build())
    assert cache.nbytes == 3 * one and len(cache) == 3
    cache.get(poses, ranges[0], build())  # a hit: ranges[0] is now the most recent
    cache.get(poses, ranges[3], build())  # evicts ranges[1], the least recently used
    assert [k[:2] for k in cache._targets] == [(4, 6), (0, 2), (6, 8)]
    _consistent(cache)
    recent = [(4, 6), (0, 2), (6, 8)]
    for r in ranges[4:]:
        cache.get(poses, r, build())
        recent.append((r.start, r.stop))
        assert [k[:2] for k in cache._targets] == recent[-3:]
        _consistent(cache)
    # the point map: built once, its bytes counted, the oldest targets evicted for it
    cache = LoopTargetCache(max_bytes=5 * one)
    for r in ranges[:4]:
        cache.get(poses, r, build())
    target = cache.get(poses, ranges[3], build())
    assert cache.nbytes == 4 * one
    m = cache.point_map(target)
    assert cache.point_map(target) is m and target.point_map is m and len(built) == 1
    assert target.nbytes == one + sum(a.nbytes for a in (m.points, m.normals, m.starts, m.order))
    _consistent(cache)
    survivors = [k[:2] for k in cache._targets]
    assert survivors[-1] == (6, 8) and len(survivors) < 4
    assert survivors == [(r.start, r.stop) for r in ranges[:4]][-len(survivors) :]
    # nothing kept: every get builds, the point map of an evicted target is still built once
    empty = LoopTargetCache(max_bytes=0)
    calls = build.calls
    t1 = empty.get(poses, ranges[0], build())
    t2 = empty.get(poses, ranges[0], build())
    assert t1 is not t2 and build.calls == calls + 2 and empty.hits == 0
    assert len(empty) == 0 and empty.nbytes == 0
    assert empty.point_map(t1) is empty.point_map(t1) and len(built) == 2
    assert empty.nbytes == 0


# ------------------------------------------------------------------- 10. the whole method


class _CheckingCache(LoopTargetCache):
    """A :class:`LoopTargetCache` that rebuilds every target it hits and checks that the
    cached one is the same bit for bit."""

    checked = 0

    def get(self, poses, members, build):
        hits = self.hits
        target = super().get(poses, members, build)
        if self.hits > hits:
            points, normals = build()
            assert_identical(target.points, points)
            assert_identical(target.normals, normals)
            self.checked += 1
        return target


def test_graph_slam_gives_the_same_poses_with_and_without_the_loop_target_cache():
    """Claim 9/10: :class:`GraphFastHoughSLAM` over the whole simulated paper world (916
    scans: the first 300 close no loop and hit the cache once) gives the same poses, bit
    for bit, and the same loop closures with the cache as with one that holds nothing; and
    each target the cache serves is the one building it again gives."""
    from fhslam.pipeline import make_backend, run_backend

    log = simulate(load_world("paper"), seed=0)
    runs = {}
    for name, cache in [
        ("cached", None),
        ("empty", LoopTargetCache(max_bytes=0)),
        ("checked", _CheckingCache()),
    ]:
        slam = make_backend("graph")
        if cache is not None:
            slam.loop_targets = cache
        runs[name] = (slam, run_backend(slam, log))
    cached, empty = runs["cached"][0], runs["empty"][0]
    assert cached.loop_targets.hits >= 10 and len(cached.loops) >= 10  # measured 39, 46
    assert empty.loop_targets.hits == 0 and empty.loop_targets.misses > 0
    assert runs["checked"][0].loop_targets.checked == cached.loop_targets.hits
    want = runs["empty"][1].poses
    for name in ("cached", "checked"):
        slam, result = runs[name]
        assert_identical(result.poses, want)
        assert_identical(slam.graph.poses, empty.graph.poses)
        assert [(lc.old, lc.new, lc.score, lc.edge) for lc in slam.loops] == [
            (lc.old, lc.new, lc.score, lc.edge) for lc in empty.loops
        ]
        for a, b in zip(slam.loops, empty.loops, strict=True):
            assert_identical(a.pose, b.pose)


# ------------------------------------------------------------- the refinement's rounds


@pytest.fixture(scope="module")
def fma():
    from numba import njit

    return njit(lambda a, b, c: _fma(a, b, c))


def test_fma_rounds_once(fma):
    from fractions import Fraction

    rng = np.random.default_rng(5)
    for a, b, c in rng.standard_normal((2000, 3)) * rng.choice([1e-8, 1, 1e8], (2000, 3)):
        exact = Fraction(float(a)) * Fraction(float(b)) + Fraction(float(c))
        assert fma(a, b, c) == float(exact)  # correctly rounded: what one rounding gives
    # where a * b + c with two roundings loses everything: (1 + 2⁻³⁰)² - (1 + 2⁻²⁹)
    e = 2.0**-30
    assert (1 + e) * (1 + e) - (1 + 2 * e) == 0.0 and fma(1 + e, 1 + e, -(1 + 2 * e)) == e * e


def _numpy_rounds(
    target, query, guess, prior=None, iterations=10, max_d=0.1, huber=0.02, soft=0.01
):
    """:func:`refine`'s rounds as they were written in NumPy (the reference)."""
    q0 = np.ascontiguousarray(query)
    x = np.asarray(guess, dtype=float).copy()
    nx, ny = target.shape
    h = np.zeros((3, 3))
    for it in range(iterations):
        h, g, n_ok, _ = _accumulate(
            q0, x[0], x[1], x[2], target.points, target.normals, target.origin, target.cell,
            nx, ny, target.starts, target.order, max_d, huber, soft,
            np.empty(len(target.points), np.int64), np.empty(len(target.points)),
        )  # fmt: skip
        if n_ok < 10:
            return x, np.zeros((3, 3))
        if it == iterations - 1:
            break
        if prior is not None:
            dp = x - prior[0]
            dp[2] = np.arctan2(np.sin(dp[2]), np.cos(dp[2]))
            delta = -np.linalg.solve(h + prior[1], g + prior[1] @ dp)
        else:
            evals, evecs = np.linalg.eigh(h)
            keep = evals > 1e-3 * max(evals[-1], 1e-12)
            delta = -(evecs[:, keep] @ ((evecs[:, keep].T @ g) / evals[keep]))
        x = x + delta
    return x, h


@pytest.mark.parametrize("prior", [False, True])
def test_compiled_rounds_equal_the_numpy_rounds(paper_scans, prior):
    """Bit for bit where NumPy's BLAS rounds its small products with fused multiply-adds as
    :func:`_dot_rows` and :func:`_dot_columns` do (OpenBLAS on x86-64 with FMA: every
    refinement of the five shared logs identical); elsewhere to 1e-12 m."""
    rng = np.random.default_rng(3)
    # a full prior (not only diagonal), so that its product is rounded as NumPy's too
    info = np.array([[4.0, 0.3, 0.1], [0.3, 2.0, -0.2], [0.1, -0.2, 9.0]])
    identical = 0
    for k in range(1, len(paper_scans)):
        target, query = paper_scans[k - 1], paper_scans[k]
        pm = PointMap.build(target, scan_normals(target))
        guess = rng.normal(0, [0.05, 0.05, 0.02])
        p = (rng.normal(0, 0.05, 3), info) if prior else None
        want, want_h = _numpy_rounds(pm, query, guess, p)
        got = refine(pm, query, guess, prior=p)
        np.testing.assert_allclose(got.pose, want, rtol=0, atol=1e-12)
        np.testing.assert_allclose(got.hessian, want_h, rtol=1e-12, atol=1e-9)
        identical += np.array_equal(got.pose, want) and np.array_equal(got.hessian, want_h)
    print(f"{identical} of {len(paper_scans) - 1} refinements identical bit for bit")


def test_dot_products_are_numpys_products_to_the_last_bit_or_two():
    """Two roundings of a three-term dot product differ by at most 2·3u·Σ|aᵢxᵢ|."""

    def close(got, want, a, x):
        assert np.all(np.abs(got - want) <= 1e-15 * (np.abs(a) @ np.abs(x)))

    rng = np.random.default_rng(4)
    for _ in range(200):
        for k in (1, 2, 3):
            a = rng.standard_normal((3, k))
            x, y = rng.standard_normal(k), rng.standard_normal(3)
            close(_dot_rows(a, x), a @ x, a, x)
            f = np.asfortranarray(a)
            close(_dot_columns(f, x), f @ x, a, x)
            close(_dot_rows(np.ascontiguousarray(a.T), y), a.T @ y, a.T, y)


def test_transform_points_equals_the_numpy_expression_bit_for_bit(paper_scans):
    from fhslam.geometry import transform_points

    rng = np.random.default_rng(6)
    clouds = [*paper_scans[:10], np.zeros((0, 2)), rng.normal(0, 1e6, (50, 2))]
    clouds.append(rng.normal(0, 1, (40, 3))[:, :2])  # a strided view
    for p in clouds:
        x, y, th = rng.normal(0, [5, 5, 2])
        c, s = np.cos(th), np.sin(th)
        want = np.column_stack([x + c * p[:, 0] - s * p[:, 1], y + s * p[:, 0] + c * p[:, 1]])
        assert_identical(transform_points([x, y, th], p), want)
