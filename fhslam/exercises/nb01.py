"""Exercises of notebook 01, the Hough transform principle (paper Fig. 1, eq. (1)) and the
classical accumulator of one laser scan."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from fhslam.baselines.classical import hough_accumulator
from fhslam.exercises import Feedback, Wrong, call, check_choice, exercise
from fhslam.geometry import TWO_PI, line_through

__all__ = [
    "check_accumulator_cells",
    "check_accumulator_reading",
    "check_line_through",
    "column_peaks",
    "line_through_cases",
]

#: Tolerance of :func:`check_line_through` on rho (metres) and theta (radians): far above
#: the rounding of any correct formula (about 1e-15), far below any mistake (>= 1e-2).
_TOL = 1e-9


def line_through_cases() -> list[tuple[str, np.ndarray, np.ndarray]]:
    """The cases :func:`check_line_through` tries: (description, p, q)."""
    theta1 = np.radians(60.0)  # Fig. 1's line: rho = 2 m, theta = 60 deg, points 1 and 4
    n1, u1 = np.array([np.cos(theta1), np.sin(theta1)]), np.array([-np.sin(theta1), np.cos(theta1)])
    theta2 = np.radians(330.0)  # a normal just below 360 deg
    n2, u2 = np.array([np.cos(theta2), np.sin(theta2)]), np.array([-np.sin(theta2), np.cos(theta2)])
    cases = [
        ("the horizontal line y = 2 m, points left to right", (-1.0, 2.0), (3.0, 2.0)),
        ("the same line y = 2 m, points right to left", (3.0, 2.0), (-1.0, 2.0)),
        ("the horizontal line y = -2.2 m, below the origin", (0.5, -2.2), (4.0, -2.2)),
        ("the vertical line x = -3 m, left of the origin", (-3.0, -1.0), (-3.0, 4.0)),
        ("the vertical line x = 3 m, points top to bottom", (3.0, 5.0), (3.0, -2.0)),
        ("the line x + y = 4 through (4, 0) and (0, 4)", (4.0, 0.0), (0.0, 4.0)),
        ("the line 3x + 4y = -12 through (-4, 0) and (0, -3)", (-4.0, 0.0), (0.0, -3.0)),
        ("the line of normal θ = 330°, 1.5 m from the origin", 1.5 * n2 - u2, 1.5 * n2 + 2 * u2),
        ("Fig. 1's line (ρ = 2 m, θ = 60°), its points 1 and 4", 2 * n1 - 1.5 * u1,
         2 * n1 + 1.6 * u1),
        ("the line y = x through the origin (ρ = 0: either normal is right)", (-1.0, -1.0),
         (2.0, 2.0)),
    ]  # fmt: skip
    return [(what, np.array(p, dtype=float), np.array(q, dtype=float)) for what, p, q in cases]


def _same_angle(a: float, b: float, period: float = TWO_PI) -> bool:
    d = np.mod(a - b, period)
    return bool(min(d, period - d) <= _TOL)


def _same_line(rho: float, theta: float, want_rho: float, want_theta: float) -> bool:
    """The same (rho, theta) up to the 2 pi wrap of theta; for rho = 0, either normal."""
    if abs(rho - want_rho) > _TOL:
        return False
    return _same_angle(theta, want_theta, np.pi if want_rho <= _TOL else TWO_PI)


def _line_hint(rho: float, theta: float, p: np.ndarray, q: np.ndarray, want: tuple) -> str:
    """What the student's (rho, theta) looks like, among the usual mistakes."""
    want_rho, want_theta = want
    d = q - p
    direction = float(np.arctan2(d[1], d[0]))
    if theta > TWO_PI + _TOL and _same_line(abs(rho), np.radians(theta), want_rho, want_theta):
        return "your θ looks like degrees: return it in radians (np.radians)"
    if _same_angle(theta, direction, np.pi) and not _same_angle(want_theta, direction, np.pi):
        return (
            "that θ is the direction of the line itself; the paper's θ is the angle of its "
            "normal OP, 90° further"
        )
    if rho < -_TOL and _same_line(-rho, theta + np.pi, want_rho, want_theta):
        return "ρ must be ≥ 0: the line (ρ, θ) with ρ < 0 is the line (-ρ, θ + π) (paper eq. (1))"
    if _same_line(rho, theta + np.pi, want_rho, want_theta):
        return (
            "θ is 180° off: the normal must point from the origin towards the line; if you "
            "made ρ ≥ 0 by dropping its sign, turn θ by π as well"
        )
    if _same_line(rho, theta, want_rho, want_theta):
        return "the line is right, but give θ in [0, 2π): add or subtract 2π"
    return (
        "the normal n = (cos θ, sin θ) is perpendicular to q - p, and "
        "ρ = x cos θ + y sin θ holds for both points"
    )


