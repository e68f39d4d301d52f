"""The Kümmerle et al. (2009) relations metric: relations files, the error, the command."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from conftest import data_dir

from fhslam.cli import main
from fhslam.geometry import compose, relative
from fhslam.io import (
    RelationsFormatError,
    read_carmen,
    read_relations,
    write_trajectory,
)
from fhslam.io import write_relations as save_relations
from fhslam.metrics import (
    RelationsError,
    extend_by_odometry,
    relations_error,
    relations_errors,
    sample_relations,
)

FIELDS = (
    "trans_mean",
    "trans_std",
    "trans_sq_mean",
    "trans_sq_std",
    "rot_mean_deg",
    "rot_std_deg",
    "rot_sq_mean_deg",
    "rot_sq_std_deg",
)


def trajectory(n: int = 80, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Timestamps (n,) at 10 Hz and a wiggly (n, 3) trajectory of poses (x, y, theta)."""
    rng = np.random.default_rng(seed)
    steps = np.column_stack(
        [rng.uniform(0.05, 0.3, n), rng.normal(0, 0.02, n), rng.normal(0, 0.2, n)]
    )
    poses = [np.array([1.0, 2.0, 0.3])]
    for s in steps[1:]:
        poses.append(compose(poses[-1], s))
    return 1000.0 + 0.1 * np.arange(n), np.array(poses)


def relations_of(t: np.ndarray, poses: np.ndarray, pairs) -> tuple[np.ndarray, ...]:
    """True relations ``(t1, t2, rel)`` between the given index pairs of a trajectory."""
    ij = np.asarray(pairs)
    return t[ij[:, 0]], t[ij[:, 1]], relative(poses[ij[:, 0]], poses[ij[:, 1]])


def write_relations(path, t1, t2, rel, header: str | None = None) -> None:
    """A relations file as the benchmark writes them (z, roll, pitch = 0)."""
    lines = [] if header is None else [f"# {header}"]
    for a, b, (x, y, yaw) in zip(t1.tolist(), t2.tolist(), rel.tolist(), strict=True):
        lines.append(f"{a!r} {b!r} {x!r} {y!r} 0.000000 0.000000 -0.000000 {yaw!r}")
    path.write_text("\n".join(lines) + "\n")


def run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "fhslam.cli", *args], capture_output=True, text=True, timeout=300
    )


# A straight line along x with one heading error of 10 degrees on pose 1. The relations
# (0, 1), (1, 2), (2, 3) are 1 m forward. By hand, with a = 10 deg:
#   (0, 1): estimate (1, 0, a)                    -> error (0, 0, a): 0 m, 10 deg;
#   (1, 2): estimate (cos a, -sin a, -a)          -> error (cos a - 1, -sin a, -a):
#           |(cos a - 1, -sin a)| = sqrt(2 - 2 cos a) = 2 sin(a / 2) m, 10 deg;
#   (2, 3): exact                                 -> 0 m, 0 deg.
LINE_T = np.array([0.0, 0.1, 0.2, 0.3])
LINE = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [3.0, 0.0, 0.0]])
LINE_T1, LINE_T2 = LINE_T[:3], LINE_T[1:]
LINE_REL = np.array([[1.0, 0.0, 0.0]] * 3)
ALPHA = np.radians(10.0)
A = 2 * np.sin(ALPHA / 2)  # 0.17431... m
LINE_EXPECTED = {
    "trans_mean": A / 3,
    "trans_std": A * np.sqrt(2) / 3,  # population std of (0, A, 0)
    "trans_sq_mean": A**2 / 3,
    "trans_sq_std": A**2 * np.sqrt(2) / 3,
    "rot_mean_deg": 20 / 3,  # (10, 10, 0) degrees
    "rot_std_deg": 10 * np.sqrt(2) / 3,
    "rot_sq_mean_deg": 200 / 3,  # (100, 100, 0) deg^2
    "rot_sq_std_deg": 100 * np.sqrt(2) / 3,
}


def perturbed_line() -> np.ndarray:
    est = LINE.copy()
    est[1, 2] += ALPHA
    return est


