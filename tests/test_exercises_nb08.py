"""Notebook 08's exercise checks: right answers accepted, wrong ones rejected in one line."""

from collections import namedtuple

import numpy as np
import pytest

from fhslam.exercises.nb08 import (
    check_paper_vs_odometry,
    check_relation_error,
    check_span_reading,
    relation_cases,
)
from fhslam.geometry import compose, inverse, relative
from fhslam.metrics import relations_error

Run = namedtuple("Run", "timestamps poses")


def todo(*args):
    raise NotImplementedError


def one_line(feedback):
    return "\n" not in str(feedback)


def turn(theta, v):
    c, s = np.cos(theta), np.sin(theta)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def right_error(p1, p2, r):
    return float(np.hypot(*(turn(-p1[2], p2[:2] - p1[:2]) - r[:2])))


def se2_error(p1, p2, r):  # the whole of Kümmerle's δ ⊖ δ*, then its translation
    e = relative(r, relative(p1, p2))
    return np.hypot(e[0], e[1])  # a numpy float


# A small log: 40 poses 1 s apart on a turning path, relations between some of them whose
# measured motions are the true ones plus known errors; two runs, one 3 times as far off.
STAMPS = np.arange(40.0) + 1e9
TRUTH = np.column_stack(
    [np.cos(STAMPS - 1e9) * 5, np.sin((STAMPS - 1e9) * 0.7) * 3, 0.3 * (STAMPS - 1e9)]
)
PAIRS = np.array([[0, 1], [3, 9], [5, 30], [10, 39], [20, 21], [2, 38]])
T1, T2 = STAMPS[PAIRS[:, 0]], STAMPS[PAIRS[:, 1]]
REL = relative(TRUTH[PAIRS[:, 0]], TRUTH[PAIRS[:, 1]])
DRIFT = np.column_stack([np.linspace(0, 2, 40), np.linspace(0, -1, 40), np.linspace(0, 0.2, 40)])
GOOD = Run(STAMPS, TRUTH + DRIFT / 3)
BAD = Run(STAMPS, TRUTH + DRIFT)


def mean_error(run):
    return relations_error(run.timestamps, run.poses, T1, T2, REL).trans_mean


# ------------------------------------------------------------------------------ 8.1


def test_paper_vs_odometry_is_decided_from_the_runs():
    ratio = mean_error(BAD) / mean_error(GOOD)
    assert 2 < ratio < 5  # "b": 1 to 10 times smaller
    ok = check_paper_vs_odometry("b", BAD, GOOD, T1, T2, REL)
    assert ok and f"= {ratio:.1f}" in ok.message and "ever pulls it back" in ok.message
    assert check_paper_vs_odometry(" (B) ", BAD, GOOD, T1, T2, REL)
    low = check_paper_vs_odometry("a", BAD, GOOD, T1, T2, REL)
    assert low.status == "wrong" and "heading" in low.message and one_line(low)
    high = check_paper_vs_odometry("d", BAD, GOOD, T1, T2, REL)
    assert high.status == "wrong" and "loop closure" in high.message and one_line(high)
    near = check_paper_vs_odometry("c", BAD, GOOD, T1, T2, REL)
    assert near.status == "wrong"
    for wrong in (low, high, near):  # a prediction: the numbers are not given away
        assert f"{ratio:.1f}" not in wrong.message and " m / " not in wrong.message, wrong
    # other runs, other right answers: worse than the odometry is "a", exact is "d"
    worse = check_paper_vs_odometry("a", GOOD, BAD, T1, T2, REL)
    assert worse and "more slowly" not in worse.message
    assert check_paper_vs_odometry("d", BAD, Run(STAMPS, TRUTH), T1, T2, REL)
    assert check_paper_vs_odometry(2.7, BAD, GOOD, T1, T2, REL).status == "wrong"
    assert check_paper_vs_odometry(-12345.0, BAD, GOOD, T1, T2, REL).status == "wrong"
    assert check_paper_vs_odometry(..., BAD, GOOD, T1, T2, REL).status == "not attempted"


# ------------------------------------------------------------------------------ 8.2


def test_relation_error_accepts_correct_variants_and_gives_the_run():
    assert check_relation_error(right_error)
    assert check_relation_error(se2_error)  # numpy float, through the full SE(2) error
    ok = check_relation_error(right_error, BAD, T1, T2, REL)
    assert ok and f"all 6 relations of this notebook's run: mean {mean_error(BAD):.3f} m" in (
        ok.message
    )
    assert "5 cases" in ok.message


