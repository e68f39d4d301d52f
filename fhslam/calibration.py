"""Loop 3's maths: the robot pose that lays the observed lines onto their reference lines.

Paper, "Self calibration and map building": "compute the deviation angle and distance between
the new detecting line segment and the corresponding referenced one and calibrate the robot's
pose". :func:`calibrate_pose` is that calibration, as a weighted Gauss-Newton fit of the
matched lines' endpoints to their reference lines; :class:`fhslam.slam.FastHoughSLAM` calls it
once or twice per scan.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.geometry import as_pose, wrap_angle
from fhslam.lines import Line

__all__ = ["Calibration", "calibrate_pose"]


@dataclass(frozen=True)
class Calibration:
    """Result of :func:`calibrate_pose`."""

    pose: NDArray[np.float64]
    """The calibrated pose ``(x, y, theta)``, world frame."""
    correction: NDArray[np.float64]
    """``pose - predicted`` (heading wrapped): what the calibration moved."""
    constrained: tuple[bool, bool]
    """Whether the position is constrained along its weakest / strongest direction (a
    corridor constrains only the strongest)."""
    n_pairs: int
    """Matched line pairs used."""


def calibrate_pose(
    observed: Sequence[Line],
    references: Sequence[Line],
    pairs: Sequence[tuple[int, int]],
    pose: ArrayLike,
    iterations: int = 3,
    min_eigen_ratio: float = 0.05,
    robust_scale: float | None = 0.02,
) -> Calibration:
    """The robot pose that best lays the observed lines onto their reference lines.

    "Compute the deviation angle and distance between the new detecting line segment and the
    corresponding referenced one and calibrate the robot's pose." The deviation of a pair is
    measured where it is seen: the signed distances of the observed segment's two endpoints
    (placed in the world at the current pose) to the reference line. The pose correction
    ``(dx, dy, dtheta)``, rotating about the robot, minimises their support-weighted squares
    (Gauss-Newton, ``iterations`` rounds). Distances measured this way do not depend on where
    the world origin lies, unlike differences of the lines' Hessian ``rho``.

    Along an eigen-direction of the 3 x 3 normal matrix whose information is under
    ``min_eigen_ratio`` of the largest (all matched lines parallel: a corridor), the pose is
    not corrected: the odometry is kept there rather than a correction invented.

    Parameters
    ----------
    observed : sequence of Line
        Lines in the robot frame.
    references : sequence of Line
        Reference lines in the world frame.
    pairs : sequence of (int, int)
        ``(observed index, reference index)`` of the matched lines.
    pose : array-like, shape (3,)
        The predicted pose ``world_T_robot``.
    iterations : int
        Gauss-Newton rounds.
    min_eigen_ratio : float
        Corridor test threshold (see above).
    robust_scale : float or None
        Huber scale of the endpoint residuals, metres: a residual ``r`` beyond it is
        down-weighted by ``robust_scale / |r|`` (iteratively reweighted least squares), so one
        wrong pair (e.g. a line fitted across a shallow corner) cannot drag the pose. ``None``
        gives plain least squares.

    Returns
    -------
    Calibration
        The calibrated pose, the correction applied ``(dx, dy, dtheta)``, whether the
        position is constrained along its weakest / strongest directions, and the number of
        pairs.
    """
    pose0 = as_pose(pose)
    x = pose0.copy()
    if not pairs:
        return Calibration(x, np.zeros(3), (False, False), 0)
    obs = [observed[i] for i, _ in pairs]
    refs = [references[j] for _, j in pairs]
    # Each pair contributes its two endpoints; robot-frame points (2P, 2).
    q = np.array([[o.sp, o.ep] for o in obs]).reshape(-1, 2)
    th_r = np.repeat([r.theta for r in refs], 2)
    rho_r = np.repeat([r.rho for r in refs], 2)
    n_r = np.column_stack([np.cos(th_r), np.sin(th_r)])
    w0 = np.repeat([min(o.n, r.n) for o, r in zip(obs, refs, strict=True)], 2).astype(float)
    constrained = (False, False)
    for _ in range(iterations):
        c, s_ = np.cos(x[2]), np.sin(x[2])
        rel = q @ np.array([[c, s_], [-s_, c]])  # rotated into the world, relative to robot
        p_w = rel + x[:2]
        r = rho_r - np.einsum("ij,ij->i", n_r, p_w)  # signed distance to the reference
        jac = np.column_stack([n_r, n_r[:, 1] * rel[:, 0] - n_r[:, 0] * rel[:, 1]])
        w = (
            w0
            if robust_scale is None
            else w0 * np.minimum(1.0, robust_scale / np.maximum(np.abs(r), 1e-12))
        )
        h = (jac * w[:, None]).T @ jac
        # Position information left once the heading is free (Schur complement): its
        # weak eigen-direction, if any, is the corridor's axis.
        schur = h[:2, :2] - np.outer(h[:2, 2], h[2, :2]) / max(h[2, 2], 1e-12)
        evals, evecs = np.linalg.eigh(schur)
        ok = evals > min_eigen_ratio * max(evals[1], 1e-12)
        constrained = (bool(ok[0]), bool(ok[1]))
        basis = np.zeros((3, int(ok.sum()) + 1))  # constrained position directions + heading
        basis[:2, :-1] = evecs[:, ok]
        basis[2, -1] = 1.0
        jr = jac @ basis
        delta = (
            basis
            @ np.linalg.lstsq((jr * w[:, None]).T @ jr, (jr * w[:, None]).T @ r, rcond=None)[0]
        )
        x = x + delta
        x[2] = wrap_angle(x[2])
    correction = x - pose0
    correction[2] = wrap_angle(correction[2])
    return Calibration(x, correction, constrained, len(pairs))