# ------------------------------------------------------------------------- relations files


def test_read_relations_round_trip_with_comments_and_blank_lines(tmp_path):
    t, poses = trajectory(20)
    t1, t2, rel = relations_of(t, poses, [[0, 5], [3, 4], [19, 2]])
    path = tmp_path / "x.relations"
    write_relations(path, t1, t2, rel, header="timestamp1 timestamp2 x y z roll pitch yaw")
    path.write_text(path.read_text() + "\n   \n# trailing comment\n")
    a, b, r = read_relations(path)
    assert a.shape == b.shape == (3,) and r.shape == (3, 3)
    np.testing.assert_array_equal(a, t1)
    np.testing.assert_array_equal(b, t2)
    np.testing.assert_array_equal(r, rel)  # x, y, yaw: z, roll, pitch are dropped


@pytest.mark.parametrize(
    ("name", "count"),
    [
        ("intel", 2984),
        ("aces", 1279),
        ("mit-csail", 1172),
        ("fr-clinic", 2820),
        ("fr079", 1685),
        ("mit-killian", 4677),
    ],
)
def test_real_relations_files(name, count):
    d = data_dir()
    path = None if d is None else d / f"{name}.relations"
    if path is None or not path.is_file():
        pytest.skip(f"{name}.relations not found: set FHSLAM_DATA or place it in ../shared/data")
    t1, t2, rel = read_relations(path)
    assert t1.shape == t2.shape == (count,) and rel.shape == (count, 3)
    assert np.all(np.isfinite(rel)) and np.all(np.abs(rel[:, 2]) <= np.pi + 1e-5)
    assert np.all(t1 != t2)
    if name == "fr-clinic":
        first = path.read_text().splitlines()[0]
        assert first.startswith("#")  # the one header line is skipped
        assert np.hypot(rel[:, 0], rel[:, 1]).max() <= 5.0 + 1e-6  # the local relation set


GOOD = "10.5 11.5 0.3 0.01 0.000000 0.000000 0.000000 0.02"


@pytest.mark.parametrize(
    ("content", "expected"),
    [
        (f"# header\n{GOOD}\n10.5 11.5 0.3 0.01 0 0 0\n", r"r\.relations:3: expected 8 fields"),
        (f"{GOOD}\n{GOOD} 7\n", r"r\.relations:2: expected 8 fields .* found 9"),
        (f"{GOOD}\n\n10.5 11.5 0.3 x 0 0 0 0.02\n", r"r\.relations:3: non-numeric value 'x'"),
        ("10.5 11.5 nan 0.01 0 0 0 0.02\n", r"r\.relations:1: non-finite"),
        (f"{GOOD}\n10.5 11.5 0.3 0.01 0.2 0 0 0.02\n", r"r\.relations:2: z = 0\.2 is not 0"),
        ("10.5 11.5 0.3 0.01 0 -0.001 0 0.02\n", r"r\.relations:1: roll = -0\.001 .*2-D"),
        ("10.5 11.5 0.3 0.01 0 0 0.5 0.02\n", r"r\.relations:1: pitch"),
        ("# only a comment\n\n", r"r\.relations: no relations found"),
    ],
    ids=["short", "long", "non-numeric", "nan", "z", "roll", "pitch", "empty"],
)
def test_malformed_relations_name_file_and_line(tmp_path, content, expected):
    path = tmp_path / "r.relations"
    path.write_text(content)
    with pytest.raises(RelationsFormatError, match=expected):
        read_relations(path)


def test_tiny_z_roll_pitch_are_accepted_and_missing_file(tmp_path):
    path = tmp_path / "r.relations"
    path.write_text("1 2 0.3 0.01 1e-7 -1e-6 0 0.02\n")
    _, _, rel = read_relations(path)
    np.testing.assert_array_equal(rel, [[0.3, 0.01, 0.02]])
    with pytest.raises(FileNotFoundError) as info:
        read_relations(tmp_path / "nope.relations")
    assert info.value.filename == str(tmp_path / "nope.relations")
    assert issubclass(RelationsFormatError, ValueError)


