"""Tests of the CARMEN log and trajectory file readers and writers."""

from __future__ import annotations

import os
import re
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from fhslam.geometry import compose
from fhslam.io import (
    CarmenFormatError,
    Log,
    TrajectoryFormatError,
    flaser_angles,
    read_carmen,
    read_trajectory,
    write_carmen,
    write_trajectory,
)
from fhslam.io.carmen import CarmenWarning
from fhslam.io.log import no_return_reading
from fhslam.sim import LaserParams, paper_world, simulate


def data_file(name: str) -> Path:
    """A shared dataset: ``$FHSLAM_DATA/name`` or ``../shared/data/name`` beside the repo."""
    folders = [Path(os.environ["FHSLAM_DATA"])] if os.environ.get("FHSLAM_DATA") else []
    folders.append(Path(__file__).resolve().parents[2] / "shared" / "data")
    for folder in folders:
        if (folder / name).is_file():
            return folder / name
    pytest.skip(f"dataset {name} not found in {', '.join(map(str, folders))} (set $FHSLAM_DATA)")


@pytest.fixture(scope="module")
def sim_log() -> Log:
    return simulate(paper_world(), seed=0, max_scans=60)


def test_round_trip_is_exact(sim_log, tmp_path):
    path = tmp_path / "paper.clf"
    write_carmen(sim_log, path)
    back = read_carmen(path)
    assert back.name == "paper" and len(back) == 60
    for field in ("timestamps", "ranges", "angles", "odometry"):
        assert np.array_equal(getattr(back, field), getattr(sim_log, field)), field
    assert back.max_range == 8.0
    assert back.truth is None and back.hits is None and back.world is None


def test_written_log_carries_odometry_not_truth(sim_log, tmp_path):
    path = tmp_path / "paper.clf"
    write_carmen(sim_log, path)
    lines = path.read_text().splitlines()
    assert lines[0].startswith("#")
    flaser = [ln.split() for ln in lines if ln.startswith("FLASER")]
    odom = [ln.split() for ln in lines if ln.startswith("ODOM")]
    assert len(flaser) == len(odom) == 60
    k = 40  # a scan after the odometry has drifted from the truth
    assert not np.allclose(sim_log.odometry[k], sim_log.truth[k])
    fields = flaser[k]
    assert fields[1] == "181" and len(fields) == 181 + 11
    pose = np.array(fields[183:189], dtype=float)
    assert np.array_equal(pose, np.r_[sim_log.odometry[k], sim_log.odometry[k]])
    assert fields[-2] == "fhslam" and fields[-1] == fields[-3] == repr(float(sim_log.timestamps[k]))
    assert np.array_equal(np.array(odom[k][1:4], dtype=float), sim_log.odometry[k])


def test_other_fields_of_view_round_trip_through_robotlaser1(tmp_path):
    laser = LaserParams(n_beams=271, fov_deg=270.0, max_range=10.0)
    log = simulate(paper_world(), seed=2, laser=laser, max_scans=5)
    path = tmp_path / "wide.clf"
    write_carmen(log, path)
    assert "ROBOTLASER1" in path.read_text()
    back = read_carmen(path)
    for field in ("timestamps", "ranges", "odometry"):
        assert np.array_equal(getattr(back, field), getattr(log, field)), field
    np.testing.assert_allclose(back.angles, log.angles, rtol=0, atol=1e-12)
    assert back.max_range == 10.0


@pytest.mark.parametrize(
    ("n", "step_deg", "last_deg"),
    [(181, 1.0, 90.0), (180, 1.0, 89.0), (361, 0.5, 90.0), (360, 0.5, 89.5), (401, 0.25, 10.0),
     (91, 2.0, 90.0)],
)  # fmt: skip
def test_flaser_angles_follow_carmens_guess(n, step_deg, last_deg):
    """CARMEN's carmen_laser_guess_angle_increment: from -90° in 1° (180/181 beams), 0.5°
    (360/361), 0.25° (400/401) steps; any other count spreads over 180°."""
    a = flaser_angles(n)
    assert a[0] == -np.pi / 2
    np.testing.assert_allclose(np.diff(a), np.radians(step_deg), rtol=0, atol=1e-12)
    assert np.degrees(a[-1]) == pytest.approx(last_deg, abs=1e-9)
    if n in (181, 361):
        assert a[-1] == np.pi / 2  # exactly, as the simulator's beams


def test_clf_and_converted_bags_share_one_bearing_rule():
    """A bag converted from a 180-beam FLASER log (increment π/179 as the converter wrote
    it) gets the same bearings as the FLASER line itself."""
    from fhslam.io import rosbag

    assert rosbag.flaser_angles is flaser_angles


def test_read_mit_csail():
    log = read_carmen(data_file("mit-csail.clf"))
    assert len(log) == 1988 and log.ranges.shape == (1988, 361)
    np.testing.assert_allclose(np.diff(log.angles), np.radians(0.5), atol=1e-12)
    # First FLASER line of the file.
    assert log.timestamps[0] == 1134864629.895182
    assert log.odometry[0].tolist() == [576.536523, 0.106594, -2.255213]
    assert log.ranges[0, :3].tolist() == [1.40, 1.39, 1.39]
    assert log.max_range == pytest.approx(81.91)  # the log's "no return" reading
    assert log.timestamps[-1] - log.timestamps[0] == pytest.approx(424.0, abs=0.05)
    assert np.all(np.diff(log.timestamps) > 0)


# ---------------------------------------------------------------------------- hand-made logs

