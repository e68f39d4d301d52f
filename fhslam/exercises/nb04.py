"""Exercises of notebook 04, the line attributes and the four similarity conditions (paper
Figs. 6-10)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from fhslam.exercises import Feedback, Wrong, call, check_choice, exercise
from fhslam.geometry import as_pose, point_on_line
from fhslam.lines import Line
from fhslam.matching import MatchParams, similarity

__all__ = [
    "CONDITIONS",
    "check_failing_conditions",
    "check_observation",
    "check_vanished_lines_reading",
    "observation_cases",
]


def observation_cases() -> list[tuple[str, float, float, tuple[float, float, float]]]:
    """The cases :func:`check_observation` tries: (description, rho, theta, pose).

    Every case but the last two is far from dir's knife edge (the robot 1 m or more from the
    line); in the last two the robot stands exactly on the line in floating point: with
    theta = 0, cos = 1 and sin = 0 are exact, so rho - x cos(theta) - y sin(theta) is exactly 0
    when x = rho, and likewise with theta = pi / 2 (sin = 1) when x = 0 and y = rho. Every
    pose has a heading that changes the answer if it is (wrongly) used.
    """
    return [
        (
            "a wall 2 m east of the origin (θ = 0), the robot on the origin's side",
            2.0,
            0.0,
            (0.5, 3.0, 0.75),
        ),
        ("the same wall (θ = 0), the robot beyond it", 2.0, 0.0, (3.25, -1.0, -2.0)),
        ("a wall 1.5 m north of the origin (θ = π/2)", 1.5, np.pi / 2, (4.0, 0.5, np.pi)),
        ("an oblique wall (θ = 2.0 rad, 115°)", 3.0, 2.0, (1.0, 1.0, -2.5)),
        ("a wall with θ = 5.5 rad (315°), the robot beyond it", 2.5, 5.5, (4.0, -3.0, 1.2)),
        ("the robot at the origin (θ = 4.0 rad)", 1.25, 4.0, (0.0, 0.0, 0.6)),
        ("the robot exactly on the line (θ = 0, x = ρ)", 2.0, 0.0, (2.0, -1.75, 1.0)),
        ("the robot exactly on the line (θ = π/2, y = ρ)", 1.5, np.pi / 2, (0.0, 1.5, -0.3)),
    ]


def _line(rho: float, theta: float) -> Line:
    """A 2 m segment of the line (rho, theta), centred on the foot of its normal."""
    sp, ep = point_on_line(rho, theta, np.array([-1.0, 1.0]))
    return Line(rho=float(rho), theta=float(theta), n=2, length=2.0, sp=sp, ep=ep)


def _formula(rho: float, theta: float, x: float, y: float) -> tuple[int, float]:
    s = rho - x * np.cos(theta) - y * np.sin(theta)
    return int(np.sign(s)), abs(float(s))


def _hint(got: tuple[float, float], rho: float, theta: float, pose: np.ndarray) -> str:
    """What the student's (dir, d) looks like, among the usual mistakes."""
    x, y, phi = pose
    want = _formula(rho, theta, x, y)
    s = rho - x * np.cos(theta) - y * np.sin(theta)
    heading = (
        "the heading φ plays no part: dir and d depend on the robot's position (x, y) only, "
        "and the line is in the same frame as the pose"
    )
    degrees = "θ is in radians already, and np.cos and np.sin take radians: do not convert it"
    mistakes = [
        (
            (int(np.sign(s)), float(s)),
            "d is a distance, never negative: take |ρ − x cos θ − y sin θ|",
        ),
        (
            (-want[0], want[1]),
            "your dir has the wrong sign: dir = sign(ρ − x cos θ − y sin θ), "
            "+1 when the robot is on the origin's side",
        ),
        (_formula(rho, np.radians(theta), x, y), degrees),
        (_formula(rho, np.degrees(theta), x, y), degrees),
        (_formula(rho, theta - phi, x, y), heading),
        (_formula(rho, theta + phi, x, y), heading),
        (_formula(rho, phi, x, y), heading + " (θ is the line's normal angle, not φ)"),
        (_formula(rho, theta, y, x), "x goes with cos θ and y with sin θ"),
        ((want[1], want[0]), "return the pair in the order (dir, d)"),
    ]
    for (m_dir, m_d), hint in mistakes:
        if (m_dir, m_d) != want and got[0] == m_dir and np.isclose(got[1], m_d, atol=1e-9):
            return hint
    if want[0] == 0 and got[0] != 0 and np.isclose(got[1], 0.0, atol=1e-9):
        return "on the line dir is 0 (np.sign(0.0) is 0); math.copysign never gives 0"
    return "dir = sign(ρ − x cos θ − y sin θ) and d = |ρ − x cos θ − y sin θ| (paper, Fig. 6)"


