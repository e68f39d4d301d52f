"""Tests of the baseline line extractors (classical Hough variants, split-and-merge)."""

from __future__ import annotations

import numpy as np
import pytest

from fhslam.baselines import (
    ClassicalHoughParams,
    SplitMergeParams,
    hough_accumulator,
    hough_numpy_accumulator,
    hough_opencv_pointset,
    hough_opencv_probabilistic,
    hough_opencv_raster,
    split_and_merge,
)
from fhslam.geometry import angle_difference_lines, line_through

ROOM = [(0, 0, 6, 0), (6, 0, 6, 4), (6, 4, 0, 4), (0, 4, 0, 0)]  # 6 x 4 m, world frame
L_CORNER = [(-1, 2, 3, 2), (3, 2, 3, -3)]


def simulate_scan(walls, pose, noise=0.01, seed=0):
    """Ray-cast 181 beams over -90..90 deg (1 deg apart) from ``pose`` against wall segments.

    Returns the points in the laser frame (N, 2), the index of the wall each point lies on
    (N,), and the true walls as (rho, theta) in the laser frame (W, 2). Range noise is
    Gaussian with ``noise`` metres standard deviation.
    """
    x, y, heading = pose
    bearings = np.radians(np.arange(-90, 91))
    walls = np.asarray(walls, dtype=float)
    a, e = walls[:, :2], walls[:, 2:] - walls[:, :2]  # wall = a + s e, s in [0, 1]
    d = np.column_stack([np.cos(heading + bearings), np.sin(heading + bearings)])
    w = a[None] - np.array([x, y])  # (B, W, 2)
    cross = lambda u, v: u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]  # noqa: E731
    with np.errstate(divide="ignore", invalid="ignore"):
        den = cross(d[:, None], e[None])
        t = cross(w, e[None]) / den  # range along the beam
        s = cross(w, d[:, None]) / den  # position along the wall
    t = np.where((t > 0) & (s >= 0) & (s <= 1), t, np.inf)
    wall_id, ranges = t.argmin(axis=1), t.min(axis=1)
    hit = np.isfinite(ranges)
    ranges = ranges + np.random.default_rng(seed).normal(0.0, noise, len(ranges))
    points = np.column_stack([ranges * np.cos(bearings), ranges * np.sin(bearings)])[hit]
    c, s_ = np.cos(heading), np.sin(heading)

    def to_laser(px, py):
        return c * (px - x) + s_ * (py - y), -s_ * (px - x) + c * (py - y)

    truth = np.array([line_through(to_laser(*w[:2]), to_laser(*w[2:])) for w in walls])
    return points, wall_id[hit], truth


SCENES = {
    "room": simulate_scan(ROOM, (2.0, 1.5, 0.3)),  # sees 3 walls with 52-76 points each
    "L-corner": simulate_scan(L_CORNER, (0.0, 0.0, 0.4)),  # 2 walls, ~80 points each
}

PEAK = ClassicalHoughParams(refine=False)
REFINED = ClassicalHoughParams(refine=True)

# Tolerances (|d rho| metres, |d theta| degrees) on the test scans:
# - refined (least-squares fit of 50-80 points with 1 cm noise): 2 cm and 1 deg;
# - Hough peak: one 1 cm rho bin plus noise, 1.5 cm; half a 1 deg theta bin plus noise,
#   1.5 deg. (These walls lie 0.19 deg off the theta grid; a wall halfway between grid angles
#   has rho errors up to ~2-3 cm, the distance along the wall times the 0.5 deg error.)
# - HoughLinesP peak: the infinite line through a HoughLinesP segment's end pixels, which
#   carry 1 cm noise plus 2 cm pixels: 3 cm and 2 deg.
REFINED_TOL = (0.02, 1.0)
PEAK_TOL = (0.015, 1.5)
HOUGH_P_PEAK_TOL = (0.03, 2.0)

# (extractor, params, tolerance, one line per wall?)
CASES = {
    "numpy-peak": (hough_numpy_accumulator, PEAK, PEAK_TOL, True),
    "numpy-refined": (hough_numpy_accumulator, REFINED, REFINED_TOL, True),
    "pointset-peak": (hough_opencv_pointset, PEAK, PEAK_TOL, True),
    "pointset-refined": (hough_opencv_pointset, REFINED, REFINED_TOL, True),
    "raster-peak": (hough_opencv_raster, PEAK, PEAK_TOL, True),
    "raster-refined": (hough_opencv_raster, REFINED, REFINED_TOL, True),
    # HoughLinesP breaks a noisy wall into pieces whose lines differ by ~1 deg; the inlier band
    # (3 cm) of the first then misses the wall's far end, which becomes a second line.
    "houghP-peak": (hough_opencv_probabilistic, PEAK, HOUGH_P_PEAK_TOL, False),
    "houghP-refined": (hough_opencv_probabilistic, REFINED, REFINED_TOL, False),
    "split-merge": (split_and_merge, SplitMergeParams(), REFINED_TOL, True),
}
ALL = [hough_numpy_accumulator, hough_opencv_pointset, hough_opencv_raster]
ALL += [hough_opencv_probabilistic, split_and_merge]


