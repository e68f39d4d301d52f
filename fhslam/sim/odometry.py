"""Drifting wheel odometry from a ground-truth trajectory.

Each step between consecutive true poses is split into "rotate, translate, rotate"
``(rot1, trans, rot2)`` and perturbed as in the odometry motion model of Thrun, Burgard and
Fox, *Probabilistic Robotics* (2005), table 5.6, plus three systematic errors real odometry
has (a wrong wheel diameter, unequal wheels, a wrong wheelbase). The noisy steps are chained
from the true start pose, so the error accumulates without bound, as the paper's
introduction says.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.geometry import compose, relative, wrap_angle


@dataclass(frozen=True)
class OdometryNoise:
    """Odometry error model (defaults: about 1-3 m of drift over the paper world's ~60 m route).

    The random part is table 5.6 of *Probabilistic Robotics*: each step's rotations and
    translation get zero-mean Gaussian noise with variance

    - ``alpha1 * rot**2 + alpha2 * trans**2`` for ``rot1`` and ``rot2``,
    - ``alpha3 * trans**2 + alpha4 * (rot1**2 + rot2**2)`` for ``trans``.

    Attributes
    ----------
    alpha1 : float
        Rotation noise from rotation, rad^2 per rad^2.
    alpha2 : float
        Rotation noise from translation, rad^2 per m^2.
    alpha3 : float
        Translation noise from translation, m^2 per m^2.
    alpha4 : float
        Translation noise from rotation, m^2 per rad^2.
    scale_error : float
        Systematic relative distance error: odometry reports ``(1 + scale_error)`` times the
        true distance (e.g. a wheel radius off by that fraction).
    heading_bias : float
        Systematic heading drift, radians per metre travelled (positive: counter-clockwise),
        e.g. from unequal wheel radii.
    turn_scale_error : float
        Systematic relative rotation error: odometry reports ``(1 + turn_scale_error)`` times
        every true rotation (e.g. an effective wheelbase off by that fraction). Unlike
        ``heading_bias`` it grows with the net angle turned, so it matters most on routes
        that keep turning the same way (loops driven several times).
    """

    alpha1: float = 0.002
    alpha2: float = 0.0005
    alpha3: float = 0.005
    alpha4: float = 0.0005
    scale_error: float = 0.01
    heading_bias: float = 0.003
    turn_scale_error: float = 0.0

    def __post_init__(self) -> None:
        for name in ("alpha1", "alpha2", "alpha3", "alpha4"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise ValueError(f"OdometryNoise.{name} must be finite and >= 0, got {value}")
        if not (np.isfinite(self.scale_error) and self.scale_error > -1):
            raise ValueError(f"OdometryNoise.scale_error must be > -1, got {self.scale_error}")
        if not (np.isfinite(self.turn_scale_error) and self.turn_scale_error > -1):
            raise ValueError(
                f"OdometryNoise.turn_scale_error must be > -1, got {self.turn_scale_error}"
            )
        if not np.isfinite(self.heading_bias):
            raise ValueError(f"OdometryNoise.heading_bias must be finite, got {self.heading_bias}")

    @classmethod
    def none(cls) -> OdometryNoise:
        """Perfect odometry: all errors zero (odometry equals the truth)."""
        return cls(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)

    @classmethod
    def drifting(cls) -> OdometryNoise:
        """Badly calibrated odometry that drifts 2-6 m over a 55-75 m run.

        Mostly systematic, as real wheel odometry is: distances 2 % long, 0.007 rad
        (0.4 degrees) of heading creep per metre, every turn reported 3.5 % too large, plus
        about half the default noise variances. Measured as the largest distance between odometry
        and true position over the run (:func:`fhslam.sim.simulate`, default motion):

        - paper world (58 m route), ``seed`` 0-19: 2.7-4.7 m, median 3.6 m (seeds 0-499:
          1.6-5.7 m, 99 % within 2-6 m);
        - ``random_world(s)``, s = 101-120, driven with ``laps=3`` (about 55-72 m) and
          ``seed=s``: 2.8-4.9 m, median 4.0 m (one lap: only 1.0-1.8 m).

        Both systematic rotation errors are counter-clockwise, and so are the loops of
        :func:`~fhslam.sim.random_world`. On a route that turns clockwise overall the turn
        error cancels much of the heading creep: the mirror images of random worlds 101-103
        drift only 0.9-1.5 m over 3 laps (against 3.7-4.3 m).
        """
        return cls(
            alpha1=0.001,
            alpha2=0.00025,
            alpha3=0.002,
            alpha4=0.00025,
            scale_error=0.02,
            heading_bias=0.007,
            turn_scale_error=0.035,
        )


def odometry_from_truth(
    truth: ArrayLike, noise: OdometryNoise, rng: np.random.Generator
) -> NDArray[np.float64]:
    """Simulate the odometry pose sequence a robot reports while following ``truth``.

    Parameters
    ----------
    truth : array-like, shape (T, 3)
        True poses ``(x, y, theta)`` at the scan times.
    noise : OdometryNoise
        The error model.
    rng : numpy.random.Generator
        Source of the random errors.

    Returns
    -------
    ndarray, shape (T, 3)
        Odometry poses, starting exactly at ``truth[0]``.
    """
    truth = np.asarray(truth, dtype=float)
    if truth.ndim != 2 or truth.shape[1] != 3 or len(truth) == 0:
        raise ValueError(f"truth must have shape (T, 3) with T >= 1, got {truth.shape}")
    if not np.all(np.isfinite(truth)):
        raise ValueError("truth contains non-finite poses")

    # Each true step in the robot frame, split into rotate - translate - rotate.
    step = relative(truth[:-1], truth[1:])  # (T-1, 3)
    trans = np.hypot(step[:, 0], step[:, 1])
    moving = trans > 1e-9
    rot1 = np.where(moving, np.arctan2(step[:, 1], step[:, 0]), 0.0)
    rot2 = wrap_angle(step[:, 2] - rot1)

    # Table 5.6: sample(b^2) draws zero-mean noise of variance b^2.
    def sample(variance: NDArray[np.float64]) -> NDArray[np.float64]:
        return rng.normal(0.0, 1.0, size=variance.shape) * np.sqrt(variance)

    rot1_n = rot1 - sample(noise.alpha1 * rot1**2 + noise.alpha2 * trans**2)
    trans_n = trans - sample(noise.alpha3 * trans**2 + noise.alpha4 * (rot1**2 + rot2**2))
    rot2_n = rot2 - sample(noise.alpha1 * rot2**2 + noise.alpha2 * trans**2)

    # Systematic errors: wrong distance and rotation scales, heading creeping with distance.
    trans_n = trans_n * (1.0 + noise.scale_error)
    rot1_n = rot1_n * (1.0 + noise.turn_scale_error)
    rot2_n = rot2_n * (1.0 + noise.turn_scale_error) + noise.heading_bias * trans

    # Chain the noisy steps from the true start pose.
    steps = np.column_stack(
        [trans_n * np.cos(rot1_n), trans_n * np.sin(rot1_n), wrap_angle(rot1_n + rot2_n)]
    )
    odom = np.empty_like(truth)
    odom[0] = truth[0]
    for k, s in enumerate(steps, start=1):
        odom[k] = compose(odom[k - 1], s)
    return odom
