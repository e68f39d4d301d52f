"""Loop 2: the four similarity conditions, matching, and merging (paper Figs. 7-11)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fhslam.lines import line_from_points
from fhslam.matching import MatchParams, match_lines, merge, similar, similarity


def seg(x0, y0, x1, y1, n=20):
    """A line fitted to n points evenly spaced from (x0, y0) to (x1, y1)."""
    t = np.linspace(0, 1, n)[:, None]
    return line_from_points(np.array([x0, y0]) + t * np.array([x1 - x0, y1 - y0]))


ROBOT = (0.0, 0.0, 0.0)


def test_same_wall_seen_twice_is_similar():
    a, b = seg(0, 2, 3, 2), seg(2, 2.03, 5, 2.02)
    s = similarity(a, b, pose=ROBOT)
    assert s.similar and s.same_direction
    assert s.angle_deg == pytest.approx(np.degrees(np.arctan(0.01 / 3)), abs=1e-6)
    assert s.overlap == pytest.approx(1.0, abs=0.01)  # common part from x=2 to x=3
    # Largest endpoint distance: a's start (0, 2) to b's line, which is at y = 2.03 + 2 * 0.01/3.
    assert s.distance == pytest.approx((0.03 + 0.02 / 3) * np.cos(np.arctan(0.01 / 3)), abs=1e-9)


def test_each_condition_can_fail_alone():
    ref = seg(0, 2, 3, 2)
    assert not similarity(ref, seg(0, 2.5, 3, 2.5), pose=ROBOT).distance_ok  # (c) 0.5 m off
    assert not similarity(ref, seg(4, 2, 6, 2), pose=ROBOT).overlap_ok  # (d) 1 m gap
    assert not similarity(ref, seg(0, 1.6, 3, 2.4), pose=ROBOT).angle_ok  # (b) 15°
    # (a): the robot between two lines 2 cm apart sees them from opposite sides.
    s = similarity(seg(0, 2, 3, 2), seg(0, 2.02, 3, 2.02), pose=(1.0, 2.01, 0.0))
    assert not s.same_direction and s.angle_ok and s.distance_ok and s.overlap_ok


def test_negative_min_overlap_accepts_a_gap_on_the_same_line():
    a, b = seg(0, 2, 3, 2), seg(3.4, 2, 6, 2)
    assert not similar(a, b, pose=ROBOT)
    assert similar(a, b, MatchParams(min_overlap=-0.5), pose=ROBOT)


def test_direction_needs_a_pose_or_dirs():
    with pytest.raises(ValueError, match="dir"):
        similarity(seg(0, 2, 3, 2), seg(0, 2, 3, 2))


def test_match_lines_picks_the_closest_similar_reference():
    refs = [seg(0, 2, 5, 2), seg(0, 2.1, 5, 2.1), seg(6, 0, 6, 4)]
    new = [seg(1, 2.08, 3, 2.08), seg(6.02, 1, 6.02, 2), seg(0, -3, 2, -3)]
    assert match_lines(new, refs, pose=ROBOT).tolist() == [1, 2, -1]
    assert match_lines(new, [], pose=ROBOT).tolist() == [-1, -1, -1]
    assert match_lines([], refs, pose=ROBOT).tolist() == []


def test_merge_extends_the_reference_to_the_union_fig11():
    ref, new = seg(0, 2, 3, 2, n=30), seg(2, 2, 6, 2, n=40)
    m = merge(ref, new)
    assert m.rho == pytest.approx(2.0, abs=1e-9) and m.theta == pytest.approx(np.pi / 2)
    np.testing.assert_allclose([m.sp, m.ep], [[0, 2], [6, 2]], atol=1e-9)  # from E to C
    assert m.n == 70 and m.length == pytest.approx(6.0)


def test_merge_weights_by_support():
    heavy, light = seg(0, 2, 4, 2, n=400), seg(0, 2.1, 4, 2.1, n=4)
    assert merge(heavy, light).rho == pytest.approx(2.0 + 0.1 * 4 / 404, abs=1e-9)


# --------------------------------------------------------------------------- properties

coord = st.floats(-10, 10)


@st.composite
def segments(draw):
    x0, y0 = draw(coord), draw(coord)
    ang, length = draw(st.floats(0, 2 * np.pi)), draw(st.floats(0.3, 6))
    return seg(x0, y0, x0 + length * np.cos(ang), y0 + length * np.sin(ang))


@settings(max_examples=200, deadline=None, derandomize=True)
@given(a=segments(), b=segments(), robot=st.tuples(coord, coord, st.just(0.0)))
def test_similarity_is_symmetric(a, b, robot):
    sab, sba = similarity(a, b, pose=robot), similarity(b, a, pose=robot)
    assert sab.similar == sba.similar
    assert sab.angle_deg == pytest.approx(sba.angle_deg, abs=1e-9)
    assert sab.distance == pytest.approx(sba.distance, abs=1e-9)
    assert sab.overlap == pytest.approx(sba.overlap, abs=1e-9)


@st.composite
def collinear_pieces(draw):
    """Three segments on one line (ρ, θ), each given by its extent along the line."""
    rho, theta = draw(st.floats(0.1, 10)), draw(st.floats(0, 2 * np.pi))
    n, u = np.array([np.cos(theta), np.sin(theta)]), np.array([-np.sin(theta), np.cos(theta)])
    pieces = []
    for _ in range(3):
        t0 = draw(st.floats(-5, 5))
        t1 = t0 + draw(st.floats(0.3, 4))
        p, q = rho * n + t0 * u, rho * n + t1 * u
        pieces.append(seg(*p, *q, n=draw(st.integers(5, 50))))
    return pieces


@settings(max_examples=100, deadline=None, derandomize=True)
@given(pieces=collinear_pieces())
def test_merging_collinear_segments_is_order_independent_and_idempotent(pieces):
    a, b, c = pieces
    m1, m2 = merge(merge(a, b), c), merge(merge(c, a), b)
    assert m1.rho == pytest.approx(m2.rho, abs=1e-6)
    assert np.cos(m1.theta - m2.theta) == pytest.approx(1.0, abs=1e-9)
    ends1 = sorted(map(tuple, np.round([m1.sp, m1.ep], 6)))
    ends2 = sorted(map(tuple, np.round([m2.sp, m2.ep], 6)))
    np.testing.assert_allclose(ends1, ends2, atol=1e-5)
    again = merge(m1, b)  # b is already covered: only n changes
    assert again.rho == pytest.approx(m1.rho, abs=1e-6)
    np.testing.assert_allclose([again.sp, again.ep], [m1.sp, m1.ep], atol=1e-6)
    assert again.n == m1.n + b.n


# --------------------------------------------------------------------- frame invariance


def wall_y0(x0, x1, rho, theta, n=20):
    """A segment of the wall y ≈ 0 from x0 to x1, as the line (rho, theta) forced on it."""
    pts = np.column_stack([np.linspace(x0, x1, n), np.zeros(n)])
    return line_from_points(pts, rho_theta=(rho, theta))


def test_wall_through_the_origin_with_opposite_normals_is_similar_from_the_same_side():
    """Two observations of the wall y ≈ 0 whose normals point opposite ways (theta 90° and
    270°, rho ≈ 0): the paper's dir differs from the same side, yet the robot sees both
    from the same side, so condition (a) holds; from opposite sides it does not."""
    up, down = wall_y0(1, 4, 0.002, np.pi / 2), wall_y0(2, 5, 0.001, 3 * np.pi / 2)
    above, below = (2.5, 1.5, 0.0), (2.5, -1.5, np.pi)
    assert up.observed_from(above).dir == -down.observed_from(above).dir  # plain dir differs
    for pose in (above, below):
        s = similarity(up, down, pose=pose)
        assert s.same_direction and s.similar, s
        assert similarity(down, up, pose=pose).similar
    # With each line's own dir: seen from the same side or from opposite sides.
    assert similar(up.observed_from(above), down.observed_from(above))
    assert similar(up.observed_from(below), down.observed_from(below))
    s = similarity(up.observed_from(above), down.observed_from(below))
    assert not s.same_direction and not s.similar
    assert s.angle_ok and s.distance_ok and s.overlap_ok  # (a) alone says no
    # The robot between the two (y = 0.002 and y = -0.001): on opposite sides.
    assert not similarity(up, down, pose=(2.5, 0.0005, 0.0)).same_direction
    # Lines both with normal 90°, robot on opposite sides of them: still not similar.
    s = similarity(wall_y0(1, 4, 0.02, np.pi / 2), up, pose=(2.5, 0.01, 0.0))
    assert not s.same_direction


def _scene(rng, k=12):
    """Reference segments, and new ones that are noisy re-observations of them (some with
    the opposite normal) or random; all within 4 m of the origin."""
    refs, new = [], []
    for _ in range(k):
        p, ang, length = rng.uniform(-4, 4, 2), rng.uniform(0, 2 * np.pi), rng.uniform(0.5, 3)
        d = np.array([np.cos(ang), np.sin(ang)])
        refs.append(seg(*p, *(p + length * d)))
        q = p + rng.uniform(-0.5, 0.5) * d + rng.normal(0, 0.03, 2)
        e = ang + rng.normal(0, np.radians(2))
        a, b = q, q + length * np.array([np.cos(e), np.sin(e)])
        new.append(seg(*a, *b) if rng.random() < 0.5 else seg(*b, *a))
    for _ in range(k // 3):
        p, q = rng.uniform(-4, 4, 2), rng.uniform(-4, 4, 2)
        new.append(seg(*p, *q))
    return new, refs


def test_similarity_matrix_is_invariant_under_a_rigid_motion():
    """Lines and robot moved together: the same conditions, the same numbers. Half the
    motions put one of the lines through the new origin (rho = 0 there)."""
    from fhslam.geometry import compose, inverse
    from fhslam.lines import transform_lines
    from fhslam.matching import similarity_matrix

    rng = np.random.default_rng(2024)
    n_similar = n_flipped = 0
    for trial in range(200):
        new, refs = _scene(rng)
        pose = np.array([*rng.uniform(-3, 3, 2), rng.uniform(-np.pi, np.pi)])
        m0 = similarity_matrix(new, refs, pose=pose)
        if trial % 2:  # the new origin on a reference line
            ln = refs[rng.integers(len(refs))]
            on = ln.sp + rng.uniform(0, 1) * (ln.ep - ln.sp)
            motion = inverse([*on, rng.uniform(-np.pi, np.pi)])
        else:
            motion = np.array([*rng.uniform(-20, 20, 2), rng.uniform(-np.pi, np.pi)])
        new_m, refs_m = transform_lines(new, motion), transform_lines(refs, motion)
        m1 = similarity_matrix(new_m, refs_m, pose=compose(motion, pose))
        for key in ("same_direction", "angle_ok", "distance_ok", "overlap_ok", "similar"):
            assert np.array_equal(m0[key], m1[key]), (trial, key)
        for key in ("distance", "overlap"):
            np.testing.assert_allclose(m1[key], m0[key], rtol=0, atol=1e-9)
        # arccos near 1 turns a last-bit difference of the cosine into ~1e-8 rad.
        np.testing.assert_allclose(m1["angle_deg"], m0["angle_deg"], rtol=0, atol=1e-5)
        n_similar += int(m0["similar"].sum())
        flipped = np.cos(np.subtract.outer([x.theta for x in new_m], [r.theta for r in refs_m]))
        n_flipped += int((m1["similar"] & (flipped < 0)).sum())
    assert n_similar >= 1000  # most re-observations match: the test is not vacuous
    assert n_flipped >= 20  # ... some of them with normals opposite to the reference's
