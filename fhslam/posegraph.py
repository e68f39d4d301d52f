"""A 2D pose graph and its least-squares optimisation (sparse Gauss-Newton).

Nodes are poses ``(x, y, theta)``; an edge ``(i, j, z, information)`` says "node ``j`` seen
from node ``i`` is at ``z``" (``z ≈ ⊖x_i ⊕ x_j``, :func:`fhslam.geometry.relative`). The
optimisation minimises ``Σ ρ(e_ij^T Ω_ij e_ij)`` over the poses with the error

    e_ij = ( R_z^T (R_i^T (t_j - t_i) - t_z),  wrap(θ_j - θ_i - θ_z) )

(Grisetti et al., "A tutorial on graph-based SLAM", 2010, with the error taken in the frame
of ``z``). Edges can carry a Cauchy kernel ``ρ`` so that a wrong loop closure is
down-weighted instead of bending the whole trajectory. The first node is held fixed (gauge).

Used by :mod:`fhslam.slam.graph`; depends only on :mod:`fhslam.geometry`.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray
from scipy.sparse.linalg import spsolve

from fhslam.geometry import wrap_angle

__all__ = ["PoseGraph", "edge_errors", "optimize"]

_R3 = np.arange(3)


def edge_errors(
    poses: NDArray[np.float64], i: NDArray[np.intp], j: NDArray[np.intp], z: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Errors ``e_ij`` (E, 3) of the edges ``i -> j`` with measurements ``z`` (E, 3)."""
    return _errors_and_jacobians(poses, i, j, z)[0]


def _errors_and_jacobians(x, i, j, z):
    xi, xj = x[i], x[j]
    ci, si = np.cos(xi[:, 2]), np.sin(xi[:, 2])
    dx, dy = xj[:, 0] - xi[:, 0], xj[:, 1] - xi[:, 1]
    qx, qy = ci * dx + si * dy, -si * dx + ci * dy  # t_j in frame i
    cz, sz = np.cos(z[:, 2]), np.sin(z[:, 2])
    ux, uy = qx - z[:, 0], qy - z[:, 1]
    e = np.column_stack(
        [cz * ux + sz * uy, -sz * ux + cz * uy, wrap_angle(xj[:, 2] - xi[:, 2] - z[:, 2])]
    )
    # A = R_z^T R_i^T; de/dt_j = A, de/dt_i = -A, de/dθ_i = R_z^T (qy, -qx), dθ: -1 / +1.
    a00, a01 = cz * ci - sz * si, cz * si + sz * ci
    a10, a11 = -sz * ci - cz * si, -sz * si + cz * ci
    ji = np.zeros((len(i), 3, 3))
    jj = np.zeros((len(i), 3, 3))
    jj[:, 0, 0], jj[:, 0, 1], jj[:, 1, 0], jj[:, 1, 1], jj[:, 2, 2] = a00, a01, a10, a11, 1.0
    ji[:, :2, :2] = -jj[:, :2, :2]
    ji[:, 0, 2] = cz * qy - sz * qx
    ji[:, 1, 2] = -sz * qy - cz * qx
    ji[:, 2, 2] = -1.0
    return e, ji, jj


def _information_matrices(information: ArrayLike, ne: int) -> NDArray[np.float64]:
    om = np.asarray(information, dtype=float)
    if (om.ndim == 2 and om.shape[1:] == (3,)) or om.size == 0:
        om = om.reshape(-1, 3)
        return om[:, :, None] * np.eye(3)
    if om.shape[1:] != (3, 3):
        raise ValueError(f"information must have shape (E, 3) or (E, 3, 3), got {om.shape}")
    return om


