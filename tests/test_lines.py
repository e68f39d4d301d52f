"""The feature line (fhslam.lines): total-least-squares fit, Line construction and rigid motion.

Lines are ``(rho, theta)`` with ``rho >= 0`` and ``theta`` in [0, 2 pi) (module docstring), so
away from the origin a line has exactly one representation and the tests compare rho and theta
directly (theta through ``wrap_angle`` of the difference, so 0 and 2 pi - 1e-13 agree). Only a
line through the origin (rho ~ 0) may come out as ``(0, theta)`` or ``(0, theta + pi)``.
Absolute tolerance ``TOL = 1e-12`` for exact data at O(10) m, looser where a test says why.
"""

from __future__ import annotations

import numpy as np
import pytest

from fhslam.geometry import (
    angle_difference_lines,
    compose,
    inverse,
    observation,
    point_on_line,
    position_on_line,
    signed_distance,
    transform_points,
    wrap_angle,
)
from fhslam.lines import Line, fit_line, line_from_points, split_runs, transform_lines

TOL = 1e-12
PI = np.pi


def points_on(rho: float, theta: float, t) -> np.ndarray:
    """Exact points at coordinates ``t`` along the line (rho, theta)."""
    return point_on_line(rho, theta, np.asarray(t, dtype=float))


def noisy_segment(rng: np.random.Generator, n: int = 25, noise: float = 0.01) -> np.ndarray:
    """n points in order along a random segment of the [-8, 8] square, with Gaussian noise."""
    a, b = rng.uniform(-8, 8, (2, 2))
    while np.hypot(*(b - a)) < 1.0:
        b = rng.uniform(-8, 8, 2)
    s = np.linspace(0, 1, n)[:, None]
    return a + s * (b - a) + rng.normal(0, noise, (n, 2))


def random_lines(seed: int, k: int = 30) -> list[Line]:
    rng = np.random.default_rng(seed)
    return [line_from_points(noisy_segment(rng, n=int(rng.integers(2, 40)))) for _ in range(k)]


def assert_same_line(got: Line, want: Line, atol: float = TOL) -> None:
    """Same geometry and bookkeeping; dir/d are compared as given."""
    assert got.rho == pytest.approx(want.rho, abs=atol)
    assert abs(wrap_angle(got.theta - want.theta)) <= atol
    np.testing.assert_allclose(got.sp, want.sp, rtol=0, atol=atol)
    np.testing.assert_allclose(got.ep, want.ep, rtol=0, atol=atol)
    assert got.length == pytest.approx(want.length, abs=atol)
    assert got.n == want.n
    assert got.rms == pytest.approx(want.rms, abs=atol)
    np.testing.assert_array_equal(got.inliers, want.inliers)
    assert (got.dir, got.d) == (want.dir, want.d)


def assert_paper_form(line: Line) -> None:
    assert line.rho >= 0 and 0 <= line.theta < 2 * PI, line


# --------------------------------------------------------------------------- fit_line


THETAS = [0.0, 1e-9, 0.3, PI / 4, PI / 2 - 1e-9, PI / 2, PI / 2 + 1e-9, 2.0, PI - 1e-9, PI,
          PI + 1e-9, 4.0, 3 * PI / 2, 5.5, 2 * PI - 1e-9]  # fmt: skip


@pytest.mark.parametrize("rho", [0.5, 7.0, 40.0])
@pytest.mark.parametrize("theta", THETAS)
def test_fit_line_recovers_an_exact_line(rho, theta):
    pts = points_on(rho, theta, np.linspace(-3.0, 4.0, 15))
    r, t, rms = fit_line(pts)
    assert r == pytest.approx(rho, abs=TOL)
    assert abs(wrap_angle(t - theta)) < TOL
    assert rms < TOL
    assert r >= 0 and 0 <= t < 2 * PI


@pytest.mark.parametrize("theta", THETAS)
def test_fit_line_through_the_origin(theta):
    # rho ~ 0: the sign of the rounding residue picks theta or theta + pi; both are the line.
    pts = points_on(0.0, theta, np.linspace(-3.0, 4.0, 15))
    r, t, rms = fit_line(pts)
    assert abs(r) < TOL
    assert angle_difference_lines(t, theta) < TOL
    assert rms < TOL
    assert r >= 0 and 0 <= t < 2 * PI


def test_fit_line_of_two_points_is_the_line_through_them():
    r, t, rms = fit_line([[1.0, -1.0], [1.0, 5.0]])  # x = 1
    assert (r, rms) == (pytest.approx(1.0, abs=TOL), pytest.approx(0.0, abs=TOL))
    assert abs(wrap_angle(t)) < TOL
    r, t, _ = fit_line([[0.0, -2.0], [3.0, -2.0]])  # y = -2
    assert (r, t) == (pytest.approx(2.0, abs=TOL), pytest.approx(3 * PI / 2, abs=TOL))


