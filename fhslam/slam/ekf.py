"""EKF line SLAM: the Kalman-filter alternative the paper's introduction lists, as a baseline.

State ``[x, y, θ, α₁, r₁, α₂, r₂, ...]``: the robot pose and each landmark line in Hessian
form (``r >= 0``), both in the *anchor frame*, the frame of the first pose. Built on
:class:`filterpy.kalman.ExtendedKalmanFilter`:

- **predict** from the odometry increment ``u = odo_{k-1} ⊖ odo_k`` with a noise model growing
  with the distance and the turn (:class:`EKFParams`);
- **measure** each line extracted by the same Loop 1 as FH-SLAM, in the robot frame:
  ``ẑ = [α − θ, r − (x cos α + y sin α)]`` (:func:`predict_measurement`, Jacobian
  :func:`measurement_jacobian`), flipped to ``[α − θ + π, −r̂]`` when ``r̂ < 0`` so the
  prediction has the measurement's form; angles compared through :func:`residual`;
- each line's covariance from its least-squares fit (Arras & Siegwart 1997; Pfister et al.
  2003): :func:`line_covariance`;
- **associate** by Mahalanobis distance with a χ² gate (2 dof), nearest first;
- **add** unmatched long lines as new landmarks by growing ``x``, ``P`` and the filter's
  dimension — filterpy fixes ``dim_x`` at construction, so :meth:`EKFLineSLAM._grow` builds a
  larger filter and copies the state over; it is the only place the dimension changes.

Where the world frame lies must not matter, yet an EKF is not invariant under a nonlinear
change of coordinates, and moving the world frame changes each landmark's ``r`` by
``t · (cos α, sin α)``, nonlinear in ``α``: linearised in the world frame, the filter would
give another trajectory for another world origin. Its state therefore lives in the anchor
frame, which the filter's inputs (odometry increments, robot-frame lines) determine alone;
:attr:`EKFLineSLAM.pose` and :meth:`EKFLineSLAM.landmarks` map it into the world. Keeping
``r >= 0`` flips a landmark to ``(α + π, −r)`` when an update or its first sighting gives
``r < 0``: that map is linear, and ``r``'s rows of the covariance and of the Jacobians flip
sign with it.

The filter's linear algebra runs on **one BLAS thread**, whatever the environment
(:meth:`EKFLineSLAM.predict` and :meth:`EKFLineSLAM.update` limit BLAS to one thread while
they run and restore the caller's setting after, through :mod:`threadpoolctl`). filterpy's
dense products of the covariance (453 x 453 at :attr:`EKFParams.max_landmarks`) are large
enough for OpenBLAS to split over threads (from 64 x 64, 31 landmarks, on), and then the
trajectory's last bits depend on the thread count, so on the machine's core count (MIT
CSAIL: 8e-12 m from scan 186 on), and a run takes 4-10x longer when the other cores are busy
(MIT CSAIL on 2 cores at load 3: 22-66 s instead of 5-8 s), the threads waiting on each other.
"""

from __future__ import annotations

import functools
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, ParamSpec, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray
from threadpoolctl import ThreadpoolController

from fhslam.extraction import ExtractionParams, extract_lines
from fhslam.geometry import (
    as_pose,
    compose,
    normalize_line,
    point_on_line,
    position_on_line,
    relative,
    wrap_angle,
)
from fhslam.lines import Line
from fhslam.scan import Scan
from fhslam.slam.base import FinalEstimate, StepResult

if TYPE_CHECKING:
    from filterpy.kalman import ExtendedKalmanFilter

__all__ = [
    "CHI2_2DOF_99",
    "EKFLandmarkLimitWarning",
    "EKFLineSLAM",
    "EKFParams",
    "line_covariance",
    "measurement_jacobian",
    "predict_measurement",
    "residual",
]

CHI2_2DOF_99 = 9.2103
"""99 % quantile of the χ² distribution with 2 degrees of freedom."""


