"""Thirty scans in a row missing from a log (3 s of a 10 Hz laser, 1-3 m of travel): the
default SLAM must pick the track up where the odometry puts the robot, and end as well as
without the gap (the 2 cm ATE limit of a simulated world).

Each built-in world with a closed route is driven twice (seed 0, the default odometry), and
the scans after ``fraction`` of the run are cut out; the odometry between the scans either
side is whole (a log with scans missing, as a CARMEN log that lost laser messages).

Two gaps fail (strict xfail: the day they pass, this file must say so). After each, the
odometry's increment is longer than a robot moves between two scans at a laser's rate, so
the tracker takes it for a glitch and also searches around the previous pose (the robot stood
still), and a match there wins: in the ``offices`` a weak one (score 0.45 against 0.32 at the
odometry's pose, neither sure) with the robot a quarter turn off, which nothing later turns
back (ATE 6.7 m); in the pillared ``hall`` a sure one (0.95) one pillar period behind, 3 m
off the odometry (1.7 m). Requiring the stood-still match to be sure mends the first only
(and makes the Freiburg hospital's sparse copy worse, 0.98 -> 1.37 m); telling a glitch from
a gap needs the time between the scans, which the SLAM's step is not given.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from fhslam.metrics import ate
from fhslam.pipeline import run_slam
from fhslam.sim import load_world, simulate

GAP = 30
"""Scans missing in a row."""
LIMIT_M = 0.02
"""The ATE limit of a simulated world."""

FAILING = {
    ("offices", 0.3): "a weak stood-still match a quarter turn off wins (ATE 6.7 m)",
    ("hall", 0.65): "a sure stood-still match one pillar period back wins (ATE 1.7 m)",
}


def without_scans(log, start: int, n: int):
    """``log`` with scans ``start + 1 .. start + n - 1`` cut out (the odometry of the rest as
    it was: the increment over the gap is whole)."""
    keep = np.ones(len(log.timestamps), bool)
    keep[start + 1 : start + n] = False
    return replace(
        log, timestamps=log.timestamps[keep], ranges=log.ranges[keep],
        odometry=log.odometry[keep], truth=log.truth[keep],
        hits=None if log.hits is None else log.hits[keep],
    )  # fmt: skip


CASES = [
    pytest.param(
        world,
        fraction,
        marks=[pytest.mark.xfail(strict=True, reason=FAILING[(world, fraction)])]
        if (world, fraction) in FAILING
        else [],
        id=f"{world}-{fraction}",
    )
    for world, fractions in (
        ("offices", (0.2, 0.3, 0.5, 0.65)),
        ("hall", (0.2, 0.35, 0.5, 0.65)),
        ("corridor", (0.2, 0.35, 0.5, 0.65)),
    )
    for fraction in fractions
]


@pytest.mark.parametrize(("world", "fraction"), CASES)
def test_a_gap_of_thirty_scans_leaves_no_lasting_error(world, fraction):
    log = simulate(load_world(world), seed=0, laps=2)
    start = int(fraction * len(log.timestamps))
    gapped = without_scans(log, start, GAP)
    assert len(gapped.timestamps) == len(log.timestamps) - GAP + 1
    travelled = np.hypot(*(log.truth[start + GAP, :2] - log.truth[start, :2]))
    assert travelled >= 1.0  # the gap is metres of travel, not a pause
    assert ate(run_slam(gapped).poses, gapped.truth).rmse <= LIMIT_M
