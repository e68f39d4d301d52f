"""ROS bag reading: real Freiburg bags (skipped when absent) and small bags built in the test."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from fhslam.io import BagFormatError, is_bag, read_bag, read_relations
from fhslam.metrics import relations_error


def _types():
    """ROS 1 Noetic's message types, with tf2_msgs/TFMessage (which rosbags lacks)."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    tf = "geometry_msgs/TransformStamped[] transforms"
    ts.register(get_types_from_msg(tf, "tf2_msgs/msg/TFMessage"))
    return ts


def write_bag(
    path,
    scans=3,
    odom=True,
    scan_topics=("/scan",),
    beams=181,
    interlaced=False,
    stamps=None,
    ranges=None,
    range_max=80.0,
    increment=None,
    odom_x=None,
    quaternion=(0.0, 0.0, 0.0, 1.0),
    mount=None,
):
    """A tiny ROS 1 bag: scans of a wall 2 m ahead, odometry moving 0.1 m per scan.
    ``interlaced``: scan k starts (k mod 4) quarter-beams later, with one beam fewer after
    the first (as the Freiburg hospital log's laser). ``stamps``: the scans' (and odometry's)
    header stamps in whole seconds (default 10, 11, ...; the bag records message k at 10 + k s).
    ``ranges(k, a)``: scan k's readings at bearings ``a`` instead of the wall; ``range_max``
    and ``increment`` (default π/(beams−1)): the scans' ``range_max`` and
    ``angle_increment``; ``odom_x(k)``: odometry message k's x (default 0.1 k);
    ``quaternion``: every odometry orientation ``(x, y, z, w)``; ``mount``: ``(x, y,
    (qx, qy, qz, qw))``, a ``/tf_static`` message base_link → laser."""
    from rosbags.rosbag1 import Writer

    ts = _types()
    T = ts.types
    scan_t, odom_t = "sensor_msgs/msg/LaserScan", "nav_msgs/msg/Odometry"

    stamps = [10 + k for k in range(scans)] if stamps is None else list(stamps)

    def header(k):
        return T["std_msgs/msg/Header"](
            seq=k, stamp=T["builtin_interfaces/msg/Time"](sec=stamps[k], nanosec=0), frame_id="x"
        )

    with Writer(path) as w:
        conns = [w.add_connection(t, scan_t, typestore=ts) for t in scan_topics]
        oc = w.add_connection("/odom", odom_t, typestore=ts) if odom else None
        if mount is not None:
            tf_t = "tf2_msgs/msg/TFMessage"
            x, y, q = mount
            tf = T[tf_t](
                transforms=[
                    T["geometry_msgs/msg/TransformStamped"](
                        header=header(0),
                        child_frame_id="laser",
                        transform=T["geometry_msgs/msg/Transform"](
                            translation=T["geometry_msgs/msg/Vector3"](x=x, y=y, z=0.0),
                            rotation=T["geometry_msgs/msg/Quaternion"](
                                **dict(zip("xyzw", map(float, q), strict=True))
                            ),
                        ),
                    )
                ]
            )
            tc = w.add_connection("/tf_static", tf_t, typestore=ts)
            w.write(tc, 10 * 10**9, ts.serialize_ros1(tf, tf_t))
        for k in range(scans):
            inc = (np.pi / max(beams - 1, 1)) if increment is None else increment
            shift = (k % 4) * inc / 4 if interlaced else 0.0
            a = -np.pi / 2 + shift + inc * np.arange(beams - (shift > 0))
            r = np.where(np.abs(a) < 1.0, 2.0 / np.cos(a), 81.9) if ranges is None else ranges(k, a)
            r = np.asarray(r, dtype=np.float32)
            a_min, a_max = (float(a[0]), float(a[-1])) if len(a) else (-np.pi / 2, -np.pi / 2)
            msg = T[scan_t](
                header=header(k), angle_min=a_min, angle_max=a_max,
                angle_increment=inc, time_increment=0.0, scan_time=0.0, range_min=0.0,
                range_max=range_max, ranges=r, intensities=np.zeros(0, np.float32),
            )  # fmt: skip
            for c in conns:
                w.write(c, (10 + k) * 10**9, ts.serialize_ros1(msg, scan_t))
            if oc is not None:
                g = T
                pose = g["geometry_msgs/msg/PoseWithCovariance"](
                    pose=g["geometry_msgs/msg/Pose"](
                        position=g["geometry_msgs/msg/Point"](
                            x=0.1 * k if odom_x is None else odom_x(k), y=0.0, z=0.0
                        ),
                        orientation=g["geometry_msgs/msg/Quaternion"](
                            **dict(zip("xyzw", map(float, quaternion), strict=True))
                        ),
                    ),
                    covariance=np.zeros(36),
                )
                twist = g["geometry_msgs/msg/TwistWithCovariance"](
                    twist=g["geometry_msgs/msg/Twist"](
                        linear=g["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0),
                        angular=g["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0),
                    ),
                    covariance=np.zeros(36),
                )
                o = g[odom_t](header=header(k), child_frame_id="base", pose=pose, twist=twist)
                w.write(oc, (10 + k) * 10**9, ts.serialize_ros1(o, odom_t))
    return path


def test_a_small_bag_reads_back(tmp_path):
    log = read_bag(write_bag(tmp_path / "a.bag", scans=4))
    assert len(log) == 4 and log.n_beams == 181
    np.testing.assert_allclose(log.timestamps, [10, 11, 12, 13])
    np.testing.assert_allclose(log.odometry[:, 0], [0, 0.1, 0.2, 0.3], atol=1e-9)
    np.testing.assert_allclose(np.degrees(log.angles[[0, 90, 180]]), [-90, 0, 90], atol=1e-9)
    assert log.max_range == 80.0 and is_bag(tmp_path / "a.bag")


def test_converted_180_beam_bags_use_carmens_one_degree_steps(tmp_path):
    log = read_bag(write_bag(tmp_path / "b.bag", beams=180))
    np.testing.assert_allclose(np.degrees(np.diff(log.angles)), 1.0)  # not 180/179
    raw = read_bag(tmp_path / "b.bag", beams="bag")
    np.testing.assert_allclose(np.degrees(np.diff(raw.angles)), 180 / 179, rtol=1e-6)


def test_bag_without_odometry_names_file_and_type(tmp_path):
    with pytest.raises(BagFormatError, match=r"c\.bag: the bag has no odometry"):
        read_bag(write_bag(tmp_path / "c.bag", odom=False))


def test_bag_without_scans_and_ambiguous_or_unknown_topics(tmp_path):
    with pytest.raises(BagFormatError, match="no laser scan"):
        read_bag(write_bag(tmp_path / "d.bag", scan_topics=()))
    two = write_bag(tmp_path / "e.bag", scan_topics=("/front", "/rear"))
    with pytest.raises(BagFormatError, match="several laser scan topics"):
        read_bag(two)
    assert len(read_bag(two, scan_topic="/rear")) == 3
    with pytest.raises(BagFormatError, match="no topic '/nope'"):
        read_bag(two, scan_topic="/nope")


def test_not_a_bag(tmp_path):
    f = tmp_path / "x.bag"
    f.write_text("FLASER 3 1 2 3 0 0 0 0 0 0 1 h 1\n")
    assert not is_bag(f)
    with pytest.raises(BagFormatError, match=r"x\.bag: not a readable ROS bag"):
        read_bag(f)
    with pytest.raises(FileNotFoundError):
        read_bag(tmp_path / "missing.bag")


def test_intel_bag_matches_its_relations_and_published_odometry_error(real_data):
    log = read_bag(real_data / "intel.orig.bag")
    assert len(log) == 13631 and log.n_beams == 180
    np.testing.assert_allclose(np.degrees(np.diff(log.angles)), 1.0)
    t1, t2, rel = read_relations(real_data / "intel.relations")
    e = relations_error(log.timestamps, log.odometry, t1, t2, rel)
    assert e.n_used == e.n_total == 2984  # every relation stamp is a scan stamp
    assert e.trans_mean == pytest.approx(7.38, abs=0.005)  # the raw odometry's 7.38 m


def test_fr079_laser_offset_from_tf_static(real_data):
    log = read_bag(real_data / "fr079.orig.bag")
    np.testing.assert_allclose(log.laser_offset, [0.04, 0.0, 0.0], atol=1e-9)  # SOURCES.md
    assert log.n_beams == 360
    np.testing.assert_allclose(np.degrees(np.diff(log.angles)), 0.5)


def test_an_interlaced_laser_gets_per_scan_bearing_offsets(tmp_path):
    """Scans starting a quarter beam apart (181, 180, 180, 180 beams) read into one Log
    whose ``scan(k)`` bearings put every point back on the wall x = 2 m."""
    from fhslam.io import write_carmen

    log = read_bag(write_bag(tmp_path / "i.bag", scans=6, interlaced=True))
    inc = np.pi / 180
    np.testing.assert_allclose(
        log.angle_offsets, np.array([0, 0.25, 0.5, 0.75, 0, 0.25]) * inc, atol=1e-6
    )
    assert log.ranges.shape == (6, 181) and np.isnan(log.ranges[1, -1])
    for k in range(6):
        pts, _ = log.scan(k).points()
        np.testing.assert_allclose(pts[:, 0], 2.0, atol=1e-5)
    with pytest.raises(ValueError, match="per-scan bearing offsets"):
        write_carmen(log, tmp_path / "i.clf")


def test_fr079_loaded_as_a_dataset_gets_its_original_mount(real_data, tmp_path):
    """The bag publishes base_link -> laser x = +0.04 m; the original CARMEN log states
    ``robot_frontlaser_offset -0.04``. The relations side with the log
    (default SLAM: 0.0301 m with -0.04 against 0.0636 m with +0.04), so the dataset loader
    corrects the mount of the dataset's file, found by name or by file name and size; the
    reader reports the file as it is, and any other file keeps its own mount."""
    import shutil

    from fhslam.datasets import MOUNT_NOTES, load_log

    assert "-0.04" in MOUNT_NOTES["fr079"]
    by_name = load_log("fr079")
    np.testing.assert_array_equal(by_name.laser_offset, [-0.04, 0.0, 0.0])
    assert by_name.laser_offset_source == "dataset"
    copy = tmp_path / "fr079.orig.bag"
    shutil.copyfile(real_data / "fr079.orig.bag", copy)
    assert load_log(copy).laser_offset_source == "dataset"
    renamed = tmp_path / "mine.bag"
    copy.rename(renamed)
    np.testing.assert_allclose(load_log(renamed).laser_offset, [0.04, 0.0, 0.0], atol=1e-9)
    assert load_log("intel").laser_offset_source == "tf_static"  # nothing to correct


def test_scans_out_of_time_order_are_sorted_with_a_warning(tmp_path):
    """A bag's scans whose header stamps go back in time are sorted with a warning."""
    from fhslam.io import BagWarning

    path = write_bag(tmp_path / "b.bag", scans=5, stamps=[10, 11, 13, 12, 12])
    with pytest.warns(BagWarning) as rec:
        log = read_bag(path)
    messages = [str(w.message) for w in rec]
    assert len(messages) == 2
    assert (
        "b.bag: the header stamp goes back in time at 1 scan of the bag (first: scan 3"
        in messages[0]
    )
    assert "b.bag: scan 3: the timestamp repeats from scan 2 (12.0 -> 12.0)" in messages[1]
    np.testing.assert_array_equal(log.timestamps, [10, 11, 12, 12, 13])


def _wall_and_far_wall(k, a):
    """A wall 2 m ahead within ±1 rad, another reading exactly 3.0 m beyond: the same scan
    every time (a robot standing still), so every reading repeats exactly."""
    return np.where(np.abs(a) < 1.0, 2.0 / np.cos(a), 3.0)


def test_a_reading_repeated_far_below_range_max_is_no_no_return_code(tmp_path):
    """A bag stating range_max 80 m whose 30 scans repeat must not take the 2.0 m straight
    ahead (read 30 times) for the no-return code, dropping every reading at or beyond 2 m
    and leaving every scan empty. A code is sought in the upper half of the stated range."""
    from fhslam.io import no_return_reading

    path = write_bag(tmp_path / "still.bag", scans=30, ranges=_wall_and_far_wall)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no "no scan has a return" any more
        log = read_bag(path)
    assert log.max_range == 80.0 and log.stated_max_range == 80.0
    # what the readings alone suggest: 3.0 m, the one value of every beam beyond ±1 rad,
    # with nothing above it (the scans repeat: they count as one)
    assert no_return_reading(log.ranges) == 3.0
    assert no_return_reading(log.ranges, stated=80.0) is None
    assert len(log.scan(0).points()[0]) == 181  # every beam a point


def test_a_code_near_range_max_is_still_found(tmp_path):
    """A code in the upper half of the stated range still sets the maximum range: the
    write_bag scans code no return beyond ±1 rad as 81.9 m above range_max 80 (the range in
    use: 80), and as 79.5 m below a range_max of 100 m (the range in use: the code)."""
    assert read_bag(write_bag(tmp_path / "a.bag")).max_range == 80.0

    def coded(k, a):
        return np.where(np.abs(a) < 1.0, 2.0 / np.cos(a), 79.5)

    log = read_bag(write_bag(tmp_path / "b.bag", scans=30, ranges=coded, range_max=100.0))
    assert log.max_range == pytest.approx(79.5) and log.stated_max_range == 100.0


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"range_max": 0.0}, r"scan 0 of topic '/scan': range_max 0 m is no laser's range"),
        ({"range_max": -1.0}, r"scan 0 of topic '/scan': range_max -1 m is no laser's"),
        ({"range_max": float("nan")}, r"scan 0 of topic '/scan': range_max nan m is no laser"),
        ({"range_max": float("inf")}, r"scan 0 of topic '/scan': range_max inf m is no laser"),
        ({"range_max": 1e6}, r"range_max 1e\+06 m is no laser's range: it must be below"),
        ({"increment": 0.0}, r"scan 0 of topic '/scan': angle_increment 0 rad: the angle"),
        ({"increment": -0.25}, r"angle_increment -0\.25 rad: the angle between beams must"),
        ({"increment": float("nan")}, r"scan 0 of topic '/scan': angle_min nan rad"),
        ({"increment": 10.0}, r"angle_increment 10 rad spreads its 181 beams over 103132 deg"),
        ({"beams": 1}, r"scan 0 of topic '/scan': the widest scan has 1 beam; a laser scan"),
        ({"beams": 0}, r"the widest scan has 0 beams; a laser scan has at least 2"),
        (
            {"odom_x": lambda k: float("nan") if k == 2 else 0.1 * k},
            r"odometry message 2 of topic '/odom': non-finite position \(x nan, y 0\.0\)",
        ),
        (
            {"quaternion": (0, 0, 0, float("nan"))},
            r"odometry message 0 of topic '/odom': non-finite orientation quaternion",
        ),
        (
            {"quaternion": (0, 0, 0, 0)},
            r"odometry message 0 of topic '/odom': orientation quaternion \[0\.0, 0\.0, 0\.0, "
            r"0\.0\] is not a rotation: its squared norm 0 is not 1",
        ),
        ({"quaternion": (0, 0, 0, 2)}, r"its squared norm 4 is not 1 \(within 0\.01\)"),
        (
            {"mount": (0.1, 0.0, (0, 0, float("nan"), 1))},
            r"message 0 of topic '/tf_static', the laser mount 'laser': non-finite orientation",
        ),
        (
            {"mount": (float("inf"), 0.0, (0, 0, 0, 1))},
            r"the laser mount 'laser': non-finite position \(x inf",
        ),
    ],
    ids=[
        "range-max-0", "range-max-negative", "range-max-nan", "range-max-inf", "range-max-1e6",
        "increment-0", "increment-negative", "increment-nan", "increment-10-rad", "one-beam",
        "no-beam", "odometry-nan", "quaternion-nan", "quaternion-zero", "quaternion-norm-2",
        "mount-quaternion-nan", "mount-inf",
    ],
)  # fmt: skip
def test_what_no_laser_or_odometry_gives_is_refused_naming_the_message(tmp_path, kw, message):
    """Refused with a message, not a traceback: range_max 0, -1 or NaN (Log.max_range must be
    positive), a NaN pose (odometry must be finite), one beam (a ZeroDivisionError); and not
    read silently: an increment of 0 or 10 rad and an all-zero quaternion (read as heading
    0)."""
    path = write_bag(tmp_path / "x.bag", scans=4, **kw)
    with pytest.raises(BagFormatError, match=r"x\.bag: .*" + message):
        read_bag(path)