@exercise("my_line_through")
def check_line_through(fn: Callable[[np.ndarray, np.ndarray], Any]) -> str:
    """Exercise 1.1 (implement): ``fn(p, q) -> (rho, theta)``, the line through the points
    ``p`` and ``q`` (arrays of shape (2,), metres) in the paper's Hessian normal form
    (eq. (1)): ``rho >= 0`` metres, ``theta`` in [0, 2 pi) radians the angle of the normal.

    Compared with :func:`fhslam.geometry.line_through` on :func:`line_through_cases`;
    theta equal up to a 2 pi wrap is right, and a line through the origin (``rho = 0``)
    may have either normal."""
    cases = line_through_cases()
    for what, p, q in cases:
        got = call(fn, p.copy(), q.copy())
        if got is None:
            raise Wrong(f"{what}: your function returned None; return (ρ, θ)")
        try:
            rho, theta = (float(v) for v in np.asarray(got, dtype=float).reshape(-1))
        except (TypeError, ValueError):
            raise Wrong(f"{what}: return two numbers (ρ, θ), got {got!r}") from None
        if not (np.isfinite(rho) and np.isfinite(theta)):
            raise Wrong(f"{what}: your (ρ, θ) = ({rho}, {theta}) is not finite")
        want = line_through(p, q)
        inside = -_TOL <= theta <= TWO_PI + _TOL and rho >= -_TOL
        if not (inside and _same_line(rho, theta, *want)):
            raise Wrong(
                f"{what}: the paper's line is ρ = {want[0]:.3f} m, θ = {want[1]:.4f} rad "
                f"({np.degrees(want[1]):.1f}°), yours ρ = {rho:.4g}, θ = {theta:.4g}; "
                f"{_line_hint(rho, theta, p, q, want)}"
            )
    return f"the same line as fhslam.geometry.line_through in all {len(cases)} cases"


def _accumulator_shape(rho_step: float, theta_step_deg: float, rho_max: float) -> tuple[int, int]:
    acc, _, _ = hough_accumulator(np.zeros((1, 2)), rho_step, np.radians(theta_step_deg), rho_max)
    return acc.shape


@exercise("my_cells")
def check_accumulator_cells(
    answer: Any,
    rho_step: float,
    theta_step_deg: float,
    rho_max: float,
    n_points: int | None = None,
) -> str:
    """Exercise 1.3 (predict): how many cells the classical accumulator of
    :func:`fhslam.baselines.hough_accumulator` has at ``rho_step`` (m), ``theta_step_deg`` and
    ``rho_max`` (m): theta columns from 0 below 180 deg, times rho rows from ``-rho_max`` to
    ``rho_max`` both included. Exact. With ``n_points``, the message adds the votes."""
    try:
        value = float(answer)
    except (TypeError, ValueError):
        raise Wrong(f"my_cells should be a number (of cells), got {answer!r}") from None
    n_theta, n_rho = _accumulator_shape(rho_step, theta_step_deg, rho_max)
    cells = n_theta * n_rho
    if not abs(value - cells) < 0.5:
        half = (n_rho - 1) // 2
        mistakes = [
            (n_theta * (n_rho - 1), "one ρ row short per column: ρ = 0 has its own row"),
            (n_theta * half, "ρ is signed: the rows run from -ρ_max to ρ_max"),
            (n_theta * (half + 1), "ρ is signed: the rows run from -ρ_max to ρ_max"),
            (2 * n_theta * n_rho, "θ spans 0 to 180° only: (ρ, θ + 180°) is the line (-ρ, θ)"),
            (2 * n_theta * (half + 1), "θ spans 0 to 180° only, and ρ is signed (-ρ_max to ρ_max)"),
            (n_theta + n_rho, "the cells form a grid: columns times rows, not plus"),
        ]  # fmt: skip
        if n_points:
            mistakes.append((n_points * n_theta, "that is the number of votes, not of cells"))
        hint = next(
            (h for v, h in mistakes if v != cells and abs(value - v) < 0.5),
            f"count the θ columns ({theta_step_deg:g}° steps from 0 up to, not including, "
            f"180°) and the ρ rows ({rho_step:g} m steps from -{rho_max:g} to {rho_max:g} m, "
            "both included)",
        )
        raise Wrong(f"my_cells = {value:g} is not the number of cells; {hint}")
    done = f"{cells} cells ({n_theta} θ columns × {n_rho} ρ rows)"
    if n_points:
        votes = n_points * n_theta
        done += (
            f"; the {n_points} points cast {votes} votes, one per column each, so at most "
            f"{votes / cells:.0%} of the cells can hold a vote: the accumulator is mostly empty"
        )
    return done