@dataclass(frozen=True)
class EKFParams:
    """Parameters of the EKF line-SLAM baseline.

    Attributes
    ----------
    extraction : ExtractionParams
        Loop 1, the same as FH-SLAM's.
    trans_noise : float
        Standard deviation of the odometry's distance error per metre driven.
    rot_noise : float
        Standard deviation of the odometry's turn error per radian turned.
    rot_per_metre : float
        Standard deviation of the heading error per metre driven, rad/m.
    min_std : tuple of float
        Floor of the motion noise per step: (metres, radians).
    range_std : float
        Floor of a line point's noise, metres (the fit's rms is used when larger).
    gate : float
        Mahalanobis gate for data association (χ², 2 dof).
    new_gate : float
        A line whose nearest landmark is farther than this (χ²) starts a new landmark;
        between ``gate`` and ``new_gate`` it is ambiguous and ignored.
    min_landmark_length : float
        Shortest line (metres) that starts a landmark.
    min_landmark_points : int
        Fewest points for a line to start a landmark.
    max_landmarks : int
        Largest number of landmarks. The filter's covariance is dense, so a step costs
        O(landmarks²) to O(landmarks³) (1.5 s per scan at several hundred landmarks, on MIT
        CSAIL an estimated 35 minutes in all); once the map holds this many, new lines start
        no landmark (they are still matched with the existing ones) and a
        :class:`EKFLandmarkLimitWarning` says so, once. The simulated worlds need 10-20.
    """

    extraction: ExtractionParams = field(default_factory=ExtractionParams)
    trans_noise: float = 0.05
    rot_noise: float = 0.05
    rot_per_metre: float = 0.02
    min_std: tuple[float, float] = (0.002, 0.002)
    range_std: float = 0.01
    gate: float = CHI2_2DOF_99
    new_gate: float = 50.0
    min_landmark_length: float = 0.8
    min_landmark_points: int = 10
    max_landmarks: int = 150


class EKFLandmarkLimitWarning(UserWarning):
    """The EKF baseline's map reached :attr:`EKFParams.max_landmarks`: no more landmarks."""


# --------------------------------------------------------------------------- models


def predict_measurement(x: NDArray, j: int) -> NDArray[np.float64]:
    """ẑ of landmark ``j`` seen from the robot state ``x[:3]``: ``[α − θ, r − (x cos α +
    y sin α)]``, flipped to ``[α − θ + π, −r̂]`` when ``r̂ < 0``; the angle wrapped to [0, 2π)."""
    a, r = x[3 + 2 * j], x[4 + 2 * j]
    rr, za = normalize_line(r - (x[0] * np.cos(a) + x[1] * np.sin(a)), a - x[2])
    return np.array([za, rr])


def measurement_jacobian(x: NDArray, j: int) -> NDArray[np.float64]:
    """∂ẑ/∂x of :func:`predict_measurement`, shape (2, len(x))."""
    a, r = x[3 + 2 * j], x[4 + 2 * j]
    rr = r - (x[0] * np.cos(a) + x[1] * np.sin(a))
    h = np.zeros((2, len(x)))
    h[0, 2] = -1.0
    h[0, 3 + 2 * j] = 1.0
    h[1, 0], h[1, 1] = -np.cos(a), -np.sin(a)
    h[1, 3 + 2 * j] = x[0] * np.sin(a) - x[1] * np.cos(a)
    h[1, 4 + 2 * j] = 1.0
    if rr < 0:
        h[1] = -h[1]
    return h


def residual(z: NDArray, zhat: NDArray) -> NDArray[np.float64]:
    """``z − ẑ`` for stacked line measurements ``[α, r, α, r, ...]``: angles wrapped, and a
    line through the robot (``r ≈ 0``, where ``(α, r)`` and ``(α + π, −r)`` are the same line)
    compared in the form closest to the prediction, so it never looks π off."""
    z = np.asarray(z, dtype=float).reshape(-1, 2)
    zh = np.asarray(zhat, dtype=float).reshape(-1, 2)
    da = wrap_angle(z[:, 0] - zh[:, 0])
    dr = z[:, 1] - zh[:, 1]
    flip = np.abs(da) > np.pi / 2
    da = np.where(flip, wrap_angle(z[:, 0] + np.pi - zh[:, 0]), da)
    dr = np.where(flip, -z[:, 1] - zh[:, 1], dr)
    return np.column_stack([da, dr]).ravel()


