"""The "no return" code and maximum range of a laser log (:func:`fhslam.io.no_return_reading`,
:func:`fhslam.io.effective_max_range`), and the plausibility of its scan rate
(:func:`fhslam.io.log.check_sequence`).

The code is the top of the range histogram: readings rounded to 1 cm or 1 mm, a robot
standing still for minutes, a few glitches must not move it, and a log without no-return
beams must lose no reading. The real logs (skipped when absent) and the simulated ones
keep the maximum range and code they are read with.
"""

from __future__ import annotations

import functools
import gzip
import shutil
import warnings
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fhslam.cli import main
from fhslam.io import (
    BagWarning,
    CarmenWarning,
    Log,
    effective_max_range,
    no_return_reading,
    read_bag,
    read_carmen,
    write_carmen,
)
from fhslam.io.log import (
    IMPLAUSIBLE_RANGE,
    SCAN_INTERVAL_MAX,
    SCAN_INTERVAL_MIN,
    check_sequence,
    counted_readings,
)
from fhslam.metrics.trajectory import ate
from fhslam.pipeline import run_slam
from fhslam.sim import (
    LaserParams,
    beam_angles,
    cast_rays,
    follow_route,
    load_world,
    paper_world,
    simulate,
)

# --------------------------------------------------------------------------- readings

WORLDS = ("paper", "offices", "hall", "ring")
"""Closed worlds: every beam hits a wall at some distance."""

WIDE = LaserParams(n_beams=361, fov_deg=360.0)
"""A 360° laser (written as ``ROBOTLASER1``, which states its maximum range)."""


@functools.cache
def _true_ranges(world: str, wide: bool) -> np.ndarray:
    """Noise-free ranges (T, B) along ``world``'s route, without a maximum range."""
    w = load_world(world)
    angles = beam_angles(WIDE if wide else LaserParams())
    r = np.array([cast_rays(w.walls, pose, angles, np.inf)[0] for pose in follow_route(w)])
    assert np.isfinite(r).all()
    r.setflags(write=False)
    return r


def _readings(
    seed: int,
    world: str = "paper",
    max_range: float = 8.0,
    step: float = 0.01,
    no_return: bool = True,
    above: float = 0.0,
    stop: int = 0,
    noisy_stop: bool = False,
    glitches: int = 0,
    n_scans: int | None = None,
    wide: bool = False,
) -> np.ndarray:
    """The readings (T, B) of a laser of ``max_range`` driving ``world`` (scaled), as the
    simulator's: 1 cm Gaussian noise, rounded to ``step``, clipped one step below the code.

    ``no_return``: the world is scaled so that 5 to 40 % of the beams see no wall within
    ``max_range`` and read the code, ``max_range + above`` (a SICK LMS in its 80 m mode:
    81.91 m, ``above`` 1.91); otherwise every wall lies within 97 % of ``max_range``.
    ``stop``: the robot first stands still for that many scans, its first scan repeated
    exactly (``noisy_stop``: measured anew each time). ``glitches``: that many readings
    replaced by spurious ones (1.5 times the maximum range to 999 m, or 1 to 50 mm).
    ``n_scans``: a stretch of the route that long, starting anywhere.
    """
    rng = np.random.default_rng(seed)
    d = _true_ranges(world, wide)
    if n_scans is not None and n_scans < len(d):
        k0 = int(rng.integers(0, len(d) - n_scans + 1))
        d = d[k0 : k0 + n_scans]
    if no_return:
        d = d * (max_range / np.quantile(d, rng.uniform(0.6, 0.95)))
    else:
        d = d * (0.97 * max_range / d.max())
    d = np.vstack([d[np.zeros(stop, dtype=int)], d])
    noisy = d + rng.normal(0.0, 0.01, d.shape)
    if stop and not noisy_stop:
        noisy[:stop] = noisy[stop]
    noisy = np.round(np.round(noisy / step) * step, 9)
    code = max_range + above
    r = np.where(d < max_range, np.clip(noisy, step, code - step), code)
    k = rng.choice(r.size, glitches, replace=False)
    far = rng.random(glitches) < 0.5
    r.flat[k] = np.where(
        far, rng.uniform(1.5 * max_range, 999.0, glitches), rng.uniform(0.001, 0.05, glitches)
    )
    return r


