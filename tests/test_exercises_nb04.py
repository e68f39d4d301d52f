"""Notebook 04's exercise checks: right answers accepted, wrong ones rejected in one line."""

import math

import numpy as np
import pytest

from fhslam.exercises.nb04 import (
    check_failing_conditions,
    check_observation,
    check_vanished_lines_reading,
    observation_cases,
)
from fhslam.figures import line_attributes_example, similarity_examples
from fhslam.lines import line_from_points
from fhslam.matching import MatchParams


def s(rho, theta, pose):
    return rho - pose[0] * np.cos(theta) - pose[1] * np.sin(theta)


def right_observation(rho, theta, pose):
    return int(np.sign(s(rho, theta, pose))), abs(s(rho, theta, pose))


def todo(*args):
    raise NotImplementedError


def one_line(feedback):
    return "\n" not in str(feedback)


def test_observation_cases_are_exact_or_far_from_the_knife_edge():
    cases = observation_cases()
    on_line = [c for c in cases if s(c[1], c[2], c[3]) == 0.0]
    assert len(on_line) == 2 and all("exactly on the line" in c[0] for c in on_line)
    assert all(abs(s(*c[1:])) > 0.99 for c in cases if c not in on_line)  # 1 m or more
    assert all(c[3][2] != 0 for c in cases)  # a heading that would change a wrong answer


def test_observation_accepts_the_definition_and_its_variants():
    assert check_observation(right_observation)
    line, pose = line_attributes_example()
    ok = check_observation(right_observation, line, pose)
    assert ok and "dir = +1, d = 1.555 m" in ok.message and "8 cases" in ok.message

    def with_math(rho, theta, pose):  # math functions, floats, dot product
        t = rho - (pose[0] * math.cos(theta) + pose[1] * math.sin(theta))
        return float(np.sign(t)), math.fabs(t)

    def as_array(rho, theta, pose):
        return np.array(right_observation(rho, theta, pose))

    def by_foot(rho, theta, pose):  # d as the distance to the foot of the perpendicular
        n = np.array([np.cos(theta), np.sin(theta)])
        t = rho - np.dot(pose[:2], n)
        return np.sign(t), float(np.hypot(*(t * n)))

    for variant in (with_math, as_array, by_foot):
        assert check_observation(variant, line, pose), variant.__name__


def test_observation_rejects_the_usual_mistakes_naming_the_case():
    def no_abs(r, t, p):
        return np.sign(s(r, t, p)), s(r, t, p)

    f = check_observation(no_abs)
    assert f.status == "wrong" and "robot beyond it" in f.message and "|ρ" in f.message

    f = check_observation(lambda r, t, p: (-np.sign(s(r, t, p)), abs(s(r, t, p))))
    assert f.status == "wrong" and "origin's side" in f.message and "wrong sign" in f.message

    f = check_observation(lambda r, t, p: right_observation(r, np.radians(t), p))
    assert "θ = π/2" in f.message and "radians already" in f.message

    for wrong in (t_minus_phi, phi_for_theta):
        f = check_observation(wrong)
        assert f.status == "wrong" and "east of the origin" in f.message
        assert "heading φ plays no part" in f.message

    f = check_observation(lambda r, t, p: (math.copysign(1, s(r, t, p)), abs(s(r, t, p))))
    assert "exactly on the line" in f.message and "dir = 0," in f.message
    assert "np.sign(0.0) is 0" in f.message

    f = check_observation(lambda r, t, p: right_observation(r, t, p)[::-1])
    assert "order (dir, d)" in f.message

    swapped = check_observation(lambda r, t, p: right_observation(r, t, (p[1], p[0], p[2])))
    assert "x goes with cos θ" in swapped.message and one_line(swapped)


def t_minus_phi(rho, theta, pose):
    return right_observation(rho, theta - pose[2], pose)


def phi_for_theta(rho, theta, pose):
    return right_observation(rho, pose[2], pose)


def test_observation_bad_returns_are_one_line():
    assert "returned None" in check_observation(lambda *a, **k: None).message
    assert "pair of two numbers" in check_observation(lambda r, t, p: (1, 2, 3)).message
    assert "pair of two numbers" in check_observation(lambda r, t, p: 1.0).message
    crash = check_observation(lambda r, t, p: p[7])
    assert crash.status == "wrong" and "IndexError" in str(crash) and one_line(crash)


def test_observation_template_is_not_attempted():
    assert check_observation(todo).status == "not attempted"
    assert "my_observation" in str(check_observation(todo))