GOOD = """\
# a small log
PARAM robot_front_laser_max 8.0 0.0 host 0.0

ODOM 0.0 0.0 0.0 0.0 0.0 0.0 0.5 host 0.5
FLASER 5 1.0 1.5 2.0 2.5 3.0 0.0 0.0 0.0 0.0 0.0 0.0 1.0 host 1.0
SYNC something 1.1 host 1.1
FLASER 5 1.1 1.6 2.1 2.6 3.1 0.1 0.0 0.01 0.1 0.0 0.01 1.2 host 1.2
FLASER 5 1.2 1.7 2.2 2.7 3.2 0.2 0.0 0.02 0.2 0.0 0.02 1.4 host 1.4
"""


def test_read_skips_comments_blank_lines_and_other_messages(tmp_path):
    path = tmp_path / "small.clf"
    path.write_text(GOOD)
    log = read_carmen(path)
    assert log.timestamps.tolist() == [1.0, 1.2, 1.4]
    assert log.ranges.shape == (3, 5) and log.ranges[2].tolist() == [1.2, 1.7, 2.2, 2.7, 3.2]
    assert log.odometry[1].tolist() == [0.1, 0.0, 0.01]
    assert np.array_equal(log.angles, np.linspace(-np.pi / 2, np.pi / 2, 5))
    assert log.max_range == 80.0  # no "no return" code: CARMEN's FLASER default
    assert read_carmen(path, max_range=4.0).max_range == 4.0


# (replacement for line 7 of GOOD, expected message fragment)
BAD_LINES = {
    "truncated": ("FLASER 5 1.1 1.6 2.1", "truncated FLASER line"),
    "truncated tail": ("FLASER 5 1.1 1.6 2.1 2.6 3.1 0.1 0.0 0.01 0.1", "truncated"),
    "non-numeric range": (
        "FLASER 5 1.1 1.6 abc 2.6 3.1 0.1 0.0 0.01 0.1 0.0 0.01 1.2 host 1.2",
        "non-numeric range reading 'abc'",
    ),
    "non-numeric count": (
        "FLASER five 1.1 1.6 2.1 2.6 3.1 0.1 0.0 0.01 0.1 0.0 0.01 1.2 host 1.2",
        "num_readings must be an integer",
    ),
    "wrong count": (
        "FLASER 6 1.1 1.6 2.1 2.6 3.1 0.1 0.0 0.01 0.1 0.0 0.01 1.2 host 1.2",
        "wrong reading count: FLASER num_readings is 6 but the line holds 5",
    ),
    "nan pose": (
        "FLASER 5 1.1 1.6 2.1 2.6 3.1 0.1 0.0 0.01 nan 0.0 0.01 1.2 host 1.2",
        "non-finite pose",
    ),
    "inf timestamp": (
        "FLASER 5 1.1 1.6 2.1 2.6 3.1 0.1 0.0 0.01 0.1 0.0 0.01 inf host 1.2",
        "non-finite ipc_timestamp",
    ),
    "beam count changes": (
        "FLASER 4 1.1 1.6 2.1 2.6 0.1 0.0 0.01 0.1 0.0 0.01 1.2 host 1.2",
        "has 4 readings but the first scan \\(line 5\\) has 5",
    ),
}


@pytest.mark.parametrize("case", list(BAD_LINES))
def test_malformed_lines_name_file_and_line(tmp_path, case):
    replacement, fragment = BAD_LINES[case]
    lines = GOOD.splitlines()
    assert lines[6].startswith("FLASER")  # line 7 of the file
    lines[6] = replacement
    path = tmp_path / "broken.clf"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(CarmenFormatError, match=rf"^{re.escape(str(path))}:7: .*{fragment}"):
        read_carmen(path)


def test_file_without_laser_messages(tmp_path):
    path = tmp_path / "odom_only.clf"
    path.write_text("# header\nODOM 0 0 0 0 0 0 1.0 host 1.0\n")
    with pytest.raises(CarmenFormatError, match=r"odom_only\.clf: no FLASER or ROBOTLASER1"):
        read_carmen(path)


def test_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"missing\.clf"):
        read_carmen(tmp_path / "missing.clf")


def test_binary_file_is_a_format_error(tmp_path):
    path = tmp_path / "data.bag"
    path.write_bytes(b"#ROSBAG V2.0\n\xff\xfe\x00\x01" * 10)
    with pytest.raises(CarmenFormatError, match=r"data\.bag: not a CARMEN text log"):
        read_carmen(path)


def robotlaser1(ranges, remissions, robot_pose, stamp, laser_pose=(9, 9, 9)):
    """A ROBOTLASER1 line: start -90 deg, fov 180, resolution 45 deg, max range 20 m."""
    head = f"ROBOTLASER1 0 {-np.pi / 2!r} {np.pi!r} {np.pi / 4!r} 20.0 0.01 0 {len(ranges)}"
    rem = "" if remissions is None else f" {len(remissions)} " + " ".join(map(str, remissions))
    pose = " ".join(map(str, robot_pose))
    laser = " ".join(map(str, laser_pose))
    return (
        f"{head} {' '.join(map(str, ranges))}{rem} {laser} {pose} 0.1 0.0 0.5 0.3 0.0 "
        f"{stamp} host {stamp}"
    )