def _chi2(e: NDArray[np.float64], om: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.einsum("ea,eab,eb->e", e, om, e)


def _blocks(p, q, b):
    rows = np.broadcast_to(3 * p[:, None, None] + _R3[None, :, None], b.shape)
    cols = np.broadcast_to(3 * q[:, None, None] + _R3[None, None, :], b.shape)
    return rows.ravel(), cols.ravel(), b.ravel()


def optimize(
    poses: ArrayLike,
    i: ArrayLike,
    j: ArrayLike,
    z: ArrayLike,
    information: ArrayLike,
    robust: ArrayLike | None = None,
    iterations: int = 10,
    tol: float = 1e-6,
) -> NDArray[np.float64]:
    """Optimise a pose graph; node 0 stays fixed.

    Parameters
    ----------
    poses : array-like, shape (N, 3)
        Initial poses.
    i, j : array-like of int, shape (E,)
        Edge endpoints.
    z : array-like, shape (E, 3)
        Measured relative poses ``⊖x_i ⊕ x_j``.
    information : array-like, shape (E, 3) or (E, 3, 3)
        Each edge's information matrix (symmetric, positive semi-definite; the translation
        part in the frame of ``z``), or its diagonal (1 / sigma², in 1/m² and 1/rad²).
    robust : array-like, shape (E,), optional
        Cauchy kernel scale per edge in units of the Mahalanobis distance (0: plain least
        squares). An edge whose ``e^T Ω e`` is ``c²`` gets half weight.
    iterations : int
        Largest number of Gauss-Newton rounds.
    tol : float
        Stop when no pose moves by more than this (metres / radians).

    Returns
    -------
    ndarray, shape (N, 3)
        The optimised poses.
    """
    x = np.array(poses, dtype=float).reshape(-1, 3)
    i = np.asarray(i, dtype=np.intp)
    j = np.asarray(j, dtype=np.intp)
    z = np.asarray(z, dtype=float).reshape(-1, 3)
    om = _information_matrices(information, len(i))
    n, ne = len(x), len(i)
    if not len(j) == len(z) == len(om) == ne:
        raise ValueError(
            "i, j, z and information must have the same length, got "
            f"{len(i)}, {len(j)}, {len(z)}, {len(om)}"
        )
    if ne and (min(i.min(), j.min()) < 0 or max(i.max(), j.max()) >= n):
        raise ValueError(f"edge endpoints must index the {n} poses")
    if n < 2 or ne == 0:
        return x
    c = np.zeros(ne) if robust is None else np.asarray(robust, dtype=float)
    for _ in range(iterations):
        e, ji, jj = _errors_and_jacobians(x, i, j, z)
        w = np.ones(ne)
        m = c > 0
        if m.any():
            w[m] = 1.0 / (1.0 + _chi2(e[m], om[m]) / c[m] ** 2)
        o = om * w[:, None, None]
        jit_o = ji.transpose(0, 2, 1) @ o
        jjt_o = jj.transpose(0, 2, 1) @ o
        hij = jit_o @ jj
        parts = [
            _blocks(i, i, jit_o @ ji),
            _blocks(i, j, hij),
            _blocks(j, i, hij.transpose(0, 2, 1)),
            _blocks(j, j, jjt_o @ jj),
        ]
        rows, cols, vals = (np.concatenate(t) for t in zip(*parts, strict=True))
        h = sp.csc_matrix((vals, (rows, cols)), shape=(3 * n, 3 * n))[3:, 3:]
        b = np.zeros(3 * n)
        np.add.at(b, (3 * i[:, None] + _R3).ravel(), np.einsum("eab,eb->ea", jit_o, e).ravel())
        np.add.at(b, (3 * j[:, None] + _R3).ravel(), np.einsum("eab,eb->ea", jjt_o, e).ravel())
        # A node that no edge reaches has an empty row: hold it with a tiny prior.
        h = h + sp.identity(3 * n - 3, format="csc") * 1e-9
        dx = spsolve(h, -b[3:])
        if not np.all(np.isfinite(dx)):
            break
        x[1:] += dx.reshape(-1, 3)
        x[:, 2] = wrap_angle(x[:, 2])
        if np.max(np.abs(dx)) < tol:
            break
    return x


class PoseGraph:
    """A growing pose graph: add nodes and edges, then :meth:`optimize`.

    Examples
    --------
    >>> g = PoseGraph()
    >>> a = g.add_node([0.0, 0.0, 0.0]); b = g.add_node([1.1, 0.0, 0.0])
    >>> g.add_edge(a, b, [1.0, 0.0, 0.0], [1e4, 1e4, 1e4])
    >>> g.optimize(); bool(abs(g.poses[1, 0] - 1.0) < 1e-9)
    True
    """

    def __init__(self) -> None:
        self._poses: list[NDArray[np.float64]] = []
        self._i: list[int] = []
        self._j: list[int] = []
        self._z: list[NDArray[np.float64]] = []
        self._info: list[NDArray[np.float64]] = []
        self._robust: list[float] = []
        self._kind: list[str] = []
        self._active: list[bool] = []

    def __len__(self) -> int:
        return len(self._poses)

    @property
    def poses(self) -> NDArray[np.float64]:
        """The current poses, shape (N, 3) (a copy)."""
        return np.array(self._poses).reshape(-1, 3)

    def pose(self, k: int) -> NDArray[np.float64]:
        """Node ``k``'s current pose."""
        return self._poses[k]

    def set_pose(self, k: int, pose: ArrayLike) -> None:
        """Replace node ``k``'s current estimate (e.g. from a refined odometry edge)."""
        self._poses[k] = np.asarray(pose, dtype=float).copy()

    def add_node(self, pose: ArrayLike) -> int:
        """Add a node at ``pose``; returns its index."""
        self._poses.append(np.asarray(pose, dtype=float).copy())
        return len(self._poses) - 1

    def add_edge(
        self,
        i: int,
        j: int,
        z: ArrayLike,
        information: ArrayLike,
        robust: float = 0.0,
        kind: str = "odometry",
    ) -> int:
        """Add the edge ``i -> j`` (see :func:`optimize`; ``information``: shape (3,) for a
        diagonal, or (3, 3)); returns its index."""
        if not (0 <= i < len(self) and 0 <= j < len(self)) or i == j:
            raise ValueError(f"edge {i} -> {j} must join two different nodes of {len(self)}")
        self._i.append(i)
        self._j.append(j)
        self._z.append(np.asarray(z, dtype=float).copy())
        self._info.append(
            _information_matrices(np.reshape(information, (1, *np.shape(information))), 1)[0]
        )
        self._robust.append(float(robust))
        self._kind.append(kind)
        self._active.append(True)
        return len(self._i) - 1

    def is_active(self, e: int) -> bool:
        """Whether edge ``e`` takes part in :meth:`optimize`."""
        return self._active[e]

    def set_active(self, e: int, active: bool) -> None:
        """Switch edge ``e`` on or off (an edge found inconsistent is switched off)."""
        self._active[e] = bool(active)

    def chi2(self, edges: ArrayLike) -> NDArray[np.float64]:
        """Squared Mahalanobis errors ``e^T Ω e`` of the given edges at the current poses."""
        k = np.asarray(edges, dtype=np.intp).reshape(-1)
        # The given edges' rows only, and only their nodes' poses (the same numbers as
        # indexing arrays of the whole graph, without building them at every call).
        i = np.array([self._i[e] for e in k], dtype=np.intp)
        j = np.array([self._j[e] for e in k], dtype=np.intp)
        z = np.array([self._z[e] for e in k]).reshape(-1, 3)
        info = np.array([self._info[e] for e in k]).reshape(-1, 3, 3)
        nodes, ends = np.unique(np.concatenate([i, j]), return_inverse=True)
        x = np.array([self._poses[n] for n in nodes]).reshape(-1, 3)
        return _chi2(edge_errors(x, ends[: len(k)], ends[len(k) :], z), info)

    def set_measurement(self, e: int, z: ArrayLike) -> None:
        """Replace edge ``e``'s measurement."""
        self._z[e] = np.asarray(z, dtype=float).copy()

    def information(self, e: int) -> NDArray[np.float64]:
        """Edge ``e``'s information (a copy)."""
        return self._info[e].copy()

    def set_information(self, e: int, information: ArrayLike) -> None:
        """Replace edge ``e``'s information (3 x 3, symmetric positive semi-definite)."""
        info = np.asarray(information, dtype=float)
        if info.shape != (3, 3) or not np.all(np.isfinite(info)):
            raise ValueError(f"edge information must be a finite 3 x 3 matrix, got {info.shape}")
        self._info[e] = info.copy()

    @property
    def edges(self) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.float64], list[str]]:
        """``(i, j, z, kind)`` of all edges."""
        return (
            np.array(self._i, dtype=np.intp),
            np.array(self._j, dtype=np.intp),
            np.array(self._z).reshape(-1, 3),
            list(self._kind),
        )

    def optimize(self, iterations: int = 10, tol: float = 1e-6) -> None:
        """Optimise all poses in place (node 0 fixed), with the active edges."""
        a = np.array(self._active, dtype=bool)
        x = optimize(
            self.poses,
            np.array(self._i, dtype=np.intp)[a],
            np.array(self._j, dtype=np.intp)[a],
            np.array(self._z).reshape(-1, 3)[a],
            np.array(self._info).reshape(-1, 3, 3)[a],
            np.array(self._robust)[a],
            iterations,
            tol,
        )
        self._poses = list(x)
