"""Correlative scan matching (Olson 2009): the pose of a query cloud in a target's frame.

A candidate pose scores the mean likelihood (:class:`fhslam.scanmatch.grids.LikelihoodGrid`)
of the query points it places in the grid. :func:`correlative_search` finds the best pose
over a window of shifts and angles, exhaustively (:func:`_search_padded`) or by branch and
bound over the grid's max-pooled pyramid (:func:`_search_bnb`): the same optimum, bit for
bit. :func:`match_clouds` runs it twice, coarse over the whole window, then fine around the
coarse optimum.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam._numba import njit
from fhslam.geometry import as_points, as_pose, transform_points
from fhslam.scanmatch.clouds import _bounds, voxel_downsample
from fhslam.scanmatch.grids import BNB_LEVELS, GRID_PAD, LikelihoodGrid

__all__ = ["BNB_MIN_SHIFTS", "MatchResult", "correlative_search", "match_clouds"]

BNB_MIN_SHIFTS = 8
"""Windows of fewer than this many shifts either side are searched exhaustively."""


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
def _angle_cells(ox, oy, res, px, py, x0, y0, th0, n_a, da):  # pragma: no cover
    """The grid cells ``(ixs, iys)``, each ``(2 n_a + 1, N)``, of the points ``(px, py)``
    placed at ``(x0, y0)`` with each heading ``th0 + (a - n_a) da`` of the search (row
    ``a``), before any shift (grid from ``(ox, oy)``, cells of ``res``)."""
    n = px.shape[0]
    na = 2 * n_a + 1
    ixs = np.empty((na, n), np.int64)
    iys = np.empty((na, n), np.int64)
    for a in range(na):
        th = th0 + (a - n_a) * da
        c, s = np.cos(th), np.sin(th)
        for k in range(n):
            ixs[a, k] = int(np.floor((c * px[k] - s * py[k] + x0 - ox) / res))
            iys[a, k] = int(np.floor((s * px[k] + c * py[k] + y0 - oy) / res))
    return ixs, iys


@njit(cache=True, nogil=True)
def _coarsest_blocks(pyr, ixs, iys, n_t, n_a, nn, res, da, w_t, w_r):  # pragma: no cover
    """For :func:`_search_bnb`, its coarsest blocks (``2**BNB_LEVELS`` shifts square, at
    every heading) in the order heading, x shift, y shift: their bounds
    (:func:`_block_score`), heading rows and first shifts ``(bounds, a, sx, sy)``."""
    pad = 1 << BNB_LEVELS
    top = BNB_LEVELS
    na = 2 * n_a + 1
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
    return cb, ca, cx, cy


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
    ixs, iys = _angle_cells(ox, oy, res, px, py, x0, y0, th0, n_a, da)
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
    cb, ca, cx, cy = _coarsest_blocks(pyr, ixs, iys, n_t, n_a, nn, res, da, w_t, w_r)
    order = np.argsort(cb)
    for t in range(cb.shape[0]):
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
    """The fine score of the best place more than ``exclude[0]`` metres from the coarse
    optimum (found on the coarse grid above ``exclude[1]`` times its score) if it is more
    than ``exclude[1]`` times the match's fine score, else 0 (0 unless :func:`match_clouds`
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
        metres (in x or y) from the coarse optimum, above ``fraction`` of the coarse score,
        and score it on the fine grid (:attr:`MatchResult.runner_up`): a match is unique
        only if nothing elsewhere scores nearly as well (a corridor with doors every few
        metres); the coarse grid's blur alone would hide what tells two places apart.
        Branch and bound looks only where that is possible, so an answer of "none" is
        cheap.
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

    qf = _thin(voxel_downsample(q, 1.5 * rf), max_points[1])
    fw = 6 * rf

    def fine_stage(centre) -> tuple[float, NDArray[np.float64]]:
        near = _crop(tg, q, centre, fw + 3 * sf)
        if len(near) < 10:
            return 0.0, centre
        grid = LikelihoodGrid.build(near, rf, sf, fw + 3 * sf)
        return correlative_search(
            grid, qf, centre, fw, np.radians(ac if window > 0 else window_deg), np.radians(af),
            prior,
        )  # fmt: skip

    def runner_up(score: float) -> float:
        """The runner-up's score, looked for once the match is worth it: found on the coarse
        grid, scored on the fine one (the coarse grid's blur hides what tells two places
        apart: a hall's pillars)."""
        if rival is None or not score >= exclude_min_score:
            return 0.0
        grid_c, points, guess_c, search_c = rival
        s_r, at = correlative_search(
            grid_c, points, guess_c, *search_c, exclude=(best, exclude[0]), floor=exclude[1] * s_c
        )
        if s_r <= 0:
            return 0.0
        s_rf = fine_stage(at)[0]
        return s_rf if s_rf > exclude[1] * score else 0.0

    s_f, pose = fine_stage(g)
    if s_f == 0.0:
        return MatchResult(g, 0.0, s_c, s_g, runner_up(0.0))
    return MatchResult(pose, s_f, s_c, s_g, runner_up(s_f))