def line_covariance(points: ArrayLike, line: Line, sigma_floor: float = 0.01) -> NDArray:
    """Covariance of a fitted line's ``(α, r)`` from its inlier points (Arras & Siegwart 1997).

    With points of isotropic noise σ (the fit's rms, at least ``sigma_floor``), spread along
    the line with coordinates ``t`` (``t̄`` their mean, measured from the foot of the
    perpendicular): ``var α = σ² / Σ(t − t̄)²``, ``var r = σ²/n + t̄² var α``,
    ``cov(α, r) = t̄ var α``.

    Parameters
    ----------
    points : array-like, shape (N, 2)
        The scan's points (in the frame of ``line``); ``line.inliers`` index them.
    """
    p = np.asarray(points, dtype=float)[line.inliers]
    u = np.array([-np.sin(line.theta), np.cos(line.theta)])
    t = p @ u
    s2 = max(line.rms, sigma_floor) ** 2
    spread = max(float(np.sum((t - t.mean()) ** 2)), 1e-6)
    var_a = s2 / spread
    tb = float(t.mean())
    return np.array([[var_a, tb * var_a], [tb * var_a, s2 / len(p) + tb**2 * var_a]])


_P = ParamSpec("_P")
_T = TypeVar("_T")


@functools.cache
def _blas_pools() -> ThreadpoolController:
    """The process's BLAS thread pools, found once (finding them takes about 1 ms, a limit
    with them 0.02 ms), after filterpy has loaded scipy's, which it uses besides numpy's."""
    _motion_ekf()
    return ThreadpoolController()


def _one_blas_thread(method: Callable[_P, _T]) -> Callable[_P, _T]:
    """Run ``method`` with BLAS limited to one thread, the caller's setting restored after
    (see the module docs: the result must not depend on the machine's core count)."""

    @functools.wraps(method)
    def limited(*args: _P.args, **kwargs: _P.kwargs) -> _T:
        with _blas_pools().limit(limits=1, user_api="blas"):
            return method(*args, **kwargs)

    return limited


@functools.cache
def _motion_ekf() -> type[ExtendedKalmanFilter]:
    """filterpy's EKF with the nonlinear motion ``x ⊕ u`` for the robot part of the state.

    Made on first use: filterpy imports ``scipy.stats`` (0.35 s), which only this baseline
    needs, so ``fhslam slam`` with another method starts that much sooner."""
    from filterpy.kalman import ExtendedKalmanFilter

    class _MotionEKF(ExtendedKalmanFilter):
        def predict_x(self, u=0):
            self.x[:3] = compose(self.x[:3], u)

    return _MotionEKF


# --------------------------------------------------------------------------- the filter


