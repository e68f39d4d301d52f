"""Tests of the simulator: worlds, ray casting, range noise, odometry drift, route following."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from fhslam.geometry import compose, inverse, line_through, point_segment_distance, wrap_angle
from fhslam.sim import (
    LaserParams,
    OdometryNoise,
    World,
    WorldFormatError,
    add_range_noise,
    beam_angles,
    campus_world,
    cast_rays,
    corridor_world,
    degrade,
    hall_world,
    load_world,
    odometry_from_truth,
    offices_world,
    paper_world,
    random_world,
    ring_world,
    route_clearance,
    simulate,
    transform_world,
)
from fhslam.sim.simulate import follow_route, lap_route

# A 4 x 4 m room centred on the origin: bottom, right, top, left.
SQUARE = np.array([[-2, -2, 2, -2], [2, -2, 2, 2], [2, 2, -2, 2], [-2, 2, -2, -2]], dtype=float)


def wall_distances(points: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """Distance of each point (N, 2) to the nearest wall, by geometry.point_segment_distance."""
    return np.min([point_segment_distance(points, w[:2], w[2:]) for w in walls], axis=0)


def dense_route(world: World, step: float = 0.01) -> np.ndarray:
    """Points every ``step`` metres along the route polyline."""
    pts = []
    for a, b in zip(world.route[:-1], world.route[1:], strict=True):
        n = max(2, int(np.ceil(np.hypot(*(b - a)) / step)) + 1)
        pts.append(a + np.linspace(0, 1, n)[:, None] * (b - a))
    return np.vstack(pts)


@pytest.fixture(scope="module")
def paper_log():
    return simulate(paper_world(), seed=0)


# ---------------------------------------------------------------------------- ray casting


def test_beam_angles_default_is_the_papers_181_beams_at_one_degree():
    a = beam_angles(LaserParams())
    assert a.shape == (181,)
    np.testing.assert_allclose(a[[0, 90, 180]], [-np.pi / 2, 0.0, np.pi / 2], atol=1e-15)
    np.testing.assert_allclose(np.diff(a), np.radians(1.0), atol=1e-12)


def test_cast_rays_square_room_from_the_centre():
    angles = np.radians([0.0, 45.0, 90.0, -90.0, 180.0, -135.0])
    r, hit = cast_rays(SQUARE, [0.0, 0.0, 0.0], angles, max_range=8.0)
    # Tolerance 1e-12 m: the intersection is exact up to rounding.
    np.testing.assert_allclose(r, [2.0, 2 * np.sqrt(2), 2.0, 2.0, 2.0, 2 * np.sqrt(2)], atol=1e-12)
    assert hit[0] == 1  # straight ahead (+x): the right wall
    assert hit[2] == 2 and hit[3] == 0 and hit[4] == 3  # top, bottom, left
    assert hit[1] in (1, 2)  # the 45 degree beam hits the corner shared by right and top


def test_cast_rays_respects_the_robot_pose():
    # At (1, 0) facing +y: ahead is the top wall 2 m away, to the right (-90 deg) the right wall.
    r, hit = cast_rays(SQUARE, [1.0, 0.0, np.pi / 2], np.radians([0.0, -90.0, 90.0]), 8.0)
    np.testing.assert_allclose(r, [2.0, 1.0, 3.0], atol=1e-12)
    assert hit.tolist() == [2, 1, 3]


def test_cast_rays_no_return_reads_max_range_and_wall_minus_one():
    wall = np.array([[5.0, -1.0, 5.0, 1.0]])  # one wall 5 m ahead
    angles = np.radians([0.0, 90.0, 180.0])
    r, hit = cast_rays(wall, [0.0, 0.0, 0.0], angles, max_range=8.0)
    assert r[0] == pytest.approx(5.0, abs=1e-12) and hit[0] == 0
    assert r[1] == 8.0 and r[2] == 8.0  # exactly max_range: sideways and behind
    assert hit[1] == -1 and hit[2] == -1
    # The same wall beyond the maximum range is no return either.
    r, hit = cast_rays(wall, [0.0, 0.0, 0.0], angles, max_range=4.0)
    assert r.tolist() == [4.0, 4.0, 4.0] and hit.tolist() == [-1, -1, -1]
    # No walls at all.
    r, hit = cast_rays(np.zeros((0, 4)), [0.0, 0.0, 0.0], angles, max_range=8.0)
    assert r.tolist() == [8.0, 8.0, 8.0] and hit.tolist() == [-1, -1, -1]


def test_noisy_hits_stay_inside_the_open_range_and_no_returns_stay_exact():
    params = LaserParams()
    clean = np.array([7.9995] * 5000 + [8.0] * 10 + [0.0005] * 5000)
    hit = np.array([0] * 5000 + [-1] * 10 + [0] * 5000)
    noisy = add_range_noise(clean, hit, params, np.random.default_rng(0))
    assert np.all(noisy[hit >= 0] > 0) and np.all(noisy[hit >= 0] < params.max_range)
    assert np.all(noisy[hit < 0] == params.max_range)


def test_range_noise_std_matches_the_parameter(paper_log):
    # Re-cast noise-free ranges from the true poses; the residual is the added noise.
    log, params = paper_log, LaserParams()
    clean = np.array(
        [cast_rays(log.world.walls, p, log.angles, params.max_range)[0] for p in log.truth]
    )
    hits = log.hits >= 0
    residual = (log.ranges - clean)[hits & (clean < params.max_range - 0.05)]
    assert residual.size > 100_000
    assert np.std(residual) == pytest.approx(params.range_noise_std, rel=0.10)
    assert abs(np.mean(residual)) < 0.001
    assert np.all(log.ranges[~hits] == params.max_range)
    # Quantised to the 1 mm resolution.
    np.testing.assert_allclose(log.ranges * 1000, np.round(log.ranges * 1000), atol=1e-6)


# ---------------------------------------------------------------------------- odometry


def test_odometry_without_noise_equals_truth(paper_log):
    odom = odometry_from_truth(paper_log.truth, OdometryNoise.none(), np.random.default_rng(0))
    # Chaining ~900 relative steps is exact up to rounding: 1e-9 m / rad.
    np.testing.assert_allclose(odom, paper_log.truth, rtol=0, atol=1e-9)
    assert np.array_equal(odom[0], paper_log.truth[0])


def test_odometry_drifts_with_default_noise(paper_log):
    err = np.hypot(*(paper_log.odometry[:, :2] - paper_log.truth[:, :2]).T)
    assert np.array_equal(paper_log.odometry[0], paper_log.truth[0])
    assert err[-1] > 0.2
    # Drift accumulates: the error at the end exceeds the error over the first tenth.
    assert err[-1] > err[: len(err) // 10].max()


def test_simulation_is_deterministic_per_seed(paper_log):
    again = simulate(paper_world(), seed=0)
    other = simulate(paper_world(), seed=1)
    for field in ("timestamps", "ranges", "odometry", "truth", "hits"):
        assert np.array_equal(getattr(again, field), getattr(paper_log, field)), field
    assert np.array_equal(other.truth, paper_log.truth)  # the path is noise-free
    assert not np.array_equal(other.ranges, paper_log.ranges)
    assert not np.array_equal(other.odometry, paper_log.odometry)


def test_odometry_noise_validation():
    with pytest.raises(ValueError, match="alpha3"):
        OdometryNoise(alpha3=-0.1)


# ---------------------------------------------------------------------------- simulate


def test_simulate_paper_world(paper_log):
    log, world = paper_log, paper_world()
    assert log.ranges.shape == (len(log), 181) and log.angles.shape == (181,)
    assert 500 < len(log) < 2000
    assert log.timestamps[0] == 0.0 and np.all(np.diff(log.timestamps) > 0)
    assert log.timestamps.tolist() == [round(k * 0.2, 6) for k in range(len(log))]
    assert np.hypot(*(log.truth[-1, :2] - world.route[-1])) < 0.5
    assert np.array_equal(log.truth[0], world.start)
    assert wall_distances(log.truth[:, :2], world.walls).min() >= 0.3


def test_simulate_max_scans():
    log = simulate(paper_world(), seed=0, max_scans=10)
    assert len(log) == 10 and log.ranges.shape == (10, 181)
    with pytest.raises(ValueError, match="max_scans"):
        simulate(paper_world(), max_scans=0)


def test_a_run_cut_short_shares_the_path_and_ranges_but_not_the_odometry_errors():
    """Documented in ``simulate``: the odometry's errors are drawn for the run as a whole."""
    whole = simulate(paper_world(), seed=0)
    cut = simulate(paper_world(), seed=0, max_scans=50)
    assert np.array_equal(cut.truth, whole.truth[:50])
    assert np.array_equal(cut.ranges, whole.ranges[:50], equal_nan=True)
    assert np.array_equal(cut.odometry[0], whole.odometry[0])
    assert np.abs(cut.odometry - whole.odometry[:50]).max() > 1e-4  # another draw


