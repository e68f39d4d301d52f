"""Notebook 01's exercise checks: right answers accepted, wrong ones rejected in one line."""

import numpy as np

from fhslam.baselines import hough_accumulator
from fhslam.exercises.nb01 import (
    check_accumulator_cells,
    check_accumulator_reading,
    check_line_through,
    column_peaks,
    line_through_cases,
)
from fhslam.geometry import line_through


def right_line(p, q):
    d = q - p
    theta = np.arctan2(d[1], d[0]) + np.pi / 2
    rho = p[0] * np.cos(theta) + p[1] * np.sin(theta)
    if rho < 0:
        rho, theta = -rho, theta + np.pi
    return rho, theta % (2 * np.pi)


def cross_line(p, q):
    """Another correct way: the normal from the cross product, as a list."""
    n = np.array([p[1] - q[1], q[0] - p[0]]) / np.hypot(*(q - p))
    if n @ p < 0:
        n = -n
    return [float(n @ p), float(np.arctan2(n[1], n[0]) % (2 * np.pi))]


def todo(*args):
    raise NotImplementedError


def one_line(feedback):
    return "\n" not in str(feedback)


# --- 1.1 implement: the line through two points ------------------------------------------


def test_line_through_accepts_correct_variants():
    assert check_line_through(right_line)
    assert check_line_through(cross_line)
    assert "10 cases" in check_line_through(line_through).message  # the package's own
    # theta 2 pi instead of 0 (a wrap), and the other normal of the line through the origin
    wrapped = check_line_through(
        lambda p, q: (3.0, 2 * np.pi) if p[0] == q[0] == 3.0 else right_line(p, q)
    )
    assert wrapped

    def other_normal(p, q):
        rho, theta = right_line(p, q)
        return (0.0, (theta + np.pi) % (2 * np.pi)) if abs(rho) < 1e-12 else (rho, theta)

    assert check_line_through(other_normal)
    assert check_line_through(lambda p, q: np.array(right_line(p, q)))  # an array of two


def test_line_through_cases_cover_the_edges():
    cases = line_through_cases()
    lines = [line_through(p, q) for _, p, q in cases]
    thetas = np.degrees([t for _, t in lines])
    assert {90.0, 180.0, 270.0, 0.0} <= {round(t, 6) for t in thetas}  # axis-parallel normals
    assert any(abs(r) < 1e-12 for r, _ in lines)  # a line through the origin
    assert any(np.allclose(p1, q2) and np.allclose(q1, p2)
               for _, p1, q1 in cases for _, p2, q2 in cases)  # fmt: skip


def test_line_through_rejects_the_usual_mistakes_naming_the_case():
    def direction(p, q):  # theta of the line itself, not of its normal
        d = q - p
        theta = np.arctan2(d[1], d[0]) % (2 * np.pi)
        return p[0] * np.cos(theta) + p[1] * np.sin(theta), theta

    wrong = check_line_through(direction)
    assert wrong.status == "wrong" and "y = 2 m, points left to right" in wrong.message
    assert "normal OP" in wrong.message and one_line(wrong)

    def unnormalised(p, q):  # rho < 0 left as it is
        d = q - p
        theta = (np.arctan2(d[1], d[0]) + np.pi / 2) % (2 * np.pi)
        return p[0] * np.cos(theta) + p[1] * np.sin(theta), theta

    wrong = check_line_through(unnormalised)
    assert "right to left" in wrong.message and "(-ρ, θ + π)" in wrong.message

    def abs_rho(p, q):  # the sign of rho dropped, theta not turned
        rho, theta = unnormalised(p, q)
        return abs(rho), theta

    wrong = check_line_through(abs_rho)
    assert "right to left" in wrong.message and "180° off" in wrong.message

    degrees = check_line_through(
        lambda p, q: (right_line(p, q)[0], np.degrees(right_line(p, q)[1]))
    )
    assert "y = 2 m" in degrees.message and "radians" in degrees.message

    def unwrapped(p, q):  # theta + pi never brought back below 2 pi
        d = q - p
        theta = np.arctan2(d[1], d[0]) + np.pi / 2
        rho = p[0] * np.cos(theta) + p[1] * np.sin(theta)
        return (-rho, theta + np.pi) if rho < 0 else (rho, theta)

    wrong = check_line_through(unwrapped)
    assert "right to left" in wrong.message and "[0, 2π)" in wrong.message

    def norm_of_p(p, q):  # rho as the distance of a point from the origin
        return float(np.hypot(*p)), right_line(p, q)[1]

    wrong = check_line_through(norm_of_p)
    assert wrong.status == "wrong" and "y = 2 m, points left to right" in wrong.message
    assert "perpendicular to q - p" in wrong.message and one_line(wrong)


def test_line_through_reports_bad_returns_in_one_line():
    assert "returned None" in check_line_through(lambda p, q: None).message
    assert "two numbers" in check_line_through(lambda p, q: (1.0, 2.0, 3.0)).message
    assert "two numbers" in check_line_through(lambda p, q: "rho").message
    assert "not finite" in check_line_through(lambda p, q: (np.nan, 0.0)).message
    crash = check_line_through(lambda p, q: p[5])
    assert crash.status == "wrong" and "IndexError" in str(crash) and one_line(crash)