def _no_warnings(call, *args, **kwargs):
    """``call(*args, **kwargs)``, failing on any warning it gives."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return call(*args, **kwargs)


# -------------------------------------------------------------------------- properties

LASERS = st.sampled_from([4.0, 5.6, 8.0, 30.0, 80.0])
STEPS = st.sampled_from([0.01, 0.001])


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    seed=st.integers(0, 2**32 - 1),
    world=st.sampled_from(WORLDS),
    max_range=LASERS,
    step=STEPS,
    above=st.sampled_from([0.0, 1.91]),
    stop=st.sampled_from([0, 50, 1000]),
    glitches=st.sampled_from([0, 3, 20]),
    n_scans=st.sampled_from([None, 300, 100]),
    wide=st.booleans(),
)
def test_the_code_is_found_whatever_the_rounding_stops_and_glitches(
    seed, world, max_range, step, above, stop, glitches, n_scans, wide
):
    r = _readings(seed, world, max_range, step, True, above, stop, False, glitches, n_scans, wide)
    code = max_range + above
    assert no_return_reading(r) == code
    assert _no_warnings(effective_max_range, r, None, 80.0, "x.clf") == (code, code)
    # a file stating the laser's range (a bag's range_max): the range in use is that one
    assert _no_warnings(effective_max_range, r, max_range, max_range, "x.bag")[0] == max_range


@settings(max_examples=40, deadline=None, derandomize=True)
@given(
    seed=st.integers(0, 2**32 - 1),
    world=st.sampled_from(WORLDS),
    max_range=LASERS,
    step=STEPS,
    stop=st.sampled_from([0, 50, 1000]),
    glitches=st.sampled_from([0, 3, 20]),
    n_scans=st.sampled_from([None, 300, 100]),
    wide=st.booleans(),
)
def test_a_log_without_no_return_beams_loses_no_reading(
    seed, world, max_range, step, stop, glitches, n_scans, wide
):
    r = _readings(seed, world, max_range, step, False, 0.0, stop, False, glitches, n_scans, wide)
    got, code = _no_warnings(effective_max_range, r, None, 80.0, "x.clf")
    assert code is None or code > r[r < IMPLAUSIBLE_RANGE].max()
    assert (r[r < IMPLAUSIBLE_RANGE] < got).all()


@settings(max_examples=25, deadline=None, derandomize=True)
@given(
    seed=st.integers(0, 2**32 - 1),
    world=st.sampled_from(WORLDS),
    max_range=LASERS,
    step=STEPS,
    no_return=st.booleans(),
    glitches=st.sampled_from([0, 3]),
    n_scans=st.sampled_from([None, 300]),
)
def test_a_stop_measured_anew_in_every_scan_makes_no_code(
    seed, world, max_range, step, no_return, glitches, n_scans
):
    """200 scans of a robot standing still, each measured anew (1 cm noise): its walls are
    read hundreds of times, yet they are no code."""
    r = _readings(seed, world, max_range, step, no_return, 0.0, 200, True, glitches, n_scans)
    got, code = effective_max_range(r, None, 80.0)
    if no_return:
        assert (got, code) == (max_range, max_range)
    else:
        assert (r[r < IMPLAUSIBLE_RANGE] < got).all()


def test_a_scan_repeated_counts_once():
    r = _readings(0, stop=1000, n_scans=100)
    counted = counted_readings(r)
    assert counted[0].all() and not counted[1:1001].any()
    assert counted[1001:].sum() > 0.9 * counted[1001:].size
    noisy = _readings(0, stop=1000, noisy_stop=True, n_scans=100)
    assert counted_readings(noisy)[1:1001].mean() < 0.1  # only the beams that moved > 3 cm


def test_a_stop_alone_is_no_evidence_of_a_code():
    """Thirty copies of one scan whose two outer beams read 19.5 m: one scan's worth of
    readings, too few for a code (it takes two scans and two beams)."""
    r = np.array([[19.5, 2.2, 2.0, 2.2, 19.5]] * 30)
    assert no_return_reading(r) is None
    moving = r + np.array([0, 0.1, 0, 0.1, 0]) * np.arange(30)[:, None]
    assert no_return_reading(moving) == 19.5


# ----------------------------------------------------------------------- logs as read


def _f32(v: float) -> float:
    """A bag's reading of ``v`` metres (float32): 81.83 m is read as 81.83000183105469."""
    return float(np.float32(v))