def test_simulate_custom_laser():
    laser = LaserParams(n_beams=361, fov_deg=270.0, max_range=5.0)
    log = simulate(paper_world(), laser=laser, max_scans=5)
    assert log.ranges.shape == (5, 361) and log.max_range == 5.0
    assert log.angles[0] == pytest.approx(-np.radians(135.0), abs=1e-12)


def test_laser_params_validation():
    with pytest.raises(ValueError, match="n_beams"):
        LaserParams(n_beams=1)
    with pytest.raises(ValueError, match="max_range"):
        LaserParams(max_range=0.0)


# ---------------------------------------------------------------------------- worlds


def test_paper_world_layout():
    w = paper_world()
    assert w.bounds == (0.0, 0.0, 18.7, 14.0)
    assert 40 <= len(w.walls) <= 70
    angles = np.degrees(np.arctan2(w.walls[:, 3] - w.walls[:, 1], w.walls[:, 2] - w.walls[:, 0]))
    off_axis = np.abs(((angles + 45) % 90) - 45) > 1.0
    assert off_axis.sum() >= 3  # a diagonal wall and rotated boxes: not purely Manhattan
    assert 50 < w.route_length < 100


def test_paper_route_keeps_half_a_metre_from_walls():
    w = paper_world()
    assert wall_distances(dense_route(w), w.walls).min() >= 0.5
    assert route_clearance(w) >= 0.5


@pytest.mark.parametrize("seed", range(8))
def test_random_world_is_clear_and_deterministic(seed):
    w = random_world(seed)
    again = random_world(seed)
    assert np.array_equal(w.walls, again.walls) and np.array_equal(w.route, again.route)
    assert np.array_equal(w.route[0], w.route[-1])  # a closed loop
    assert wall_distances(dense_route(w), w.walls).min() >= 0.6
    assert len(w.walls) >= 6 + 3 * 4  # outline + at least 3 boxes


def test_random_worlds_differ_and_can_be_driven():
    a, b = random_world(1), random_world(2)
    assert a.walls.shape != b.walls.shape or not np.allclose(a.walls, b.walls)
    truth = follow_route(a)
    assert wall_distances(truth[:, :2], a.walls).min() >= 0.3
    assert np.hypot(*(truth[-1, :2] - a.route[-1])) < 0.5