# ------------------------------------------------------------------------------ the metric


def test_relations_of_the_true_trajectory_give_zero_error():
    t, poses = trajectory()
    rng = np.random.default_rng(5)
    pairs = np.column_stack([rng.integers(0, 80, 200), rng.integers(0, 80, 200)])
    t1, t2, rel = relations_of(t, poses, pairs)  # short and long, both directions
    e = relations_error(t, poses, t1, t2, rel)
    assert (e.n_used, e.n_total) == (200, 200)
    for name in FIELDS:
        assert getattr(e, name) < 1e-12, name
    # A rigid motion of the whole trajectory changes no relative motion.
    e = relations_error(t, compose([5.0, -3.0, 2.0], poses), t1, t2, rel)
    assert max(getattr(e, name) for name in FIELDS) < 1e-12
    # On an axis-aligned trajectory the arithmetic is exact: exactly 0.
    e = relations_error(LINE_T, LINE, LINE_T1, LINE_T2, LINE_REL)
    assert all(getattr(e, name) == 0.0 for name in FIELDS)


def test_one_heading_error_gives_the_hand_computed_numbers():
    e = relations_error(LINE_T, perturbed_line(), LINE_T1, LINE_T2, LINE_REL)
    assert isinstance(e, RelationsError)
    for name, value in LINE_EXPECTED.items():
        assert getattr(e, name) == pytest.approx(value, rel=1e-12, abs=1e-15), name
    assert (e.n_used, e.n_total) == (3, 3)
    # Per relation: Kümmerle's δ ⊖ δ* puts the translational error on relation (1, 2).
    trans, rot, used = relations_errors(LINE_T, perturbed_line(), LINE_T1, LINE_T2, LINE_REL)
    np.testing.assert_allclose(trans, [0.0, A, 0.0], atol=1e-15)
    np.testing.assert_allclose(np.degrees(rot), [10.0, 10.0, 0.0], atol=1e-12)
    assert used.all()


def test_rotation_error_is_wrapped():
    est = LINE.copy()
    est[3, 2] += 2 * np.pi - np.radians(1.0)  # a -1 degree error written as +359 degrees
    trans, rot, _ = relations_errors(LINE_T, est, LINE_T1, LINE_T2, LINE_REL)
    np.testing.assert_allclose(np.degrees(rot), [0.0, 0.0, 1.0], atol=1e-9)
    assert trans.max() < 1e-12


def test_relation_with_an_unknown_stamp_is_skipped_and_counted():
    t1 = np.r_[LINE_T1, 0.1, 7.0]
    t2 = np.r_[LINE_T2, 42.0, 0.2]  # (0.1, 42.0) and (7.0, 0.2): one stamp not in the log
    rel = np.vstack([LINE_REL, [[5.0, 5.0, 1.0], [5.0, 5.0, 1.0]]])
    e = relations_error(LINE_T, perturbed_line(), t1, t2, rel)
    assert (e.n_used, e.n_total) == (3, 5)
    for name, value in LINE_EXPECTED.items():
        assert getattr(e, name) == pytest.approx(value, rel=1e-12, abs=1e-15), name
    _, _, used = relations_errors(LINE_T, perturbed_line(), t1, t2, rel)
    np.testing.assert_array_equal(used, [True, True, True, False, False])


def test_stamps_within_max_diff_match():
    # Off by 0.3-0.9 ms, like mit-csail's 5-decimal relation stamps against its 6-decimal log.
    t1 = LINE_T1 + np.array([4e-4, -6e-4, 9e-4])
    t2 = LINE_T2 + np.array([-8e-4, 3e-4, 7e-4])
    e = relations_error(LINE_T, perturbed_line(), t1, t2, LINE_REL)
    assert e.n_used == 3 and e.rot_mean_deg == pytest.approx(20 / 3)
    e = relations_error(LINE_T, perturbed_line(), t1, t2, LINE_REL, max_diff=6.5e-4)
    assert (e.n_used, e.n_total) == (1, 3)  # only relation (1, 2) has both within 0.65 ms
    assert e.rot_mean_deg == pytest.approx(10.0) and e.trans_mean == pytest.approx(A)
    with pytest.raises(ValueError, match=r"no relation can be used: 2 of the 6 relation"):
        relations_error(LINE_T, perturbed_line(), t1, t2, LINE_REL, max_diff=4.5e-4)
    with pytest.raises(ValueError, match=r"0 of the 6 relation timestamps match"):
        relations_error(LINE_T + 100.0, LINE, LINE_T1, LINE_T2, LINE_REL)