def _signed(v: float) -> str:
    return "0" if v == 0 else f"{v:+g}"


def _pair(got: Any, what: str) -> tuple[float, float]:
    if got is None:
        raise Wrong(f"{what}: your function returned None; return the pair (dir, d)")
    try:
        first, second = got
        return float(first), float(second)
    except (TypeError, ValueError):
        raise Wrong(f"{what}: return a pair of two numbers (dir, d), got {got!r}") from None


@exercise("my_observation")
def check_observation(
    fn: Callable[[float, float, np.ndarray], Any],
    line: Line | None = None,
    pose: ArrayLike | None = None,
) -> str:
    """Exercise 4.1 (implement): ``fn(rho, theta, pose) -> (dir, d)``, the observation
    direction ``dir = sign(rho - x cos(theta) - y sin(theta))`` (+1, -1 or 0) and the
    distance ``d`` from the robot at ``pose = (x, y, phi)`` to the line (paper, under Fig. 6),
    as :meth:`fhslam.lines.Line.observed_from` gives them.

    Tried on :func:`observation_cases`, then, when given, on the notebook's ``line`` seen from
    ``pose`` (Fig. 6), whose values the success message gives. ``dir`` may be any number type
    (1, 1.0, np.int64(1)); ``d`` must agree within 1e-9 m."""
    cases = [(what, rho, theta, as_pose(p)) for what, rho, theta, p in observation_cases()]
    if line is not None and pose is not None:
        cases.append(("this notebook's line of Fig. 6", line.rho, line.theta, as_pose(pose)))
    for what, rho, theta, p in cases:
        got = _pair(call(fn, rho, theta, p.copy()), what)
        want = _line(rho, theta).observed_from(p)
        if got[0] != want.dir or not np.isclose(got[1], want.d, rtol=0, atol=1e-9):
            raise Wrong(
                f"{what} (ρ = {rho:g} m, θ = {theta:.4g} rad, robot at x = {p[0]:g}, "
                f"y = {p[1]:g}, φ = {p[2]:.3g} rad): "
                f"dir = {_signed(want.dir)}, d = {want.d:.4g} m, "
                f"yours dir = {_signed(got[0])}, d = {got[1]:.4g}; {_hint(got, rho, theta, p)}"
            )
    n = len(observation_cases())
    done = (
        f"the same dir and d as Line.observed_from in all {n} cases, "
        "the robot exactly on the line (dir = 0) included"
    )
    if line is not None and pose is not None:
        seen = line.observed_from(pose)
        done += f"; Fig. 6's line: dir = {seen.dir:+d}, d = {seen.d:.3f} m, as printed above"
    return done


#: The similarity conditions, as the notebook names them.
CONDITIONS = "abcd"


def _why(s: Any, p: MatchParams, dirs: tuple[int, int]) -> dict[str, tuple[bool, str]]:
    """Condition letter -> (holds, why), with the numbers of ``s``."""
    return {
        "a": (
            s.same_direction,
            "(a) holds: the robot sees both lines from the same side"
            if s.same_direction
            else f"(a) fails: the robot sees the two lines from opposite sides (dir {dirs[0]:+d} "
            f"and {dirs[1]:+d}), like the two faces of a wall: never the same line",
        ),
        "b": (
            s.angle_ok,
            f"(b) {'holds' if s.angle_ok else 'fails'}: they meet at {s.angle_deg:.1f}°, "
            f"{'within' if s.angle_ok else 'more than'} {p.max_angle_deg:g}°",
        ),
        "c": (
            s.distance_ok,
            f"(c) {'holds' if s.distance_ok else 'fails'}: the farthest endpoint lies "
            f"{s.distance:.3f} m from the other line, "
            f"{'within' if s.distance_ok else 'more than'} {p.max_distance:g} m",
        ),
        "d": (
            s.overlap_ok,
            f"(d) holds: projected onto each other they share {s.overlap:.2f} m"
            if s.overlap_ok
            else f"(d) fails: projected onto each other they leave a gap of {-s.overlap:.2f} m"
            if s.overlap < 0
            else f"(d) fails: projected onto each other they share only {s.overlap:.2f} m, "
            f"less than {p.min_overlap:g} m",
        ),
    }