@pytest.mark.parametrize("world", [hall_world(), corridor_world()], ids=["hall", "corridor"])
def test_small_worlds_have_walls_through_the_origin_and_a_clear_loop(world):
    rho = np.array([line_through(w[:2], w[2:])[0] for w in world.walls])
    assert (rho < 1e-12).sum() >= 2  # the walls on x = 0 and y = 0
    assert np.array_equal(world.route[0], world.route[-1])
    assert wall_distances(dense_route(world), world.walls).min() >= 1.0
    assert world.route_length == pytest.approx(24.0)
    assert load_world(world.name).walls.tolist() == world.walls.tolist()


def test_the_ring_is_a_corridor_round_a_block_with_alcoves():
    w = ring_world()
    assert w.route_length == pytest.approx(150.0)
    assert np.array_equal(w.route[0], w.route[-1])
    assert wall_distances(dense_route(w), w.walls).min() == pytest.approx(1.25)  # centre line
    lengths = np.hypot(w.walls[:, 2] - w.walls[:, 0], w.walls[:, 3] - w.walls[:, 1])
    alcoves = np.sum(np.isclose(lengths, 1.0))  # each: two sides 0.8 m deep, a back 1 m wide
    assert np.sum(np.isclose(lengths, 0.8)) == 2 * alcoves
    assert 24 <= alcoves <= 40  # 7-13 m apart on both sides of 150 m of corridor
    assert load_world("ring").walls.tolist() == w.walls.tolist()


def test_the_campus_is_a_kilometre_of_corridors_driven_both_ways():
    w = campus_world()
    assert w.route_length == pytest.approx(1062.5)
    assert route_clearance(w) == pytest.approx(1.25)  # the corridors' centre lines
    lengths = np.hypot(w.walls[:, 2] - w.walls[:, 0], w.walls[:, 3] - w.walls[:, 1])
    alcoves = np.sum(np.isclose(lengths, 1.0))
    assert np.sum(np.isclose(lengths, 0.8)) == 2 * alcoves
    assert 130 <= alcoves <= 200  # 7-13 m apart on both sides of about 1.2 km of wall
    # the south corridor's west half is driven east first, then west (after 531 m), the
    # middle corridor twice southward, the south corridor's east half twice eastward
    r = w.route
    assert r[0].tolist() == [1.25, 1.25] and r[5].tolist() == [1.25, 1.25]
    assert r[3:5].tolist() == r[7:9].tolist() == [[100.0, 118.75], [100.0, 1.25]]
    assert load_world("campus").walls.tolist() == w.walls.tolist()


def test_the_offices_route_drives_its_corridor_both_ways():
    w = offices_world()
    assert np.array_equal(w.route[0], w.route[-1])
    assert wall_distances(dense_route(w), w.walls).min() >= 0.5
    rho = np.array([line_through(x[:2], x[2:])[0] for x in w.walls])
    assert (rho < 1e-12).sum() >= 2  # the outer walls on x = 0 and y = 0
    step = np.diff(w.route, axis=0)
    corridor = (np.abs(step[:, 0]) > 3) & (np.abs(w.route[1:, 1] - 6.1) < 0.2)  # y 5.9-6.3
    assert set(np.sign(step[corridor, 0])) == {-1.0, 1.0}  # east and back west
    assert step[corridor, 0].min() == -18.0  # the whole corridor back
    assert load_world("offices").walls.tolist() == w.walls.tolist()


MOTIONS = [(5.0, 5.0, 0.0), (-3.3, 2.1, np.radians(37)), (0.0, -15.0, np.pi / 2)]


def test_transform_world_moves_walls_route_and_start():
    w = hall_world()
    m = np.array([-3.3, 2.1, np.radians(37)])
    moved = transform_world(w, m)
    c, s = np.cos(m[2]), np.sin(m[2])
    rot = np.array([[c, -s], [s, c]])
    np.testing.assert_allclose(moved.walls[:, :2], w.walls[:, :2] @ rot.T + m[:2], atol=1e-12)
    np.testing.assert_allclose(moved.walls[:, 2:], w.walls[:, 2:] @ rot.T + m[:2], atol=1e-12)
    np.testing.assert_allclose(moved.route, w.route @ rot.T + m[:2], atol=1e-12)
    np.testing.assert_allclose(moved.start, [*(rot @ w.start[:2] + m[:2]), 0.05 + m[2]])
    assert moved.name == w.name and moved.route_length == pytest.approx(w.route_length)
    back = transform_world(moved, inverse(m))
    np.testing.assert_allclose(back.walls, w.walls, atol=1e-12)


@pytest.mark.parametrize("world", [hall_world(), corridor_world()], ids=["hall", "corridor"])
@pytest.mark.parametrize("motion", MOTIONS)
def test_a_moved_world_gives_the_same_scans_and_the_moved_poses(world, motion):
    """The premise of tests/test_invariance.py: the noise is drawn in the robot frame, so a
    moved world gives the very same ranges, and truth and odometry moved with it."""
    a, b = simulate(world, seed=3), simulate(transform_world(world, motion), seed=3)
    assert np.array_equal(a.ranges, b.ranges) and np.array_equal(a.hits, b.hits)
    for got, want in ((b.truth, a.truth), (b.odometry, a.odometry)):
        d = got - compose(motion, want)
        assert np.abs(d[:, :2]).max() < 1e-9 and np.abs(wrap_angle(d[:, 2])).max() < 1e-9


def test_world_dict_round_trip_and_default_start():
    w = World.from_dict({"name": "t", "walls": SQUARE.tolist(), "route": [[0, 0], [1, 1]]})
    np.testing.assert_allclose(w.start, [0.0, 0.0, np.pi / 4], atol=1e-15)
    back = World.from_dict(json.loads(json.dumps(w.to_dict())))
    assert back.name == "t"
    for field in ("walls", "route", "start"):
        assert np.array_equal(getattr(back, field), getattr(w, field))
    assert w.bounds == (-2.0, -2.0, 2.0, 2.0)