def test_read_robotlaser1_with_and_without_remissions(tmp_path):
    path = tmp_path / "robot.clf"
    path.write_text(
        "ODOM 0 0 0 0 0 0 0.9 host 0.9\n"
        + robotlaser1([1, 2, 3, 4, 5], [7, 7, 7, 7, 7], [1.0, 2.0, 0.5], 1.0)
        + "\n"
        + robotlaser1([2, 3, 4, 5, 6], None, [1.5, 2.0, 0.5], 2.0)
        + "\n"
        + robotlaser1([3, 4, 5, 6, 7], [], [2.0, 2.0, 0.5], 3.0)
        + "\n"
    )
    log = read_carmen(path)
    assert log.timestamps.tolist() == [1.0, 2.0, 3.0]
    assert log.odometry.tolist() == [[1.0, 2.0, 0.5], [1.5, 2.0, 0.5], [2.0, 2.0, 0.5]]
    assert log.ranges[1].tolist() == [2, 3, 4, 5, 6]
    np.testing.assert_allclose(log.angles, np.radians([-90, -45, 0, 45, 90]), atol=1e-12)
    assert log.max_range == 20.0


def test_robotlaser1_wrong_count(tmp_path):
    line = robotlaser1([1, 2, 3, 4, 5], [7, 7, 7], [1.0, 2.0, 0.5], 1.0)
    path = tmp_path / "robot.clf"
    path.write_text("# c\n" + line.replace(" 0 5 ", " 0 6 ", 1) + "\n")
    with pytest.raises(CarmenFormatError, match=r"robot\.clf:2: "):
        read_carmen(path)


# ---------------------------------------------------------------------------- trajectories


def test_trajectory_round_trip_is_exact(sim_log, tmp_path):
    path = tmp_path / "truth.txt"
    write_trajectory(path, sim_log.timestamps, sim_log.truth, header="ground truth\nworld paper")
    text = path.read_text().splitlines()
    assert text[:2] == ["# ground truth", "# world paper"]
    t, poses = read_trajectory(path)
    assert np.array_equal(t, sim_log.timestamps) and np.array_equal(poses, sim_log.truth)


@pytest.mark.parametrize(
    ("line", "fragment"),
    [
        ("0.2 1.0 2.0", "expected 4 fields"),
        ("0.2 1.0 two 0.0", "non-numeric value 'two'"),
        ("0.2 1.0 2.0 nan", "non-finite value"),
    ],
)
def test_trajectory_errors_name_file_and_line(tmp_path, line, fragment):
    path = tmp_path / "traj.txt"
    path.write_text(f"# header\n0.0 0 0 0\n\n{line}\n")
    with pytest.raises(TrajectoryFormatError, match=rf"traj\.txt:4: {fragment}"):
        read_trajectory(path)


def test_trajectory_empty_and_missing(tmp_path):
    path = tmp_path / "empty.txt"
    path.write_text("# nothing\n")
    with pytest.raises(TrajectoryFormatError, match=r"empty\.txt: no poses"):
        read_trajectory(path)
    with pytest.raises(FileNotFoundError, match=r"absent\.txt"):
        read_trajectory(tmp_path / "absent.txt")
    with pytest.raises(ValueError, match="poses must have shape"):
        write_trajectory(path, [0.0, 1.0], [[0.0, 0.0, 0.0]])


# ---------------------------------------------------------------------------- max range


def _flaser_log(rows: list[list[float]]) -> str:
    return "".join(
        f"FLASER {len(r)} {' '.join(map(str, r))} 0 0 0 0 0 0 {k + 1}.0 host {k + 1}.0\n"
        for k, r in enumerate(rows)
    )