def test_line_through_template_is_not_attempted():
    assert check_line_through(todo).status == "not attempted"
    assert "my_line_through" in str(check_line_through(todo))


# --- 1.2 interpret: peaks in one column -----------------------------------------------------


def scan_like():
    """Points on three walls parallel to x (y = -2.2, 3.8, 5.8 m) and one across (x = 3.7 m)."""
    t = np.arange(-2.0, 2.0, 0.1)
    walls = [np.column_stack([t, np.full_like(t, y)]) for y in (-2.2, 3.8, 5.8)]
    walls.append(np.column_stack([np.full(20, 3.7), np.linspace(-1.5, 2.0, 20)]))
    return np.vstack([walls[0], walls[1], walls[2][:12], walls[3]])


def test_accumulator_reading_quotes_the_peaks_of_the_column():
    points = scan_like()
    acc, thetas, rhos = hough_accumulator(points, 0.02, np.radians(1.0), 8.0)
    right = check_accumulator_reading("b", acc, thetas, rhos)
    assert right and check_accumulator_reading(" (B) ", acc, thetas, rhos)
    assert "θ = 90° column" in right.message
    assert "-2.2 m (40 votes), 3.8 m (40 votes), 5.8 m (12 votes)" in right.message
    assert "ρ < 0" in right.message and one_line(right)
    even = check_accumulator_reading("c", acc, thetas, rhos)
    assert even.status == "wrong" and f"exactly {len(points)} votes" in even.message
    for wrong in ("a", "d"):
        feedback = check_accumulator_reading(wrong, acc, thetas, rhos)
        assert feedback.status == "wrong" and one_line(feedback)
    assert "one of" in check_accumulator_reading("e", acc, thetas, rhos).message
    assert check_accumulator_reading(2, acc, thetas, rhos).status == "wrong"
    assert check_accumulator_reading(..., acc, thetas, rhos).status == "not attempted"


def test_accumulator_reading_with_one_peak_and_dropped_votes():
    t = np.arange(0.0, 3.0, 0.1)
    points = np.vstack([np.column_stack([t, np.full_like(t, 2.0)]), [[7.9, 7.9]]])
    acc, thetas, rhos = hough_accumulator(points, 0.02, np.radians(1.0), 8.0)
    right = check_accumulator_reading("b", acc, thetas, rhos)
    assert right and "single peak (ρ = 2.0 m (30 votes))" in right.message
    assert "ρ < 0" not in right.message
    # the far point's rho exceeds 8 m at some theta: those columns hold one vote fewer
    assert "at most 31 votes" in check_accumulator_reading("c", acc, thetas, rhos).message


def test_column_peaks():
    column = np.zeros(11, int)
    column[[2, 3, 8]] = [10, 9, 4]
    rhos = np.arange(-5, 6) * 0.125  # exact in binary
    # cell 3 is 0.125 m from the stronger cell 2; cell 8 holds 4 >= 3 and >= 10 / 6 votes
    assert column_peaks(column, rhos) == [(-0.375, 10), (0.375, 4)]
    assert column_peaks(column, rhos, min_separation=0.1) == [(-0.375, 10), (-0.25, 9), (0.375, 4)]
    assert column_peaks(column, rhos, at_least=5) == [(-0.375, 10)]


# --- 1.3 predict: accumulator cells ---------------------------------------------------------


def test_accumulator_cells_is_exact_and_computed_from_the_grid():
    assert check_accumulator_cells(144180, 0.02, 1.0, 8.0)
    assert check_accumulator_cells(180 * 801.0, 0.02, 1.0, 8.0)
    assert check_accumulator_cells("144180", 0.02, 1.0, 8.0)
    ok = check_accumulator_cells(144180, 0.02, 1.0, 8.0, 181)
    assert "180 θ columns × 801 ρ rows" in ok.message and "32580 votes" in ok.message
    assert "23%" in ok.message
    assert check_accumulator_cells(90 * 101, 0.1, 2.0, 5.0)  # another grid, another answer
    assert check_accumulator_cells(144180, 0.1, 2.0, 5.0).status == "wrong"


def test_accumulator_cells_rejects_the_usual_mistakes():
    hints = {
        144000: "ρ = 0 has its own row",
        72000: "ρ is signed",
        72180: "ρ is signed",
        288360: "θ spans 0 to 180° only",
        360 * 401: "θ spans 0 to 180° only, and ρ is signed",
        981: "columns times rows",
        32580: "votes, not of cells",
        -12345.0: "count the θ columns",
    }
    for value, hint in hints.items():
        wrong = check_accumulator_cells(value, 0.02, 1.0, 8.0, 181)
        assert wrong.status == "wrong" and hint in wrong.message, (value, wrong)
        assert one_line(wrong)
    assert check_accumulator_cells(144181, 0.02, 1.0, 8.0).status == "wrong"  # exact
    # without the number of points, 32580 is just a wrong count
    assert "count the θ columns" in check_accumulator_cells(32580, 0.02, 1.0, 8.0).message
    assert check_accumulator_cells("many", 0.02, 1.0, 8.0).status == "wrong"
    assert check_accumulator_cells(float("nan"), 0.02, 1.0, 8.0).status == "wrong"
    assert check_accumulator_cells(..., 0.02, 1.0, 8.0).status == "not attempted"