def test_load_world_builtins_and_files(tmp_path):
    assert load_world("paper").name == "paper"
    assert np.array_equal(load_world("random:3").walls, random_world(3).walls)
    path = tmp_path / "room.json"
    path.write_text(json.dumps({"name": "room", "walls": SQUARE.tolist(), "route": [[0, 0], [1, 0]],
                                "start": [0, 0, 0.5]}))  # fmt: skip
    w = load_world(path)
    assert w.name == "room" and w.start.tolist() == [0.0, 0.0, 0.5]
    assert load_world(str(path)).name == "room"


def test_a_world_start_heading_is_wrapped(tmp_path):
    """A start heading outside (-pi, pi] is wrapped (7.0 is 7.0 - 2 pi), in the world, its
    JSON and the simulated truth; one inside it is kept exactly; the caller's array too."""
    room = {"name": "room", "walls": SQUARE.tolist(), "route": [[0, 0], [1, 0]]}
    path = tmp_path / "room.json"
    path.write_text(json.dumps({**room, "start": [0, 0, 7.0]}))
    w = load_world(path)
    assert w.start[:2].tolist() == [0.0, 0.0]
    assert w.start[2] == pytest.approx(7.0 - 2 * np.pi, abs=1e-12)
    assert World.from_dict(w.to_dict()).start.tolist() == w.start.tolist()
    log = simulate(w, seed=0, max_scans=5)
    assert log.truth[0].tolist() == w.start.tolist()
    for poses in (log.truth, log.odometry):
        assert np.all((poses[:, 2] > -np.pi) & (poses[:, 2] <= np.pi))
    for given, want in ((-np.pi, np.pi), (-7.0, 2 * np.pi - 7.0), (3 * np.pi, np.pi)):
        start = np.array([0.0, 0.0, given])
        got = World.from_dict({**room, "start": start}).start[2]
        assert got == pytest.approx(want, abs=1e-12) and -np.pi < got <= np.pi
        assert start[2] == given and start.flags.writeable  # not the caller's array
    for kept in (0.5, np.pi, -np.nextafter(np.pi, 0)):
        assert World.from_dict({**room, "start": [0, 0, kept]}).start[2] == kept


def test_load_world_unknown_name_lists_builtins():
    with pytest.raises(ValueError, match=r"unknown world 'office'.*paper.*random:SEED"):
        load_world("office")
    with pytest.raises(ValueError, match="seed"):
        load_world("random:x")


def test_load_world_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"nope\.json"):
        load_world(tmp_path / "nope.json")
    with pytest.raises(FileNotFoundError, match=r"nope\.json"):
        load_world("nope.json")


@pytest.mark.parametrize(
    ("content", "match"),
    [
        ("{not json", "not valid JSON"),
        ('{"walls": [[0, 0, 1]], "route": [[0, 0], [1, 0]]}', r"'walls' must have shape \(N, 4\)"),
        ('{"walls": [[0, 0, 1, 1]], "route": [[0, 0]]}', "'route' needs at least 2 rows"),
        ('{"walls": [[0, 0, 1, 1]]}', "missing field 'route'"),
        ('{"walls": [[0, 0, 0, 0]], "route": [[0, 0], [1, 0]]}', "'walls' row 0 has zero length"),
        ('{"walls": [[0, 0, NaN, 1]], "route": [[0, 0], [1, 0]]}', "'walls' row 0 is not finite"),
        ('{"walls": [[0, 0, 1, 1]], "route": [[0, 0], [1, 0]], "start": [0, 0]}', "'start'"),
        ('{"walls": [["a", 0, 1, 1]], "route": [[0, 0], [1, 0]]}', "'walls' must be a list"),
        ("[1, 2]", "expected a JSON object"),
        # the robot cannot drive through a wall: on its route, from a start outside the
        # building (a RuntimeError from deep in the simulator before), from a start on a wall
        (
            '{"walls": [[5, -1, 5, 9]], "route": [[2, 2], [8, 2]]}',
            r"route.*from \[2.0, 2.0\] to \[8.0, 2.0\] \(a leg of the route\) meets wall row 0",
        ),
        (
            '{"walls": [[0, 0, 9, 0], [9, 0, 9, 9], [9, 9, 0, 9], [0, 9, 0, 0]], '
            '"route": [[2, 2], [8, 2]], "start": [500, 500, 0]}',
            r"from \[500.0, 500.0\] to \[2.0, 2.0\] \(start to first waypoint\) meets wall",
        ),
        (
            '{"walls": [[0, 0, 9, 0]], "route": [[2, 2], [8, 2]], "start": [3, 0, 0]}',
            r"from \[3.0, 0.0\] to \[2.0, 2.0\] \(start to first waypoint\) meets wall row 0",
        ),
    ],
)
def test_load_world_malformed_files_name_file_and_field(tmp_path, content, match):
    path = tmp_path / "bad_world.json"
    path.write_text(content)
    with pytest.raises(WorldFormatError, match=rf"bad_world\.json(:\d+)?: .*{match}"):
        load_world(path)


BOX = {"walls": [[0, 0, 6, 0], [6, 0, 6, 4], [6, 4, 0, 4], [0, 4, 0, 0]], "route": [[1, 1], [5, 1]]}


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        # `true` is not read as 1, nor "1" as 1, nor null in 'start' as NaN ("not finite")
        ({"walls": [*BOX["walls"][:3], [0, 4, 0, True]]},
         "field 'walls' must be a list of [number, number, number, number] rows: row 3 holds "
         "true, which is not a number"),
        ({"route": [[1, 1], [5, False]]}, "field 'route' must be a list of [number, number] "
         "rows: row 1 holds false, which is not a number"),
        ({"route": [[1, 1], [5, "1"]]}, 'row 1 holds "1", which is not a number'),
        ({"start": [1, 1, None]}, "field 'start' must be [x, y, theta] numbers: null is not a "
         "number"),
        ({"start": [True, 1, 0]}, "field 'start' must be [x, y, theta] numbers: true is not"),
        ({"walls": 5}, "field 'walls' must be a list of [number, number, number, number] rows, "
         "got 5"),
        ({"walls": {"a": 1}}, "field 'walls' must be a list of"),
    ],
)  # fmt: skip
def test_a_world_coordinate_must_be_a_json_number(tmp_path, changes, message):
    path = tmp_path / "w.json"
    path.write_text(json.dumps({**BOX, **changes}))
    with pytest.raises(WorldFormatError) as e:
        load_world(path)
    assert str(e.value).startswith(f"{path}: field ") and message in str(e.value)


