"""Exercises of notebook 05, merging lines (paper Fig. 11) and self-calibration (paper,
"Self calibration and map building")."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from fhslam.calibration import calibrate_pose
from fhslam.exercises import Feedback, Wrong, call, check_choice, exercise
from fhslam.geometry import wrap_angle
from fhslam.lines import Line

__all__ = [
    "check_corridor_pose",
    "check_heading_correction",
    "check_merge_reading",
    "heading_cases",
]


def check_merge_reading(answer: Any) -> Feedback:
    """Exercise 5.1 (interpret): why the line merged from EF (θ = 90.00°) and AB (90.69°)
    of Fig. 11 comes out at 89.37°, outside both. The numbers in the explanations are
    computed here with :func:`fhslam.matching.merge` on :func:`fhslam.figures.merging_example`."""
    from fhslam.figures.scenes import merging_example
    from fhslam.lines import line_from_points
    from fhslam.matching import merge

    ef, ab = merging_example()
    deg = np.degrees
    merged = deg(merge(ef, ab).theta)
    mean = deg((ef.n * ef.theta + ab.n * ab.theta) / (ef.n + ab.n))
    height = 0.5 * (ab.sp[1] + ab.ep[1])
    flat_ab = line_from_points(np.linspace((ab.sp[0], height), (ab.ep[0], height), ab.n))
    flat = deg(merge(ef, flat_ab).theta)
    return check_choice(
        answer,
        right="b",
        why={
            "a": f"the support-weighted mean of the angles, ({ef.n} × {deg(ef.theta):.2f}° + "
            f"{ab.n} × {deg(ab.theta):.2f}°) / {ef.n + ab.n} = {mean:.2f}°, lies between the two; "
            f"merge does not average angles, and {merged:.2f}° is far from any rounding.",
            "b": "merge refits one line to both segments, each its support spread along it; AB "
            "lies 3-6 cm above EF and mostly left of it, so the points are higher on the left "
            "and the best line through all of them tilts down to the right, whatever AB's own "
            f"direction (with AB flat at its mean height it would be {flat:.2f}°).",
            "c": "the projection CD of Fig. 11 only decides how far EF is extended (to C); the "
            "line is refitted to AB where it lies, 3-6 cm above EF. Projected onto EF first, AB "
            f"would add length but no tilt: the merged line would stay at {deg(ef.theta):.2f}°.",
        },
    )


def _fmt(value: float, digits: int) -> str:
    """``value`` rounded, never "-0.00" (a last-bit sign must not change the output)."""
    return f"{round(float(value), digits) + 0.0:.{digits}f}"


def check_corridor_pose(
    answer: Any,
    observed: Sequence[Line],
    references: Sequence[Line],
    pairs: Sequence[tuple[int, int]],
    predicted: ArrayLike,
    tolerance: float = 0.03,
    heading_tolerance: float = 0.005,
) -> Feedback:
    """Exercise 5.2 (predict): the pose ``(x, y, theta)`` (metres, radians) that
    :func:`fhslam.calibration.calibrate_pose` returns from the corridor's two parallel walls,
    starting from ``predicted``. Right within ``tolerance`` metres along and across the
    corridor and ``heading_tolerance`` radians; the answer is computed here by the package. A
    wrong answer is told which of the three is off and what to ask of it, not the calibrated
    pose (a prediction)."""

    @exercise("my_pose")
    def check(answer: Any) -> str:
        try:
            got = np.asarray(answer, dtype=float)
        except (TypeError, ValueError):
            got = np.zeros(0)
        if got.shape != (3,) or not np.all(np.isfinite(got)):
            raise Wrong(
                f"my_pose should be three numbers (x, y, theta) in metres and radians, "
                f"got {answer!r}"
            )
        cal = calibrate_pose(observed, references, pairs, predicted)
        pose, start = cal.pose, np.asarray(predicted, dtype=float)
        axis = references[pairs[0][1]].theta  # the walls' normal; the corridor runs across it
        normal = np.array([np.cos(axis), np.sin(axis)])
        along_dir = np.array([-normal[1], normal[0]])
        d = got[:2] - pose[:2]
        along, across = abs(d @ along_dir), abs(d @ normal)
        turn = abs(wrap_angle(got[2] - pose[2]))
        moved_along = abs((pose[:2] - start[:2]) @ along_dir)
        if along > tolerance:
            raise Wrong(
                f"along the corridor your pose is more than {100 * tolerance:g} cm from the "
                "calibrated one: do two parallel walls say where along them the robot is? And "
                "where the lines say nothing, what should a calibration do?"
            )
        if across > tolerance:
            raise Wrong(
                f"across the corridor your pose is more than {100 * tolerance:g} cm from the "
                "calibrated one: what do the distances to the two walls say?"
            )
        if turn > heading_tolerance:
            raise Wrong(
                f"your heading is more than {heading_tolerance:g} rad from the calibrated one: "
                "what does the walls' direction say? (Give it in radians.)"
            )
        where = f"calibrated ({_fmt(pose[0], 2)}, {_fmt(pose[1], 2)}, {_fmt(pose[2], 3)})"
        return (
            f"{where}: the heading and the position across the corridor corrected, the "
            f"odometry kept along it (moved {_fmt(100 * moved_along, 1)} cm along); "
            f"constrained (weak, strong direction): {cal.constrained}"
        )

    return check(answer)


def heading_cases() -> list[tuple[str, np.ndarray, np.ndarray, np.ndarray]]:
    """The cases :func:`check_heading_correction` tries: (description, theta_observed,
    theta_reference, weights). No difference lies near ±pi, where the wrap is a knife edge;
    every usual mistake is off by far more than rounding in at least one case."""
    a = np.array
    return [
        ("one pair, the reference 0.25 rad more than the new line (support 40)",
         a([1.0]), a([1.25]), a([40.0])),
        ("three pairs, supports 10, 30 and 60, differences +0.05, -0.05 and +0.10 rad",
         a([0.10, 1.50, -0.80]), a([0.15, 1.45, -0.70]), a([10.0, 30.0, 60.0])),
        ("one pair across ±pi (new line 3.10 rad, reference -3.10 rad)",
         a([3.10]), a([-3.10]), a([25.0])),
        ("two pairs, one across 0 and 2 pi (new lines 0.05 and 1.00 rad, references 6.25 "
         "and 1.10 rad, supports 75 and 25)",
         a([0.05, 1.00]), a([6.25, 1.10]), a([75.0, 25.0])),
        ("five lines of a scan turned by about 0.05 rad, angles in [0, 2 pi) and in "
         "(-pi, pi], supports 12 to 50",
         a([6.26, -3.12, 1.50, 3.10, -1.60]), a([0.03, 3.21, 1.56, -3.14, 4.73]),
         a([12.0, 7.0, 30.0, 18.0, 50.0])),
    ]  # fmt: skip


def _mistakes(obs: np.ndarray, ref: np.ndarray, w: np.ndarray, want: float):
    """The usual mistakes' results, each with its hint."""
    raw = ref - obs
    wrapped = wrap_angle(raw)
    flat_raw = float(np.sum(w * raw) / np.sum(w))
    i = int(np.argmax(np.abs(raw - wrapped))) if len(raw) else 0
    turn = f"{raw[i]:.2f} rad and {wrapped[i]:.2f} rad are the same turn"
    j = int(np.argmin(raw))
    return [
        (flat_raw, f"wrap each difference to (-pi, pi] before averaging: {turn}"),
        (-want, "the sign: the correction is reference - observed, what turns the new "
         "lines onto their references"),
        (float(np.mean(wrapped)), "weight each difference by its support: "
         "sum(w * diff) / sum(w), not the plain mean"),
        (float(np.degrees(want)), "return radians, not degrees"),
        (float(np.sum(w * np.mod(raw, 2 * np.pi)) / np.sum(w)),
         f"wrap to (-pi, pi], not to [0, 2 pi): a difference of {raw[j]:.2f} rad is a small "
         f"turn, not {np.mod(raw[j], 2 * np.pi):.2f} rad"),
        (float(wrap_angle(flat_raw)), "wrap each difference, not the average of the "
         "unwrapped ones"),
        (float(np.sum(w * wrapped) / len(w)), "divide by the sum of the weights, not by the "
         "number of pairs"),
    ]  # fmt: skip