def test_ros_no_return_codes_are_read_without_a_warning(tmp_path):
    """REP 117: +inf is no return, -inf too close, NaN invalid; the reader reads them as no
    return without calling them implausible (before: +inf was "beyond 1000 m"). A negative
    reading is no code: warned."""
    from fhslam.io import BagWarning

    def coded(k, a):
        r = np.where(np.abs(a) < 1.0, 2.0 / np.cos(a), np.inf)
        r[:3] = [-np.inf, np.nan, np.inf]
        return r

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        log = read_bag(write_bag(tmp_path / "a.bag", ranges=coded))
    assert log.max_range == 80.0 and len(log.scan(0).points()[0]) == 115

    def negative(k, a):
        return np.where(np.abs(a) < 1.0, -1.0, 3.0)

    with pytest.warns(BagWarning, match=r"b\.bag: scan 0: 345 readings in 3 scans are negative"):
        read_bag(write_bag(tmp_path / "b.bag", ranges=negative))


def test_a_leap_of_more_than_a_day_is_warned(tmp_path):
    """A leap forward of 1e9 s is warned of, as time going back is."""
    from fhslam.io import BagWarning

    path = write_bag(tmp_path / "t.bag", scans=4, stamps=[10, 11, 10**9, 10**9 + 1])
    with pytest.warns(BagWarning) as rec:
        log = read_bag(path)
    assert [str(w.message) for w in rec] == [
        f"{path}: scan 2: time leaps forward more than a day (86400 s) from scan 1 "
        "(11.0 -> 1000000000.0); read as it is"
    ]
    assert len(log) == 4