def test_fit_line_rms_is_the_orthogonal_residual():
    # Symmetric +-0.1 about y = 0: the fit is y = 0 (rho 0, theta pi/2), every residual 0.1.
    pts = [[0.0, 0.1], [1.0, -0.1], [2.0, -0.1], [3.0, 0.1]]
    r, t, rms = fit_line(pts)
    assert r == pytest.approx(0.0, abs=TOL)
    assert angle_difference_lines(t, PI / 2) < TOL
    assert rms == pytest.approx(0.1, abs=TOL)


def test_fit_line_matches_an_svd_total_least_squares_fit():
    rng = np.random.default_rng(40)
    for _ in range(40):
        p = noisy_segment(rng, n=int(rng.integers(3, 60)), noise=0.05)
        r, t, rms = fit_line(p)
        c = p.mean(axis=0)
        normal = np.linalg.svd(p - c)[2][-1]  # direction of least variance
        rho = c @ normal
        theta = np.arctan2(normal[1], normal[0]) + (PI if rho < 0 else 0.0)
        assert r == pytest.approx(abs(rho), abs=1e-9)
        assert abs(wrap_angle(t - theta)) < 1e-9
        assert rms == pytest.approx(np.sqrt(np.mean(signed_distance(p, r, t) ** 2)), abs=TOL)
        # Least squares: turning or shifting the line only adds residual.
        for dr, dt in [(1e-3, 0), (-1e-3, 0), (0, 1e-3), (0, -1e-3)]:
            worse = np.sqrt(np.mean(signed_distance(p, r + dr, t + dt) ** 2))
            assert worse > rms


@pytest.mark.parametrize(
    "bad",
    [np.zeros((1, 2)), np.zeros((0, 2)), np.zeros((5, 3)), np.zeros(4), np.zeros((2, 2, 2))],
    ids=["one_point", "no_points", "3_columns", "flat", "3d"],
)
def test_fit_line_rejects_wrong_shapes(bad):
    with pytest.raises(ValueError, match=r"fit_line needs an \(N, 2\) array with N >= 2"):
        fit_line(bad)


def test_fit_line_rejects_identical_points():
    with pytest.raises(ValueError, match="identical points"):
        fit_line([[1.0, 2.0]] * 5)


# --------------------------------------------------------------------------- line_from_points


def test_line_from_points_hand_values():
    pts = np.array([[1.0, -1.0], [1.0, 0.5], [1.0, 3.0]])  # on x = 1, in scan order
    line = line_from_points(pts)
    assert (line.rho, line.theta) == (pytest.approx(1.0, abs=TOL), pytest.approx(0.0, abs=TOL))
    np.testing.assert_allclose(line.sp, [1, -1], atol=TOL)
    np.testing.assert_allclose(line.ep, [1, 3], atol=TOL)
    assert line.length == pytest.approx(4.0, abs=TOL)
    assert line.n == 3 and line.rms == pytest.approx(0.0, abs=TOL)
    np.testing.assert_array_equal(line.inliers, [0, 1, 2])
    assert line.dir is None and line.d is None
    np.testing.assert_allclose(line.normal, [1, 0], atol=TOL)
    np.testing.assert_allclose(line.midpoint, [1, 1], atol=TOL)


def test_line_from_points_end_points_follow_scan_order():
    rng = np.random.default_rng(41)
    for _ in range(20):
        p = noisy_segment(rng)
        fwd, back = line_from_points(p), line_from_points(p[::-1])
        np.testing.assert_allclose(back.sp, fwd.ep, atol=1e-9)
        np.testing.assert_allclose(back.ep, fwd.sp, atol=1e-9)
        # sp is the first point's projection, ep the last's (points are ordered along it).
        for line in (fwd, back):
            q = p if line is fwd else p[::-1]
            t = position_on_line(q, line.theta)
            np.testing.assert_allclose(
                position_on_line(np.vstack([line.sp, line.ep]), line.theta), t[[0, -1]], atol=1e-9
            )
            np.testing.assert_allclose(
                signed_distance(np.vstack([line.sp, line.ep]), line.rho, line.theta), 0, atol=1e-9
            )
            assert line.length == pytest.approx(np.ptp(t), abs=1e-9)
            assert line.length == pytest.approx(np.linalg.norm(line.ep - line.sp), abs=1e-9)
            assert_paper_form(line)