@pytest.fixture(scope="module")
def thin_wall():
    """The notebook's pair: the two faces of a 10 cm wall, each seen from its own side."""
    x = np.linspace(0, 3, 31)
    south = line_from_points(np.column_stack([x, np.full(31, 3.0)]), pose=(1.5, 1.0, 1.57))
    north = line_from_points(np.column_stack([x, np.full(31, 3.1)]), pose=(1.5, 5.0, -1.57))
    return south, north


def test_failing_conditions_accepts_the_computed_set_in_any_spelling(thin_wall):
    for answer in ("a", "(a)", " A ", ["a"], ("(a)",)):
        assert check_failing_conditions(answer, *thin_wall), answer
    ok = check_failing_conditions("a", *thin_wall)
    assert "fails (a): not similar" in ok.message and "0.100 m" in ok.message
    assert check_failing_conditions("a", *thin_wall[::-1])  # symmetric


def test_failing_conditions_hints_without_giving_the_answer_away(thin_wall):
    for answer in ("none", "c", "a and c", "abcd"):
        f = check_failing_conditions(answer, *thin_wall)
        assert f.status == "wrong" and f.message.startswith("not the conditions that fail")
        assert "same side" in f.message and "5°" in f.message and "0.15 m" in f.message
        assert "fails" not in f.message.replace("that fail", "") and "holds" not in f.message
        assert "0.100" not in f.message and "0.0°" not in f.message and one_line(f)
    for bad in (-12345.0, "e", "", 3, ["a", 1]):
        f = check_failing_conditions(bad, *thin_wall)
        assert f.status == "wrong" and 'or "none"' in f.message and one_line(f)
    assert check_failing_conditions(..., *thin_wall).status == "not attempted"


def test_failing_conditions_on_the_papers_figures():
    """The right answer comes from fhslam.matching.similarity, here the paper's captions."""
    expected = {7: "none", 8: "c", 9: "bd", 10: "b, c"}
    for fig, (ref, new, pose) in similarity_examples().items():
        assert check_failing_conditions(expected[fig], ref, new, pose=pose), fig
    ref, new, pose = similarity_examples()[9]
    assert "gap of 0.20 m" in check_failing_conditions("bd", ref, new, pose=pose).message
    assert "gap" not in check_failing_conditions("b", ref, new, pose=pose).message
    # other thresholds, another answer: Fig. 9 at 15° fails (d) only
    assert check_failing_conditions("d", ref, new, MatchParams(max_angle_deg=15.0), pose)


def test_vanished_lines_reading():
    assert check_vanished_lines_reading("b") and check_vanished_lines_reading("(B)")
    assert "doorway" in check_vanished_lines_reading("b").message
    for wrong in ("a", "c", "d"):
        feedback = check_vanished_lines_reading(wrong)
        assert feedback.status == "wrong" and one_line(feedback)
    assert "0.40 m" in check_vanished_lines_reading("a").message
    assert "one of" in check_vanished_lines_reading(-12345.0).message
    assert check_vanished_lines_reading(...).status == "not attempted"


def test_vanished_lines_numbers_are_the_notebooks():
    """The numbers the explanations quote, from the notebook's scans 200 and 205."""
    from fhslam.extraction import extract_lines
    from fhslam.figures import paper_log
    from fhslam.lines import transform_lines
    from fhslam.matching import similarity_matrix

    log = paper_log(0)

    def world_lines(k):
        return transform_lines(extract_lines(log.scan(k).points()[0]), log.truth[k])

    first, second = world_lines(200), world_lines(205)
    m = similarity_matrix(second, first, pose=log.truth[205])
    assert m["similar"].any(axis=1).all()  # every line of scan 205 has a partner
    assert round(100 * m["distance"][m["similar"]].max(), 1) == 1.3  # "at most 1.3 cm"
    assert round(float(np.hypot(*(log.truth[205, :2] - log.truth[200, :2]))), 2) == 0.40
    lost = np.flatnonzero(~m["similar"].any(axis=0)).tolist()
    assert lost == [0, 7]
    for j in lost:  # the wall y = 6 m, the robot about 1 cm from its line at scan 205
        assert abs(first[j].midpoint[1] - 6.0) < 0.05
        assert first[j].observed_from(log.truth[205]).d < 0.02
        assert abs(first[j].observed_from(log.truth[200]).d - 0.39) < 0.02
    # no line of scan 205 anywhere near that wall; line 0 of scan 205 is the wall x = 6 m
    assert all(m["distance"][:, j].min() > 2.5 for j in lost)
    assert abs(second[0].midpoint[0] - 6.0) < 0.05 and np.argmax(m["similar"][0]) == 1