def test_statistics_against_numpy_by_hand():
    t, poses = trajectory(seed=7)
    rng = np.random.default_rng(8)
    pairs = np.column_stack([rng.integers(0, 80, 300), rng.integers(0, 80, 300)])
    t1, t2, rel = relations_of(t, poses, pairs)
    rel = rel + rng.normal(0, [0.05, 0.05, 0.03], rel.shape)  # noisy "true" relations
    e = relations_error(t, poses, t1, t2, rel)

    def rot(th):
        return np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])

    trans, rot_deg = [], []
    for (i, j), (x, y, yaw) in zip(pairs, rel, strict=True):
        # Estimated motion in frame i, then its difference from the true one in SE(2)
        # matrices: E = T*^-1 T_est.
        d = rot(poses[i, 2]).T @ (poses[j, :2] - poses[i, :2])
        dth = poses[j, 2] - poses[i, 2]
        err_xy = rot(yaw).T @ (d - np.array([x, y]))
        err_th = np.arctan2(np.sin(dth - yaw), np.cos(dth - yaw))
        trans.append(np.hypot(*err_xy))
        rot_deg.append(abs(err_th) * 180 / np.pi)
    trans, rot_deg = np.array(trans), np.array(rot_deg)

    def mean_std(v):
        m = v.sum() / len(v)
        return m, np.sqrt(((v - m) ** 2).sum() / len(v))  # population std

    expected = [
        *mean_std(trans),
        *mean_std(trans**2),
        *mean_std(rot_deg),
        *mean_std(rot_deg**2),
    ]
    for name, value in zip(FIELDS, expected, strict=True):
        assert getattr(e, name) == pytest.approx(value, rel=1e-9), name
    assert e.n_used == e.n_total == 300
    assert e.as_dict() == {**{n: getattr(e, n) for n in FIELDS}, "n_used": 300, "n_total": 300}


def test_bad_arguments():
    with pytest.raises(ValueError, match="same length"):
        relations_error(LINE_T[:3], LINE, LINE_T1, LINE_T2, LINE_REL)
    with pytest.raises(ValueError, match="t1, t2 and rel"):
        relations_error(LINE_T, LINE, LINE_T1[:2], LINE_T2, LINE_REL)
    with pytest.raises(ValueError, match="rel must have shape"):
        relations_error(LINE_T, LINE, LINE_T1, LINE_T2, LINE_REL[:, :2])
    with pytest.raises(ValueError, match="max_diff"):
        relations_error(LINE_T, LINE, LINE_T1, LINE_T2, LINE_REL, max_diff=-1.0)
    with pytest.raises(ValueError, match="no relation can be used"):
        relations_error(np.zeros(0), np.zeros((0, 3)), LINE_T1, LINE_T2, LINE_REL)


# ----------------------------------------------------------------------------- the command


@pytest.fixture
def line_files(tmp_path):
    """The perturbed line as a trajectory file and its relations, plus one 50 ms off."""
    traj, rels = tmp_path / "traj.txt", tmp_path / "line.relations"
    write_trajectory(traj, LINE_T, perturbed_line())
    write_relations(rels, np.r_[LINE_T1, 0.35], np.r_[LINE_T2, 0.1], np.vstack([LINE_REL, LINE[1]]))
    return traj, rels