def test_line_from_points_end_points_are_the_extreme_projections():
    # Scan order not monotonic along the line: the extremes still bound the segment.
    pts = np.array([[0.0, 2.0], [3.0, 2.0], [-1.0, 2.0], [5.0, 2.0]])  # y = 2
    line = line_from_points(pts)
    np.testing.assert_allclose(line.sp, [-1, 2], atol=TOL)  # first point lies on this side
    np.testing.assert_allclose(line.ep, [5, 2], atol=TOL)
    assert line.length == pytest.approx(6.0, abs=TOL)


def test_line_from_points_uses_only_the_inliers():
    pts = np.array([[9.0, 9.0], [0.0, 1.0], [-5.0, -5.0], [2.0, 1.0], [4.0, 1.0]])
    line = line_from_points(pts, inliers=[1, 3, 4])
    assert (line.rho, line.theta) == (
        pytest.approx(1.0, abs=TOL),
        pytest.approx(PI / 2, abs=TOL),
    )
    assert line.n == 3 and line.rms == pytest.approx(0.0, abs=TOL)
    np.testing.assert_array_equal(line.inliers, [1, 3, 4])
    np.testing.assert_allclose([line.sp, line.ep], [[0, 1], [4, 1]], atol=TOL)


def test_line_from_points_with_a_given_line():
    pts = np.array([[-2.1, 0.0], [-1.9, 1.0], [-2.0, 2.0]])
    line = line_from_points(pts, rho_theta=(-2.0, 0.0))  # normalised to (2, pi): x = -2
    assert (line.rho, line.theta) == (pytest.approx(2.0, abs=TOL), pytest.approx(PI, abs=TOL))
    assert line.rms == pytest.approx(np.sqrt(0.02 / 3), abs=TOL)
    np.testing.assert_allclose([line.sp, line.ep], [[-2, 0], [-2, 2]], atol=TOL)


def test_line_from_points_with_a_pose_and_observed_from():
    line = line_from_points([[2.0, -1.0], [2.0, 1.0]])  # x = 2
    seen = line_from_points([[2.0, -1.0], [2.0, 1.0]], pose=[0.5, 3.0, 1.0])
    assert (seen.dir, seen.d) == (1, pytest.approx(1.5, abs=TOL))
    assert type(seen.dir) is int and type(seen.d) is float
    beyond = line.observed_from([3.0, 0.0, 0.0])
    assert (beyond.dir, beyond.d) == (-1, pytest.approx(1.0, abs=TOL))
    on = line.observed_from([2.0, 7.0, 0.0])
    assert (on.dir, on.d) == (0, pytest.approx(0.0, abs=TOL))
    assert line.dir is None  # frozen: observed_from returns a new line
    rng = np.random.default_rng(42)
    for ln in random_lines(43, 10):
        x, y = rng.uniform(-10, 10, 2)
        side, d = observation(ln.rho, ln.theta, x, y)
        obs = ln.observed_from([x, y, 0.3])
        assert (obs.dir, obs.d) == (int(side), pytest.approx(float(d), abs=TOL))


def test_observed_from_rejects_a_bad_pose():
    line = line_from_points([[2.0, -1.0], [2.0, 1.0]])
    with pytest.raises(ValueError, match=r"^pose must have shape \(3,\)"):
        line.observed_from([1.0, 2.0])
    with pytest.raises(ValueError, match=r"^pose must be finite"):
        line.observed_from([1.0, np.nan, 0.0])


# --------------------------------------------------------------------------- rigid motion


def test_transformed_hand_values():
    line = line_from_points([[1.0, 0.0], [1.0, 2.0]])  # x = 1, rho 1, theta 0
    moved = line.transformed([2.0, 0.0, 0.0])  # x = 3
    assert (moved.rho, moved.theta) == (pytest.approx(3.0), pytest.approx(0.0, abs=TOL))
    np.testing.assert_allclose([moved.sp, moved.ep], [[3, 0], [3, 2]], atol=TOL)
    turned = line.transformed([0.0, 0.0, PI / 2])  # y = 1
    assert (turned.rho, turned.theta) == (pytest.approx(1.0), pytest.approx(PI / 2))
    np.testing.assert_allclose([turned.sp, turned.ep], [[0, 1], [-2, 1]], atol=TOL)
    flipped = line.transformed([-3.0, 0.0, 0.0])  # x = -2: rho would be -2, so theta flips
    assert (flipped.rho, flipped.theta) == (pytest.approx(2.0), pytest.approx(PI))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_transform_lines_equals_transformed_one_by_one(seed):
    lines = [ln.observed_from([0.1, 0.2, 0.3]) for ln in random_lines(50 + seed)]
    rng = np.random.default_rng(60 + seed)
    for pose in [*rng.uniform(-10, 10, (5, 3)), np.zeros(3), np.array([0.0, 0.0, PI])]:
        many = transform_lines(lines, pose)
        assert len(many) == len(lines)
        for got, ln in zip(many, lines, strict=True):
            want = ln.transformed(pose)
            assert_same_line(got, want)
            assert got.dir is None and got.d is None  # dropped: they referred to the old frame
            assert_paper_form(got)