class EKFLineSLAM:
    """EKF line SLAM on filterpy, driven like :class:`fhslam.slam.FastHoughSLAM`.

    ``ekf.x`` and ``ekf.P`` are in the anchor frame, the first pose's (see the module docs);
    :attr:`anchor` is that pose in the world.
    """

    def __init__(self, params: EKFParams | None = None, initial_pose: ArrayLike | None = None):
        self.params = params or EKFParams()
        self.ekf: ExtendedKalmanFilter | None = None
        self.anchor: NDArray[np.float64] | None = None
        self._init_pose = None if initial_pose is None else as_pose(initial_pose)
        self._last_odometry: NDArray | None = None
        self._ends: list[NDArray] = []  # per landmark: its two extreme observed points (2, 2)
        self._support: list[int] = []
        self._limit_warned = False

    @property
    def pose(self) -> NDArray[np.float64]:
        """The robot pose in the world frame."""
        return compose(self.anchor, self.ekf.x[:3])

    @property
    def n_landmarks(self) -> int:
        return 0 if self.ekf is None else (self.ekf.dim_x - 3) // 2

    def _start(self, pose: NDArray) -> None:
        self.anchor = pose.astype(float).copy()
        self.ekf = _motion_ekf()(dim_x=3, dim_z=2)
        self.ekf.x = np.zeros(3)  # the anchor frame's origin
        self.ekf.P = np.eye(3) * 1e-9  # "suppose the initial localization is correct"

    def _grow(self, landmark: NDArray, cov_rows: NDArray, cov_lm: NDArray) -> None:
        """Append one landmark: the only place the filter's dimension changes.

        ``cov_rows`` (2, n) is the landmark's covariance with the current state and ``cov_lm``
        (2, 2) its own; a new :class:`filterpy.kalman.ExtendedKalmanFilter` of dimension
        ``n + 2`` takes over ``x`` and ``P`` (filterpy sizes ``_I``, ``F``, ``Q`` at
        construction).
        """
        old = self.ekf
        n = old.dim_x
        new = _motion_ekf()(dim_x=n + 2, dim_z=2)
        new.x = np.concatenate([old.x, landmark])
        p = np.zeros((n + 2, n + 2))
        p[:n, :n] = old.P
        p[n:, :n] = cov_rows
        p[:n, n:] = cov_rows.T
        p[n:, n:] = cov_lm
        new.P = p
        self.ekf = new

    @_one_blas_thread
    def predict(self, odometry: ArrayLike) -> None:
        """Predict from the odometry increment since the last call (the first call starts the
        filter); on one BLAS thread."""
        odo = as_pose(odometry, "odometry")
        if self.ekf is None:
            self._start(self._init_pose if self._init_pose is not None else odo)
            self._last_odometry = odo
            return
        u = relative(self._last_odometry, odo)
        self._last_odometry = odo
        pr = self.params
        dist, turn = float(np.hypot(u[0], u[1])), abs(float(u[2]))
        s_t = pr.trans_noise * dist + pr.min_std[0]
        s_r = pr.rot_noise * turn + pr.rot_per_metre * dist + pr.min_std[1]
        th = self.ekf.x[2]
        c, s = np.cos(th), np.sin(th)
        n = self.ekf.dim_x
        f = np.eye(n)
        f[0, 2] = -s * u[0] - c * u[1]
        f[1, 2] = c * u[0] - s * u[1]
        ju = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        q = np.zeros((n, n))
        q[:3, :3] = ju @ np.diag([s_t**2, s_t**2, s_r**2]) @ ju.T
        self.ekf.F, self.ekf.Q = f, q
        self.ekf.predict(u=u)

    def _associate(self, lines: list[Line], covs: list[NDArray]) -> list[tuple[int, float]]:
        """Nearest landmark by Mahalanobis distance (χ²) for each line, and that distance
        (``(-1, inf)``: no landmark whose innovation covariance is positive definite).

        All lines against all landmarks at once: the Jacobian of a landmark's ``ẑ`` is zero
        but in the robot's three columns and the landmark's two
        (:func:`measurement_jacobian`), so ``H P Hᵀ`` needs only that 5 x 5 block of ``P``
        (not the whole dense product, which made a step cost 0.2 s at 150 landmarks); the
        2 x 2 innovation covariances are inverted in closed form.
        """
        m = self.n_landmarks
        if m == 0:
            return [(-1, np.inf)] * len(lines)
        x, p = self.ekf.x, self.ekf.P
        a, r = x[3::2], x[4::2]
        c, s = np.cos(a), np.sin(a)
        rr = r - (x[0] * c + x[1] * s)
        sign = np.where(rr < 0, -1.0, 1.0)  # the flipped form's Jacobian row, as predicted
        h = np.zeros((m, 2, 5))  # columns: x, y, θ, α_j, r_j
        h[:, 0, 2], h[:, 0, 3] = -1.0, 1.0
        h[:, 1, 0], h[:, 1, 1] = -c * sign, -s * sign
        h[:, 1, 3] = (x[0] * s - x[1] * c) * sign
        h[:, 1, 4] = sign
        cols = np.empty((m, 5), dtype=np.intp)
        cols[:, :3] = [0, 1, 2]
        cols[:, 3] = 3 + 2 * np.arange(m)
        cols[:, 4] = cols[:, 3] + 1
        block = p[cols[:, :, None], cols[:, None, :]]  # (m, 5, 5)
        hph = np.einsum("mik,mkl,mjl->mij", h, block, h)  # (m, 2, 2)
        zr, za = normalize_line(rr, a - x[2])  # ẑ of every landmark
        z = np.array([[ln.theta, ln.rho] for ln in lines])  # (L, 2)
        sm = hph[None] + np.asarray(covs)[:, None]  # (L, m, 2, 2)
        y = residual(
            np.repeat(z, m, axis=0), np.tile(np.column_stack([za, zr]), (len(lines), 1))
        ).reshape(len(lines), m, 2)
        s00, s01, s10, s11 = sm[..., 0, 0], sm[..., 0, 1], sm[..., 1, 0], sm[..., 1, 1]
        det = s00 * s11 - s01 * s10
        ya, yr = y[..., 0], y[..., 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            d2 = (s11 * ya * ya - (s01 + s10) * ya * yr + s00 * yr * yr) / det
        d2 = np.where((det > 0) & (s00 > 0) & np.isfinite(d2), d2, np.inf)
        best = np.argmin(d2, axis=1)
        best_d2 = d2[np.arange(len(lines)), best]
        return [
            (int(j), float(d)) if np.isfinite(d) else (-1, np.inf)
            for j, d in zip(best, best_d2, strict=True)
        ]

    @_one_blas_thread
    def update(self, lines: list[Line], points: NDArray) -> tuple[int, int]:
        """Associate, update with all matched lines at once, add new landmarks; on one BLAS
        thread.

        Returns (matched, added)."""
        pr = self.params
        covs = [line_covariance(points, ln, pr.range_std) for ln in lines]
        assoc = self._associate(lines, covs)
        matched = [(i, j) for i, (j, d2) in enumerate(assoc) if j >= 0 and d2 <= pr.gate]
        if matched:
            z = np.concatenate([[lines[i].theta, lines[i].rho] for i, _ in matched])
            r = np.zeros((len(z), len(z)))
            for k, (i, _) in enumerate(matched):
                r[2 * k : 2 * k + 2, 2 * k : 2 * k + 2] = covs[i]
            idx = [j for _, j in matched]
            self._safe_update(z, r, idx)
            for i, j in matched:
                self._extend(j, lines[i])
        added = 0
        for i, (j, d2) in enumerate(assoc):
            ln = lines[i]
            long_enough = ln.length >= pr.min_landmark_length and ln.n >= pr.min_landmark_points
            if (j < 0 or d2 > pr.new_gate) and long_enough:
                if self.n_landmarks >= pr.max_landmarks:
                    if not self._limit_warned:
                        self._limit_warned = True
                        warnings.warn(
                            f"EKF baseline: the map holds EKFParams.max_landmarks = "
                            f"{pr.max_landmarks} landmarks (its covariance is dense: each more "
                            "slows every step); from here on new lines start no landmark",
                            EKFLandmarkLimitWarning,
                            stacklevel=3,  # the caller of update, not its BLAS wrapper
                        )
                    continue
                self._add_landmark(ln, covs[i])
                added += 1
        return len(matched), added

    def _safe_update(self, z: NDArray, r: NDArray, idx: list[int]) -> None:
        """filterpy's update over the stacked measurements; skipped (state unchanged) when the
        innovation covariance is singular or the result would not be finite."""
        x0, p0 = self.ekf.x.copy(), self.ekf.P.copy()

        def hj(x):
            return np.vstack([measurement_jacobian(x, j) for j in idx])

        def hx(x):
            return np.concatenate([predict_measurement(x, j) for j in idx])

        try:
            self.ekf.update(z, hj, hx, R=r, residual=residual)
        except np.linalg.LinAlgError:
            self.ekf.x, self.ekf.P = x0, p0
            return
        if not (np.all(np.isfinite(self.ekf.x)) and np.all(np.isfinite(self.ekf.P))):
            self.ekf.x, self.ekf.P = x0, p0
            return
        self.ekf.x[2] = wrap_angle(self.ekf.x[2])
        lm = self.ekf.x[3:].reshape(-1, 2)
        rows = 4 + 2 * np.flatnonzero(lm[:, 1] < 0)
        lm[:, 1], lm[:, 0] = normalize_line(lm[:, 1], lm[:, 0])  # keep r >= 0
        # (α, r) -> (α + π, −r) is linear: the flipped r's covariances change sign.
        self.ekf.P[rows, :] *= -1.0
        self.ekf.P[:, rows] *= -1.0

    def _add_landmark(self, ln: Line, cov_z: NDArray) -> None:
        """Append the robot-frame line ``ln`` (covariance ``cov_z`` of its ``(α, r)``) as a
        landmark, with its covariance from the Jacobians of ``(α, r) = (α_z + θ, r_z + x cos α
        + y sin α)`` by the pose (``gx``) and by the measurement (``gz``)."""
        x, y, th = self.ekf.x[:3]
        a = ln.theta + th
        r = ln.rho + x * np.cos(a) + y * np.sin(a)
        dr_da = -x * np.sin(a) + y * np.cos(a)  # ∂r/∂θ = ∂r/∂α_z
        gx = np.array([[0.0, 0.0, 1.0], [np.cos(a), np.sin(a), dr_da]])
        gz = np.array([[1.0, 0.0], [dr_da, 1.0]])
        if r < 0:  # stored as (α + π, −r): r's rows flip sign
            gx[1], gz[1] = -gx[1], -gz[1]
        r, a = normalize_line(r, a)
        p = self.ekf.P
        rows = gx @ p[:3, :]
        cov_lm = gx @ p[:3, :3] @ gx.T + gz @ cov_z @ gz.T
        self._grow(np.array([a, r]), rows, cov_lm)
        self._ends.append(np.empty((0, 2)))
        self._support.append(0)
        self._extend(self.n_landmarks - 1, ln)

    def _extend(self, j: int, ln: Line) -> None:
        """Grow landmark j's seen extent with the observed segment (for the map output).

        The extremes are kept as points (anchor frame), not as coordinates along the line: a
        landmark through the origin (r ≈ 0) flips between (α, r) and (α + π, −r), which would
        reverse such coordinates.
        """
        w = ln.transformed(self.ekf.x[:3])
        pts = np.vstack([self._ends[j], w.sp, w.ep])
        t = position_on_line(pts, self.ekf.x[3 + 2 * j])
        self._ends[j] = pts[[int(np.argmin(t)), int(np.argmax(t))]]
        self._support[j] += ln.n

    def step(self, scan: Scan | None, odometry: ArrayLike) -> StepResult:
        """Predict from odometry and, if there is a scan, update (``scan=None``: dropped)."""
        self.predict(odometry)
        if scan is None:
            return StepResult(self.pose, 0, 0, 0, False)
        points, _ = scan.points()
        lines = extract_lines(points, self.params.extraction)
        matched, added = self.update(lines, points) if lines else (0, 0)
        return StepResult(self.pose, len(lines), matched, added, matched > 0, lines)

    def landmarks(self) -> list[Line]:
        """The map, world frame: each landmark line over the extent it was seen."""
        out = []
        for j in range(self.n_landmarks):
            a, r = self.ekf.x[3 + 2 * j : 5 + 2 * j]
            lo, hi = np.sort(position_on_line(self._ends[j], a))
            sp, ep = point_on_line(r, a, np.array([lo, hi]))
            out.append(
                Line(rho=float(r), theta=float(a), n=self._support[j], length=float(hi - lo),
                     sp=sp, ep=ep).transformed(self.anchor)
            )  # fmt: skip
        return out

    def finish(self) -> FinalEstimate:
        """The map (:meth:`landmarks`); the filter's poses at each step stand."""
        return FinalEstimate(self.landmarks())
