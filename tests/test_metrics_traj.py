"""Trajectory metrics (ATE, RPE, association), map metrics and map files."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from conftest import ROOM

from fhslam.geometry import compose, distance_to_segments, transform_points
from fhslam.io import MapFormatError, lines_from_segments, read_map, write_map
from fhslam.metrics import (
    ErrorStats,
    align_se2,
    associate,
    ate,
    error_stats,
    map_coverage,
    map_error,
    rpe,
    rpe_errors,
    rpe_pairs,
    rpe_rot_deg,
    sample_segments,
)
from fhslam.sim import observed_wall_points, paper_world, simulate, visible_wall_points


def trajectory(n: int = 60, seed: int = 0) -> np.ndarray:
    """A wiggly (n, 3) trajectory of poses (x, y, theta)."""
    rng = np.random.default_rng(seed)
    steps = np.column_stack(
        [rng.uniform(0.05, 0.2, n), rng.normal(0, 0.01, n), rng.normal(0, 0.1, n)]
    )
    poses = [np.array([1.0, 2.0, 0.3])]
    for s in steps[1:]:
        poses.append(compose(poses[-1], s))
    return np.array(poses)


# ------------------------------------------------------------------------------- statistics


def test_error_stats_match_numpy():
    e = np.random.default_rng(1).exponential(0.2, 101)
    s = error_stats(e)
    assert isinstance(s, ErrorStats)
    assert s.rmse == pytest.approx(np.sqrt(np.mean(e**2)), abs=1e-15)
    assert s.mean == pytest.approx(e.sum() / len(e), abs=1e-15)
    assert s.median == np.sort(e)[50]
    assert s.std == pytest.approx(np.sqrt(np.mean((e - e.mean()) ** 2)), abs=1e-15)
    assert (s.min, s.max) == (e.min(), e.max())
    assert s.as_dict() == {
        "rmse": s.rmse,
        "mean": s.mean,
        "median": s.median,
        "std": s.std,
        "min": s.min,
        "max": s.max,
    }
    with pytest.raises(ValueError, match="at least one"):
        error_stats([])
    with pytest.raises(ValueError, match="non-finite"):
        error_stats([0.1, np.nan])


# ------------------------------------------------------------------------------- association


def test_associate_jittered_timestamps():
    rng = np.random.default_rng(2)
    t_ref = np.arange(50) * 0.2
    t_est = t_ref + rng.uniform(-0.004, 0.004, 50)
    t_est[[7, 30]] += 0.05  # two late estimates: no partner within 10 ms
    i_est, i_ref = associate(t_est, t_ref)
    keep = np.setdiff1d(np.arange(50), [7, 30])
    np.testing.assert_array_equal(i_est, keep)
    np.testing.assert_array_equal(i_ref, keep)
    assert np.abs(t_est[i_est] - t_ref[i_ref]).max() <= 0.01


def test_associate_iterates_the_shorter_trajectory_in_any_order():
    t_ref = np.arange(100) * 0.1  # dense truth
    t_est = np.array([5.003, 0.998, 3.0, 42.0])  # sparse, unsorted, one outside
    i_est, i_ref = associate(t_est, t_ref)
    np.testing.assert_array_equal(i_est, [0, 1, 2])
    np.testing.assert_array_equal(i_ref, [50, 10, 30])
    # The other way round: the estimate is the longer one.
    i_est, i_ref = associate(t_ref, t_est)
    np.testing.assert_array_equal(i_est, [50, 10, 30])
    np.testing.assert_array_equal(i_ref, [0, 1, 2])
    assert associate([], t_ref)[0].shape == (0,)
    np.testing.assert_array_equal(associate(t_est, t_ref, max_diff=0.001), [[2], [30]])
    with pytest.raises(ValueError, match="max_diff"):
        associate(t_est, t_ref, max_diff=-1)


# ------------------------------------------------------------------------------------- ATE


def test_ate_identical_is_zero():
    p = trajectory()
    assert ate(p, p) == ErrorStats(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def test_ate_constant_offset_is_exactly_half_a_metre():
    ref = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.5], [2.0, 1.0, 1.0], [2.0, 3.0, -2.0]])
    est = ref + np.array([0.3, 0.4, 0.0])
    s = ate(est, ref)
    for value in (s.rmse, s.mean, s.median, s.min, s.max):
        assert value == pytest.approx(0.5, abs=1e-15)  # up to the rounding of ref + 0.3
    assert s.std < 1e-15


def test_ate_align_recovers_a_rigid_motion():
    ref = trajectory()
    motion = np.array([3.0, -2.0, 0.7])
    est = compose(motion, ref)
    assert ate(est, ref).rmse > 1.0
    assert ate(est, ref, align=True).max < 1e-9
    t = align_se2(est, ref)
    np.testing.assert_allclose(compose(t, motion), 0.0, atol=1e-12)


def test_ate_align_is_least_squares():
    rng = np.random.default_rng(3)
    ref = trajectory()
    est = compose([0.5, 0.2, -0.3], ref) + rng.normal(0, 0.05, ref.shape)
    best = ate(est, ref, align=True).rmse
    t = align_se2(est, ref)
    for dt in ([1e-3, 0, 0], [0, 1e-3, 0], [0, 0, 1e-3], [0, 0, -1e-3]):
        moved = transform_points(compose(dt, t), est[:, :2])  # perturb the optimum
        assert np.sqrt(np.mean(np.sum((moved - ref[:, :2]) ** 2, axis=1))) > best


def test_ate_needs_associated_poses():
    with pytest.raises(ValueError, match="associate"):
        ate(np.zeros((3, 3)), np.zeros((4, 3)))
    with pytest.raises(ValueError, match="shape"):
        ate(np.zeros((3, 4)), np.zeros((3, 4)))


# ------------------------------------------------------------------------------------- RPE


def test_rpe_of_a_constant_offset_is_zero():
    ref = trajectory()
    est = ref + np.array([0.3, 0.4, 0.0])
    assert rpe(est, ref).max < 1e-12
    assert rpe_rot_deg(est, ref).max < 1e-12
    # A rigid motion of the whole trajectory changes no relative pose either.
    est = compose([3.0, -2.0, 0.7], ref)
    assert rpe(est, ref, delta=5, all_pairs=True).max < 1e-12


def test_rpe_sees_a_single_jump_once():
    ref = trajectory(21)
    est = ref.copy()
    est[10:, :2] += [0.6, -0.8]  # a 1 m jump between frames 9 and 10
    trans, rot = rpe_errors(est, ref)
    assert len(trans) == 20
    assert trans[9] == pytest.approx(1.0, abs=1e-12)
    assert np.delete(trans, 9).max() < 1e-12
    assert rot.max() < 1e-12
    s = rpe(est, ref)
    assert s.max == pytest.approx(1.0) and s.mean == pytest.approx(1.0 / 20)
    assert s.rmse == pytest.approx(np.sqrt(1.0 / 20))
    # A heading jump of 10 degrees shows in the rotation part.
    est = ref.copy()
    est[10:, 2] += np.radians(10)
    assert rpe_rot_deg(est, ref).max == pytest.approx(10.0)


def test_rpe_pairs_follow_evo():
    np.testing.assert_array_equal(rpe_pairs(7, 3), [[0, 3], [3, 6]])
    np.testing.assert_array_equal(rpe_pairs(5, 3, all_pairs=True), [[0, 3], [1, 4]])
    assert rpe_pairs(3, 3).shape == (0, 2)
    with pytest.raises(ValueError, match="delta"):
        rpe_pairs(5, 0)
    with pytest.raises(ValueError, match="at least 4 poses"):
        rpe(np.zeros((3, 3)), np.zeros((3, 3)), delta=3)


# --------------------------------------------------------------------------------- the map


def test_sample_segments_spacing_and_ends():
    pts = sample_segments([[0, 0, 1, 0], [0, 0, 0, 0.12]], step=0.05)
    assert len(pts) == 21 + 4
    np.testing.assert_allclose(pts[[0, 20]], [[0, 0], [1, 0]])
    np.testing.assert_allclose(np.diff(pts[:21, 0]), 0.05)
    np.testing.assert_allclose(pts[21:, 1], [0, 0.04, 0.08, 0.12])


def test_distance_to_segments_matches_a_loop():
    rng = np.random.default_rng(4)
    pts = rng.uniform(-1, 7, (500, 2))
    d = distance_to_segments(pts, ROOM)
    for p, dp in zip(pts[:50], d[:50], strict=True):
        best = np.inf
        for x1, y1, x2, y2 in ROOM:
            a, b = np.array([x1, y1]), np.array([x2, y2])
            t = np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0, 1)
            best = min(best, np.hypot(*(p - a - t * (b - a))))
        assert dp == pytest.approx(best, abs=1e-12)


def test_map_error_of_the_true_walls_is_zero():
    walls = paper_world().walls
    assert map_error(lines_from_segments(walls), walls) < 1e-9
    assert map_error(walls, walls) < 1e-9
    assert np.isnan(map_error([], walls))


def test_map_error_of_walls_moved_out_by_3cm():
    # Each wall of the room moved 3 cm outward along its normal: every sample is 3 cm away.
    out = ROOM + 0.03 * np.array([[0, -1, 0, -1], [1, 0, 1, 0], [0, 1, 0, 1], [-1, 0, -1, 0]])
    assert map_error(lines_from_segments(out), ROOM) == pytest.approx(0.03, abs=1e-9)


def test_map_coverage_full_none_and_part():
    observed = sample_segments(ROOM, 0.01)
    assert map_coverage(lines_from_segments(ROOM), observed) == 1.0
    assert map_coverage([], observed) == 0.0
    # Moved 0.5 m north: only the side walls above y = 0.5 m still overlap (7 m of 20 m).
    up = ROOM + np.array([0.0, 0.5, 0.0, 0.5])
    fine = sample_segments(ROOM, 0.001)
    assert map_coverage(up, fine, tol=1e-9) == pytest.approx(7 / 20, abs=1e-3)
    assert map_coverage(up, fine) == pytest.approx(7.2 / 20, abs=1e-3)  # tol 5 cm: 0.2 m more
    far = ROOM + np.array([10.0, 0.0, 10.0, 0.0])
    assert map_coverage(far, observed) == 0.0
    # Half the bottom wall only: 3 m of the 20 m perimeter.
    half = np.array([[0, 0, 3, 0]])
    assert map_coverage(half, fine, tol=1e-9) == pytest.approx(3 / 20, abs=1e-3)
    with pytest.raises(ValueError, match="observed"):
        map_coverage(ROOM, np.zeros((0, 2)))


def test_observed_wall_points_lie_on_the_walls_and_match_ray_casting():
    log = simulate(paper_world(), seed=0)
    pts = observed_wall_points(log, every=5)
    n_hits = int((log.hits[::5] >= 0).sum())
    assert pts.shape == (n_hits, 2)
    assert distance_to_segments(pts, log.world.walls).max() < 1e-9
    # The measured (noisy) points are near their exact counterparts.
    k = 10
    hit = log.hits[k] >= 0
    a = log.angles[hit] + log.truth[k, 2]
    noisy = log.truth[k, :2] + log.ranges[k, hit, None] * np.column_stack([np.cos(a), np.sin(a)])
    exact = observed_wall_points(log, every=1)[(log.hits[:k] >= 0).sum() :][: hit.sum()]
    assert np.hypot(*(noisy - exact).T).max() < 0.06
    cast = visible_wall_points(log.world.walls, log.truth, every=5)
    np.testing.assert_allclose(cast, pts, atol=1e-9)
    assert map_coverage(log.world.walls, pts) == 1.0


# ------------------------------------------------------------------------------- map files


def test_map_json_round_trip(tmp_path):
    lines = lines_from_segments(paper_world().walls, n=7)
    path = tmp_path / "map.json"
    write_map(path, lines)
    back = read_map(path)
    assert len(back) == len(lines)
    for a, b in zip(lines, back, strict=True):
        assert (a.rho, a.theta, a.n, a.length) == (b.rho, b.theta, b.n, b.length)
        np.testing.assert_array_equal(a.sp, b.sp)
        np.testing.assert_array_equal(a.ep, b.ep)
    data = json.loads(path.read_text())
    assert set(data) == {"lines"}
    assert set(data["lines"][0]) == {"sp", "ep", "rho", "theta", "n"}
    write_map(path, [])
    assert read_map(path) == []


GOOD = {"sp": [0, 0], "ep": [1, 0], "rho": 0.0, "theta": 1.5707963267948966, "n": 3}


@pytest.mark.parametrize(
    ("content", "expected"),
    [
        ('{"lines": [\n  {"sp": [0, 0],,\n]}', r"map\.json:2: not valid JSON"),
        ("[1, 2]", r"map\.json: expected a JSON object"),
        ('{"lines": 3}', r"map\.json: 'lines' must be a list"),
        (json.dumps({"lines": [GOOD, {**GOOD, "ep": None}]}), r"map\.json: lines\[1\]: 'ep'"),
        (
            json.dumps({"lines": [GOOD, GOOD, {k: v for k, v in GOOD.items() if k != "rho"}]}),
            r"map\.json: lines\[2\]: missing key 'rho'",
        ),
        (
            json.dumps({"lines": [{**GOOD, "sp": [0, float("nan")]}]}),
            r"map\.json: lines\[0\]: 'sp' coordinate is not finite",
        ),
        (json.dumps({"lines": [{**GOOD, "rho": "1"}]}), r"lines\[0\]: 'rho' must be a number"),
        (json.dumps({"lines": [{**GOOD, "rho": -1.0}]}), r"lines\[0\]: 'rho' must be >= 0"),
        (json.dumps({"lines": [{**GOOD, "n": 2.5}]}), r"lines\[0\]: 'n' must be"),
        (json.dumps({"lines": [GOOD, "oops"]}), r"lines\[1\]: expected an object"),
        (
            json.dumps({"lines": [GOOD, {**GOOD, "ep": [1e308, 0]}]}),
            r"lines\[1\]: 'ep' coordinate 1e\+308 m is beyond the plausible 1e\+06 m",
        ),
        (json.dumps({"lines": [{**GOOD, "rho": 2e6}]}), r"lines\[0\]: 'rho' 2e\+06 m is beyond"),
    ],
    ids=[
        "bad-json",
        "not-object",
        "lines-not-list",
        "bad-point",
        "missing-key",
        "nan",
        "string",
        "negative-rho",
        "fractional-n",
        "not-dict",
        "huge-coordinate",
        "huge-rho",
    ],
)
def test_malformed_map_names_file_and_line(tmp_path, content, expected):
    path = tmp_path / "map.json"
    path.write_text(content)
    with pytest.raises(MapFormatError, match=expected):
        read_map(path)


def test_missing_map_file(tmp_path):
    with pytest.raises(FileNotFoundError) as info:
        read_map(tmp_path / "nope.json")
    assert info.value.filename == str(tmp_path / "nope.json")


def test_write_map_refuses_non_finite(tmp_path):
    (line,) = lines_from_segments([[0, 0, 1, 0]])
    bad = replace(line, ep=np.array([np.inf, 0.0]))
    with pytest.raises(ValueError, match=r"lines\[1\]"):
        write_map(tmp_path / "m.json", [line, bad])
    assert not (tmp_path / "m.json").exists()