REAL = [
    ("intel.orig.bag", 80.0, _f32(81.83)),
    ("aces.orig.bag", 50.0, 50.0),
    ("mit-csail.clf", 81.91, 81.91),
    ("fr079.orig.bag", 80.0, _f32(81.91)),
    ("fr-clinic_robotlaser.orig.bag", _f32(81.83), _f32(81.83)),
    ("mit-killian.clf2bag.bag", _f32(51.06), _f32(51.06)),
    ("fr101.carmen.log.gz", 81.91, 81.91),
]
"""Each real log's maximum range in use and detected no-return code: the range_max (80 m)
below a SICK's code for Intel and Freiburg 079, the lower of two codes (81.83 and 81.91 m)
for the Freiburg hospital, 51.06 m (not 51.05 m, read 0.07 % of the time, below
:data:`~fhslam.io.log.NO_RETURN_MIN_SHARE`) for the MIT Killian bag."""


@pytest.mark.parametrize(("name", "max_range", "code"), REAL, ids=[n for n, _, _ in REAL])
def test_the_real_logs_keep_their_range_and_code(real_data, tmp_path, name, max_range, code):
    path = real_data / name
    if not path.exists():
        pytest.skip(f"{name} not in {real_data}")
    if path.suffix == ".gz":
        plain = tmp_path / path.stem
        with gzip.open(path, "rb") as src, plain.open("wb") as dst:
            shutil.copyfileobj(src, dst)
        path = plain
    read = read_bag if path.suffix == ".bag" else read_carmen
    log = _no_warnings(read, path)  # no scan-rate warning, no range warning either
    assert log.max_range == max_range
    assert no_return_reading(log.ranges, stated=log.stated_max_range) == code


SIMULATED = [
    *[(w, LaserParams(), 8.0, 8.0) for w in ("paper", "hall", "corridor", "ring", "offices")],
    *[(w, LaserParams(), 8.0, 8.0) for w in ("random:1", "random:2")],
    ("paper", LaserParams(max_range=4.0), 4.0, 4.0),
    ("paper", LaserParams(max_range=5.6), 5.6, 5.6),
    ("paper", LaserParams(max_range=30.0), 80.0, None),  # no beam reaches 30 m: no code
    ("paper", LaserParams(max_range=80.0), 80.0, None),
    ("paper", WIDE, 8.0, 8.0),
    ("paper", LaserParams(resolution=0.0), 8.0, 8.0),
    ("paper", LaserParams(resolution=0.01), 8.0, 8.0),
    ("offices", LaserParams(resolution=0.01), 8.0, 8.0),
    ("hall", LaserParams(max_range=4.0, resolution=0.01), 4.0, 4.0),
    ("paper", replace(WIDE, resolution=0.01), 8.0, 8.0),
]
"""Simulated logs (seed 0) written as CARMEN logs: the maximum range and code read back.
A laser that no wall leaves without a return has no code: CARMEN's 80 m for ``FLASER``."""


@pytest.mark.parametrize(
    ("world", "laser", "max_range", "code"),
    SIMULATED,
    ids=[f"{w}-{la.n_beams}-{la.max_range:g}m-{la.resolution:g}" for w, la, _, _ in SIMULATED],
)
def test_simulated_logs_read_with_their_range(tmp_path, world, laser, max_range, code):
    path = tmp_path / "sim.clf"
    write_carmen(simulate(load_world(world), seed=0, laser=laser), path)
    log = _no_warnings(read_carmen, path)
    assert log.max_range == max_range
    assert no_return_reading(log.ranges, stated=log.stated_max_range) == code


