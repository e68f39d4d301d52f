"""The default SLAM on the real logs: each log's relation error within its limit, and how
little range noise, dropped scans and the odometry's last bit move it (the robustness bound);
the hospital's return after 900 m without a closure."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from fhslam.geometry import wrap_angle
from fhslam.pipeline import run_slam
from fhslam.sim import degrade, perturb_odometry


@functools.cache
def _plain_run(name):
    """The default SLAM on a shared log as it is: its timestamps and poses (run once per
    session)."""
    from fhslam.datasets import load_log

    r = run_slam(load_log(name))
    return r.timestamps, r.poses


def _relations_error(real_data, name, odometry_noise_seed=None):
    """The relation error of the default SLAM on the whole log ``name``, its odometry
    perturbed in the last bit (with a seed; the plain run is made once per session)."""
    from fhslam.datasets import find_dataset, load_log
    from fhslam.io import read_relations
    from fhslam.metrics import relations_error

    rel = read_relations(find_dataset(name, "relations"))
    if odometry_noise_seed is None:
        return relations_error(*_plain_run(name), *rel)
    # last-bit noise: what another CPU may do
    r = run_slam(perturb_odometry(load_log(name), odometry_noise_seed))
    return relations_error(r.timestamps, r.poses, *rel)


def _robustness_bound(every_scan: float) -> float:
    """The robustness bound: a perturbation may change a log's relation error by at most
    25 % or 1 cm, whichever is larger."""
    return max(1.25 * every_scan, every_scan + 0.01)


# Mean translational relation error over all relations, metres, with the default method and
# the same defaults for every log: (the limit, measured on a 2-core machine). The assertion
# is the limit: the measured values leave room for last-bit differences between CPUs.
REAL_LOGS = {
    "intel": (0.05, 0.0138),
    "aces": (0.06, 0.0340),
    "mit-csail": (0.06, 0.0266),
    "fr079": (0.08, 0.0302),
    "fr-clinic": (0.15, 0.1221),
}


@pytest.mark.parametrize("name", REAL_LOGS)
def test_real_log_relations_error_meets_its_limit(real_data, name):
    limit, measured = REAL_LOGS[name]
    e = _relations_error(real_data, name)
    assert e.n_used == e.n_total
    assert e.trans_mean <= limit, f"{name}: {e.trans_mean:.4f} m (measured {measured} m)"


# The two long logs, scored against pseudo ground truth (relations between the poses of a
# reference SLAM run: a floor of a few centimetres): (the limit, measured), as REAL_LOGS.
LONG_LOGS = {"fr101": (0.07, 0.0544), "mit-killian-full": (0.40, 0.3582)}


@pytest.mark.parametrize("name", LONG_LOGS)
def test_a_long_log_meets_its_limit(real_data, name):
    """Freiburg 101 (gzipped CARMEN, 17 minutes) within 0.07 m; MIT Killian Court at full
    rate (17,480 scans, 1.9 km) within 0.40 m (measured 0.358 m; 0.33-0.62 m over the 24
    draws of ``fhslam benchmark``); its aim of 0.15 m is not met
    (``test_killian_meets_the_aim``)."""
    limit, measured = LONG_LOGS[name]
    e = _relations_error(real_data, name)
    assert e.trans_mean <= limit, f"{name}: {e.trans_mean:.4f} m (measured {measured} m)"


@pytest.mark.xfail(strict=True, reason="0.358 m: 65 % of it from relations over 50 m, whose "
                   "directions lie up to 1 degree off the reference's")  # fmt: skip
def test_killian_meets_the_aim(real_data):
    """MIT Killian Court within 0.15 m of its pseudo ground truth (GMapping's poses, a floor
    not known). Relations under 10 m are 0.05-0.07 m off; those over 50 m (14 % of them)
    1.68 m, their directions -0.95 to +1.1 degrees off (10th-90th percentile). Lengths come
    out 0.4 % short, but the best uniform scale explains only 0.012 m of the error, and the
    odometry lengthened by its own 0.8 % shortfall 0.017 m."""
    e = _relations_error(real_data, "mit-killian-full")
    assert e.trans_mean <= 0.15, f"{e.trans_mean:.4f} m"


def test_the_hospitals_relations_under_a_minute_hold(real_data):
    """The hospital's mean over all relations is decided by its return to the start (closed
    by the global search, above); its 2,642 relations under a minute measure the local
    accuracy: 0.0950 m (0.0957 and 0.0994 m with 1 mm range noise or 10 % of the scans
    dropped; the odometry's 0.0772 m is still better)."""
    from fhslam.datasets import find_dataset
    from fhslam.io import read_relations
    from fhslam.metrics import relations_error

    t1, t2, z = read_relations(find_dataset("fr-clinic", "relations"))
    short = np.abs(t2 - t1) < 60
    e = relations_error(*_plain_run("fr-clinic"), t1[short], t2[short], z[short])
    assert e.n_used == short.sum() == 2642
    assert e.trans_mean <= 0.105, f"{e.trans_mean:.4f} m"


HOSPITAL_DRAWN = (
    "two of the 24 draws of the benchmark seeded 3209647287 (fhslam benchmark --draw-seed "
    "3209647287): the return to the start is missed, 0.449 m with the noise, 0.504 m with the "
    "drops (the other 22: 0.115-0.135 m)"
)


def _clinic_error(params=None, **degraded) -> float:
    """The hospital's mean translational relation error (metres) of a run of the default
    SLAM (or ``params``) on the log degraded by ``degraded`` (:func:`fhslam.sim.degrade`)."""
    from fhslam.datasets import find_dataset, load_log
    from fhslam.io import read_relations
    from fhslam.metrics import relations_error

    r = run_slam(degrade(load_log("fr-clinic"), **degraded), params=params)
    rel = read_relations(find_dataset("fr-clinic", "relations"))
    return relations_error(r.timestamps, r.poses, *rel).trans_mean


@pytest.mark.parametrize(
    "degraded",
    [
        {"range_noise": 0.001, "seed": 0},
        {"drop_fraction": 0.1, "seed": 0},
        {"drop_fraction": 0.1, "seed": 3},
        pytest.param(
            {"range_noise": 0.001, "seed": 955905649},
            marks=pytest.mark.xfail(strict=True, reason=HOSPITAL_DRAWN),
            id="range-noise-drawn",
        ),
        pytest.param(
            {"drop_fraction": 0.1, "seed": 219205979},
            marks=pytest.mark.xfail(strict=True, reason=HOSPITAL_DRAWN),
            id="dropped-scans-drawn",
        ),
    ],
    ids=["range-noise", "dropped-scans", "dropped-scans-seed-3", None, None],
)
def test_the_hospital_is_robust(real_data, degraded):
    """The robustness bound: 1 mm of Gaussian noise on every range, or 10 % of the scans
    dropped, may change the relation error by at most 25 % (or 1 cm). Measured 0.1219 m
    with the noise, 0.1309 m with the drops and 0.1409 m with the drops of seed 3 (0.1268 m
    unperturbed). Seed 3's return scores 0.59 where it is found: with a ``search.min_score``
    of 0.6 it is missed (2.13 m). Without the global search looking where the odometry puts
    the robot, and from 10 m without a closure on, the noise and the drops give 3.14 m and
    4.47 m: the return to the start lies 85-146 m and 25-40 degrees off the estimate."""
    measured = REAL_LOGS["fr-clinic"][1]
    e = _clinic_error(**degraded)
    assert e <= _robustness_bound(measured), f"{e:.4f} m"


HOSPITAL_CURVED_WALL = (
    "the tracker turns 13-16 degrees too far over the hospital's scans 2541-2564 (a curved "
    "wall 3-5 m away, people about), where the odometry agrees with the benchmark's "
    "relations to 0.01 degrees; scan-to-scan matching without a map does the same (+14 "
    "degrees): so the return closed at scans 2599-2644 leaves the start out of reach."
)


@pytest.mark.xfail(strict=True, reason=HOSPITAL_CURVED_WALL)
def test_the_hospitals_curved_wall_turns_as_the_relations_say(real_data):
    """The known failure behind the hospital's map of scans 2599-2644, on 60 scans (0.5 s):
    the default SLAM from scan 2520 to 2579, its headings between scans of the benchmark's
    relations there (relations 35.2, 44.8 and 16.7 degrees; measured 40.8, 54.1 and 23.9).
    Strict: a change that fixes it must say so."""
    import dataclasses

    from fhslam.datasets import find_dataset, load_log
    from fhslam.io import read_relations

    full = load_log("fr-clinic")
    lo, hi = 2520, 2580
    cut = {f: getattr(full, f)[lo:hi] for f in ("timestamps", "ranges", "odometry")}
    log = dataclasses.replace(full, angle_offsets=full.angle_offsets[lo:hi], **cut)
    r = run_slam(log)
    t1, t2, z = read_relations(find_dataset("fr-clinic", "relations"))
    pairs = [(2541, 2551), (2546, 2556), (2551, 2561)]
    for a, b in pairs:
        (q,) = np.flatnonzero(
            (np.abs(t1 - full.timestamps[a]) < 1e-3) & (np.abs(t2 - full.timestamps[b]) < 1e-3)
        )
        ours = r.poses[b - lo, 2] - r.poses[a - lo, 2]
        off = np.degrees(wrap_angle(ours - z[q, 2]))
        assert abs(off) <= 3.0, f"scans {a}-{b}: {off:+.1f} degrees off the relation"


@pytest.mark.parametrize("seed", [1, 2])
def test_mit_csail_does_not_turn_on_the_last_bit(real_data, seed):
    """The odometry multiplied by (1 + 1e-15 ε): closures that would move a keyframe far wait
    for an independent one (without that, seed 2 gave 0.394 m); measured 0.0266 m for seeds
    1, 2 and unperturbed."""
    e = _relations_error(real_data, "mit-csail", odometry_noise_seed=seed)
    assert e.trans_mean <= 0.035, f"seed {seed}: {e.trans_mean:.4f} m"


# The robustness checks run on the shortest log whole and on the first third of the scans of
# the longer ones (a whole run each is the relation test's): the plain run's error over the
# relations within that window (metres), measured as REAL_LOGS was.
WINDOWS = {"intel": 0.0152, "aces": 0.0322, "fr079": 0.0241, "mit-csail": REAL_LOGS["mit-csail"][1]}


@functools.cache
def _window(name):
    """The log ``name``, or its first third of scans (a key of :data:`WINDOWS` other than
    MIT CSAIL), and the benchmark's relations within it."""
    from fhslam.datasets import find_dataset, load_log
    from fhslam.experiments.bench import log_head
    from fhslam.io import read_relations

    log = load_log(name)
    if name != "mit-csail":
        log = log_head(log, len(log.timestamps) // 3)
    t1, t2, z = read_relations(find_dataset(name, "relations"))
    inside = (t1 <= log.timestamps[-1]) & (t2 <= log.timestamps[-1])
    return log, (t1[inside], t2[inside], z[inside])


def _window_error(name, odometry_noise_seed=None, **degraded):
    """The relation error of the default SLAM on :func:`_window` of ``name``, its odometry
    perturbed in the last bit (seed) or the log degraded (:func:`fhslam.sim.degrade`)."""
    from fhslam.metrics import relations_error

    log, relations = _window(name)
    if odometry_noise_seed is not None:
        log = perturb_odometry(log, odometry_noise_seed)
    if degraded:
        log = degrade(log, seed=0, **degraded)
    r = run_slam(log)
    return relations_error(r.timestamps, r.poses, *relations)


@pytest.mark.parametrize("name", WINDOWS)
def test_range_noise_changes_little(real_data, name):
    """1 mm of Gaussian noise on every range (the robustness bound: no log's error may change
    by more than 25 % or 1 cm; the hospital: ``test_the_hospital_is_robust``). Measured
    (degrade seed 0), windows of Intel 0.0161 m, ACES 0.0319, Freiburg 079 0.0243, MIT CSAIL
    whole 0.0265 m (see :data:`WINDOWS` for every scan)."""
    every_scan = WINDOWS[name]
    e = _window_error(name, range_noise=0.001)
    assert e.n_used == e.n_total
    assert e.trans_mean <= _robustness_bound(every_scan), (
        f"{name}: {e.trans_mean:.4f} m (every scan {every_scan} m)"
    )


@pytest.mark.parametrize(("name", "seed"), [("intel", 1), ("intel", 2), ("fr079", 2)])
def test_the_last_bit_changes_little(real_data, name, seed):
    """The odometry multiplied by (1 + 1e-15 epsilon), what another CPU may do, on a window
    (MIT CSAIL and ACES whole: their own tests) changes the error by under 1 mm: no decision
    of the default flips on it. Measured: Intel 0.0152 m (seeds 1 and 2), Freiburg 079
    0.0241 m (seed 2), as every scan (to 1e-12 m on the whole logs, the benchmark's draws)."""
    every_scan = WINDOWS[name]
    e = _window_error(name, odometry_noise_seed=seed)
    assert abs(e.trans_mean - every_scan) <= 0.001, f"{e.trans_mean:.4f} m"


def test_the_last_bit_changes_the_hospital_little(real_data):
    """The hospital whole (its return after 900 m is what the last bit could flip): measured
    0.1268 m with seeds 1 and 2, as every scan."""
    every_scan = REAL_LOGS["fr-clinic"][1]
    e = _relations_error(real_data, "fr-clinic", odometry_noise_seed=1)
    assert abs(e.trans_mean - every_scan) <= 0.001, f"{e.trans_mean:.4f} m"


@pytest.mark.parametrize("name", WINDOWS)
def test_dropped_scans_change_little(real_data, name):
    """10 % of the scans dropped (the robustness bound: no log's error may change by more
    than 25 % or 1 cm). MIT CSAIL: a 5 Hz laser then turns up to 50 degrees between two
    scans, into space the local map has not seen; unless the tracker matches such a scan
    against the previous one, five doubtful scans follow the odometry and force a keyframe
    14-17 degrees off: 0.73 m (measured 0.0287 m). Freiburg 079: with the bag's laser mount
    (+0.04 m) the result swings between 0.064 m and 0.040 m over the whole log. Measured on
    the windows: Intel 0.0168 m, ACES 0.0322 m, Freiburg 079 0.0254 m."""
    every_scan = WINDOWS[name]
    e = _window_error(name, drop_fraction=0.1)
    assert e.n_used < e.n_total  # relations at dropped scans cannot be evaluated
    assert e.trans_mean <= _robustness_bound(every_scan), (
        f"{name}: {e.trans_mean:.4f} m (every scan {every_scan} m)"
    )


@pytest.mark.parametrize("seed", [None, 1])
def test_aces_revisit_is_closed_whatever_the_last_bit(real_data, seed):
    """ACES's revisit (scans 158-172 against 4194-4422): with a Cauchy scale of 1 the
    closures there lost most of their pull and the two visits stayed 1.1-1.3 m apart unless
    the last bit happened to help (0.0465 m unperturbed, 0.0345 m with seed 1); measured
    0.0341 m unperturbed and with seed 1 (at the default 3)."""
    e = _relations_error(real_data, "aces", odometry_noise_seed=seed)
    assert e.trans_mean <= 0.040, f"seed {seed}: {e.trans_mean:.4f} m"


# Sparse copies (one scan per metre or half radian, fhslam.sim.sparsify), scored on the whole
# log's relations with the scans between extended by the odometry
# (fhslam.metrics.extend_by_odometry: a floor of 4-16 cm, the full run's poses extended so).
# Measured mean translational error, metres: the default, the paper's procedure, odometry.
SPARSE = {
    "intel": (0.0500, 6.15, 7.38),
    "aces": (0.0407, 0.659, 0.549),
    "mit-csail": (0.0535, 1.57, 1.68),
    "fr079": (0.4066, 4.77, 6.50),
    "fr101": (0.1568, 1.03, 3.46),
    "mit-killian-full": (1.547, 15.74, 28.35),
}


@functools.cache
def _sparse_error(name, method):
    from fhslam.datasets import find_dataset, load_log
    from fhslam.experiments.draw_runs import sparse_error
    from fhslam.io import read_relations

    return sparse_error(load_log(name), read_relations(find_dataset(name, "relations")), method)


@pytest.mark.parametrize("name", SPARSE)
def test_a_sparse_copy_beats_the_odometry_and_the_papers_procedure(real_data, name):
    """Every step a metre or half a radian: the default at most half the odometry's and the
    paper's procedure's error, and within 25 % or 1 cm of what was measured."""
    measured, fht, odometry = SPARSE[name]
    got = _sparse_error(name, "graph")
    assert got <= max(1.25 * measured, measured + 0.01), f"{name}: {got:.4f} m"
    assert got <= 0.5 * min(_sparse_error(name, "fht"), _sparse_error(name, "odometry"))
    assert _sparse_error(name, "odometry") == pytest.approx(odometry, rel=1e-3)
    assert _sparse_error(name, "fht") == pytest.approx(fht, rel=0.25)


@pytest.mark.xfail(strict=True, reason="the hospital's sparse copy is tracked worse than odometry")
def test_the_hospitals_sparse_copy_beats_its_odometry(real_data):
    """Measured 0.98 m against the odometry's 0.61 m (the paper's procedure 3.2 m): among
    people, a scan every three seconds scores under ``min_score`` along its corridors and is
    left at the odometry's guess, and the stood-still search can still win there."""
    assert _sparse_error("fr-clinic", "graph") < _sparse_error("fr-clinic", "odometry")
