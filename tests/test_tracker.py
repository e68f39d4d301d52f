"""Scan-to-map tracking (the default method's front end): odometry glitches survived."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from fhslam.geometry import compose, inverse
from fhslam.metrics import ate
from fhslam.pipeline import run_slam
from fhslam.sim import load_world, simulate
from fhslam.slam.tracker import TrackerParams


@pytest.fixture(scope="module")
def paper_log():
    return simulate(load_world("paper"), seed=3)


def _glitch(log, k, extra):
    """The odometry from scan ``k`` on moved by ``extra`` (x, y, θ) at scan ``k - 1``: the
    increment into scan ``k`` is ``extra ⊕ true increment``, every later one is unchanged."""
    odo = log.odometry.copy()
    a = compose(odo[k - 1], compose(np.asarray(extra, float), inverse(odo[k - 1])))
    odo[k:] = compose(a, odo[k:])
    return replace(log, odometry=odo)


@pytest.mark.parametrize(
    "extra",
    [(0.0, 0.0, np.radians(60)), (0.0, 0.0, np.radians(-35)), (0.6, -0.3, 0.0)],
    ids=["turn+60", "turn-35", "jump-0.67m"],
)
def test_an_odometry_glitch_is_absorbed(paper_log, extra):
    clean = ate(run_slam(paper_log, "graph").poses, paper_log.truth).rmse
    log = _glitch(paper_log, len(paper_log) // 3, extra)
    odometry = ate(log.odometry, log.truth).rmse
    r = run_slam(log, "graph")
    got = ate(r.poses, log.truth).rmse
    assert odometry > 0.5  # the glitch alone throws dead reckoning off by 0.65-7.9 m
    assert got <= max(0.03, 1.5 * clean)  # measured: clean 3.7 cm, glitched 0.8-2.7 cm


def test_tracker_parameters_are_checked():
    with pytest.raises(ValueError, match="resolution must be > 0"):
        TrackerParams(resolution=0.0)
    with pytest.raises(ValueError, match=r"min_score must be in \[0, 1\]"):
        TrackerParams(min_score=2.0)
    with pytest.raises(ValueError, match="prior_sigma must be two values > 0"):
        TrackerParams(prior_sigma=(0.05, 0.0))
    with pytest.raises(ValueError, match="residual_sigma must be > 0"):
        TrackerParams(residual_sigma=-1.0)
