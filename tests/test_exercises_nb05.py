"""Notebook 05's exercise checks: right answers accepted, wrong ones rejected in one line."""

import numpy as np
import pytest

from fhslam.exercises.nb05 import (
    check_corridor_pose,
    check_heading_correction,
    check_merge_reading,
    heading_cases,
)
from fhslam.geometry import wrap_angle
from fhslam.lines import line_from_points, transform_lines


def wrap(d):
    return np.arctan2(np.sin(d), np.cos(d))


def right_heading(theta_observed, theta_reference, weights):
    return float(np.sum(weights * wrap(theta_reference - theta_observed)) / np.sum(weights))


def todo(*args):
    raise NotImplementedError


def one_line(feedback):
    return "\n" not in str(feedback)


# notebook 05's corridor: walls y = 0 and y = 2, robot at (5, 1, 0), odometry (5.4, 1.1, 0.02)
CORRIDOR = [
    line_from_points(np.column_stack([np.linspace(0, 10, 50), np.full(50, y)])) for y in (0.0, 2.0)
]
SEEN = transform_lines(CORRIDOR, (-5.0, -1.0, 0.0))
PAIRS = [(0, 0), (1, 1)]
PREDICTED = np.array([5.4, 1.1, 0.02])


def corridor(answer, predicted=PREDICTED):
    return check_corridor_pose(answer, SEEN, CORRIDOR, PAIRS, predicted)


def test_merge_reading():
    ok = check_merge_reading("b")
    assert ok and check_merge_reading(" (B) ") and "89.29°" in ok.message
    mean = check_merge_reading("a")
    assert mean.status == "wrong" and "= 90.21°" in mean.message and "89.37°" in mean.message
    projected = check_merge_reading("c")
    assert projected.status == "wrong" and "stay at 90.00°" in projected.message
    assert one_line(mean) and one_line(projected)
    assert "one of" in check_merge_reading("d").message
    assert check_merge_reading(-12345.0).status == "wrong"
    assert check_merge_reading(...).status == "not attempted"


def test_corridor_pose_keeps_the_odometry_along_the_corridor():
    ok = corridor((5.4, 1.0, 0.0))
    assert ok and "calibrated (5.40, 1.00, 0.000)" in ok.message
    assert "moved 0.0 cm along" in ok.message and "(False, True)" in ok.message
    assert corridor([5.42, 0.98, -0.003])  # within 3 cm and 0.005 rad, a list
    assert corridor(np.array([5.4, 1.0, 2 * np.pi]))  # the same heading, another turn


def test_corridor_pose_names_the_direction_that_is_wrong():
    full = corridor((5.0, 1.0, 0.0))  # the true pose: "the calibration fixes everything"
    assert full.status == "wrong" and "along the corridor" in full.message
    assert "parallel walls" in full.message and one_line(full)
    across = corridor((5.4, 1.1, 0.0))  # the odometry's y kept
    assert across.status == "wrong" and "across the corridor" in across.message
    assert "distances to the two walls" in across.message
    heading = corridor((5.4, 1.0, 0.02))  # the odometry's heading kept
    assert heading.status == "wrong" and "walls' direction" in heading.message
    nothing = corridor(PREDICTED)  # nothing corrected
    assert nothing.status == "wrong"
    for wrong in (full, across, heading, nothing):  # a prediction: the pose is not given away
        assert "calibrated (" not in wrong.message and "5.40" not in wrong.message, wrong
        assert "40 cm" not in wrong.message and "10 cm" not in wrong.message, wrong
    # another odometry, another answer: 30 cm back along the corridor is kept
    assert corridor((4.7, 1.0, 0.0), np.array([4.7, 0.95, -0.01]))
    assert corridor((5.4, 1.0, 0.0), np.array([4.7, 0.95, -0.01])).status == "wrong"


@pytest.mark.parametrize("answer", [-12345.0, "5.4, 1, 0", (5.4, 1.0), (5.4, 1.0, float("nan"))])
def test_corridor_pose_wants_three_numbers(answer):
    wrong = corridor(answer)
    assert wrong.status == "wrong" and "three numbers" in wrong.message and one_line(wrong)


def test_corridor_pose_template_is_not_attempted():
    assert corridor(...).status == "not attempted" and "my_pose" in corridor(...).message


def test_heading_correction_accepts_any_wrap():
    assert check_heading_correction(right_heading)
    assert check_heading_correction(
        lambda o, r, w: np.average(wrap_angle(r - o), weights=w)  # a numpy float
    )
    assert check_heading_correction(
        lambda o, r, w: np.sum(w * np.angle(np.exp(1j * (r - o)))) / np.sum(w)
    )
    assert "all 5 cases" in check_heading_correction(right_heading).message


def test_heading_cases_cross_the_wrap_and_stay_far_from_pi():
    crossing = 0
    for _, obs, ref, w in heading_cases():
        d = ref - obs
        assert np.all(np.abs(np.abs(wrap(d)) - np.pi) > 2.5)  # no knife edge at ±pi
        crossing += int(np.any(np.abs(d) > np.pi))
        assert len(obs) == len(ref) == len(w) and np.all(w > 0)
    assert crossing >= 3


def test_heading_correction_names_each_usual_mistake():
    def check(fn):
        feedback = check_heading_correction(fn)
        assert feedback.status == "wrong" and one_line(feedback), feedback
        return feedback.message

    no_wrap = check(lambda o, r, w: np.sum(w * (r - o)) / np.sum(w))
    assert "across ±pi" in no_wrap and "wrap each difference to (-pi, pi]" in no_wrap
    sign = check(lambda o, r, w: right_heading(r, o, w))
    assert "0.25 rad" in sign and "the sign" in sign and "wrap" not in sign
    plain = check(lambda o, r, w: np.mean(wrap(r - o)))
    assert "supports 10, 30 and 60" in plain and "weight each difference" in plain
    degrees = check(lambda o, r, w: np.degrees(right_heading(o, r, w)))
    assert "radians, not degrees" in degrees
    mod = check(lambda o, r, w: np.sum(w * np.mod(r - o, 2 * np.pi)) / np.sum(w))
    assert "not to [0, 2 pi)" in mod
    late = check(lambda o, r, w: wrap(np.sum(w * (r - o)) / np.sum(w)))
    assert "across 0 and 2 pi" in late and "not the average" in late
    count = check(lambda o, r, w: np.sum(w * wrap(r - o)) / len(w))
    assert "sum of the weights" in count
    other = check(lambda o, r, w: right_heading(o, r, w) + 0.01)
    assert "sum(w * wrap(reference - observed)) / sum(w)" in other


def test_heading_correction_wants_one_number_and_reports_a_crash():
    assert "returned None" in check_heading_correction(lambda o, r, w: None).message
    per_pair = check_heading_correction(lambda o, r, w: wrap(r - o))
    assert per_pair.status == "wrong" and "one number" in per_pair.message
    text = check_heading_correction(lambda o, r, w: "a quarter")
    assert text.status == "wrong" and "one number" in text.message
    crash = check_heading_correction(lambda o, r, w: o[10])
    assert crash.status == "wrong" and "IndexError" in str(crash) and one_line(crash)


def test_heading_correction_template_is_not_attempted():
    assert check_heading_correction(todo).status == "not attempted"
    assert "my_heading_correction" in str(check_heading_correction(todo))
    assert check_heading_correction(...).status == "not attempted"