def test_a_world_nested_too_deeply_is_a_format_error(tmp_path):
    # 100,000 nested '[': a format error, not a RecursionError from the json module
    path = tmp_path / "deep.json"
    path.write_text("[" * 100_000)
    with pytest.raises(WorldFormatError, match=r"deep\.json: not readable JSON \(lists or objects"):
        load_world(path)


def test_an_unknown_world_key_is_ignored_with_one_warning(tmp_path):
    """A misspelled key ("strat") is ignored (the world is well defined without it), but not
    without a word: it is named, with the keys a world has."""
    from fhslam.errors import InputWarning

    path = tmp_path / "w.json"
    path.write_text(json.dumps({**BOX, "strat": [1, 1, 0.5]}))
    with pytest.warns(InputWarning) as caught:
        w = load_world(path)
    assert [str(c.message) for c in caught] == [
        f"{path}: unknown key 'strat' ignored; a world has 'name', 'walls', 'route', 'start'"
    ]
    assert w.start.tolist() == [1.0, 1.0, 0.0]  # the default start, not the misspelled one
    path.write_text(json.dumps({**BOX, "Name": "x", "comment": "mine"}))
    with pytest.warns(InputWarning, match="unknown keys 'Name', 'comment' ignored"):
        load_world(path)


def test_a_world_built_from_arrays_still_takes_numpy_numbers():
    w = World(name="np", walls=SQUARE.astype(np.float32), route=np.array([[0, 0], [1, 0]]),
              start=np.array([0, 0, 0.1]))  # fmt: skip
    assert w.walls.dtype == np.float64 and w.start.tolist() == [0.0, 0.0, 0.1]
    with pytest.raises(WorldFormatError, match="row 0 holds true"):
        World(name="b", walls=np.array([[True, False, True, True]]), route=[[0, 0], [1, 0]])


# ---------------------------------------------------------------------------- drifting odometry

# Two beams: the laser stream is independent of the odometry stream, so the odometry (and
# the drift) is the same as with the full 181-beam laser, at a fraction of the casting cost.
TWO_BEAMS = LaserParams(n_beams=2)


def max_and_final_drift(log) -> tuple[float, float]:
    """Largest and final distance between odometry and true position over a log, metres."""
    err = np.hypot(*(log.odometry[:, :2] - log.truth[:, :2]).T)
    return float(err.max()), float(err[-1])


def test_drifting_preset_drifts_2_to_6_m_on_the_paper_world():
    log = simulate(paper_world(), seed=0, odometry=OdometryNoise.drifting())
    worst, final = max_and_final_drift(log)
    assert 2.0 <= worst <= 6.0
    assert 2.0 <= final <= 6.0
    # The default noise drifts far less: the preset is what makes the run hard.
    assert max_and_final_drift(simulate(paper_world(), seed=0))[0] < 2.0


def test_drifting_preset_is_mostly_systematic():
    noise = OdometryNoise.drifting()
    assert noise.heading_bias > 0 and noise.turn_scale_error > 0 and noise.scale_error > 0
    default = OdometryNoise()
    assert noise.alpha1 < default.alpha1 and noise.alpha3 < default.alpha3


def test_drifting_preset_drift_over_seeds_as_documented():
    # The docstring states: paper world seeds 0-19, and random_world(s) for s = 101-120
    # driven 3 laps with seed=s, all drift 2-6 m at worst.
    noise = OdometryNoise.drifting()
    paper = [
        max_and_final_drift(simulate(paper_world(), seed=s, laser=TWO_BEAMS, odometry=noise))
        for s in range(20)
    ]
    rand = [
        max_and_final_drift(
            simulate(random_world(s), seed=s, laser=TWO_BEAMS, odometry=noise, laps=3)
        )
        for s in range(101, 121)
    ]
    for drifts in (np.array(paper), np.array(rand)):
        assert np.all((drifts[:, 0] >= 2.0) & (drifts[:, 0] <= 6.0)), drifts[:, 0]
        assert 3.0 <= np.median(drifts[:, 0]) <= 4.5
        assert np.all(drifts[:, 1] <= drifts[:, 0])


def test_turn_scale_error_scales_every_rotation():
    # A robot turning on the spot by 0.1 rad per step: odometry reports 1.1 times that.
    truth = np.column_stack([np.zeros(11), np.zeros(11), np.linspace(0.0, 1.0, 11)])
    noise = OdometryNoise(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, turn_scale_error=0.1)
    odom = odometry_from_truth(truth, noise, np.random.default_rng(0))
    np.testing.assert_allclose(odom[:, 2], 1.1 * truth[:, 2], atol=1e-12)
    np.testing.assert_allclose(odom[:, :2], 0.0, atol=1e-12)
    with pytest.raises(ValueError, match="turn_scale_error"):
        OdometryNoise(turn_scale_error=-1.0)


# ---------------------------------------------------------------------------- laps


def path_length(truth: np.ndarray) -> float:
    return float(np.hypot(*np.diff(truth[:, :2], axis=0).T).sum())