@pytest.mark.parametrize(
    ("mistake", "case", "hint"),
    [
        (
            lambda p1, p2, r: np.hypot(*((p2 - p1)[:2] - r[:2])),
            "facing north",
            "world-frame difference",
        ),
        (
            lambda p1, p2, r: np.hypot(*(turn(p1[2], p2[:2] - p1[:2]) - r[:2])),
            "facing north",
            "by +theta1",
        ),
        (
            lambda p1, p2, r: np.hypot(*(relative(p2, p1)[:2] - r[:2])),
            "facing north",
            "from pose 2 back to pose 1",
        ),
        (
            lambda p1, p2, r: abs(np.hypot(*(p2 - p1)[:2]) - np.hypot(*r[:2])),
            "as far, elsewhere",
            "lengths of the two motions",
        ),
        (
            lambda p1, p2, r: np.linalg.norm(relative(r, relative(p1, p2))),
            "only the heading",
            "heading error (radians)",
        ),
        (
            lambda p1, p2, r: np.hypot(*compose(relative(p1, p2), inverse(r))[:2]),
            "only the heading",
            "Cartographer",
        ),
        (lambda p1, p2, r: right_error(p1, p2, r) ** 2, "as far, elsewhere", "squared error"),
        (lambda p1, p2, r: 100 * right_error(p1, p2, r), "as far, elsewhere", "centimetres"),
    ],
    ids=[
        "world",
        "plus-theta",
        "backwards",
        "lengths",
        "with-theta",
        "cartographer",
        "squared",
        "cm",
    ],
)
def test_relation_error_rejects_the_usual_mistakes_naming_the_case(mistake, case, hint):
    feedback = check_relation_error(mistake)
    assert feedback.status == "wrong" and one_line(feedback)
    assert case in feedback.message and hint in feedback.message, feedback.message


def test_relation_error_other_wrong_answers():
    sign = check_relation_error(lambda p1, p2, r: -right_error(p1, p2, r))
    assert sign.status == "wrong" and "as far, elsewhere" in sign.message
    assert "estimate = pose 1's rotation transposed" in sign.message  # no known mistake
    vector = check_relation_error(lambda p1, p2, r: turn(-p1[2], p2[:2] - p1[:2]) - r[:2])
    assert "one number" in vector.message and "(2,)" in vector.message
    assert "returned None" in check_relation_error(lambda *a: None).message
    assert "returned nan" in check_relation_error(lambda *a: float("nan")).message
    crash = check_relation_error(lambda p1, p2, r: p1[5])
    assert crash.status == "wrong" and "IndexError" in str(crash) and one_line(crash)
    # right on the small cases, wrong on the run's relations (a time-dependent error)
    calls = []

    def late(p1, p2, r):
        calls.append(1)
        return right_error(p1, p2, r) + (0.5 if len(calls) > len(relation_cases()) + 2 else 0)

    run = check_relation_error(late, BAD, T1, T2, REL)
    assert run.status == "wrong" and one_line(run)
    assert "this notebook's run, relation 2 (25.00 s apart)" in run.message


def test_relation_error_cases_are_far_from_the_mistakes():
    """Each case's right value is 0 or clearly apart from what a mistake gives."""
    for what, p1, p2, r in relation_cases():
        want = relations_error([0, 1], np.array([p1, p2]), [0], [1], [r]).trans_mean
        assert want == pytest.approx(right_error(p1, p2, r), abs=1e-12), what


def test_relation_error_template_is_not_attempted():
    feedback = check_relation_error(todo)
    assert feedback.status == "not attempted" and "my_relation_error" in str(feedback)
    assert check_relation_error(todo, BAD, T1, T2, REL).status == "not attempted"


# ------------------------------------------------------------------------------ 8.3


def test_span_reading():
    assert check_span_reading("b") and check_span_reading("(B)")
    assert "no loop closure" in check_span_reading("b").message
    for wrong in ("a", "c", "d"):
        feedback = check_span_reading(wrong)
        assert feedback.status == "wrong" and one_line(feedback)
    assert "heading" in check_span_reading("a").message
    assert "every method" in check_span_reading("c").message
    assert "over a minute apart" in check_span_reading("d").message
    assert "one of" in check_span_reading("e").message
    assert check_span_reading(-12345.0).status == "wrong"
    assert check_span_reading(...).status == "not attempted"
    assert "my_reading" in check_span_reading(...).message