def test_no_return_code_below_noisy_long_returns_is_found(tmp_path):
    """A log whose no-return code (50.0 m) is exceeded by a few noisy real readings: the
    code, not the largest reading, is the maximum range, so no-return beams give no points
    (not a max range of 50.3 m and a phantom arc of points at 50 m)."""
    rng = np.random.default_rng(0)
    rows = []
    for k in range(400):
        r = np.round(rng.uniform(0.5, 12.0, 181), 2)
        r[rng.random(181) < 0.2] = 50.0  # no return
        if k % 50 == 0:
            r[90] = 50.3 + 0.01 * (k // 50)  # a rare, noisy long return
        rows.append(r.tolist())
    path = tmp_path / "code50.clf"
    path.write_text(_flaser_log(rows))
    log = read_carmen(path)
    assert log.max_range == 50.0
    assert no_return_reading(log.ranges) == 50.0
    pts = [log.scan(k).points()[0] for k in range(len(log))]
    assert max(np.hypot(*p.T).max() for p in pts) < 12.0 + 1e-9  # no phantom at 50 m


def test_the_lowest_of_two_codes_is_the_maximum_range():
    """The Freiburg hospital codes no return as 81.83 and 81.91 m."""
    rng = np.random.default_rng(1)
    r = np.round(rng.uniform(0.3, 30.0, (300, 180)), 2)
    r[rng.random(r.shape) < 0.10] = 81.91
    r[rng.random(r.shape) < 0.01] = 81.83
    assert no_return_reading(r) == 81.83


@pytest.mark.parametrize(
    "ranges",
    [
        np.array([[1.0, 1.5, 2.0, 2.5, 3.0], [1.1, 1.6, 2.1, 2.6, 3.1]]),  # all distinct
        np.round(np.random.default_rng(2).uniform(0.2, 7.9, (50, 181)), 3),  # no code
        np.full((2, 3), np.nan),  # nothing valid
    ],
)
def test_logs_without_a_code_have_none(ranges):
    assert no_return_reading(ranges) is None


def test_max_range_can_be_overridden_and_is_reported(tmp_path):
    path = tmp_path / "small.clf"
    path.write_text(GOOD)
    assert read_carmen(path, max_range=2.05).max_range == 2.05
    assert len(read_carmen(path, max_range=2.05).scan(0).points()[0]) == 3  # 1.0 1.5 2.0


# ---------------------------------------------------------------------------- laser mount

ODOM_PATH = np.array(
    [[0.0, 0.0, 0.0], [1.0, 0.1, 0.3], [1.8, 0.6, 1.2], [2.0, 1.5, 2.4], [1.4, 2.1, 3.1],
     [0.6, 2.0, -2.9]]
)  # fmt: skip
"""Odometry of the hand-made mount logs: it turns through ±π, so a wrongly composed or
unwrapped offset shows."""

MOUNT = np.array([0.22, -0.05, 0.1])


def _pose(p) -> str:
    return " ".join(f"{v:f}" for v in p)  # CARMEN's %f: 6 decimals


def mount_log(laser_poses, odometry=ODOM_PATH, params: str = "", n: int = 5) -> str:
    """A FLASER log: ``params`` (PARAM lines) then one line per pose pair, CARMEN style."""
    lines = [params] if params else []
    for k, (laser, odom) in enumerate(zip(laser_poses, odometry, strict=True)):
        ranges = " ".join(f"{1.0 + 0.5 * b + 0.01 * k:.2f}" for b in range(n))
        t = f"{100.0 + 0.2 * k:f}"
        lines.append(f"FLASER {n} {ranges} {_pose(laser)} {_pose(odom)} {t} host {t}")
    return "\n".join(lines) + "\n"


def _read_quietly(path: Path) -> Log:
    """read_carmen, failing the test on any warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return read_carmen(path)


def test_mount_from_the_flaser_laser_poses(tmp_path):
    """No PARAM: the laser poses sit at one constant offset from the odometry (to CARMEN's
    printed precision), so that offset is the mount."""
    path = tmp_path / "mounted.clf"
    path.write_text(mount_log(compose(ODOM_PATH, MOUNT)))
    log = _read_quietly(path)
    np.testing.assert_allclose(log.laser_offset, MOUNT, rtol=0, atol=5e-6)
    assert log.laser_offset_source == "laser pose"
    np.testing.assert_allclose(log.odometry, ODOM_PATH, rtol=0, atol=1e-12)  # not the laser's


def test_a_rear_facing_mount_across_the_angle_wrap(tmp_path):
    """A laser looking backwards: its offset angle is ±π, which must not read as varying."""
    mount = np.array([-0.3, 0.0, np.pi])
    path = tmp_path / "rear.clf"
    path.write_text(mount_log(compose(ODOM_PATH, mount)))
    log = _read_quietly(path)
    np.testing.assert_allclose(log.laser_offset[:2], mount[:2], rtol=0, atol=5e-6)
    assert abs(abs(log.laser_offset[2]) - np.pi) < 5e-6
    assert log.laser_offset_source == "laser pose"


def test_mount_from_param_lines(tmp_path):
    """PARAM lines state the mount; here the laser poses agree with it (CARMEN's robot
    module computed them from it), so no warning. The tail of a PARAM line may be short."""
    params = (
        "PARAM robot_frontlaser_offset 0.22 100.0 host 100.0\n"
        "PARAM robot_frontlaser_side_offset -0.05 nohost 0\n"
        "PARAM robot_frontlaser_angular_offset 0.1 100.0 host 100.0"
    )
    path = tmp_path / "param.clf"
    path.write_text(mount_log(compose(ODOM_PATH, MOUNT), params=params))
    log = _read_quietly(path)
    assert log.laser_offset.tolist() == [0.22, -0.05, 0.1]  # exactly the stated values
    assert log.laser_offset_source == "PARAM"


def test_param_mount_with_corrected_laser_poses(tmp_path):
    """Laser poses that are corrected poses (not odometry + a constant) say nothing about
    the mount and do not contradict the PARAM; an unstated PARAM component is 0."""
    rng = np.random.default_rng(0)
    corrected = ODOM_PATH + rng.normal(0, 0.2, ODOM_PATH.shape)
    path = tmp_path / "corrected.clf"
    path.write_text(mount_log(corrected, params="PARAM robot_frontlaser_offset 0.04 0 host 0"))
    log = _read_quietly(path)
    assert log.laser_offset.tolist() == [0.04, 0.0, 0.0]
    assert log.laser_offset_source == "PARAM"


def test_corrected_laser_poses_without_param_give_no_mount(tmp_path):
    """Laser poses off the odometry by 5 mm more on one scan than on the others: not a
    constant mount (the tolerance is 1 mm), so no offset at all."""
    laser = compose(ODOM_PATH, MOUNT)
    laser[3] = compose(ODOM_PATH[3], MOUNT + np.array([0.005, 0.0, 0.0]))
    path = tmp_path / "varying.clf"
    path.write_text(mount_log(laser))
    log = _read_quietly(path)
    assert log.laser_offset.tolist() == [0.0, 0.0, 0.0]
    assert log.laser_offset_source == "none"


def test_param_and_laser_poses_that_disagree_warn_and_param_wins(tmp_path):
    """A log rewritten by a program that copied the odometry into both triples, keeping
    the PARAM line of a laser 4 cm ahead of the robot's centre."""
    path = tmp_path / "disagree.clf"
    path.write_text(mount_log(ODOM_PATH, params="PARAM robot_frontlaser_offset 0.04 0 host 0"))
    with pytest.warns(CarmenWarning) as record:
        log = read_carmen(path)
    assert len(record) == 1
    message = str(record[0].message)
    assert str(path) in message and "line 1" in message
    assert "x 0.04 m" in message and "x 0 m" in message  # both values
    assert log.laser_offset.tolist() == [0.04, 0.0, 0.0]
    assert log.laser_offset_source == "PARAM"


def test_mount_from_robotlaser1(tmp_path):
    """ROBOTLASER1 lines carry laser_pose and robot_pose: a constant offset is the mount;
    the placeholder laser pose (9 9 9) of the other ROBOTLASER1 test is none."""
    odom = ODOM_PATH[:4]
    laser = compose(odom, [0.22, 0.0, 0.0])
    path = tmp_path / "robot.clf"
    path.write_text(
        "".join(
            robotlaser1([1, 2, 3, 4, 5], [7] * 5, [f"{v:f}" for v in o], 1.0 + k,
                        [f"{v:f}" for v in lp]) + "\n"
            for k, (o, lp) in enumerate(zip(odom, laser, strict=True))
        )
    )  # fmt: skip
    log = _read_quietly(path)
    np.testing.assert_allclose(log.laser_offset, [0.22, 0.0, 0.0], rtol=0, atol=5e-6)
    assert log.laser_offset_source == "laser pose"
    np.testing.assert_allclose(log.odometry, odom, rtol=0, atol=1e-6)

    placeholder = tmp_path / "placeholder.clf"
    placeholder.write_text(
        robotlaser1([1, 2, 3, 4, 5], None, [1.0, 2.0, 0.5], 1.0)
        + "\n"
        + robotlaser1([2, 3, 4, 5, 6], None, [1.5, 2.0, 0.5], 2.0)
        + "\n"
    )
    log = _read_quietly(placeholder)
    assert log.laser_offset.tolist() == [0.0, 0.0, 0.0] and log.laser_offset_source == "none"


def test_robotlaser1_ignores_the_flaser_resolution_param(tmp_path):
    path = tmp_path / "robot.clf"
    path.write_text(
        "PARAM laser_front_laser_resolution 1.0 0 host 0\n"
        + robotlaser1([1, 2, 3, 4, 5], None, [1.0, 2.0, 0.5], 1.0)
        + "\n"
    )
    log = _read_quietly(path)
    np.testing.assert_allclose(np.degrees(log.angles), [-90, -45, 0, 45, 90], atol=1e-9)


def test_read_mit_csail_has_no_mount_and_unchanged_bearings(real_data, monkeypatch):
    """mit-csail.clf has no PARAM lines and copies the odometry into the laser poses of all
    1988 FLASER lines: a mount of exactly zero, and CARMEN's default 0.5° bearings."""
    from fhslam.datasets import find_dataset

    monkeypatch.setenv("FHSLAM_DATA", str(real_data))
    path = find_dataset("mit-csail")
    if not path.is_file():  # pragma: no cover (find_dataset raises first)
        pytest.skip("mit-csail.clf not found")
    log = _read_quietly(path)
    assert len(log) == 1988
    assert log.laser_offset.tolist() == [0.0, 0.0, 0.0]
    assert log.laser_offset_source == "laser pose"
    assert np.array_equal(log.angles, flaser_angles(361))
    assert np.array_equal(log.angles, np.linspace(-np.pi / 2, np.pi / 2, 361))


# ---------------------------------------------------------------------------- beam layout


@pytest.mark.parametrize(
    ("params", "n", "degrees"),
    [
        ("PARAM laser_front_laser_resolution 10.0 0 host 0", 5, [-20, -10, 0, 10, 20]),
        # 4 beams 45° apart over 180°: the driver's last beam (+90°) is not sent
        ("PARAM laser_front_laser_resolution 45\nPARAM laser_front_laser_fov 180", 4,
         [-90, -45, 0, 45]),
        ("PARAM laser_front_laser_fov 100.0 0 host 0", 5, [-50, -25, 0, 25, 50]),
        # 180 beams at 1°: the same bearings as CARMEN's own guess
        ("PARAM laser_front_laser_resolution 1.0", 180, np.arange(-90.0, 90.0)),
        # 400 beams at 0.25°: a SICK in its 100° mode, centred (the guess says -90°..+10°)
        ("PARAM laser_front_laser_resolution 0.25", 400, -50 + 0.25 * np.arange(400)),
    ],
)  # fmt: skip
def test_resolution_and_fov_params_set_the_flaser_bearings(tmp_path, params, n, degrees):
    path = tmp_path / "layout.clf"
    path.write_text(mount_log(ODOM_PATH, params=params, n=n))
    log = _read_quietly(path)
    np.testing.assert_allclose(np.degrees(log.angles), degrees, rtol=0, atol=1e-9)
    if n == 5:  # the default rule spreads 5 beams over 180°
        assert np.degrees(flaser_angles(5)[0]) == pytest.approx(-90.0)


# (PARAM lines, line number of the error, expected message fragment)
BAD_PARAMS = {
    "missing value": (
        "PARAM robot_frontlaser_offset", 1, "PARAM robot_frontlaser_offset has no value"
    ),
    "non-numeric offset": (
        "PARAM x 1\nPARAM robot_frontlaser_side_offset left 0 host 0", 2,
        "robot_frontlaser_side_offset value 'left' is not a number",
    ),
    "nan angle": (
        "PARAM robot_frontlaser_angular_offset nan 0 host 0", 1, "is not finite"
    ),
    "angle in degrees": (
        "PARAM robot_frontlaser_angular_offset 90 0 host 0", 1, "radians, not degrees"
    ),
    "non-numeric resolution": (
        "PARAM laser_front_laser_resolution 0.5deg 0 host 0", 1, "is not a number"
    ),
    "zero resolution": ("PARAM laser_front_laser_resolution 0 0 host 0", 1, "not an angle"),
    "negative fov": ("PARAM laser_front_laser_fov -180 0 host 0", 1, "not an angle"),
    "contradiction": (
        "PARAM robot_frontlaser_offset 0.1\nPARAM robot_frontlaser_offset 0.2", 2,
        "contradicts line 1",
    ),
    "over a full turn": (
        "PARAM laser_front_laser_resolution 100", 1,
        "5 beams of the FLASER lines \\(first: line 2\\) a field of view of 400 degrees",
    ),
    "fov and resolution disagree": (
        "PARAM laser_front_laser_fov 180\nPARAM laser_front_laser_resolution 1.0", 2,
        "make scans of 181 beams \\(or 180 without the last\\), but the FLASER lines "
        "\\(first: line 3\\) hold 5",
    ),
    "no name": ("PARAM", 1, "PARAM line without a parameter name"),
}  # fmt: skip


@pytest.mark.parametrize("case", list(BAD_PARAMS))
def test_bad_params_name_file_and_line(tmp_path, case):
    params, lineno, fragment = BAD_PARAMS[case]
    path = tmp_path / "params.clf"
    path.write_text(mount_log(ODOM_PATH, params=params))
    with pytest.raises(CarmenFormatError, match=rf"^{re.escape(str(path))}:{lineno}: .*{fragment}"):
        read_carmen(path)


def test_other_params_are_ignored_whatever_their_value(tmp_path):
    params = (
        "PARAM robot_use_laser on 0 host 0\n"
        "PARAM laser_front_laser_dev /dev/ttyS0 0 host 0\n"
        "PARAM robot_rearlaser_offset behind 0 host 0\n"  # not the front laser's mount
        "PARAM some_flag\n"
        "PARAM robot_frontlaser_offset 0.1 0 host 0\n"
        "PARAM robot_frontlaser_offset 0.1 5 host 5"  # restated, the same: fine
    )
    path = tmp_path / "params.clf"
    path.write_text(mount_log(compose(ODOM_PATH, [0.1, 0, 0]), params=params))
    log = _read_quietly(path)
    assert log.laser_offset.tolist() == [0.1, 0.0, 0.0] and log.laser_offset_source == "PARAM"
    assert np.array_equal(log.angles, flaser_angles(5))


# ---------------------------------------------------------------------------- writing a mount


@pytest.mark.parametrize("beams", ["flaser", "robotlaser1"])
def test_written_mount_reads_back_exactly(tmp_path, beams):
    laser = None if beams == "flaser" else LaserParams(n_beams=271, fov_deg=270.0, max_range=10.0)
    log = simulate(paper_world(), seed=0, max_scans=20, **({"laser": laser} if laser else {}))
    mounted = replace(log, laser_offset=np.array([0.25, -0.1, 0.1]))
    path = tmp_path / "mounted.clf"
    write_carmen(mounted, path)
    text = path.read_text()
    assert "PARAM robot_frontlaser_offset 0.25 " in text
    assert "PARAM robot_frontlaser_side_offset -0.1 " in text
    assert "PARAM robot_frontlaser_angular_offset 0.1 " in text
    back = _read_quietly(path)  # PARAM and laser poses agree: no warning
    assert back.laser_offset.tolist() == [0.25, -0.1, 0.1]
    assert back.laser_offset_source == "PARAM"
    assert np.array_equal(back.odometry, log.odometry)
    # The laser-pose triple is the odometry + the mount, as CARMEN's robot module writes it.
    first = next(ln.split() for ln in text.splitlines() if ln.startswith(("FLASER", "ROBOTL")))
    at = 2 + log.n_beams if beams == "flaser" else 10 + log.n_beams
    np.testing.assert_allclose(
        np.array(first[at : at + 6], dtype=float),
        np.r_[compose(log.odometry[0], mounted.laser_offset), log.odometry[0]],
        rtol=0,
        atol=1e-12,
    )


def test_written_log_without_mount_states_zero(sim_log, tmp_path):
    path = tmp_path / "paper.clf"
    write_carmen(sim_log, path)
    back = _read_quietly(path)
    assert back.laser_offset.tolist() == [0.0, 0.0, 0.0] and back.laser_offset_source == "PARAM"


def _flaser(t: float, x: float) -> str:
    ranges = "2.5 2.6 2.7 2.8 2.9"  # (all alike would read as the no-return code)
    return f"FLASER 5 {ranges} {x} 0 0 {x} 0 0 {t} host {t}"


@pytest.mark.parametrize(
    ("times", "xs", "message"),
    [
        # each is warned of, not read silently: one demonstrably corrupts the evaluation
        (
            [0.0, 0.2, 0.1, 0.3],
            [0, 0.1, 0.2, 0.3],
            r"t\.clf:3: time goes backwards from the "
            r"scan on line 2 \(0\.2 -> 0\.1\); read as it is",
        ),
        (
            [0.0, 0.2, 0.2, 0.2],
            [0, 0.1, 0.2, 0.3],
            r"t\.clf:3: the timestamp repeats from the "
            r"scan on line 2 \(0\.2 -> 0\.2\) \(and at 1 more scan\)",
        ),
        (
            [0.0, 0.2, 0.4, 0.6],
            [0, 0.1, 1e6, 0.3],
            r"t\.clf:3: the odometry jumps more than 10 m "
            r"from the scan on line 2 \(1e\+06 m\) \(and at 1 more scan\)",
        ),
        # a leap forward is warned of too (the odometry's timestamps lie)
        (
            [0.0, 0.2, 1e9, 1e9 + 0.2],
            [0, 0.1, 0.2, 0.3],
            r"t\.clf:3: time leaps forward more than a day \(86400 s\) from the "
            r"scan on line 2 \(0\.2 -> 1000000000\.0\); read as it is",
        ),
    ],
    ids=["backwards", "repeated", "odometry-jump", "leap-forward"],
)
def test_implausible_sequences_are_read_with_a_warning_naming_the_line(
    tmp_path, times, xs, message
):
    path = tmp_path / "t.clf"
    path.write_text("\n".join(_flaser(t, x) for t, x in zip(times, xs, strict=True)) + "\n")
    with pytest.warns(CarmenWarning, match=message) as record:
        log = read_carmen(path)
    assert len(record) == 1
    # documented acceptance: the scans as they are, in file order
    np.testing.assert_array_equal(log.timestamps, times)
    np.testing.assert_array_equal(log.odometry[:, 0], xs)


def test_a_plausible_log_reads_without_warnings(tmp_path):
    path = tmp_path / "t.clf"
    path.write_text("\n".join(_flaser(0.2 * k, 0.1 * k) for k in range(5)) + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(read_carmen(path)) == 5


@pytest.mark.parametrize("value", ["nan", "inf", "-1.5", "1e308", "5000"])
def test_readings_no_laser_gives_are_no_returns_with_a_warning(tmp_path, value):
    """A 1e308 reading must not make the maximum range 1e308 m and the reading a point
    1e308 m away, nor may NaN, inf and negative readings be dropped without a word."""
    rows = [[2.0, 2.1, 2.2, 2.3, 2.4 + 0.1 * k] for k in range(3)]
    path = tmp_path / "t.clf"
    path.write_text(_flaser_log(rows).replace("2.2 2.3", f"2.2 {value}", 1))
    with pytest.warns(CarmenWarning, match=r"t\.clf:1: 1 reading in 1 scan is negative"):
        log = read_carmen(path)
    assert log.max_range == 80.0  # CARMEN's FLASER default: no no-return code in this log
    assert len(log.scan(0).points()[0]) == 4 and len(log.scan(1).points()[0]) == 5


def test_scans_without_a_return_are_named(tmp_path):
    rows = [[2.0, 2.1, 2.2], [81.91] * 3, [81.91] * 3, [2.0, 2.1, 2.2]] + [[81.91] * 3] * 20
    path = tmp_path / "t.clf"
    path.write_text(_flaser_log(rows))
    with pytest.warns(
        CarmenWarning,
        match=r"t\.clf:2: 22 of 24 scans have no return below the maximum range 81.91 m",
    ) as rec:
        log = read_carmen(path)
    assert len(rec) == 1 and log.max_range == pytest.approx(81.91)


def _robotlaser1_head(start="-1.5707963", res="0.7853982", max_range="20.0") -> str:
    """The robotlaser1() line of 5 beams with its start angle, resolution and maximum range
    replaced (fields 3, 5 and 6)."""
    f = robotlaser1([1, 2, 3, 4, 5], None, [1.0, 2.0, 0.5], 1.0).split()
    f[2], f[4], f[5] = start, res, max_range
    return " ".join(f)


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"max_range": "0"}, "ROBOTLASER1 maximum_range 0 m is no laser's range: it must be a "
         "positive number of metres"),
        ({"max_range": "-5"}, "ROBOTLASER1 maximum_range -5 m is no laser's range"),
        ({"max_range": "1e308"}, "ROBOTLASER1 maximum_range 1e+308 m is no laser's range: it "
         "must be below 1000 m"),
        ({"max_range": "nan"}, "non-finite ROBOTLASER1 start_angle/fov/resolution/max_range"),
        ({"res": "0"}, "ROBOTLASER1 angular_resolution 0 rad: the angle between beams must be "
         "positive"),
        ({"res": "-0.0174533"}, "ROBOTLASER1 angular_resolution -0.0174533 rad: the angle"),
        ({"res": "100"}, "ROBOTLASER1 angular_resolution 100 rad spreads its 5 beams over "
         "22918.3 degrees, more than a full turn"),
        ({"res": "1.6"}, "ROBOTLASER1 angular_resolution 1.6 rad spreads its 5 beams over "
         "366.693 degrees, more than a full turn"),
        ({"start": "-90"}, "ROBOTLASER1 start_angle -90 is more than a full turn: CARMEN "
         "states it in radians, not degrees"),
    ],
    ids=["max-range-0", "max-range-negative", "max-range-1e308", "max-range-nan", "res-0",
         "res-negative", "res-100-rad", "res-over-a-turn", "start-in-degrees"],
)  # fmt: skip
def test_a_robotlaser1_header_no_laser_states_is_an_error(tmp_path, fields, message):
    """A maximum_range of 0 or -5 (Log.max_range must be positive) and a resolution of 0,
    -1° or 100 rad per beam are errors with a line number, not a traceback or silence (the
    FLASER PARAM lines' "more than 360 degrees" check covers ROBOTLASER1 as well)."""
    path = tmp_path / "rl.clf"
    good = robotlaser1([2, 3, 4, 5, 6], None, [1.5, 2.0, 0.5], 2.0)
    path.write_text(f"{good}\n{_robotlaser1_head(**fields)}\n")
    with pytest.raises(CarmenFormatError, match=re.escape(f"rl.clf:2: {message}")):
        read_carmen(path)


