"""Exercises of notebook 08, the real laser logs (Intel Research Lab, MIT CSAIL) and the
relations metric of Kümmerle et al. (2009)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.exercises import Feedback, Wrong, call, check_band, check_choice, exercise
from fhslam.geometry import compose, inverse, relative
from fhslam.metrics import relations_error, relations_errors

__all__ = [
    "GAIN_CHOICES",
    "check_paper_vs_odometry",
    "check_relation_error",
    "check_span_reading",
    "relation_cases",
]


class Run(Protocol):
    """A trajectory: one pose per scan, with the scans' timestamps."""

    timestamps: NDArray[np.float64]
    poses: NDArray[np.float64]


#: Exercise 8.1's choices: letter -> (lowest ratio, highest ratio, wording), the ratio of the
#: raw odometry's mean translational relations error to the paper's procedure's; a decade
#: apart, so that Intel's ratio (between 2 and 3) is far from every bound.
GAIN_CHOICES: dict[str, tuple[float, float, str]] = {
    "a": (0.0, 1.0, "larger than the odometry's"),
    "b": (1.0, 10.0, "1 to 10 times smaller than the odometry's"),
    "c": (10.0, 100.0, "10 to 100 times smaller than the odometry's"),
    "d": (100.0, np.inf, "over 100 times smaller than the odometry's"),
}


def check_paper_vs_odometry(
    answer: Any, odometry: Run, paper: Run, t1: ArrayLike, t2: ArrayLike, rel: ArrayLike
) -> Feedback:
    """Exercise 8.1 (predict): how the mean translational relations error of the paper's
    procedure (``paper``, method ``"fht"``) compares with the raw odometry's on the log of
    the relations ``t1, t2, rel``, as a choice among :data:`GAIN_CHOICES`; the right choice
    is computed here with :func:`fhslam.metrics.relations_error`."""
    odo = relations_error(odometry.timestamps, odometry.poses, t1, t2, rel).trans_mean
    fht = relations_error(paper.timestamps, paper.poses, t1, t2, rel).trans_mean
    ratio = odo / fht if fht > 0 else np.inf
    low, high, _ = GAIN_CHOICES["b"]
    slower = (
        " The matched reference lines correct each pose, so the procedure drifts more slowly "
        "than the odometry, but nothing ever pulls it back: over the whole log the drift still "
        "adds up."
    )
    return check_band(
        answer,
        ratio,
        GAIN_CHOICES,
        f"odometry {odo:.2f} m / paper's procedure {fht:.2f} m = {ratio:.1f}",
        right="." + (slower if low <= ratio < high else ""),
        too_low="Matching the scan's lines to the reference lines corrects the heading step by "
        "step, and the heading is what makes odometry drift, so the procedure does help.",
        too_high="Each new reference line is placed with the pose of its time and never "
        "corrected, and without loop closure a return to a room does not pull the map "
        "together again: the small errors add up over minutes.",
    )


def _reference(pose_1: np.ndarray, pose_2: np.ndarray, relation: np.ndarray) -> float:
    """The translational error of one relation, by :func:`fhslam.metrics.relations_error`."""
    e = relations_error([0.0, 1.0], np.array([pose_1, pose_2]), [0.0], [1.0], [relation])
    return e.trans_mean


def relation_cases() -> list[tuple[str, np.ndarray, np.ndarray, np.ndarray]]:
    """The cases :func:`check_relation_error` tries: (description, pose 1, pose 2, relation),
    poses ``(x, y, theta)`` in the world frame, the relation ``(x, y, theta)`` in pose 1's."""
    p1 = np.array([10.0, -3.0, 2.5])
    p2 = np.array([11.2, -2.1, 2.9])
    measured = relative(p1, p2) + np.array([0.05, -0.03, 0.02])
    return [
        (
            "the robot facing north (theta 90°) drives 3 m ahead and turns 45° right, "
            "measured exactly",
            np.array([1.0, 2.0, np.pi / 2]),
            np.array([1.0, 5.0, np.pi / 4]),
            np.array([3.0, 0.0, -np.pi / 4]),
        ),
        (
            "pose 2 is 5 m away at (3, 4), the relation says (4, 3): as far, elsewhere",
            np.array([0.0, 0.0, 0.0]),
            np.array([3.0, 4.0, 0.0]),
            np.array([4.0, 3.0, 0.0]),
        ),
        (
            "the translation is right, only the heading is 0.5 rad off",
            np.array([0.0, 0.0, 0.0]),
            np.array([1.0, 0.0, 0.5]),
            np.array([1.0, 0.0, 0.0]),
        ),
        (
            "both poses turned (2.5 and 2.9 rad), the relation off by 5 cm, 3 cm and 0.02 rad",
            p1,
            p2,
            measured,
        ),
        (
            "pose 1 turned -135°, a relation with a sideways part",
            np.array([-2.0, 1.0, -3 * np.pi / 4]),
            np.array([-4.5, -0.5, 2.0]),
            np.array([2.0, -1.0, 0.5]),
        ),
    ]