@pytest.mark.parametrize("seed", [101, 107])
def test_three_laps_triple_the_path_on_a_random_world(seed):
    world = random_world(seed)
    one, three = follow_route(world), follow_route(world, laps=3)
    assert path_length(three) == pytest.approx(3 * path_length(one), rel=0.02)
    assert 50 < path_length(three) < 75  # 18-25 m loops
    assert np.hypot(*(three[-1, :2] - world.route[0])) < 0.5  # back at the start
    assert wall_distances(three[:, :2], world.walls).min() >= 0.3
    # The first lap is driven exactly as a single lap.
    np.testing.assert_array_equal(three[: len(one) - 1], one[:-1])


def test_simulate_laps_keeps_the_one_lap_world():
    world = random_world(101)
    log = simulate(world, seed=0, laser=TWO_BEAMS, laps=2)
    assert log.world is world
    assert path_length(log.truth) == pytest.approx(2 * path_length(follow_route(world)), rel=0.02)


def test_laps_on_an_open_route_raise():
    with pytest.raises(ValueError, match=r"laps=3 needs a closed route"):
        simulate(paper_world(), laps=3)
    with pytest.raises(ValueError, match="closed route"):
        follow_route(paper_world(), laps=2)
    assert len(simulate(paper_world(), laps=1, max_scans=3)) == 3  # one lap is fine


@pytest.mark.parametrize("laps", [0, -1, 1.5, True])
def test_laps_must_be_a_positive_integer(laps):
    with pytest.raises(ValueError, match="laps must be an integer >= 1"):
        follow_route(random_world(101), laps=laps)


def test_lap_route_tiles_a_closed_route():
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], dtype=float)
    tiled = lap_route(square, 3)
    assert tiled.shape == (13, 2)
    np.testing.assert_array_equal(tiled[4::4], np.zeros((3, 2)))
    np.testing.assert_array_equal(lap_route(square, 1), square)
    with pytest.raises(ValueError, match="closed route"):
        lap_route(square[:-1], 2)


# ---------------------------------------------------------------------------- degrade


@pytest.fixture(scope="module")
def degraded(paper_log):
    return degrade(paper_log, drop_fraction=0.1, clutter_fraction=0.05, seed=7)


def kept_rows(log, degraded_log) -> np.ndarray:
    """Indices into ``log`` of the scans ``degraded_log`` kept (timestamps are unique)."""
    idx = np.searchsorted(log.timestamps, degraded_log.timestamps)
    assert np.array_equal(log.timestamps[idx], degraded_log.timestamps)
    return idx


def test_degrade_drops_the_stated_number_of_scans_never_the_first(paper_log, degraded):
    t = len(paper_log)
    assert len(degraded) == t - round(0.1 * (t - 1))
    assert degraded.timestamps[0] == paper_log.timestamps[0]
    rows = kept_rows(paper_log, degraded)
    assert rows[0] == 0 and np.all(np.diff(rows) > 0)
    # Whole rows go: odometry and truth follow the kept scans.
    np.testing.assert_array_equal(degraded.odometry, paper_log.odometry[rows])
    np.testing.assert_array_equal(degraded.truth, paper_log.truth[rows])
    assert degraded.ranges.shape == (len(degraded), 181) and degraded.hits.shape == (
        len(degraded),
        181,
    )
    assert degraded.world is paper_log.world and degraded.max_range == paper_log.max_range


@pytest.mark.parametrize(
    ("t", "fraction", "dropped"),
    [(11, 0.1, 1), (11, 0.5, 5), (2, 0.9, 1), (1, 0.5, 0), (101, 0.0, 0)],
)
def test_degrade_drop_count_rule(paper_log, t, fraction, dropped):
    short = simulate(paper_world(), seed=0, laser=TWO_BEAMS, max_scans=t)
    out = degrade(short, drop_fraction=fraction, seed=1)
    assert len(out) == t - dropped
    assert out.timestamps[0] == 0.0


def test_degrade_clutter_share_ranges_and_hits(paper_log, degraded):
    rows = kept_rows(paper_log, degraded)
    before, after = paper_log.ranges[rows], degraded.ranges
    valid = before < paper_log.max_range
    changed = after != before
    clutter = degraded.hits == -1
    assert np.array_equal(changed, clutter & valid)  # clutter only on valid beams, hits -1
    share = changed.sum() / valid.sum()
    assert share == pytest.approx(0.05, abs=0.01)
    # Every scan gets its share, give or take the rounding of the per-scan count.
    per_scan = changed.sum(axis=1) - 0.05 * valid.sum(axis=1)
    assert np.all(np.abs(per_scan) < 1.0)
    # Clutter is short of the wall: within [0.3 m, 0.9 x the logged range] up to rounding,
    # and shorter than the noise-free range to the wall.
    true_range = np.array(
        [cast_rays(paper_log.world.walls, p, paper_log.angles, 8.0)[0] for p in degraded.truth]
    )
    fake, wall = after[changed], before[changed]
    assert np.all(fake >= 0.3 - 0.0005) and np.all(fake <= 0.9 * wall + 0.0005)
    assert np.all(fake < true_range[changed])
    assert fake.min() < 0.5 and np.median(fake / wall) < 0.7  # spread over the interval
    # Still quantised to the laser's 1 mm.
    np.testing.assert_allclose(after * 1000, np.round(after * 1000), atol=1e-6)
    # Everything else is untouched.
    np.testing.assert_array_equal(after[~changed], before[~changed])
    np.testing.assert_array_equal(degraded.hits[~changed], paper_log.hits[rows][~changed])