def test_evaluate_relations_json(line_files, capsys):
    traj, rels = line_files
    assert main(["evaluate", str(traj), "--relations", str(rels), "--json"]) == 0
    out = capsys.readouterr().out
    assert out.count("\n") == 1
    result = json.loads(out)
    assert set(result) == {f"relations_{n}" for n in FIELDS} | {
        "relations_used",
        "relations_total",
    }
    for name, value in LINE_EXPECTED.items():
        assert result[f"relations_{name}"] == pytest.approx(value, rel=1e-12, abs=1e-15)
    assert (result["relations_used"], result["relations_total"]) == (3, 4)


def test_evaluate_relations_table(line_files, capsys):
    traj, rels = line_files
    assert main(["evaluate", str(traj), "--relations", str(rels)]) == 0
    text = capsys.readouterr().out
    assert f"translational error: {A / 3:.4f} ± {A * np.sqrt(2) / 3:.4f} m" in text
    assert "rotational error:" in text and "6.667 ± 4.714 deg" in text
    assert "squared 66.667 ± 47.140 deg²" in text and "m²" in text
    assert "3 of 4 relations used" in text


def test_evaluate_truth_and_relations_together_is_a_usage_error(line_files):
    traj, rels = line_files
    r = run("evaluate", str(traj), "--truth", str(traj), "--relations", str(rels))
    assert r.returncode == 2 and "not allowed with" in r.stderr
    r = run("evaluate", str(traj))
    assert r.returncode == 2 and "--truth" in r.stderr and "--relations" in r.stderr


def test_evaluate_relations_errors_are_one_line(line_files, tmp_path):
    traj, rels = line_files
    r = run("evaluate", str(traj), "--relations", str(rels), "--world", "paper")
    assert r.returncode == 2 and r.stderr.count("\n") == 1
    assert "--world" in r.stderr and "--truth" in r.stderr
    bad = tmp_path / "bad.relations"
    bad.write_text(f"{GOOD}\n1 2 3\n")
    r = run("evaluate", str(traj), "--relations", str(bad), "--json")
    assert r.returncode == 2 and r.stdout == "" and "Traceback" not in r.stderr
    assert r.stderr.count("\n") == 1 and "bad.relations:2:" in r.stderr
    far = tmp_path / "far.relations"
    far.write_text(GOOD + "\n")
    r = run("evaluate", str(traj), "--relations", str(far))
    assert r.returncode == 2 and r.stderr.count("\n") == 1
    assert "traj.txt" in r.stderr and "far.relations" in r.stderr
    assert "no relation can be used" in r.stderr
    # --max-diff widens the matching: the stamp 0.35 is 50 ms from the pose at 0.3.
    r = run("evaluate", str(traj), "--relations", str(rels), "--max-diff", "0.06", "--json")
    assert r.returncode == 0 and json.loads(r.stdout)["relations_used"] == 4


# ------------------------------------------------------------------------------- real data


def test_mit_csail_odometry_against_its_relations():
    d = data_dir()
    if (
        d is None
        or not (d / "mit-csail.clf").is_file()
        or not (d / "mit-csail.relations").is_file()
    ):
        pytest.skip("mit-csail.clf/.relations not found: set FHSLAM_DATA or use ../shared/data")
    log = read_carmen(d / "mit-csail.clf")
    t1, t2, rel = read_relations(d / "mit-csail.relations")
    e = relations_error(log.timestamps, log.odometry, t1, t2, rel)
    print(
        f"mit-csail odometry: trans {e.trans_mean:.4f} ± {e.trans_std:.4f} m, "
        f"rot {e.rot_mean_deg:.3f} ± {e.rot_std_deg:.3f} deg, {e.n_used} of {e.n_total}"
    )
    assert (e.n_used, e.n_total) == (1172, 1172)  # 5-decimal stamps vs the log's 6
    assert np.isfinite(e.trans_mean) and e.trans_mean > 0
    assert np.isfinite(e.rot_mean_deg) and e.rot_mean_deg > 0
    # The rounding is below 10 µs: with 0.1 ms of slack every relation still matches.
    assert relations_error(log.timestamps, log.odometry, t1, t2, rel, max_diff=1e-4).n_used == 1172