def _letters(answer: Any) -> set[str]:
    """The conditions named by an answer: "a", "(a)", "a, c", "ac", ["a", "c"], "none"."""
    if isinstance(answer, (list, tuple, set, frozenset)):
        if not all(isinstance(x, str) for x in answer):
            raise ValueError
        answer = ",".join(answer)
    if not isinstance(answer, str):
        raise ValueError
    text = answer.lower().replace("and", " ")
    for ch in "(),;+&/ ":
        text = text.replace(ch, "")
    if text in ("none", "nothing", "similar"):
        return set()
    if not text or set(text) - set(CONDITIONS):
        raise ValueError
    return set(text)


@exercise("my_prediction")
def check_failing_conditions(
    answer: Any,
    a: Line,
    b: Line,
    params: MatchParams | None = None,
    pose: ArrayLike | None = None,
) -> str:
    """Exercise 4.2 (predict): which of the similarity conditions (a)-(d) the lines ``a`` and
    ``b`` fail, as letters (``"a"``, ``"bd"``, ``"b, d"``) or ``"none"`` when they are
    similar. The right answer is computed here by :func:`fhslam.matching.similarity` (with
    each line's own ``dir`` unless ``pose`` is given). A wrong answer gets what to ask of
    each condition, not the numbers that decide it (a prediction); the right one gets every
    condition explained with its numbers."""
    try:
        said = _letters(answer)
    except ValueError:
        raise Wrong(
            f'answer with the letters of the conditions that fail, e.g. "b" or "bd", or '
            f'"none" if the lines are similar; got {answer!r}'
        ) from None
    p = params or MatchParams()
    s = similarity(a, b, p, pose)
    if pose is None:
        dirs = (a.dir, b.dir)
    else:
        dirs = (a.observed_from(pose).dir, b.observed_from(pose).dir)
    why = _why(s, p, dirs)
    fails = {c for c, (holds, _) in why.items() if not holds}
    if said != fails:
        raise Wrong(
            "not the conditions that fail. For each of (a)-(d) ask: does the robot see both "
            f"lines from the same side, do they meet at less than {p.max_angle_deg:g}°, do the "
            f"endpoints of each lie within {p.max_distance:g} m of the other line, do their "
            "projections onto each other overlap? Then run the cell that prints their similarity."
        )
    failed = ", ".join(f"({c})" for c in sorted(fails))
    verdict = f"fails {failed}: not similar" if fails else "no condition fails: similar"
    return f"{verdict}. " + "; ".join(why[c][1] for c in CONDITIONS) + "."


def check_vanished_lines_reading(answer: Any) -> Feedback:
    """Exercise 4.3 (interpret): why lines 0 and 7 of scan 200 (the wall y = 6 m either
    side of the doorway the robot drives through) have no partner among the lines of scan
    205, while each line of scan 205 is similar to one of scan 200."""
    return check_choice(
        answer,
        right="b",
        why={
            "a": "the lines of both scans are placed in the world with the true poses, so the "
            "same wall gives the same line whatever the pose it was seen from: the six matched "
            "pairs lie at most 1.3 cm apart although the robot moved 0.40 m. Lines 0 and 7 "
            "have no line of scan 205 near them at all.",
            "b": "at scan 205 the robot stands in the doorway, on the line of that wall (about "
            "1 cm from it): the wall is edge-on, at the very edge of the 180° field of view, "
            "its beams graze it and give almost no points, so no line is extracted there. "
            "The wall has not changed; it is out of view.",
            "c": "the robot did cross the wall's line between the two scans, but no line of "
            "scan 205 lies on y = 6 m at all: there is nothing to compare with, and (a) never "
            "comes into it.",
            "d": "line 0 of scan 205 is the wall x = 6 m (θ ≈ 0°), square to the wall y = 6 m "
            "(θ ≈ 90°): (b) fails by 90°. It is similar to line 1 of scan 200, the same wall "
            "x = 6 m.",
        },
    )