def _hint(got: float, p1: np.ndarray, p2: np.ndarray, rel: np.ndarray, want: float) -> str:
    """What the student's number looks like, among the usual mistakes."""
    world = p2[:2] - p1[:2]
    c, s = np.cos(p1[2]), np.sin(p1[2])
    wrong_turn = np.array([c * world[0] - s * world[1], s * world[0] + c * world[1]])
    est = relative(p1, p2)
    err = relative(rel, est)
    cartographer = compose(est, inverse(rel))
    mistakes = [
        (
            float(np.hypot(*(world - rel[:2]))),
            "that compares the world-frame difference pose 2 - pose 1 with the relation, which "
            "is in pose 1's frame: rotate the difference by -theta1 first",
        ),
        (
            float(np.hypot(*(wrong_turn - rel[:2]))),
            "that rotates the world-frame difference by +theta1; into pose 1's frame it is "
            "-theta1 (the transpose of pose 1's rotation)",
        ),
        (
            float(np.hypot(*(relative(p2, p1)[:2] - rel[:2]))),
            "that is the motion from pose 2 back to pose 1: the relation goes from 1 to 2",
        ),
        (
            abs(float(np.hypot(*world)) - float(np.hypot(*rel[:2]))),
            "that compares the lengths of the two motions only: compare the vectors",
        ),
        (
            float(np.sqrt(np.sum(err**2))),
            "that puts the heading error (radians) into the translational error: use x and y "
            "of the difference only",
        ),
        (
            float(np.hypot(*cartographer[:2])),
            "that composes estimate ⊕ ⊖relation (Cartographer's tool), whose translation "
            "picks up the heading error; Kümmerle's error is ⊖relation ⊕ estimate",
        ),
        (want**2, "that is the squared error: take the length, not its square"),
        (100 * want, "that is in centimetres: return metres"),
    ]
    for value, hint in mistakes:
        if not np.isclose(value, want, rtol=1e-6, atol=1e-9) and np.isclose(
            got, value, rtol=1e-6, atol=1e-9
        ):
            return hint
    return (
        "estimate = pose 1's rotation transposed times (pose 2 - pose 1) in x, y; the error is "
        "the length of (estimate - relation) in x, y"
    )


def _metres(x: float) -> str:
    """A length for a message: floating-point dust (1e-16 m) shown as 0."""
    return f"{round(float(x), 9) + 0.0:.4g} m"


def _number(got: Any, what: str) -> float:
    if got is None:
        raise Wrong(f"{what}: your function returned None; return the error in metres")
    shape = np.shape(got)
    if shape != ():
        raise Wrong(f"{what}: return one number (the error's length in metres), got shape {shape}")
    try:
        value = float(got)
    except (TypeError, ValueError):
        raise Wrong(f"{what}: return one number, got {got!r}") from None
    if not np.isfinite(value):
        raise Wrong(f"{what}: your function returned {value}")
    return value


