"""SE(2) poses, angle wrapping and the point / line / segment helpers of fhslam.geometry.

Tolerances: poses and points here are O(10) m, so a few rounding steps cost ~1e-14; every
comparison uses ``TOL = 1e-12`` (absolute) unless a test states otherwise. Angles are compared
through ``wrap_angle`` of their difference, so pi and -pi (or 0 and 2 pi) count as equal.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from fhslam import geometry
from fhslam.geometry import (
    angle_difference_lines,
    as_points,
    as_pose,
    compose,
    distance_to_segments,
    inverse,
    line_through,
    normalize_line,
    observation,
    point_on_line,
    point_segment_distance,
    polar_to_points,
    position_on_line,
    project_onto_line,
    ray_segment_intersection,
    relative,
    segment_distances,
    signed_distance,
    tls_normal_angle,
    transform_points,
    wrap_angle,
)

TOL = 1e-12
PI = np.pi


def random_poses(rng: np.random.Generator, *shape: int) -> np.ndarray:
    """Poses of shape (*shape, 3): x, y in [-10, 10) m, theta in [-pi, pi)."""
    xy = rng.uniform(-10, 10, (*shape, 2))
    th = rng.uniform(-PI, PI, (*shape, 1))
    return np.concatenate([xy, th], axis=-1)


def assert_poses_close(a, b, atol: float = TOL) -> None:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape
    np.testing.assert_allclose(a[..., :2], b[..., :2], rtol=0, atol=atol)
    np.testing.assert_allclose(wrap_angle(a[..., 2] - b[..., 2]), 0.0, rtol=0, atol=atol)


def assert_wrapped(theta) -> None:
    """Angles in the documented interval (-pi, pi]."""
    theta = np.asarray(theta)
    assert np.all(theta > -PI) and np.all(theta <= PI), theta


# --------------------------------------------------------------------------- wrap_angle


@pytest.mark.parametrize("k", [1, -1, 3, -3, 5, -5, 7, -7])
def test_wrap_angle_maps_odd_multiples_of_pi_to_plus_pi(k):
    # k * np.pi is exactly k times the float pi for these k, so the (-pi, pi] convention
    # decides: every one of them is +pi, never -pi.
    assert wrap_angle(k * PI) == PI


@pytest.mark.parametrize(
    ("a", "expected"),
    [
        (0.0, 0.0),
        (2 * PI, 0.0),
        (-2 * PI, 0.0),
        (4 * PI, 0.0),
        (PI / 2, PI / 2),
        (-PI / 2, -PI / 2),
        (3 * PI / 2, -PI / 2),
        (-3 * PI / 2, PI / 2),
        (2 * PI + 0.25, 0.25),
        (-2 * PI - 0.25, -0.25),
        (PI + 0.5, -PI + 0.5),
        (-PI - 0.5, PI - 0.5),
    ],
)
def test_wrap_angle_hand_values(a, expected):
    assert wrap_angle(a) == pytest.approx(expected, abs=1e-15)


def test_wrap_angle_is_the_identity_inside_the_interval():
    # The result is pi - (pi - a): exact up to one rounding at the scale of pi (4.4e-16).
    a = np.random.default_rng(0).uniform(-PI, PI, 1000)
    np.testing.assert_allclose(wrap_angle(a), a, rtol=0, atol=4.5e-16)


@pytest.mark.parametrize("k", [1, -1, 7, -50, 1000, -1000, 10**6])
def test_wrap_angle_removes_multiples_of_two_pi(k):
    a = np.random.default_rng(1).uniform(-3.0, 3.0, 100)  # clear of the +-pi seam
    shifted = a + k * 2 * PI
    # Forming a + 2 pi k already rounds at the scale of |a + 2 pi k|: allow a few ulps of it.
    atol = 4 * np.spacing(abs(k) * 2 * PI + PI)
    np.testing.assert_allclose(wrap_angle(shifted), a, rtol=0, atol=atol)


def test_wrap_angle_output_interval_and_equivalence_for_large_angles():
    a = np.random.default_rng(2).uniform(-1e4, 1e4, 10_000)
    w = wrap_angle(a)
    assert_wrapped(w)
    # Same direction as the input (to the rounding of |a| ~ 1e4).
    np.testing.assert_allclose(np.cos(w), np.cos(a), atol=1e-11)
    np.testing.assert_allclose(np.sin(w), np.sin(a), atol=1e-11)


def test_wrap_angle_returns_a_float_for_scalars_and_keeps_array_shapes():
    assert type(wrap_angle(7.0)) is float
    assert type(wrap_angle(np.float64(7.0))) is float
    assert type(wrap_angle(np.array(7.0))) is float
    assert type(wrap_angle(7)) is float  # ints are angles too
    out = wrap_angle([[0.0, 4.0, -4.0], [7.0, -7.0, 2 * PI]])
    assert isinstance(out, np.ndarray) and out.shape == (2, 3)
    np.testing.assert_allclose(
        out, [[0.0, 4.0 - 2 * PI, 2 * PI - 4.0], [7.0 - 2 * PI, 2 * PI - 7.0, 0.0]], atol=1e-15
    )
    assert wrap_angle(np.zeros(0)).shape == (0,)


def test_wrap_angle_never_returns_minus_pi():
    """np.mod(pi - a, 2 pi) rounds the tiny negative pi - a = -4.4e-16 up to exactly 2 pi."""
    just_above_pi = np.nextafter(PI, np.inf)
    assert_wrapped(wrap_angle(just_above_pi))
    assert wrap_angle(just_above_pi) == PI
    assert_wrapped(wrap_angle(np.array([just_above_pi, -PI, np.nextafter(-PI, -np.inf), 3 * PI])))


# --------------------------------------------------------------------------- SE(2) group


def test_compose_and_inverse_hand_values():
    # Turned left (pi/2) at (1, 2), then 3 m ahead and another left turn.
    np.testing.assert_allclose(compose([1, 2, PI / 2], [3, 0, PI / 2]), [1, 5, PI], atol=TOL)
    np.testing.assert_allclose(inverse([1, 2, PI / 2]), [-2, 1, -PI / 2], atol=TOL)
    # b is 2 m straight ahead of a (both heading +y).
    np.testing.assert_allclose(relative([1, 1, PI / 2], [1, 3, PI / 2]), [2, 0, 0], atol=TOL)
    np.testing.assert_allclose(relative([1, 1, 0], [1, 3, 0]), [0, 2, 0], atol=TOL)


def test_single_poses_compose_bit_for_bit_as_batches():
    # compose / inverse / relative of two (3,) poses take a scalar path (the SLAM front end
    # calls them a few times per scan); it must give exactly the batch path's bits, also
    # where the sum of headings wraps at +-pi, or a run would depend on the call's shape.
    rng = np.random.default_rng(13)
    a, b = random_poses(rng, 2000), random_poses(rng, 2000)
    a[:200, 2] = PI * rng.choice([-1.0, 1.0], 200)
    b[:200, 2] = np.nextafter(PI, 0) * rng.choice([-1.0, 1.0], 200)
    batch = compose(a, b), inverse(a), relative(a, b)
    for k in range(len(a)):
        assert compose(a[k], b[k]).tolist() == batch[0][k].tolist()
        assert inverse(a[k]).tolist() == batch[1][k].tolist()
        assert relative(a[k], b[k]).tolist() == batch[2][k].tolist()
    # and each result is a fresh float array of shape (3,)
    out = compose([1, 2, 0.5], (0, 0, 0))
    assert out.shape == (3,) and out.dtype == np.float64
    assert compose(a[0], b[0]) is not a[0]


def test_compose_associative():
    rng = np.random.default_rng(10)
    a, b, c = (random_poses(rng, 200) for _ in range(3))
    assert_poses_close(compose(compose(a, b), c), compose(a, compose(b, c)))


def test_identity_is_neutral():
    p = random_poses(np.random.default_rng(11), 200)
    zero = np.zeros(3)
    assert_poses_close(compose(zero, p), p)
    assert_poses_close(compose(p, zero), p)
    assert_poses_close(inverse(zero), zero)
    assert_poses_close(relative(p, p), np.zeros_like(p))


def test_inverse_cancels_on_both_sides():
    p = random_poses(np.random.default_rng(12), 200)
    assert_poses_close(compose(p, inverse(p)), np.zeros_like(p))
    assert_poses_close(compose(inverse(p), p), np.zeros_like(p))


def test_inverse_is_an_involution():
    p = random_poses(np.random.default_rng(13), 200)
    assert_poses_close(inverse(inverse(p)), p)


def test_inverse_of_a_composition_reverses_the_order():
    rng = np.random.default_rng(14)
    a, b = random_poses(rng, 200), random_poses(rng, 200)
    assert_poses_close(inverse(compose(a, b)), compose(inverse(b), inverse(a)))


def test_relative_is_inverse_then_compose_and_compose_undoes_it():
    rng = np.random.default_rng(15)
    a, b = random_poses(rng, 200), random_poses(rng, 200)
    assert_poses_close(relative(a, b), compose(inverse(a), b))
    assert_poses_close(compose(a, relative(a, b)), b)


def test_outputs_are_wrapped_even_for_unwrapped_inputs():
    rng = np.random.default_rng(16)
    a = random_poses(rng, 500)
    b = random_poses(rng, 500)
    a[:, 2] *= 7.0  # headings up to +-7 pi
    b[:, 2] += 2 * PI * rng.integers(-3, 4, 500)
    for out in (compose(a, b), inverse(a), relative(a, b)):
        assert_wrapped(out[:, 2])
    # The angle convention at the seam: pi, never -pi.
    assert compose([0, 0, PI / 2], [0, 0, PI / 2])[2] == PI
    assert compose([0, 0, -PI / 2], [0, 0, -PI / 2])[2] == PI
    assert inverse([0, 0, PI])[2] == PI


def test_transform_points_respects_composition():
    rng = np.random.default_rng(17)
    pts = rng.uniform(-5, 5, (50, 2))
    for a, b in zip(random_poses(rng, 20), random_poses(rng, 20), strict=True):
        np.testing.assert_allclose(
            transform_points(compose(a, b), pts),
            transform_points(a, transform_points(b, pts)),
            rtol=0,
            atol=TOL,
        )
        np.testing.assert_allclose(
            transform_points(inverse(a), transform_points(a, pts)), pts, rtol=0, atol=TOL
        )


def test_transform_points_hand_values_and_rigidity():
    np.testing.assert_allclose(
        transform_points([1, 2, PI / 2], [[1, 0], [0, 1], [0, 0]]),
        [[1, 3], [0, 2], [1, 2]],
        atol=TOL,
    )
    rng = np.random.default_rng(18)
    pts = rng.uniform(-5, 5, (30, 2))
    moved = transform_points(random_poses(rng), pts)
    assert moved.shape == (30, 2)
    dists = np.linalg.norm(pts[:, None] - pts[None], axis=-1)
    np.testing.assert_allclose(
        np.linalg.norm(moved[:, None] - moved[None], axis=-1), dists, atol=TOL
    )


def _rowwise(fn, a, b):
    a, b = np.broadcast_arrays(np.asarray(a, float), np.asarray(b, float))
    flat = [fn(x, y) for x, y in zip(a.reshape(-1, 3), b.reshape(-1, 3), strict=True)]
    return np.reshape(flat, a.shape)


@pytest.mark.parametrize(
    ("shape_a", "shape_b", "shape_out"),
    [
        ((3,), (3,), (3,)),
        ((7, 3), (3,), (7, 3)),
        ((3,), (7, 3), (7, 3)),
        ((7, 3), (7, 3), (7, 3)),
        ((4, 1, 3), (7, 3), (4, 7, 3)),
    ],
)
@pytest.mark.parametrize("fn", [compose, relative], ids=["compose", "relative"])
def test_compose_and_relative_broadcast(fn, shape_a, shape_b, shape_out):
    rng = np.random.default_rng(19)
    a = random_poses(rng, *shape_a[:-1])
    b = random_poses(rng, *shape_b[:-1])
    out = fn(a, b)
    assert out.shape == shape_out
    assert_poses_close(out, _rowwise(fn, a, b))


def test_inverse_broadcasts_over_leading_dims():
    p = random_poses(np.random.default_rng(20), 4, 5)
    out = inverse(p)
    assert out.shape == (4, 5, 3)
    assert_poses_close(out, np.reshape([inverse(q) for q in p.reshape(-1, 3)], (4, 5, 3)))


# --------------------------------------------------------------------------- as_pose / as_points


def test_as_pose_returns_a_float_pose():
    p = as_pose([1, 2, 3])
    assert p.dtype == np.float64 and p.shape == (3,)
    np.testing.assert_array_equal(p, [1.0, 2.0, 3.0])


@pytest.mark.parametrize(
    "bad",
    [[1.0, 2.0], [1.0, 2.0, 3.0, 4.0], [[1.0, 2.0, 3.0]], 5.0, np.zeros((2, 3))],
    ids=["len2", "len4", "row", "scalar", "two_poses"],
)
def test_as_pose_rejects_wrong_shapes_naming_the_argument(bad):
    with pytest.raises(ValueError, match=r"^start must have shape \(3,\)"):
        as_pose(bad, name="start")
    with pytest.raises(ValueError, match=r"^pose must have shape \(3,\)"):
        as_pose(bad)


@pytest.mark.parametrize("bad", [[np.nan, 0, 0], [0, np.inf, 0], [0, 0, -np.inf]])
def test_as_pose_rejects_non_finite_values_naming_the_argument(bad):
    with pytest.raises(ValueError, match=r"^offset must be finite"):
        as_pose(bad, name="offset")


def test_as_points_accepts_n_by_2_and_rejects_the_rest():
    p = as_points([[1, 2], [3, 4]])
    assert p.dtype == np.float64 and p.shape == (2, 2)
    assert as_points(np.zeros((0, 2))).shape == (0, 2)
    for bad in ([1.0, 2.0], np.zeros((3, 3)), np.zeros((2, 2, 2))):
        with pytest.raises(ValueError, match=r"^scan must have shape \(N, 2\)"):
            as_points(bad, name="scan")


def test_as_points_names_the_first_non_finite_row():
    pts = [[0, 0], [1, 1], [np.nan, 2], [3, np.inf]]
    with pytest.raises(ValueError, match=r"^scan contains 2 non-finite rows \(first at index 2"):
        as_points(pts, name="scan")


# --------------------------------------------------------------------------- lines


def test_polar_to_points_hand_values():
    np.testing.assert_allclose(
        polar_to_points([2.0, 1.0, 3.0], [0.0, PI / 2, PI]),
        [[2, 0], [0, 1], [-3, 0]],
        atol=TOL,
    )


@pytest.mark.parametrize(
    ("rho", "theta", "expected"),
    [
        (2.0, 0.5, (2.0, 0.5)),
        (-2.0, 0.5, (2.0, 0.5 + PI)),
        (-2.0, 4.0, (2.0, 4.0 - PI)),
        (1.0, -0.5, (1.0, 2 * PI - 0.5)),
        (1.0, 2 * PI + 0.5, (1.0, 0.5)),
        (0.0, 1.0, (0.0, 1.0)),
    ],
)
def test_normalize_line(rho, theta, expected):
    r, t = normalize_line(rho, theta)
    assert float(r) == pytest.approx(expected[0], abs=TOL)
    assert float(t) == pytest.approx(expected[1], abs=TOL)


def test_normalize_line_keeps_the_line_and_the_interval_for_arrays():
    rng = np.random.default_rng(21)
    rho, theta = rng.uniform(-5, 5, 300), rng.uniform(-10, 10, 300)
    r, t = normalize_line(rho, theta)
    assert np.all(r >= 0) and np.all((t >= 0) & (t < 2 * PI))
    # Same set of points: a point of the input line lies on the output line.
    pts = point_on_line(rho, theta, rng.uniform(-5, 5, 300))
    dist = pts[:, 0] * np.cos(t) + pts[:, 1] * np.sin(t) - r
    np.testing.assert_allclose(dist, 0, atol=TOL)


def test_normalize_line_theta_stays_below_two_pi():
    """np.mod of a tiny negative angle rounds up to exactly 2 pi: that is theta 0."""
    _, t = normalize_line(1.0, -1e-17)
    assert t == 0.0
    r, t = normalize_line([1.0, -1.0, 2.0], [-1e-17, np.nextafter(-PI, -np.inf), 2 * PI])
    assert np.all((t >= 0.0) & (t < 2 * PI))
    np.testing.assert_array_equal(r, [1.0, 1.0, 2.0])


@pytest.mark.parametrize(
    ("p", "q", "expected"),
    [
        ((1, -1), (1, 5), (1.0, 0.0)),  # x = 1
        ((-1, -1), (-1, 5), (1.0, PI)),  # x = -1
        ((0, 2), (3, 2), (2.0, PI / 2)),  # y = 2
        ((0, -2), (3, -2), (2.0, 3 * PI / 2)),  # y = -2
        ((2, 0), (0, 2), (np.sqrt(2), PI / 4)),  # x + y = 2
    ],
)
def test_line_through_hand_values(p, q, expected):
    r, t = line_through(p, q)
    assert r == pytest.approx(expected[0], abs=TOL)
    assert abs(wrap_angle(t - expected[1])) < TOL
    r2, t2 = line_through(q, p)  # the same undirected line
    assert r2 == pytest.approx(r, abs=TOL) and abs(wrap_angle(t2 - t)) < TOL


def test_line_through_rejects_one_point_twice():
    with pytest.raises(ValueError, match="two distinct points"):
        line_through([1.0, 2.0], [1.0, 2.0])


def test_signed_distance_and_projection():
    pts = np.array([[3.0, 7.0], [0.0, 0.0], [1.0, -2.0]])
    np.testing.assert_allclose(signed_distance(pts, 1.0, 0.0), [2, -1, 0], atol=TOL)  # x = 1
    np.testing.assert_allclose(
        project_onto_line(pts, 1.0, 0.0), [[1, 7], [1, 0], [1, -2]], atol=TOL
    )
    rng = np.random.default_rng(22)
    pts = rng.uniform(-5, 5, (100, 2))
    proj = project_onto_line(pts, 2.5, 2.0)
    np.testing.assert_allclose(signed_distance(proj, 2.5, 2.0), 0, atol=TOL)
    np.testing.assert_allclose(project_onto_line(proj, 2.5, 2.0), proj, atol=TOL)


def test_observation_hand_values():
    # The line x = 2 (rho 2, theta 0) seen from three places.
    side, d = observation(2.0, 0.0, np.array([0.0, 3.0, 2.0]), np.array([0.0, 5.0, 7.0]))
    np.testing.assert_array_equal(side, [1, -1, 0])
    assert side.dtype == np.int64
    np.testing.assert_allclose(d, [2, 1, 0], atol=TOL)
    # Several lines (y = 1, x = -3, x + y = sqrt 2) from one robot at (1, -1).
    side, d = observation([1.0, 3.0, 1.0], [PI / 2, PI, PI / 4], 1.0, -1.0)
    np.testing.assert_array_equal(side, [1, 1, 1])
    np.testing.assert_allclose(d, [2, 4, 1], atol=TOL)
    side, d = observation([1.0], [PI / 2], 0.0, 3.0)  # beyond y = 1
    np.testing.assert_array_equal(side, [-1])
    np.testing.assert_allclose(d, [2], atol=TOL)


def test_observation_broadcasts_lines_against_positions():
    rng = np.random.default_rng(23)
    rho, theta = rng.uniform(0, 5, 4), rng.uniform(0, 2 * PI, 4)
    x, y = rng.uniform(-5, 5, (6, 1)), rng.uniform(-5, 5, (6, 1))
    side, d = observation(rho, theta, x, y)
    assert side.shape == d.shape == (6, 4)
    s = signed_distance(np.stack(np.broadcast_arrays(x, y), -1), rho, theta)
    np.testing.assert_array_equal(side, -np.sign(s))
    np.testing.assert_allclose(d, np.abs(s), atol=TOL)


def test_position_and_point_on_line_hand_values():
    assert position_on_line([1.0, 2.0], 0.0) == pytest.approx(2.0)  # u = (0, 1)
    assert position_on_line([1.0, 2.0], PI / 2) == pytest.approx(-1.0)  # u = (-1, 0)
    np.testing.assert_allclose(point_on_line(2.0, 0.0, 3.0), [2, 3], atol=TOL)
    np.testing.assert_allclose(point_on_line(2.0, PI / 2, 3.0), [-3, 2], atol=TOL)
    np.testing.assert_allclose(
        point_on_line(1.0, PI, np.array([-1.0, 0.0, 1.0])), [[-1, 1], [-1, 0], [-1, -1]], atol=TOL
    )


def test_point_on_line_round_trips_and_broadcasts():
    rng = np.random.default_rng(24)
    rho, theta = rng.uniform(0, 5, (3, 1)), rng.uniform(0, 2 * PI, (3, 1))
    t = rng.uniform(-10, 10, 4)
    p = point_on_line(rho, theta, t)
    assert p.shape == (3, 4, 2)
    np.testing.assert_allclose(signed_distance(p, rho, theta), 0, atol=TOL)
    np.testing.assert_allclose(position_on_line(p, theta), np.broadcast_to(t, (3, 4)), atol=TOL)
    assert point_on_line(1.0, 0.5, np.arange(5.0)).shape == (5, 2)


@pytest.mark.parametrize(
    ("sxx", "syy", "sxy", "expected"),
    [
        (4.0, 0.0, 0.0, PI / 2),  # spread along x: horizontal line, normal +y
        (0.0, 4.0, 0.0, PI),  # spread along y: vertical line
        (2.0, 2.0, 2.0, 3 * PI / 4),  # along the diagonal y = x
        (2.0, 2.0, -2.0, PI / 4),  # along y = -x
        (3.0, 1.0, np.sqrt(3.0), 2 * PI / 3),  # direction 30 degrees
    ],
)
def test_tls_normal_angle_hand_values(sxx, syy, sxy, expected):
    assert tls_normal_angle(sxx, syy, sxy) == pytest.approx(expected, abs=TOL)
    assert tls_normal_angle(10 * sxx, 10 * syy, 10 * sxy) == pytest.approx(expected, abs=TOL)


def test_tls_normal_angle_is_the_least_variance_direction():
    rng = np.random.default_rng(25)
    for _ in range(50):
        q = rng.normal(size=(30, 2)) * [3.0, 0.3] @ np.linalg.qr(rng.normal(size=(2, 2)))[0]
        q -= q.mean(axis=0)
        sxx, syy, sxy = (q[:, 0] ** 2).sum(), (q[:, 1] ** 2).sum(), (q[:, 0] * q[:, 1]).sum()
        theta = tls_normal_angle(sxx, syy, sxy)
        assert 0 < theta <= PI
        normal = np.linalg.svd(q)[2][-1]  # right singular vector of the smallest value
        assert angle_difference_lines(theta, np.arctan2(normal[1], normal[0])) < 1e-9


def test_angle_difference_lines():
    assert angle_difference_lines(0.0, PI) == pytest.approx(0.0, abs=TOL)
    assert angle_difference_lines(0.1, PI + 0.1) == pytest.approx(0.0, abs=TOL)
    assert angle_difference_lines(0.0, PI / 2) == pytest.approx(PI / 2, abs=TOL)
    assert angle_difference_lines(0.1, 2 * PI - 0.1) == pytest.approx(0.2, abs=TOL)
    assert angle_difference_lines(3.0, 0.2) == pytest.approx(PI - 2.8, abs=TOL)
    assert type(angle_difference_lines(0.0, 1.0)) is float
    d = angle_difference_lines(np.random.default_rng(26).uniform(-10, 10, (5, 20)), 1.0)
    assert d.shape == (5, 20) and np.all((d >= 0) & (d <= PI / 2))


# --------------------------------------------------------------------------- segments


@pytest.mark.parametrize(
    ("point", "expected"),
    [
        ((1.0, 1.0), 1.0),  # above the middle
        ((1.5, -0.25), 0.25),  # below
        ((0.7, 0.0), 0.0),  # on the segment
        ((-1.0, 0.0), 1.0),  # beyond a, on the line
        ((3.0, 4.0), np.sqrt(17.0)),  # beyond b: distance to b
        ((-3.0, -4.0), 5.0),  # beyond a: distance to a
    ],
)
def test_point_segment_distance_hand_values(point, expected):
    a, b = np.array([0.0, 0.0]), np.array([2.0, 0.0])
    assert point_segment_distance(point, a, b) == pytest.approx(expected, abs=TOL)
    assert point_segment_distance(point, b, a) == pytest.approx(expected, abs=TOL)


def test_point_segment_distance_of_a_degenerate_segment_is_the_point_distance():
    pts = np.array([[4.0, 5.0], [1.0, 1.0], [1.0, -2.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no divide-by-zero RuntimeWarning either
        d = point_segment_distance(pts, [1.0, 1.0], [1.0, 1.0])
    np.testing.assert_allclose(d, [5, 0, 3], atol=TOL)


def test_point_segment_distance_broadcasts_points_against_segments():
    rng = np.random.default_rng(27)
    pts, a, b = rng.uniform(-5, 5, (9, 2)), rng.uniform(-5, 5, (4, 2)), rng.uniform(-5, 5, (4, 2))
    d = point_segment_distance(pts[:, None, :], a, b)
    assert d.shape == (9, 4)
    for i, p in enumerate(pts):
        for j in range(4):
            assert d[i, j] == pytest.approx(point_segment_distance(p, a[j], b[j]), abs=TOL)
    # Sampled densely, no point of the segment is closer than the returned distance.
    s = np.linspace(0, 1, 2001)[:, None]
    for j in range(4):
        sampled = np.linalg.norm(pts[:, None] - (a[j] + s * (b[j] - a[j])), axis=-1).min(1)
        step = np.linalg.norm(b[j] - a[j]) / 2000
        assert np.all(d[:, j] <= sampled + TOL)
        assert np.all(sampled <= d[:, j] + step / 2 + TOL)


def test_distance_to_segments_hand_values_and_shapes():
    square = [[0, 0, 2, 0], [2, 0, 2, 2], [2, 2, 0, 2], [0, 2, 0, 0]]
    pts = [[1.0, 1.0], [1.0, 0.5], [3.0, 3.0], [-1.0, 1.0], [2.0, 0.0]]
    np.testing.assert_allclose(
        distance_to_segments(pts, square), [1, 0.5, np.sqrt(2), 1, 0], atol=TOL
    )
    np.testing.assert_allclose(
        distance_to_segments(pts, [0, 0, 2, 0]), [1, 0.5, np.sqrt(10), np.sqrt(2), 0], atol=TOL
    )
    assert distance_to_segments(np.zeros((0, 2)), square).shape == (0,)


def test_distance_to_segments_blocks_give_the_same_answer(monkeypatch):
    rng = np.random.default_rng(28)
    pts, segs = rng.uniform(-5, 5, (101, 2)), rng.uniform(-5, 5, (7, 4))
    whole = distance_to_segments(pts, segs)
    monkeypatch.setattr(geometry, "_CHUNK", 20)  # blocks of 2 points
    np.testing.assert_array_equal(distance_to_segments(pts, segs), whole)
    monkeypatch.setattr(geometry, "_CHUNK", 1)  # fewer elements than segments: 1 point a block
    np.testing.assert_array_equal(distance_to_segments(pts, segs), whole)


def test_distance_to_segments_needs_a_segment():
    with pytest.raises(ValueError, match="at least one segment"):
        distance_to_segments([[0.0, 0.0]], np.zeros((0, 4)))


@pytest.mark.parametrize(
    ("s", "t", "expected"),
    [
        ((0, 0, 2, 2), (0, 2, 2, 0), 0.0),  # an X
        ((0, 0, 2, 0), (0, 1, 2, 1), 1.0),  # parallel, one above the other
        ((0, 0, 1, 0), (3, 0, 5, 0), 2.0),  # collinear with a gap
        ((0, 0, 2, 0), (1, 0, 1, 3), 0.0),  # a T: endpoint on the other segment
        ((0, 0, 1, 0), (4, 4, 4, 9), 5.0),  # apart: endpoint to endpoint
        ((0, 0, 4, 0), (2, 1, 2, 5), 1.0),  # endpoint above the middle of the other
        ((0, 0, 1, 0), (1, 0, 2, 0), 0.0),  # sharing an endpoint
        ((1, 1, 1, 1), (0, 0, 2, 0), 1.0),  # a degenerate (point) segment
    ],
)
def test_segment_distances_hand_values(s, t, expected):
    assert segment_distances(s, t)[0, 0] == pytest.approx(expected, abs=TOL)
    assert segment_distances(t, s)[0, 0] == pytest.approx(expected, abs=TOL)


def test_segment_distances_shape_symmetry_and_dense_sampling():
    rng = np.random.default_rng(29)
    s, t = rng.uniform(-3, 3, (5, 4)), rng.uniform(-3, 3, (4, 4))
    d = segment_distances(s, t)
    assert d.shape == (5, 4)
    assert (d == 0).any() and (d > 0).any()  # crossing and separate pairs both occur
    np.testing.assert_allclose(segment_distances(t, s), d.T, atol=TOL)
    u = np.linspace(0, 1, 201)[:, None]
    for i, si in enumerate(s):
        ps = si[:2] + u * (si[2:] - si[:2])
        hs = np.linalg.norm(si[2:] - si[:2]) / 200
        for j, tj in enumerate(t):
            pt = tj[:2] + u * (tj[2:] - tj[:2])
            ht = np.linalg.norm(tj[2:] - tj[:2]) / 200
            sampled = np.linalg.norm(ps[:, None] - pt[None], axis=-1).min()
            assert d[i, j] <= sampled + TOL
            assert sampled <= d[i, j] + (hs + ht) / 2 + TOL


def test_ray_segment_intersection_hit_miss_behind():
    o, d = [0.0, 0.0], [1.0, 0.0]
    t, s = ray_segment_intersection(o, d, [2.0, -1.0], [2.0, 1.0])  # hit in the middle
    assert (t, s) == (pytest.approx(2.0), pytest.approx(0.5))
    t, s = ray_segment_intersection(o, d, [2.0, 1.0], [2.0, 3.0])  # line hit, segment missed
    assert (t, s) == (pytest.approx(2.0), pytest.approx(-0.5))
    t, s = ray_segment_intersection(o, d, [-3.0, -1.0], [-3.0, 1.0])  # behind the origin
    assert (t, s) == (pytest.approx(-3.0), pytest.approx(0.5))
    t, s = ray_segment_intersection([1.0, 1.0], [0.0, 2.0], [0.0, 4.0], [4.0, 4.0])  # |d| = 2
    assert (t, s) == (pytest.approx(1.5), pytest.approx(0.25))


def test_ray_segment_intersection_parallel_is_not_finite_and_silent():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        t, _ = ray_segment_intersection([0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [5.0, 1.0])
        assert not np.isfinite(t)  # parallel: inf
        t, _ = ray_segment_intersection([0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [3.0, 0.0])
        assert np.isnan(t)  # collinear: 0 / 0


def test_ray_segment_intersection_broadcasts_beams_against_walls():
    rng = np.random.default_rng(30)
    origin = np.array([0.5, -0.5])
    angles = rng.uniform(-PI, PI, 8)
    beams = np.column_stack([np.cos(angles), np.sin(angles)])[:, None, :]  # (8, 1, 2)
    a, b = rng.uniform(-5, 5, (6, 2)), rng.uniform(-5, 5, (6, 2))
    t, s = ray_segment_intersection(origin, beams, a, b)
    assert t.shape == s.shape == (8, 6)
    # Both parametrisations name the same point.
    np.testing.assert_allclose(origin + t[..., None] * beams, a + s[..., None] * (b - a), atol=1e-9)
