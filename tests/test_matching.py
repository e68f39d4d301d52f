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