def lap(n_per_lap: int = 399, laps: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """A circle of radius 5 m driven ``laps`` times at 8/3 Hz, 150 s a lap."""
    a = 2 * np.pi * np.arange(n_per_lap * laps) / n_per_lap
    poses = np.column_stack([5 * np.cos(a), 5 * np.sin(a), a + np.pi / 2])
    return 1000.0 + 0.375 * np.arange(len(a)), poses


def test_sampled_relations_step_along_the_path_and_join_revisits():
    t, p = lap()
    t1, t2, rel = sample_relations(t, p)
    chord = 10 * np.sin(np.pi / 399)  # 7.87 cm a pose: anchors every 7th (0.55 m, 6.3 deg)
    seq = np.arange(len(t1)) < (len(t) - 1) // 7  # one relation from each anchor to the next
    np.testing.assert_allclose(np.diff(t1[seq]), 7 * 0.375)
    np.testing.assert_allclose(np.hypot(rel[seq, 0], rel[seq, 1]), 10 * np.sin(7 * np.pi / 399))
    np.testing.assert_allclose(rel[seq, 2], 14 * np.pi / 399)
    assert chord < 0.08
    # revisits: the 57 anchors of the second lap lie on those of the first, 150 s later
    # (identity relations), and the first lap's last anchor, 0.55 m short of the start
    # and 147 s after it, joins the first
    rev = ~seq
    assert rev.sum() == 58
    same = np.isclose(t2 - t1, 399 * 0.375)
    assert same.sum() == 57 and not same[seq].any()
    np.testing.assert_allclose(rel[same], 0.0, atol=1e-9)
    # on the truth the error is zero; on a copy whose second lap is shifted by 0.3 m
    # only its revisits and the one relation across the shift see it
    e = relations_error(t, p, t1, t2, rel)
    assert e.trans_mean == pytest.approx(0.0, abs=1e-12) and e.n_used == len(t1)
    moved = p.copy()
    moved[399:, 0] += 0.3
    trans, _, _ = relations_errors(t, moved, t1, t2, rel)
    np.testing.assert_allclose(trans[same], 0.3, rtol=1e-9)
    assert np.count_nonzero(trans[~same] > 1e-9) == 1


def test_sampled_relations_are_frame_invariant_and_turns_make_anchors():
    t, p = lap(laps=1)
    moved = np.column_stack(
        [
            p[:, 0] * np.cos(0.6) - p[:, 1] * np.sin(0.6) - 3.3,
            p[:, 0] * np.sin(0.6) + p[:, 1] * np.cos(0.6) + 2.1,
            p[:, 2] + 0.6,
        ]
    )
    a, b = sample_relations(t, p), sample_relations(t, moved)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_allclose(a[2], b[2], atol=1e-9)
    # turning on the spot by 0.7 degrees a pose: an anchor every 15 poses (10.5 degrees)
    spin = np.column_stack([np.zeros(106), np.zeros(106), np.radians(0.7 * np.arange(106))])
    t1, _, rel = sample_relations(0.1 * np.arange(106), spin)
    assert len(t1) == 7
    np.testing.assert_allclose(np.degrees(rel[:, 2]), 10.5, atol=1e-9)


@pytest.mark.parametrize("seed", range(4))
def test_sampled_anchors_do_not_hang_on_the_last_bit(seed):
    # A robot 10 cm a scan reaches 0.5 m at the fifth scan exactly, as a simulated one does;
    # noise of 1e-12 m (far above a last bit, far below anything measured) moves no anchor.
    x = 0.1 * np.arange(101) + np.random.default_rng(seed).normal(0.0, 1e-12, 101)
    t1, t2, rel = sample_relations(np.arange(101.0), np.column_stack([x, 0 * x, 0 * x]))
    np.testing.assert_array_equal(t1, 5.0 * np.arange(20))
    np.testing.assert_array_equal(t2, t1 + 5.0)
    np.testing.assert_allclose(rel[:, 0], 0.5, atol=1e-11)


@pytest.mark.parametrize(
    "args, message",
    [
        ((np.arange(3.0), np.zeros((2, 3))), "one pose per timestamp"),
        ((np.arange(3.0), np.full((3, 3), np.nan)), "truth must be finite"),
        ((np.array([0.0, 1.0, 1.0]), np.zeros((3, 3))), "strictly increasing"),
        ((np.arange(3.0), np.zeros((3, 3))), "too little for one relation"),
        ((np.arange(3.0), np.zeros((3, 3)), 0.0), "step must be a positive number"),
    ],
)
def test_sample_relations_bad_input(args, message):
    with pytest.raises(ValueError, match=message):
        sample_relations(*args)


def test_write_relations_round_trip_and_bad_input(tmp_path):
    t, p = lap(laps=1)
    t1, t2, rel = sample_relations(t, p)
    path = tmp_path / "r.relations"
    save_relations(path, t1, t2, rel, header="made here\nsecond line")
    assert path.read_text().startswith("# made here\n# second line\n")
    r1, r2, rr = read_relations(path)
    np.testing.assert_array_equal(r1, t1)
    np.testing.assert_array_equal(r2, t2)
    np.testing.assert_array_equal(rr, rel)
    with pytest.raises(ValueError, match="shapes"):
        save_relations(path, t1, t2[:-1], rel)
    with pytest.raises(ValueError, match="finite"):
        save_relations(path, t1, t2, np.full_like(rel, np.inf))


def test_simulate_relations_measure_a_run_as_a_real_log_is(tmp_path, capsys):
    log, truth, rel = tmp_path / "c.clf", tmp_path / "t.txt", tmp_path / "c.relations"
    main(["simulate", "corridor", "--log", str(log), "--truth", str(truth),
          "--relations", str(rel)])  # fmt: skip
    assert "61 relations to" in capsys.readouterr().out
    main(["evaluate", str(truth), "--relations", str(rel), "--json"])
    e = json.loads(capsys.readouterr().out)
    assert e["relations_used"] == e["relations_total"] == 61
    assert e["relations_trans_mean"] == pytest.approx(0.0, abs=1e-9)


def test_extend_by_odometry_fills_the_scans_between_by_the_odometry():
    """Scans between two trajectory scans get the earlier one's pose moved by the odometry:
    a trajectory that is the odometry moved rigidly extends to exactly that motion."""
    rng = np.random.default_rng(3)
    odo = np.cumsum(rng.normal(0, 0.1, (40, 3)), axis=0)
    t = np.arange(40) * 0.1 + 5.0
    keep = np.array([0, 7, 8, 20, 39])
    moved = compose([1.0, -2.0, 0.7], odo)
    out = extend_by_odometry(t[keep], moved[keep], t, odo)
    np.testing.assert_allclose(out, moved, atol=1e-12)
    # a kept pose that is off carries its error to the scans after it, until the next one
    off = moved[keep].copy()
    off[1, 0] += 0.5
    err = np.hypot(*(extend_by_odometry(t[keep], off, t, odo) - moved)[:, :2].T)
    assert np.all(err[7] == pytest.approx(0.5)) and np.all(err[:7] < 1e-12)
    assert np.all(err[8:] < 1e-12)


@pytest.mark.parametrize(
    "keep",
    [[1, 5], [0, 5, 5], [0, 3, 2], [], [0, 40]],
    ids=["not-from-the-first", "repeated", "not-increasing", "empty", "beyond-the-log"],
)
def test_extend_by_odometry_refuses_a_trajectory_not_of_the_log(keep):
    odo = np.zeros((40, 3))
    t = np.arange(40) * 0.1
    ts = np.array([t[k] if k < 40 else 99.0 for k in keep])
    with pytest.raises(ValueError, match="scan timestamps of the log"):
        extend_by_odometry(ts, np.zeros((len(keep), 3)), t, odo)
    with pytest.raises(ValueError, match="same lengths"):
        extend_by_odometry(t[:3], np.zeros((2, 3)), t, odo)