def column_peaks(
    column: ArrayLike, rhos: ArrayLike, min_separation: float = 0.25, at_least: int = 3
) -> list[tuple[float, int]]:
    """The peaks of one theta column of an accumulator: (rho, votes), strongest first.

    A cell is a peak when it holds at least ``at_least`` votes and a sixth of the column's
    highest, and lies over ``min_separation`` metres from every stronger peak."""
    votes = np.asarray(column)
    r = np.asarray(rhos, dtype=float)
    floor = max(at_least, votes.max() / 6) if len(votes) else at_least
    peaks: list[tuple[float, int]] = []
    for j in np.argsort(-votes, kind="stable"):
        if votes[j] < floor or len(peaks) == 4:
            break
        if all(abs(r[j] - rho) > min_separation for rho, _ in peaks):
            peaks.append((float(r[j]), int(votes[j])))
    return peaks


def check_accumulator_reading(
    answer: Any, acc: ArrayLike, thetas: ArrayLike, rhos: ArrayLike
) -> Feedback:
    """Exercise 1.2 (interpret): why several bright peaks share the strongest peak's theta
    column of the accumulator ``acc`` (theta columns ``thetas``, rho rows ``rhos``, as
    :func:`fhslam.baselines.hough_accumulator` returns them). The explanations quote the
    notebook's own peaks and votes per column."""
    a = np.asarray(acc)
    i = int(np.unravel_index(a.argmax(), a.shape)[0])
    theta = float(np.degrees(np.asarray(thetas)[i]))
    peaks = sorted(column_peaks(a[i], rhos))
    listed = ", ".join(f"{rho:.1f} m ({n} votes)" for rho, n in peaks)
    if len(peaks) > 1:
        here = f"here the θ = {theta:.0f}° column has peaks at ρ = {listed}"
    else:
        here = (
            f"here the strongest column, θ = {theta:.0f}°, has a single peak (ρ = {listed}): "
            "this scan sees no wall parallel to that one"
        )
    if any(rho < 0 for rho, _ in peaks):
        here += "; ρ < 0 means the normal points the other way: the paper's (-ρ, θ + 180°)"
    per_column = a.sum(axis=1)
    if per_column.min() == per_column.max():
        columns = f"every column holds exactly {per_column.max()} votes, one per point"
    else:
        columns = (
            f"every column holds at most {per_column.max()} votes, one per point "
            "(votes beyond ρ_max are dropped)"
        )
    return check_choice(
        answer,
        right="b",
        why={
            "a": "one wall's points agree on a single (ρ, θ) cell; in any other cell of that "
            "column their votes spread thin along ρ. One wall makes one peak.",
            "b": "parallel walls share their normal angle θ and differ only in ρ, their "
            f"distance from the laser; {here}.",
            "c": f"each point votes exactly once in every column: {columns}. A column is "
            "bright where many of its votes fall on one ρ, not because it gets more.",
            "d": "two walls meeting at a corner have normals 90° apart: they give two "
            "peaks in two different columns, not in one; a corner point is just one more "
            "sinusoid.",
        },
        what="my_reading",
    )