def _matched(run: Run, t1: np.ndarray, t2: np.ndarray, max_diff: float = 0.001):
    """For each relation the indices of the run's poses at t1 and t2, and which are used
    (as :func:`fhslam.metrics.relations_errors` matches them)."""
    ts = np.asarray(run.timestamps, dtype=float)
    order = np.argsort(ts, kind="stable")

    def nearest(q: np.ndarray) -> np.ndarray:
        i = np.clip(np.searchsorted(ts[order], q), 1, len(ts) - 1)
        left, right = order[i - 1], order[i]
        return np.where(np.abs(ts[left] - q) <= np.abs(ts[right] - q), left, right)

    i1, i2 = nearest(t1), nearest(t2)
    used = (np.abs(ts[i1] - t1) <= max_diff) & (np.abs(ts[i2] - t2) <= max_diff)
    return i1[used], i2[used], used


@exercise("my_relation_error")
def check_relation_error(
    fn: Callable[[np.ndarray, np.ndarray, np.ndarray], Any],
    run: Run | None = None,
    t1: ArrayLike | None = None,
    t2: ArrayLike | None = None,
    rel: ArrayLike | None = None,
) -> str:
    """Exercise 8.2 (implement): ``fn(pose_1, pose_2, relation) -> float``, the translational
    error of one Kümmerle relation in metres: the estimated motion ``⊖pose_1 ⊕ pose_2``
    compared with the measured ``relation`` (both in pose 1's frame), as
    :func:`fhslam.metrics.relations_error` computes it.

    Tried on :func:`relation_cases`, then on every relation of ``t1, t2, rel`` that ``run``
    (the notebook's trajectory) has poses for; the success message gives their mean."""
    cases = relation_cases()
    for what, p1, p2, r in cases:
        got = _number(call(fn, p1.copy(), p2.copy(), r.copy()), what)
        want = _reference(p1, p2, r)
        if not np.isclose(got, want, rtol=1e-6, atol=1e-9):
            raise Wrong(
                f"{what}: error {_metres(want)}, yours {_metres(got)}; "
                f"{_hint(got, p1, p2, r, want)}"
            )
    done = f"the same as fhslam.metrics.relations_error in all {len(cases)} cases"
    if run is None:
        return done
    a, b, r_all = (np.asarray(x, dtype=float) for x in (t1, t2, rel))
    i1, i2, used = _matched(run, a, b)
    poses = np.asarray(run.poses, dtype=float)
    trans, _, _ = relations_errors(run.timestamps, poses, a, b, r_all)
    mine = np.empty(len(trans))
    which = np.flatnonzero(used)
    for k, (j1, j2, r) in enumerate(zip(i1, i2, r_all[used], strict=True)):
        n = which[k]
        what = f"this notebook's run, relation {n} ({b[n] - a[n]:.2f} s apart)"
        mine[k] = _number(call(fn, poses[j1].copy(), poses[j2].copy(), r.copy()), what)
        if not np.isclose(mine[k], trans[k], rtol=1e-6, atol=1e-9):
            raise Wrong(
                f"{what}: error {_metres(trans[k])}, yours {_metres(mine[k])}; "
                f"{_hint(mine[k], poses[j1], poses[j2], r, float(trans[k]))}"
            )
    return (
        f"{done} and on all {len(trans)} relations of this notebook's run: mean "
        f"{mine.mean():.3f} m, as in the table"
    )


def check_span_reading(answer: Any) -> Feedback:
    """Exercise 8.3 (interpret): what the relations error by time span says about the
    paper's procedure and the pose graph on Intel (local accuracy against global
    consistency)."""
    return check_choice(
        answer,
        right="b",
        why={
            "a": "below 5 s the paper's procedure is within a few millimetres of the odometry "
            "in translation and better in heading; its metres come from the relations over a "
            "minute apart, not from the short ones.",
            "b": "between scans seconds apart it is as good as the odometry; over minutes "
            "its small errors add up and nothing corrects them (no loop closure), so "
            "relations far apart in time are metres off. The pose graph's loop closures keep "
            "even relations half an hour apart at about the short-span error: its curve "
            "stays flat.",
            "c": "the same relations over a minute apart come out at under 2 cm for the pose "
            "graph: a reference wrong by metres there would show in every method.",
            "d": "the short relations are the more numerous, but their errors are "
            "centimetres: over all relations the mean of metres is almost entirely that of "
            "the relations over a minute apart (their share of the relations times their "
            "mean error of several metres).",
        },
        what="my_reading",
    )