def test_a_reading_repeated_far_below_the_stated_range_is_no_code(tmp_path):
    """A ROBOTLASER1 log stating 20 m whose scans repeat exactly must not take the 2.0 m
    ahead for the no-return code and drop every reading from 2 m on. A code is sought in
    the upper half of the stated range only; and the readings alone give none either: the
    scans repeat (a robot standing still), so they count as one scan, in which no value is
    read often enough."""
    rows = [[2.5, 2.2, 2.0, 2.2, 2.5]] * 30
    path = tmp_path / "rl.clf"
    path.write_text(
        "".join(robotlaser1(r, None, [0.1 * k, 0, 0], float(k)) + "\n" for k, r in enumerate(rows))
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        log = read_carmen(path)
    assert log.max_range == 20.0 and log.stated_max_range == 20.0
    assert len(log.scan(0).points()[0]) == 5
    assert no_return_reading(log.ranges) is None
    assert no_return_reading(log.ranges, stated=20) is None
    # a code near the stated range, in scans of a robot on the move: still found
    coded = [[2.5 + 0.1 * k, 2.2, 19.5, 2.2 + 0.1 * k, 19.5] for k in range(30)]
    path.write_text(
        "".join(robotlaser1(r, None, [0.1 * k, 0, 0], float(k)) + "\n" for k, r in enumerate(coded))
    )
    assert read_carmen(path).max_range == 19.5


def test_no_return_reading_with_a_stated_range_keeps_the_five_logs_codes():
    """The stated range only ever raises the scale the code is sought in: codes at or above
    half of it (the Freiburg bags: 81.83 and 81.91 m against 80 or 81.9 m stated, ACES 50 m
    against 50 m) are found as before."""
    rng = np.random.default_rng(3)
    r = np.round(rng.uniform(0.3, 30.0, (300, 180)), 2)
    r[rng.random(r.shape) < 0.10] = 81.91
    r[rng.random(r.shape) < 0.01] = 81.83
    for stated in (None, 80.0, 81.9, 100.0, 160.0):
        assert no_return_reading(r, stated=stated) == 81.83
    assert no_return_reading(r, stated=170.0) is None  # 81.83 m is far below 170 m


# ------------------------------------------------------------------ headings counting turns


def _count_turns(text: str, turns: float) -> str:
    """A CARMEN log ``text`` with ``turns`` full turns added to every heading: the laser
    pose's and the odometry's of each ``FLASER`` line, and each ``ODOM`` line's."""
    out = []
    for line in text.splitlines():
        f = line.split()
        if f and f[0] == "FLASER":
            n = int(f[1])
            for i in (4 + n, 7 + n):  # laser theta, odom theta
                f[i] = repr(float(f[i]) + turns * 2 * np.pi)
        elif f and f[0] == "ODOM":
            f[3] = repr(float(f[3]) + turns * 2 * np.pi)
        out.append(" ".join(f) if f else line)
    return "\n".join(out) + "\n"


@pytest.mark.parametrize("turns", [1, -1, 3])
def test_log_headings_counting_turns_are_wrapped_on_reading(tmp_path, turns):
    """A log whose headings count the turns (theta + 2 pi k) reads as the same log: every
    odometry heading in (-pi, pi] (the convention of fhslam.geometry), equal to the plain log's."""
    log = simulate(paper_world(), seed=0)  # the whole drive: headings all round the circle
    plain_path = tmp_path / "plain.clf"
    write_carmen(log, plain_path)
    turned_path = tmp_path / "turned.clf"
    turned_path.write_text(_count_turns(plain_path.read_text(), turns))
    plain, turned = read_carmen(plain_path), read_carmen(turned_path)
    theta = turned.odometry[:, 2]
    assert np.all((theta > -np.pi) & (theta <= np.pi)), (theta.min(), theta.max())
    assert np.abs(plain.odometry[:, 2]).max() > 3.1  # the test covers headings near ±pi
    np.testing.assert_allclose(turned.odometry, plain.odometry, rtol=0, atol=1e-12)
    assert np.array_equal(plain.odometry, log.odometry)  # the plain log: bit for bit as before
    np.testing.assert_allclose(turned.laser_offset, plain.laser_offset, rtol=0, atol=1e-12)


def test_log_wraps_headings_and_keeps_wrapped_ones_bit_for_bit():
    """Log wraps the headings of odometry, truth and the laser's mount to (-pi, pi]; a
    heading already in it is kept exactly, and the caller's arrays are left alone."""
    thetas = np.array([0.1, np.pi, -np.pi, 7.0, -7.0, 3 * np.pi, -np.nextafter(np.pi, 0)])
    want = np.array(
        [0.1, np.pi, np.pi, 7.0 - 2 * np.pi, 2 * np.pi - 7.0, np.pi, -np.nextafter(np.pi, 0)]
    )
    t = len(thetas)
    odometry = np.column_stack([np.arange(t, dtype=float), np.zeros(t), thetas])
    truth = odometry[::-1].copy()
    given = odometry.copy(), truth.copy()
    offset = np.array([0.2, 0.0, 4.0])
    log = Log(
        name="turns",
        timestamps=np.arange(t, dtype=float),
        ranges=np.ones((t, 3)),
        angles=np.array([-0.1, 0.0, 0.1]),
        odometry=odometry,
        max_range=8.0,
        truth=truth,
        laser_offset=offset,
    )
    np.testing.assert_allclose(log.odometry[:, 2], want, rtol=0, atol=1e-12)
    np.testing.assert_allclose(log.truth[:, 2], want[::-1], rtol=0, atol=1e-12)
    for got in (log.odometry, log.truth):
        assert np.all((got[:, 2] > -np.pi) & (got[:, 2] <= np.pi))
    keep = [0, 1, 6]  # in (-pi, pi] already: the very same floats
    assert log.odometry[keep, 2].tolist() == thetas[keep].tolist()
    assert np.array_equal(log.odometry[:, :2], odometry[:, :2])
    assert log.laser_offset[2] == pytest.approx(4.0 - 2 * np.pi, abs=1e-12)
    assert log.laser_offset[:2].tolist() == [0.2, 0.0]
    assert np.array_equal(odometry, given[0]) and np.array_equal(truth, given[1])
    assert offset.tolist() == [0.2, 0.0, 4.0]
    again = replace(log)  # idempotent: a wrapped log is rebuilt bit for bit
    assert np.array_equal(again.odometry, log.odometry)
    assert np.array_equal(again.truth, log.truth)