def _rounded(log: Log, step: float) -> Log:
    """``log`` with every reading but the no-return ones rounded to ``step`` metres."""
    r = log.ranges
    return replace(
        log, ranges=np.where(r < log.max_range, np.round(np.round(r / step) * step, 9), r)
    )


def _stopped(log: Log, seconds: float = 200.0, period: float = 0.2) -> Log:
    """``log`` after the robot stood still at its start for ``seconds``: its first scan
    repeated, one every ``period``."""
    n = round(seconds / period)
    k = np.r_[np.zeros(n, dtype=int), np.arange(len(log))]
    t = np.round(np.r_[np.arange(n) * period, log.timestamps + n * period], 6)
    return replace(
        log, timestamps=t, ranges=log.ranges[k], odometry=log.odometry[k], truth=log.truth[k],
        hits=None,
    )  # fmt: skip


@pytest.fixture(scope="module")
def paper_log() -> Log:
    return simulate(paper_world(), seed=0)


@pytest.mark.parametrize(
    "variant",
    [
        pytest.param(lambda log: _rounded(log, 0.01), id="rounded-to-1-cm"),
        pytest.param(_stopped, id="200-s-stop"),
        pytest.param(lambda log: _stopped(_rounded(log, 0.01)), id="rounded-and-stopped"),
    ],
)
def test_info_reports_the_paper_worlds_8_m(paper_log, variant, tmp_path, capsys):
    path = tmp_path / "paper.clf"
    write_carmen(variant(paper_log), path)
    assert main(["info", str(path)]) == 0
    out, err = capsys.readouterr()
    assert "max range 8 m; no-return reading: 8 m" in out
    assert err == ""


def test_slam_is_as_good_on_readings_rounded_to_1_cm(tmp_path):
    """The default SLAM on the paper world, its readings rounded to 1 mm (the simulator's)
    or to 1 cm: the same maximum range (8 m) and, over eight seeds, the same mean ATE
    within 10 % (1.78 and 1.77 cm; a range of 4 m makes it 44 cm). A single run is
    no measure: moving every reading by 1 µm changes one run's ATE by up to a factor 2.3
    (seed 6: 1.27 -> 2.90 cm)."""
    errors = {0.001: [], 0.01: []}
    for seed in range(8):
        log = simulate(paper_world(), seed=seed)
        for step, ates in errors.items():
            path = tmp_path / f"paper-{step}.clf"
            write_carmen(_rounded(log, step), path)
            back = _no_warnings(read_carmen, path)
            assert back.max_range == 8.0
            ates.append(ate(run_slam(back).poses, log.truth).rmse)
    mm, cm = np.mean(errors[0.001]), np.mean(errors[0.01])
    assert max(errors[0.01]) < 0.05
    assert abs(cm - mm) <= 0.1 * mm


# ----------------------------------------------------------------- the range in use


def test_a_stated_range_below_repeated_readings_is_warned(tmp_path):
    """A ROBOTLASER1 log stating 4 m of a laser that measures to 8 m: its readings beyond
    4 m are read as no return, with a warning naming the file; not when the maximum range
    is given."""
    log = simulate(paper_world(), seed=0, laser=WIDE, max_scans=300)
    path = tmp_path / "short.clf"
    write_carmen(replace(log, max_range=4.0), path)
    with pytest.warns(CarmenWarning) as rec:
        back = read_carmen(path)
    assert back.max_range == 4.0 and back.stated_max_range == 4.0
    assert len(rec) == 1
    message = str(rec[0].message)
    assert message.startswith(f"{path}: the maximum range in use, 4 m (the range the file ")
    assert "well below" in message and "give the laser's maximum range" in message
    assert _no_warnings(read_carmen, path, max_range=8.0).max_range == 8.0