def _number(got: Any, what: str) -> float:
    if got is None:
        raise Wrong(f"{what}: your function returned None; return the correction in radians")
    shape = np.shape(got)
    if shape != ():
        raise Wrong(f"{what}: return one number (the mean correction), got shape {shape}")
    try:
        return float(got)
    except (TypeError, ValueError):
        raise Wrong(f"{what}: return one number, got {got!r}") from None


@exercise("my_heading_correction")
def check_heading_correction(fn: Callable[[np.ndarray, np.ndarray, np.ndarray], Any]) -> str:
    """Exercise 5.3 (implement): ``fn(theta_observed, theta_reference, weights) -> float``,
    the support-weighted mean of the angle differences ``reference - observed``, each wrapped
    to (-pi, pi] (as :func:`fhslam.geometry.wrap_angle`), in radians. Any wrap that agrees
    away from ±pi is accepted (``arctan2(sin, cos)``, ``np.angle``, ...). A wrong answer is
    named after the usual mistake it matches: no wrap, the sign, the unweighted mean,
    degrees, a wrap to [0, 2 pi), the average wrapped instead of the differences, or a
    division by the number of pairs."""
    cases = heading_cases()
    for what, obs, ref, w in cases:
        want = float(np.sum(w * wrap_angle(ref - obs)) / np.sum(w))
        got = _number(call(fn, obs.copy(), ref.copy(), w.copy()), what)
        if np.isclose(got, want, rtol=0.0, atol=1e-9):
            continue
        hint = "the correction is sum(w * wrap(reference - observed)) / sum(w), in radians"
        for value, why in _mistakes(obs, ref, w, want):
            if not np.isclose(value, want, atol=1e-6) and np.isclose(got, value, atol=1e-6):
                hint = why
                break
        raise Wrong(f"{what}: the correction is {want:.4f} rad, yours {got:.4g}; {hint}")
    return f"the support-weighted mean of the wrapped differences in all {len(cases)} cases"
