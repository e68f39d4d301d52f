"""The default SLAM on worlds nobody tuned on (held-out simulated worlds, in any frame:
ATE ≤ 3 cm).

``random:300`` … ``random:303`` were drawn for this test and used for nothing else: no
default was chosen by looking at them. Each is driven three laps with drifting odometry
(2–6 m off), its frame moved by (−3.3, 2.1) m and turned 37°, with 1 mm of noise on every
range and 10 % of the scans dropped — the hardest of the robustness conditions, all at
once. Measured: ATE 0.33, 0.37, 0.52 and 0.43 cm; the same four conditions over
``random:300`` … ``random:339`` stay within 0.30–0.92 cm. The bound is the 3 cm limit for a
simulated world, not the measurement: the test says the defaults generalise, not that these
four numbers hold to the last bit.
"""

from __future__ import annotations

import numpy as np
import pytest

from fhslam.metrics import ate
from fhslam.pipeline import run_slam
from fhslam.sim import degrade, load_world, simulate, transform_world
from fhslam.sim.odometry import OdometryNoise

LIMIT_M = 0.03
"""The ATE limit for held-out simulated worlds, in any frame."""


@pytest.mark.parametrize("world", [f"random:{s}" for s in range(300, 304)])
def test_the_default_slam_meets_the_limit_on_unseen_worlds_moved_noisy_and_dropped(world):
    moved = transform_world(load_world(world), (-3.3, 2.1, np.radians(37.0)))
    log = simulate(moved, seed=0, odometry=OdometryNoise.drifting(), laps=3)
    log = degrade(log, range_noise=0.001, drop_fraction=0.1, seed=0)
    # the odometry alone is metres off: the SLAM has work to do
    assert ate(log.odometry, log.truth).rmse > 0.5
    assert ate(run_slam(log).poses, log.truth).rmse <= LIMIT_M


@pytest.mark.xfail(strict=True, reason="3.98 cm (the paper's procedure 3.20 cm): the 2 cm limit")
def test_a_paper_world_log_nobody_picked_meets_the_limit():
    """Seed 209544132 of the paper world at the ``medium`` odometry noise, one of the eight
    the benchmark seeded 3209647287 drew (``fhslam benchmark --draw-seed 3209647287``; three
    of them end over 2 cm: 2.11, 2.26 and this one's 3.98 cm, in every frame alike)."""
    from fhslam.experiments.compare import one_run

    (graph,) = one_run("paper", "medium", 209544132, ("graph",))
    assert graph.odometry_ate_rmse > 1.0  # the odometry drifts metres
    assert graph.ate_rmse <= 0.02