def test_a_bag_whose_range_max_is_too_short_is_warned(tmp_path):
    from test_rosbag import write_bag

    def walls(k, a):  # walls 2 to 5 m away across the scan, 5 cm further in each scan
        return 2.0 + 3.0 * (a + np.pi / 2) / np.pi + 0.05 * k

    path = write_bag(tmp_path / "short.bag", scans=30, ranges=walls, range_max=4.0)
    with pytest.warns(BagWarning, match=r"short\.bag: the maximum range in use, 4 m") as rec:
        log = read_bag(path)
    assert log.max_range == 4.0 and len(rec) == 1
    assert "readings the log repeats from 4.2" in str(rec[0].message)
    _no_warnings(read_bag, write_bag(tmp_path / "long.bag", scans=30, ranges=walls))


def test_nothing_dropped_nothing_warned(paper_log):
    assert _no_warnings(effective_max_range, paper_log.ranges, None, 80.0, "p.clf")[0] == 8.0


# --------------------------------------------------------------------------- scan rate


@pytest.mark.parametrize(
    ("scale", "shown", "why"),
    [(1000.0, "200 s apart", "milliseconds"), (1e-4, "2e-05 s apart", "another unit")],
    ids=["milliseconds-as-seconds", "too-fast"],
)
def test_an_implausible_scan_rate_is_warned(tmp_path, scale, shown, why):
    log = simulate(paper_world(), seed=0, max_scans=50)
    path = tmp_path / "ms.clf"
    write_carmen(replace(log, timestamps=log.timestamps * scale), path)
    with pytest.warns(CarmenWarning) as rec:
        read_carmen(path)
    assert len(rec) == 1
    message = str(rec[0].message)
    assert message.startswith(f"{path}: the scans are {shown} (the median of 49 steps")
    assert why in message and message.endswith("Read as it is")


def test_the_scan_rate_bounds_leave_real_rates_and_poses_alone():
    t = np.arange(100) * 0.2
    _no_warnings(check_sequence, "a.clf", t, None, None)  # 5 scans a second
    _no_warnings(check_sequence, "a.clf", t * 5 * SCAN_INTERVAL_MAX * 0.999, None, None)
    _no_warnings(check_sequence, "a.clf", t * 5 * SCAN_INTERVAL_MIN * 1.001, None, None)
    _no_warnings(check_sequence, "t.txt", t * 1000, None, None, noun="pose")  # a trajectory
    with pytest.warns(UserWarning, match=r"a\.clf: the scans are 10\.01 s apart"):
        check_sequence("a.clf", t * 5 * 10.01, None, None)


def _hostile_cases():
    """Cases of ``tests/test_hostile.py``'s corpus (``warn``: exit 0, one warning line per
    finding naming the file) for the scan rate and the range in use."""
    from test_hostile import BASE_RL, RL_LINES, _clf, _set_times, _slam

    def stated(value: str) -> str:
        lines = list(BASE_RL)
        for i in RL_LINES:
            f = lines[i].split()
            f[5] = value  # maximum_range
            lines[i] = " ".join(f)
        return _clf(lines)

    return [
        _slam("log.clf", _set_times([200.0 * k for k in range(12)]), "warn",
              names=["log.clf: the scans are 200 s apart"], id="clf-times-in-milliseconds"),
        _slam("log.clf", _set_times([2e-5 * k for k in range(12)]), "warn",
              names=["log.clf: the scans are 2e-05 s apart"], id="clf-times-too-fast"),
        _slam("log.clf", stated("2.0"), "warn",
              names=["log.clf: the maximum range in use, 2 m"], id="clf-stated-range-too-short"),
    ]  # fmt: skip


@pytest.mark.parametrize("case", _hostile_cases(), ids=lambda c: c.id)
def test_hostile_inputs_of_rate_and_range_end_cleanly(case, tmp_path, capsys):
    from test_hostile import _check, _materialise, _run, _snapshot

    argv = _materialise(case, tmp_path)
    inputs = _snapshot(tmp_path)
    code, out, err = _run(case, argv, capsys)
    _check(case, tmp_path, inputs, code, out, err)
