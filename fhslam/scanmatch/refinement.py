"""Point-to-line refinement: the pose of a query cloud against a
:class:`fhslam.scanmatch.grids.PointMap`, by Gauss-Newton rounds of soft nearest-neighbour
pairs (compiled; the steps rounded as NumPy's and LAPACK's, bit for bit).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from llvmlite import ir
from numpy.typing import ArrayLike, NDArray

from fhslam._numba import intrinsic, njit, types
from fhslam.geometry import as_points, as_pose
from fhslam.scanmatch.grids import PointMap

__all__ = ["Refinement", "refine"]


@njit(cache=True, nogil=True, inline="always")
def _gap(u, i, a, cell):  # pragma: no cover
    """Distance along one axis from a point ``a`` metres into cell ``i`` to cell ``u``."""
    if u == i:
        return 0.0
    return (u - i) * cell - a if u > i else a + (i - u - 1) * cell


@njit(cache=True, nogil=True)
def _candidates(
    qx, qy, pts, lo, cell, nx, ny, starts, order, max_d, soft, cand_j, cand_d
):  # pragma: no cover
    """The map points that may pair with ``(qx, qy)``: those within ``soft`` of the nearest
    distance so far (into ``cand_j``, ``cand_d``: distances). Returns their number and the nearest
    squared distance (``max_d²`` if no point is nearer). Cells in rings around the point's
    own; a cell (or a ring) whose nearest edge is farther than that bound cannot hold a
    candidate (the margin covers rounding in the cell index)."""
    ix, iy = int(np.floor((qx - lo[0]) / cell)), int(np.floor((qy - lo[1]) / cell))
    ax, ay = qx - lo[0] - ix * cell, qy - lo[1] - iy * cell
    best, bound2, m = max_d * max_d, max_d * max_d, 0
    for r in range(int(np.ceil(max_d / cell)) + 1):
        if r >= 2 and ((r - 1) * cell) ** 2 > bound2 * (1 + 1e-9) + 1e-18:
            break
        for u in range(max(ix - r, 0), min(ix + r + 1, nx)):
            gx = _gap(u, ix, ax, cell)
            step = 1 if abs(u - ix) == r else 2 * r
            for v in range(iy - r, iy + r + 1, max(step, 1)):
                if v < 0 or v >= ny:
                    continue
                gy = _gap(v, iy, ay, cell)
                if gx * gx + gy * gy > bound2 * (1 + 1e-9) + 1e-18:
                    continue
                cc = u * ny + v
                for t in range(starts[cc], starts[cc + 1]):
                    j = order[t]
                    dx, dy = qx - pts[j, 0], qy - pts[j, 1]
                    d2 = dx * dx + dy * dy
                    if d2 >= bound2:
                        continue
                    d = np.sqrt(d2)
                    cand_j[m], cand_d[m] = j, d
                    m += 1
                    if d2 < best:
                        best = d2
                        bound2 = min((d + soft) ** 2, max_d * max_d)
    return m, best


@njit(cache=True, nogil=True)
def _soft_pairs(
    qx, qy, x, y, m, best, cand_j, cand_d, pts, nrm, max_d, huber, soft, out
):  # pragma: no cover
    """Add the pairs of ``(qx, qy)`` with its ``m`` candidates (at distances ``cand_d``) less
    than ``soft`` farther than the nearest (``best``: squared distance), each weighted by
    its kernel over the kernels' sum, its Huber weight and taper, to ``out`` (the upper
    triangle of ``H``, then ``g``, then the squared residual: ten sums)."""
    dmin = np.sqrt(best)
    bound = min(dmin + soft, max_d)
    ksum = h00 = h01 = h02 = h11 = h12 = h22 = g0 = g1 = g2 = rr = 0.0
    for t in range(m):
        e = (cand_d[t] - dmin) / soft
        if cand_d[t] >= bound or e >= 1.0:
            continue
        j = cand_j[t]
        k = (1.0 - e * e) ** 2
        nx_, ny_ = nrm[j, 0], nrm[j, 1]
        r = nx_ * (qx - pts[j, 0]) + ny_ * (qy - pts[j, 1])
        j2 = ny_ * (qx - x) - nx_ * (qy - y)
        # Huber on the residual, tapered to 0 at max_d: a pair forming or breaking at the
        # cut-off changes nothing abruptly
        w = k * min(1.0, huber / max(abs(r), 1e-12)) * (1.0 - (cand_d[t] / max_d) ** 2) ** 2
        h00 += w * nx_ * nx_
        h01 += w * nx_ * ny_
        h02 += w * nx_ * j2
        h11 += w * ny_ * ny_
        h12 += w * ny_ * j2
        h22 += w * j2 * j2
        g0 += w * nx_ * r
        g1 += w * ny_ * r
        g2 += w * j2 * r
        rr += k * r * r
        ksum += k
    for i, v in enumerate((h00, h01, h02, h11, h12, h22, g0, g1, g2, rr)):
        out[i] += v / ksum


@njit(cache=True, nogil=True)
def _accumulate(
    q0, x, y, th, pts, nrm, lo, cell, nx, ny, starts, order, max_d, huber, soft, cand_j, cand_d
):  # pragma: no cover
    """One Gauss-Newton round of :func:`refine`: each query point at the pose ``(x, y, th)``
    whose nearest map point lies closer than ``max_d`` is paired with every map point less
    than ``soft`` farther than that one, weighted by ``(1 - (extra / soft)²)²`` (the
    weights of a point sum to one: a point halfway between two map points of different
    normals moves from one to the other continuously, never by a flip); returns the
    weighted normal equations ``(H, g)``, the number of query points paired and the sum of
    their (weighted) squared residuals. ``cand_j`` and ``cand_d`` (one entry per map point)
    are scratch space for :func:`_candidates`."""
    out = np.zeros(10)
    c, s = np.cos(th), np.sin(th)
    n_ok = 0
    for k in range(q0.shape[0]):
        qx = c * q0[k, 0] - s * q0[k, 1] + x
        qy = s * q0[k, 0] + c * q0[k, 1] + y
        m, best = _candidates(
            qx, qy, pts, lo, cell, nx, ny, starts, order, max_d, soft, cand_j, cand_d
        )
        if best < max_d * max_d:
            _soft_pairs(qx, qy, x, y, m, best, cand_j, cand_d, pts, nrm, max_d, huber, soft, out)
            n_ok += 1
    h = np.empty((3, 3))
    h[0, 0], h[0, 1], h[0, 2] = out[0], out[1], out[2]
    h[1, 0], h[1, 1], h[1, 2] = out[1], out[3], out[4]
    h[2, 0], h[2, 1], h[2, 2] = out[2], out[4], out[5]
    return h, out[6:9].copy(), n_ok, out[9]


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
    soft: float = 0.01,
    min_eigen_ratio: float = 1e-3,
    prior: tuple[ArrayLike, ArrayLike] | None = None,
) -> Refinement:
    """Point-to-line ICP: the pose of ``query`` in ``target``'s frame near ``guess``.

    Each query point is paired with its nearest target point within ``max_distance`` and,
    with weights that fall smoothly to zero, with the target points less than ``soft``
    metres farther than that one: a query point halfway between two target points of
    different normals passes from one to the other continuously, so a last-bit change of
    ``guess`` or of the target moves the result by about as much, not by a flip of the
    nearest neighbour. The pose minimises the weighted squared distances of the query points
    to those points' tangent lines (Gauss-Newton, a fixed number of rounds: Huber weights,
    tapered to zero at ``max_distance``). Along a direction the pairs do not constrain (a
    corridor's axis: eigenvalue under ``min_eigen_ratio`` of the largest) the guess is kept;
    :attr:`Refinement.hessian` tells the caller how little is known there.

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
    if not soft > 0:
        raise ValueError(f"soft must be > 0, got {soft}")
    if len(target.points) == 0 or iterations < 1:
        return Refinement(x, np.zeros((3, 3)), 0, 0.0)
    nx, ny = target.shape
    if prior is None:
        prior_pose, prior_info = np.zeros(3), np.zeros((3, 3))
    x, h, n_ok, rms = _gauss_newton(
        np.ascontiguousarray(q0), x, target.points, target.normals, target.origin,
        target.cell, nx, ny, target.starts, target.order, float(max_distance), float(huber),
        float(soft), int(iterations), float(min_eigen_ratio), prior is not None,
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
    soft,
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
    cand_j, cand_d = np.empty(pts.shape[0], np.int64), np.empty(pts.shape[0])
    for it in range(iterations):
        h, g, n_ok, ss = _accumulate(
            q0, x[0], x[1], x[2], pts, nrm, lo, cell, nx, ny, starts, order, max_d, huber, soft,
            cand_j, cand_d,
        )  # fmt: skip
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
