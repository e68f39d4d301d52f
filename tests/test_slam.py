"""Loop 3: pose calibration from matched lines, and FH-SLAM runs on simulated worlds."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fhslam.calibration import calibrate_pose
from fhslam.geometry import compose, inverse, wrap_angle
from fhslam.lines import line_from_points
from fhslam.pipeline import run_slam
from fhslam.scan import Scan
from fhslam.slam import FastHoughSLAM


def seg(x0, y0, x1, y1, n=40):
    t = np.linspace(0, 1, n)[:, None]
    return line_from_points(np.array([x0, y0]) + t * np.array([x1 - x0, y1 - y0]))


ROOM_LINES = [seg(0, 0, 6, 0), seg(6, 0, 6, 4), seg(6, 4, 0, 4), seg(0, 4, 0, 0)]
CORRIDOR = [seg(0, 0, 10, 0), seg(0, 2, 10, 2)]


def observe(world_lines, pose):
    """The world lines as the robot at ``pose`` sees them (robot frame)."""
    return [ln.transformed(inverse(pose)) for ln in world_lines]


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    dx=st.floats(-0.3, 0.3),
    dy=st.floats(-0.3, 0.3),
    dth=st.floats(-0.08, 0.08),
    x=st.floats(1.5, 4.5),
    y=st.floats(1.0, 3.0),
    th=st.floats(-np.pi, np.pi),
)
def test_calibration_recovers_a_known_pose_offset(dx, dy, dth, x, y, th):
    """< 1 cm and < 0.1° from offsets up to 30 cm and 4.6°."""
    truth = np.array([x, y, th])
    observed = observe(ROOM_LINES, truth)
    predicted = compose(truth, (dx, dy, dth))
    pairs = [(i, i) for i in range(4)]
    cal = calibrate_pose(observed, ROOM_LINES, pairs, predicted, iterations=5)
    assert np.hypot(*(cal.pose[:2] - truth[:2])) < 0.01
    assert abs(np.degrees(wrap_angle(cal.pose[2] - truth[2]))) < 0.1
    assert cal.constrained == (True, True) and cal.n_pairs == 4


def test_corridor_keeps_odometry_along_it():
    truth = np.array([5.0, 1.0, 0.0])
    predicted = truth + np.array([0.4, 0.1, 0.02])  # 40 cm wrong along the corridor
    cal = calibrate_pose(observe(CORRIDOR, truth), CORRIDOR, [(0, 0), (1, 1)], predicted)
    assert cal.pose[1] == pytest.approx(1.0, abs=1e-3)  # across: corrected
    assert cal.pose[2] == pytest.approx(0.0, abs=1e-4)  # heading: corrected
    assert cal.pose[0] == pytest.approx(5.4, abs=1e-3)  # along: odometry kept, not invented
    assert cal.constrained == (False, True)


def test_no_pairs_keeps_the_prediction():
    cal = calibrate_pose([], ROOM_LINES, [], (1, 2, 0.3))
    np.testing.assert_array_equal(cal.pose, [1, 2, 0.3])
    assert cal.n_pairs == 0


def test_dropped_scans_and_empty_scans_keep_odometry():
    slam = FastHoughSLAM(initial_pose=(0, 0, 0))
    r = slam.step(None, (0, 0, 0))
    assert r.n_lines == 0 and not r.corrected
    r = slam.step(Scan(np.full(181, np.nan), np.radians(np.arange(-90, 91.0))), (1.0, 0.5, 0.1))
    np.testing.assert_allclose(r.pose, [1.0, 0.5, 0.1])
    assert r.n_lines == 0 and slam.references == []


def test_unknown_method_is_a_clear_error(paper_log_small):
    with pytest.raises(ValueError, match="unknown SLAM method 'ekf2'"):
        run_slam(paper_log_small, "ekf2")


def test_perfect_odometry_stays_on_the_truth(paper_log_perfect):
    r = run_slam(paper_log_perfect, "fht")
    err = np.hypot(*(r.poses[:, :2] - paper_log_perfect.truth[:, :2]).T)
    assert np.sqrt(np.mean(err**2)) < 0.02  # FH-SLAM must not corrupt a correct pose


# --------------------------------------------------------------------------- acceptance

HELD_OUT = ("random:101", "random:106", "random:109", "random:118")
"""Worlds FH-SLAM was not tuned on (it was developed on the paper world only)."""


def _run(name, laps, degraded=False):
    from fhslam.metrics import ate, map_coverage, map_error
    from fhslam.sim import OdometryNoise, degrade, load_world, observed_wall_points, simulate

    log = simulate(load_world(name), seed=0, odometry=OdometryNoise.drifting(), laps=laps)
    if degraded:
        log = degrade(log, drop_fraction=0.1, clutter_fraction=0.05, seed=1)
    r = run_slam(log, "fht")
    return {
        "ate": ate(r.poses, log.truth).rmse,
        "odometry_ate": ate(log.odometry, log.truth).rmse,
        "drift": np.hypot(*(log.odometry[:, :2] - log.truth[:, :2]).T).max(),
        "map_error": map_error(r.map, log.world.walls),
        "coverage": map_coverage(r.map, observed_wall_points(log)),
    }


@pytest.mark.parametrize("world", HELD_OUT)
def test_fh_slam_on_held_out_worlds_meets_its_limits(world):
    m = _run(world, laps=3)
    assert 2.0 <= m["drift"] <= 6.0  # the odometry really drifts 2-6 m
    assert m["ate"] <= 0.15 and m["ate"] <= 0.2 * m["odometry_ate"]
    assert m["map_error"] <= 0.05
    assert m["coverage"] >= 0.80


@pytest.mark.parametrize(("world", "laps"), [("paper", 1)] + [(w, 3) for w in HELD_OUT])
def test_dropped_scans_and_clutter_at_most_double_the_ate(world, laps):
    """10% of scans dropped and 5% clutter returns (short of the wall). Over all 20 held-out
    worlds the ratio has median 1.2; on 2 of them it reaches 2.5 (2-3 mm clean, 6-8 mm)."""
    clean, bad = _run(world, laps), _run(world, laps, degraded=True)
    assert bad["ate"] <= 2.0 * clean["ate"]
    assert bad["ate"] <= 0.15


def test_laser_mounted_off_the_robot_origin_reports_robot_poses():
    """A log whose scans come from a laser 0.25 m ahead of the robot's origin."""
    from dataclasses import replace

    from fhslam.metrics import ate
    from fhslam.sim import OdometryNoise, paper_world, simulate

    offset = np.array([0.25, 0.0, 0.0])  # robot_T_laser
    sim = simulate(paper_world(), seed=1, odometry=OdometryNoise.drifting(), max_scans=400)
    # The simulated poses are the laser's; the robot sits 0.25 m behind it.
    robot_truth = compose(sim.truth, inverse(offset))
    log = replace(sim, odometry=compose(sim.odometry, inverse(offset)), truth=robot_truth,
                  laser_offset=offset)  # fmt: skip
    with_offset = ate(run_slam(log, "fht").poses, robot_truth).rmse
    ignoring = ate(run_slam(replace(log, laser_offset=None), "fht").poses, robot_truth).rmse
    assert with_offset < 0.05
    assert with_offset < 0.5 * ignoring  # pretending the laser is at the origin is worse