def test_transform_lines_of_no_lines():
    assert transform_lines([], [1.0, 2.0, 3.0]) == []


def test_transform_lines_rejects_a_bad_pose():
    lines = random_lines(70, 2)
    with pytest.raises(ValueError, match=r"^pose must have shape \(3,\)"):
        transform_lines(lines, [1.0, 2.0])
    with pytest.raises(ValueError, match=r"^pose must be finite"):
        transform_lines(lines, [np.inf, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"^pose must be finite"):
        lines[0].transformed([0.0, 0.0, np.nan])


def test_transform_then_inverse_gives_the_line_back():
    lines = random_lines(71)
    rng = np.random.default_rng(72)
    for pose in rng.uniform(-10, 10, (10, 3)):
        back = transform_lines(transform_lines(lines, pose), inverse(pose))
        for got, want in zip(back, lines, strict=True):
            assert_same_line(got, want, atol=1e-11)


def test_transforms_compose_and_keep_lengths():
    lines = random_lines(73)
    rng = np.random.default_rng(74)
    for a, b in zip(rng.uniform(-5, 5, (5, 3)), rng.uniform(-5, 5, (5, 3)), strict=True):
        twice = transform_lines(transform_lines(lines, b), a)
        once = transform_lines(lines, compose(a, b))
        for got, want, orig in zip(twice, once, lines, strict=True):
            assert_same_line(got, want, atol=1e-11)
            assert np.linalg.norm(got.ep - got.sp) == pytest.approx(orig.length, abs=1e-11)
            assert got.length == orig.length


def test_fit_commutes_with_a_rigid_motion():
    """Fitting the moved points == moving the fitted line (sp, ep, rms and all)."""
    rng = np.random.default_rng(75)
    for _ in range(30):
        pts = noisy_segment(rng, n=int(rng.integers(2, 40)), noise=0.02)
        pose = np.array([*rng.uniform(-10, 10, 2), rng.uniform(-PI, PI)])
        fit_then_move = line_from_points(pts).transformed(pose)
        move_then_fit = line_from_points(transform_points(pose, pts))
        assert_same_line(move_then_fit, fit_then_move, atol=1e-9)
        r, t, rms = fit_line(transform_points(pose, pts))
        assert (r, rms) == (pytest.approx(fit_then_move.rho, abs=1e-9), pytest.approx(rms))
        assert abs(wrap_angle(t - fit_then_move.theta)) < 1e-9


def test_a_line_seen_from_a_pose_matches_observation_in_the_robot_frame():
    # A world line seen by a robot at pose: transformed(inverse(pose)) has d = its rho.
    rng = np.random.default_rng(76)
    for ln in random_lines(77, 15):
        pose = np.array([*rng.uniform(-10, 10, 2), rng.uniform(-PI, PI)])
        seen = ln.transformed(inverse(pose))
        obs = ln.observed_from(pose)
        assert seen.rho == pytest.approx(obs.d, abs=1e-11)


def test_transformed_theta_stays_below_two_pi():
    """Theta 0.3 turned by -(0.1 + 0.2) sums to -5.6e-17, which np.mod rounds up to exactly
    2 pi: normalize_line must make that 0."""
    line = line_from_points(points_on(1.0, 0.3, [0.0, 1.0]), rho_theta=(1.0, 0.3))
    pose = [0.0, 0.0, -(0.1 + 0.2)]
    assert_paper_form(line.transformed(pose))
    assert_paper_form(transform_lines([line], pose)[0])


# --------------------------------------------------------------------------- split_runs


def test_split_runs_cuts_at_gaps_over_max_gap():
    pts = np.column_stack([[0.0, 0.1, 0.2, 1.0, 1.1, 9.0, 3.0, 3.5], np.zeros(8)])
    runs = split_runs(pts, [0, 1, 2, 3, 4, 6, 7], max_gap=0.5)
    assert [r.tolist() for r in runs] == [[0, 1, 2], [3, 4], [6, 7]]
    assert all(r.dtype == np.intp for r in runs)
    # A gap equal to max_gap does not cut.
    assert [r.tolist() for r in split_runs(pts, [6, 7], max_gap=0.5)] == [[6, 7]]
    assert [r.tolist() for r in split_runs(pts, [0, 1, 2], max_gap=0.01)] == [[0], [1], [2]]


def test_split_runs_of_short_index_lists():
    pts = np.zeros((3, 2))
    assert split_runs(pts, [], max_gap=1.0) == []
    (only,) = split_runs(pts, [2], max_gap=1.0)
    assert only.tolist() == [2]
