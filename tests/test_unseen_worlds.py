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


PAPER_WORLD_MISSES = {
    209544132: "3.98 cm (the paper's procedure 3.20 cm): the 2 cm limit",
    147531616: "5.23 cm where the paper's procedure is at 1.99 cm: the 2 cm limit",
    1783398030: "3.60 cm (the paper's procedure 2.15 cm): the 2 cm limit",
}
"""Paper-world seeds drawn by ``fhslam benchmark`` (209544132 with ``--draw-seed 3209647287``,
147531616 and 1783398030 with ``--draw-seed 1711281636``) on which the default misses the
limit by over a centimetre, in every frame alike; all three go wrong in the 2 m corridor
(y 6-8 m) just after turning east into it."""


@pytest.mark.parametrize(
    "seed",
    [
        pytest.param(s, marks=pytest.mark.xfail(strict=True, reason=r))
        for s, r in PAPER_WORLD_MISSES.items()
    ],
)
def test_a_paper_world_log_nobody_picked_meets_the_limit(seed):
    """A paper world at the ``medium`` odometry noise, drawn by the benchmark: the default
    within 2 cm (of the eight seeds of draw seed 3209647287 three end over it: 2.11, 2.26 and
    3.98 cm; of those of 1711281636 two: 3.60 and 5.23 cm)."""
    from fhslam.experiments.compare import one_run

    (graph,) = one_run("paper", "medium", seed, ("graph",))
    assert graph.odometry_ate_rmse > 1.0  # the odometry drifts metres
    assert graph.ate_rmse <= 0.02