def test_degrade_keeps_the_lasers_mount_and_per_scan_bearing_offsets(paper_log):
    """A real log's laser mount (Freiburg hospital 0.22 m) and an interlaced laser's per-scan
    bearing offsets belong to the log: dropping scans must keep them, the offsets row by row
    (they were lost once, and a dropped-scan run then saw the laser at the robot's origin)."""
    from dataclasses import replace

    t = len(paper_log)
    offsets = np.where(np.arange(t) % 2 == 1, 0.0131, 0.0)  # an interlaced laser
    log = replace(
        paper_log,
        laser_offset=np.array([0.22, 0.0, 0.0]),
        laser_offset_source="tf_static",
        angle_offsets=offsets,
    )
    out = degrade(log, drop_fraction=0.1, seed=7)
    np.testing.assert_array_equal(out.laser_offset, [0.22, 0.0, 0.0])
    assert out.laser_offset_source == "tf_static"
    np.testing.assert_array_equal(out.angle_offsets, offsets[kept_rows(log, out)])


def test_degrade_is_deterministic_per_seed_and_leaves_the_input_alone(paper_log, degraded):
    ranges_before = paper_log.ranges.copy()
    again = degrade(paper_log, drop_fraction=0.1, clutter_fraction=0.05, seed=7)
    for field in ("timestamps", "ranges", "odometry", "truth", "hits"):
        assert np.array_equal(getattr(again, field), getattr(degraded, field)), field
    other = degrade(paper_log, drop_fraction=0.1, clutter_fraction=0.05, seed=8)
    assert not np.array_equal(other.timestamps, degraded.timestamps)
    assert np.array_equal(paper_log.ranges, ranges_before)


def test_degrade_choices_are_nested_across_fractions(paper_log):
    light = degrade(paper_log, drop_fraction=0.05, clutter_fraction=0.02, seed=3)
    heavy = degrade(paper_log, drop_fraction=0.2, clutter_fraction=0.1, seed=3)
    assert set(heavy.timestamps) <= set(light.timestamps)
    # Same clutter draws: a beam cluttered in the light log is cluttered the same way in the
    # heavy one (where the scan survives).
    rows = np.searchsorted(light.timestamps, heavy.timestamps)
    light_clutter = light.ranges[rows] != paper_log.ranges[kept_rows(paper_log, heavy)]
    np.testing.assert_array_equal(heavy.ranges[light_clutter], light.ranges[rows][light_clutter])


def test_degrade_with_zero_fractions_copies(paper_log):
    out = degrade(paper_log)
    assert out is not paper_log and out.ranges is not paper_log.ranges
    for field in ("timestamps", "ranges", "odometry", "truth", "hits"):
        assert np.array_equal(getattr(out, field), getattr(paper_log, field)), field


def test_degrade_works_without_truth_or_hits(paper_log):
    from fhslam.io.log import Log

    bare = Log(name="real", timestamps=paper_log.timestamps, ranges=paper_log.ranges,
               angles=paper_log.angles, odometry=paper_log.odometry, max_range=8.0)  # fmt: skip
    out = degrade(bare, drop_fraction=0.1, clutter_fraction=0.05, seed=7)
    assert out.truth is None and out.hits is None
    assert len(out) == len(bare) - round(0.1 * (len(bare) - 1))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"drop_fraction": 1.0}, "drop_fraction"),
        ({"drop_fraction": -0.1}, "drop_fraction"),
        ({"clutter_fraction": 1.5}, "clutter_fraction"),
        ({"clutter_fraction": float("nan")}, "clutter_fraction"),
        ({"clutter_fraction": "lots"}, "clutter_fraction"),
        ({"resolution": -0.001}, "resolution"),
        ({"range_noise": -0.001}, "range_noise"),
        ({"range_noise": float("inf")}, "range_noise"),
        ({"range_noise": True}, "range_noise"),
        ({"range_noise": "1 mm"}, "range_noise"),
        ({"seed": -1}, "seed"),
        ({"seed": 1.5}, "seed"),
    ],
)
def test_degrade_rejects_bad_arguments(paper_log, kwargs, match):
    with pytest.raises(ValueError, match=match):
        degrade(paper_log, **kwargs)


def test_degrade_range_noise_on_valid_beams_only(paper_log):
    """The robustness check: Gaussian noise of 1 mm on every return, none on a
    no-return, every return still one (inside (0, max_range))."""
    out = degrade(paper_log, range_noise=0.001, seed=5)
    valid = (paper_log.ranges > 0) & (paper_log.ranges < paper_log.max_range)
    d = out.ranges - paper_log.ranges
    assert valid.sum() > 10_000
    assert abs(d[valid].mean()) < 3 * 0.001 / np.sqrt(valid.sum())  # unbiased
    assert np.std(d[valid]) == pytest.approx(0.001, rel=0.03)
    assert np.count_nonzero(d[valid]) == valid.sum()  # not rounded away to the 1 mm grid
    np.testing.assert_array_equal(out.ranges[~valid], paper_log.ranges[~valid])
    assert np.all(out.ranges[valid] > 0) and np.all(out.ranges[valid] < paper_log.max_range)
    np.testing.assert_array_equal(out.hits, paper_log.hits)


def test_degrade_range_noise_near_max_range_stays_a_return(paper_log):
    from dataclasses import replace

    ranges = np.where(paper_log.ranges < paper_log.max_range, paper_log.max_range - 1e-5, 8.0)
    out = degrade(replace(paper_log, ranges=ranges), range_noise=0.01, seed=0)
    hit = ranges < 8.0
    assert np.all(out.ranges[hit] < 8.0) and np.all(out.ranges[~hit] == 8.0)