def on_wall(line, rho, theta, tol=(0.1, 5.0)):
    """Whether ``line`` lies on the wall (rho, theta) within a loose tolerance."""
    return (
        abs(line.rho - rho) <= tol[0]
        and np.degrees(angle_difference_lines(line.theta, theta)) <= tol[1]
        and np.cos(line.theta - theta) > 0  # same side of the origin
    )


@pytest.mark.parametrize("scene", SCENES)
@pytest.mark.parametrize("case", CASES)
def test_finds_every_wall(case, scene):
    extract, params, (tol_rho, tol_deg), one_per_wall = CASES[case]
    points, wall_id, truth = SCENES[scene]
    lines = extract(points, params)
    counts = np.bincount(wall_id, minlength=len(truth))
    assert counts.max() >= 20
    for w, (rho, theta) in enumerate(truth):
        on = [line for line in lines if on_wall(line, rho, theta)]
        if counts[w] < 20:
            continue
        assert on, f"wall {w} ({counts[w]} points) not found"
        if one_per_wall:
            assert len(on) == 1, f"wall {w} found {len(on)} times: {on}"
        best = max(on, key=lambda line: line.n)
        assert abs(best.rho - rho) <= tol_rho, (best, rho)
        assert np.degrees(angle_difference_lines(best.theta, theta)) <= tol_deg, (best, theta)
    # No line off the walls.
    assert all(any(on_wall(line, *t) for t in truth) for line in lines)


@pytest.mark.parametrize("case", CASES)
def test_inliers_are_valid(case):
    extract, params, _, _ = CASES[case]
    points, _, _ = SCENES["room"]
    lines = extract(points, params)
    assert lines
    used = np.concatenate([line.inliers for line in lines])
    assert len(np.unique(used)) == len(used)  # no point on two lines
    for line in lines:
        assert line.n == len(line.inliers)
        assert np.all(np.diff(line.inliers) > 0)
        assert line.inliers[0] >= 0 and line.inliers[-1] < len(points)
        assert line.rho >= 0 and 0 <= line.theta < 2 * np.pi


@pytest.mark.parametrize("extract", ALL)
def test_pose_passes_through(extract):
    points, _, _ = SCENES["room"]
    lines = extract(points, pose=(0.0, 0.0, 0.0))  # the laser at its own origin
    assert lines
    for line in lines:
        assert line.dir == 1 and line.d == pytest.approx(line.rho)


@pytest.mark.parametrize("extract", ALL)
def test_too_few_points(extract):
    assert extract(np.zeros((0, 2))) == []
    assert extract(np.array([[1.0, 2.0]])) == []


@pytest.mark.parametrize("extract", ALL)
def test_bad_input(extract):
    points = SCENES["room"][0].copy()
    with pytest.raises(ValueError, match="shape"):
        extract(points[:, :1])
    with pytest.raises(ValueError, match="shape"):
        extract(points.ravel())
    points[5, 1] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        extract(points)


def test_accumulator_peak_at_true_cell():
    # 30 noise-free points on rho = 1.5 m, theta = 30 deg (on the 1 cm x 1 deg grid).
    rho, theta = 1.5, np.radians(30)
    n = np.array([np.cos(theta), np.sin(theta)])
    u = np.array([-n[1], n[0]])
    points = rho * n + np.linspace(-1.0, 1.0, 30)[:, None] * u
    acc, thetas, rhos = hough_accumulator(points, 0.01, np.radians(1.0), 8.0)
    assert acc.shape == (180, len(rhos)) and len(thetas) == 180
    assert acc.sum() == 30 * 180  # every point votes once per theta
    i, j = np.unravel_index(np.argmax(acc), acc.shape)
    assert acc[i, j] == 30
    assert thetas[i] == pytest.approx(theta)
    assert rhos[j] == pytest.approx(rho)


def test_pointset_peak_on_vertical_line():
    # Points on x = 2: the peak is the cell (rho, theta) = (2 m, 0), reported as is.
    points = np.column_stack([np.full(21, 2.0), np.linspace(-1.0, 1.0, 21)])
    lines = hough_opencv_pointset(points)
    assert len(lines) == 1
    assert lines[0].rho == pytest.approx(2.0, abs=0.005)  # half a 1 cm rho bin
    assert np.degrees(angle_difference_lines(lines[0].theta, 0.0)) < 0.5
    assert lines[0].n == 21


def test_params_are_validated():
    with pytest.raises(ValueError, match="rho_step"):
        ClassicalHoughParams(rho_step=0.0)
    with pytest.raises(ValueError, match="min_points"):
        ClassicalHoughParams(min_points=1)
    with pytest.raises(ValueError, match="split_dist"):
        SplitMergeParams(split_dist=-1.0)