def test_degrade_range_noise_changes_no_other_choice(paper_log):
    """Noise draws from a stream of its own: the same scans dropped, the same clutter, with
    and without it (and so the same as before range noise existed)."""
    plain = degrade(paper_log, drop_fraction=0.1, clutter_fraction=0.05, seed=7)
    noisy = degrade(paper_log, drop_fraction=0.1, clutter_fraction=0.05, seed=7, range_noise=0.002)
    np.testing.assert_array_equal(noisy.timestamps, plain.timestamps)
    np.testing.assert_array_equal(noisy.hits, plain.hits)
    clutter = plain.hits == -1
    np.testing.assert_array_equal(noisy.ranges[clutter], plain.ranges[clutter])  # not noisy
    valid = plain.ranges < paper_log.max_range
    assert np.count_nonzero(noisy.ranges[valid & ~clutter] != plain.ranges[valid & ~clutter]) > 0
    again = degrade(paper_log, drop_fraction=0.1, clutter_fraction=0.05, seed=7, range_noise=0.002)
    np.testing.assert_array_equal(again.ranges, noisy.ranges)


def test_perturb_odometry_changes_the_last_bits_only(paper_log):
    from fhslam.sim import perturb_odometry

    out = perturb_odometry(paper_log, seed=1)
    nz = paper_log.odometry != 0
    rel = out.odometry[nz] / paper_log.odometry[nz] - 1
    assert np.count_nonzero(rel) > 0.9 * nz.sum()
    assert np.abs(rel).max() < 1e-14  # a few units in the last place
    np.testing.assert_array_equal(perturb_odometry(paper_log, seed=1).odometry, out.odometry)
    assert not np.array_equal(perturb_odometry(paper_log, seed=2).odometry, out.odometry)
    np.testing.assert_array_equal(out.ranges, paper_log.ranges)
    np.testing.assert_array_equal(out.truth, paper_log.truth)
    bigger = perturb_odometry(paper_log, seed=1, relative=1e-3)
    assert np.abs(bigger.odometry[nz] / paper_log.odometry[nz] - 1).max() > 1e-4
    for bad in (-1e-15, float("nan"), "tiny"):
        with pytest.raises(ValueError, match="relative"):
            perturb_odometry(paper_log, seed=1, relative=bad)
    for bad in (-1, 0.5, True):
        with pytest.raises(ValueError, match="seed"):
            perturb_odometry(paper_log, seed=bad)


def test_sparsify_keeps_a_scan_per_metre_or_half_radian(paper_log):
    """Each kept scan is the first whose odometry is 1 m or 0.5 rad from the last kept one's;
    the scans between are dropped with everything they carry."""
    from fhslam.sim import sparsify

    out = sparsify(paper_log)
    idx = kept_rows(paper_log, out)
    assert idx[0] == 0 and 10 < len(out) < len(paper_log) / 5
    odo = paper_log.odometry
    for a, b in itertools.pairwise(idx):
        step = np.hypot(*(odo[a + 1 : b + 1, :2] - odo[a, :2]).T)
        turn = np.abs(wrap_angle(odo[a + 1 : b + 1, 2] - odo[a, 2]))
        reached = (step >= 1.0) | (turn >= 0.5)
        assert reached[-1] and not reached[:-1].any()
    for field in ("timestamps", "ranges", "odometry", "truth", "hits"):
        np.testing.assert_array_equal(getattr(out, field), getattr(paper_log, field)[idx])
    assert len(sparsify(paper_log, distance=0.3)) > len(out)
    assert len(sparsify(paper_log, distance=1e9, angle=1e9)) == 1
    for bad in ({"distance": 0.0}, {"angle": -0.5}, {"distance": float("nan")}):
        with pytest.raises(ValueError, match=r"distance|angle"):
            sparsify(paper_log, **bad)


# ------------------------------------------------------------------- how long a route is


@pytest.mark.parametrize("name", ["paper", "hall", "corridor", "random:0", "random:101"])
def test_expected_scans_is_within_six_per_cent_of_the_drive(name):
    from fhslam.sim.simulate import expected_scans

    w = load_world(name)
    for laps in (1, 3) if name != "paper" else (1,):
        n = len(follow_route(w, laps=laps))
        assert abs(expected_scans(w, laps=laps) - n) <= 0.06 * n, laps


def test_a_route_beyond_the_scan_limit_is_refused_before_any_work(monkeypatch):
    """A 100 km route is not simulated for minutes without a word: simulate() refuses a
    route of more than MAX_SCANS scans before driving it."""
    import sys

    from fhslam.errors import InputError

    sim = sys.modules["fhslam.sim.simulate"]  # the module: fhslam.sim.simulate is the function

    long = World(name="long", walls=np.array([[0, 0, 1e5, 0], [0, 4, 1e5, 4]]),
                 route=np.array([[1, 2], [1e5 - 1, 2]]))  # fmt: skip
    assert sim.expected_scans(long) == 1_249_976 > sim.MAX_SCANS
    monkeypatch.setattr(sim, "follow_route", lambda *a, **k: pytest.fail("drove the route"))
    with pytest.raises(InputError) as e:
        simulate(long)
    assert str(e.value) == (
        "world 'long': its route of 99,998 m is about 1,249,976 scans at 0.4 m/s and 5 scans "
        "per second; the limit is 500,000 scans (nothing was simulated)"
    )
    with pytest.raises(InputError, match=r"world w\.json \('long'\): its route of 99,998 m"):
        sim.check_scan_limit(long, source="w.json")
    # every built-in run, a hundred laps included, is far below the limit
    assert sim.check_scan_limit(paper_world()) < 1000
    assert 100 * sim.check_scan_limit(random_world(0), laps=1) < sim.MAX_SCANS / 10


def test_progress_bars_do_not_change_the_simulation(capsys):
    a = simulate(hall_world(), seed=2, progress=True)
    err = capsys.readouterr().err.replace("\r", "\n")
    assert "simulate hall: driving: 100%" in err and "simulate hall: laser: 100%" in err
    b = simulate(hall_world(), seed=2)
    np.testing.assert_array_equal(a.truth, b.truth)
    np.testing.assert_array_equal(a.ranges, b.ranges)
    assert capsys.readouterr().err == ""
