"""Exercises of notebook 07, the paper's claims measured: fast Hough against classical Hough
and EKF line SLAM over the Monte-Carlo sweep that ``fhslam sweep`` writes
(``notebooks/results/sweep_paper.csv``, read with
:func:`fhslam.experiments.compare.load_sweep`).

The right answers of the predict and interpret exercises are computed here from the sweep the
notebook loads (passed to the check), with :func:`fhslam.experiments.compare.summary`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from fhslam.exercises import Feedback, Wrong, call, check_choice, exercise
from fhslam.experiments.compare import LABELS, RunResult, summary

__all__ = [
    "METHOD_CHOICES",
    "READINGS",
    "ate_stats_cases",
    "check_ate_stats",
    "check_classical_reading",
    "check_lowest_ate",
]

#: Exercise 7.1's choices: letter -> SLAM method (as in the sweep file).
METHOD_CHOICES: dict[str, str] = {
    "a": "fht",
    "b": "graph",
    "c": "classical",
    "d": "ekf",
    "e": "odometry",
}

#: What each method does that decides its accuracy (true whichever ranks first).
_WHY_METHOD = {
    "fht": "FH-SLAM fixes each pose once on the lines it matches (Loop 3) and never revises a "
    "past pose or line with later evidence.",
    "graph": "the pose graph re-optimises past poses when it closes a loop, which pays most when "
    "the odometry drifts most.",
    "classical": "classical Hough as Loop 1 extracts less precise lines (section 1), and every "
    "pose is calibrated on them.",
    "ekf": "the EKF keeps the joint covariance of the pose and every line and corrects both at "
    "each scan; with some twenty lines seen over and over, its linearisation errors stay small: "
    'the paper\'s "can only deal with linear problem" does not show here.',
    "odometry": "the odometry is what every SLAM method starts from: its systematic errors add up "
    "to metres.",
}


def _cm(metres: float) -> str:
    return f"{100 * metres:.1f} cm" if metres < 1 else f"{metres:.2f} m"


def check_lowest_ate(answer: Any, rows: Sequence[RunResult], level: str = "high") -> Feedback:
    """Exercise 7.1 (predict): which method has the lowest median ATE rmse at ``level`` over
    the sweep ``rows``, a letter of :data:`METHOD_CHOICES`. The right letter is computed here
    with :func:`fhslam.experiments.compare.summary`; the right answer's explanation gives the
    medians, a wrong one's what decides that method's accuracy, not the medians (a
    prediction)."""
    s = summary(rows)
    medians = {m: s[(level, m)]["ate_median"] for m in METHOD_CHOICES.values() if (level, m) in s}
    best = min(medians, key=medians.__getitem__)
    right = next(k for k, m in METHOD_CHOICES.items() if m == best)
    ranking = ", ".join(
        f"{LABELS[m]} {_cm(v)}" for m, v in sorted(medians.items(), key=lambda kv: kv[1])
    )
    why = {}
    for letter, m in METHOD_CHOICES.items():
        if m not in medians:
            why[letter] = f"{LABELS[m]} is not in this sweep at level {level!r}."
        elif m == best:
            why[letter] = (
                f"{LABELS[m]} has the lowest median ATE at {level} (medians: {ranking}): "
                f"{_WHY_METHOD[m]}"
            )
        else:
            why[letter] = (
                f"{LABELS[m]} does not have the lowest median ATE at {level}: {_WHY_METHOD[m]}"
            )
    return check_choice(answer, right, why, what="my_prediction")


# ------------------------------------------------------------------------- exercise 7.2


def _row(method: str, level: str, seed: int, ate_rmse: float) -> RunResult:
    """A made-up run: the odometry's ATE differs from the method's, so using the wrong column
    shows."""
    return RunResult(
        method=method,
        level=level,
        seed=seed,
        ate_rmse=ate_rmse,
        odometry_ate_rmse=8.0 + ate_rmse,
        map_error=0.015625,
        ms_per_step=2.0,
        n_map_lines=20,
    )


def ate_stats_cases() -> list[tuple[str, list[RunResult], str, str]]:
    """The small cases :func:`check_ate_stats` tries: (description, rows, method, level).

    Every ATE is a multiple of 1/32, exact in binary floating point, and so are the medians.
    The mean, the median over other levels or methods and the middle element of an even count
    all differ from the right median, so each usual mistake fails a case."""
    mixed = [
        _row("fht", "low", 0, 0.5),
        _row("ekf", "low", 0, 0.125),
        _row("fht", "medium", 0, 8.0),
        _row("fht", "low", 1, 0.25),
        _row("ekf", "low", 1, 0.0625),
        _row("fht", "medium", 1, 16.0),
        _row("fht", "low", 2, 4.0),
        _row("ekf", "low", 2, 0.03125),
    ]
    even = [_row("classical", "high", s, a) for s, a in enumerate([0.5, 8.0, 0.125, 0.25])] + [
        _row("fht", "high", s, 1.0) for s in range(4)
    ]
    one = [_row("ekf", "medium", 3, 0.375), _row("ekf", "high", 3, 0.75)]
    return [
        ("three FH-SLAM runs at low among other levels and methods", mixed, "fht", "low"),
        ("the EKF's runs at low in the same list", mixed, "ekf", "low"),
        ("four classical runs at high (an even number)", even, "classical", "high"),
        ("a single EKF run at medium", one, "ekf", "medium"),
    ]


def _want(rows: Sequence[RunResult], method: str, level: str) -> tuple[float, float]:
    v = summary(rows)[(level, method)]
    return v["ate_median"], v["ate_max"]


def _pair(got: Any, what: str) -> tuple[float, float]:
    if got is None:
        raise Wrong(f"{what}: your function returned None; return (median, maximum)")
    try:
        a = np.asarray(got, dtype=float)
    except (TypeError, ValueError):
        raise Wrong(f"{what}: return two numbers (median, maximum), got {got!r}") from None
    if a.shape != (2,):
        raise Wrong(f"{what}: return two numbers (median, maximum), got shape {a.shape}")
    return float(a[0]), float(a[1])


def _hint(got: tuple[float, float], rows: Sequence[RunResult], method: str, level: str) -> str:
    """What the student's pair looks like, among the usual mistakes."""
    want = _want(rows, method, level)
    sel = sorted(r.ate_rmse for r in rows if (r.method, r.level) == (method, level))
    by_method = [r.ate_rmse for r in rows if r.method == method]
    by_level = [r.ate_rmse for r in rows if r.level == level]
    odo = [r.odometry_ate_rmse for r in rows if (r.method, r.level) == (method, level)]
    mistakes = [
        ((want[1], want[0]), "the order is (median, maximum)"),
        ((float(np.mean(sel)), want[1]), "that is the mean: take the median"),
        (
            (sel[len(sel) // 2], want[1]),
            "with an even number of runs the median is the mean of the two middle ones",
        ),
        (
            (sel[(len(sel) - 1) // 2], want[1]),
            "with an even number of runs the median is the mean of the two middle ones",
        ),
        ((want[0], float(np.min(sel))), "that is the minimum: the table gives the worst run"),
        (
            (float(np.median(by_method)), float(np.max(by_method))),
            "those are over every level: keep the rows of this level only",
        ),
        (
            (float(np.median(by_level)), float(np.max(by_level))),
            "those are over every method: keep the rows of this method only",
        ),
        (
            (float(np.median(odo)), float(np.max(odo))),
            "that is odometry_ate_rmse, the odometry's error: use ate_rmse, the method's",
        ),
    ]
    for value, hint in mistakes:
        if not np.allclose(value, want, rtol=1e-9) and np.allclose(got, value, rtol=1e-9):
            return hint
    return "the median and the maximum of ate_rmse over the rows of this method and level"


@exercise("my_ate_stats")
def check_ate_stats(
    fn: Callable[[Sequence[RunResult], str, str], Any],
    rows: Sequence[RunResult] | None = None,
) -> str:
    """Exercise 7.2 (implement): ``fn(rows, method, level) -> (median, maximum)`` of the ATE
    rmse (``ate_rmse``) over the runs of ``method`` at ``level``: the table's "ATE median" and
    "ATE max", as :func:`fhslam.experiments.compare.summary` computes them.

    Tried on :func:`ate_stats_cases`, then on every (level, method) of ``rows`` (the loaded
    sweep), whose FH-SLAM values at each level the success message gives."""
    cases = [(what, list(rs), m, lv) for what, rs, m, lv in ate_stats_cases()]
    if rows:
        rows = list(rows)
        for lv, m in summary(rows):
            cases.append((f"the sweep's {LABELS[m]} at {lv}", rows, m, lv))
    for what, rs, m, lv in cases:
        given = [replace(r) for r in rs]  # a copy: the student's function may sort or pop
        got = _pair(call(fn, given, m, lv), what)
        want = _want(rs, m, lv)
        if not np.allclose(got, want, rtol=1e-9, atol=0.0):
            raise Wrong(
                f"{what}: (median, maximum) = ({want[0]:.4g}, {want[1]:.4g}) m, yours "
                f"({got[0]:.4g}, {got[1]:.4g}); {_hint(got, rs, m, lv)}"
            )
    done = f"the same as fhslam.experiments.compare.summary in all {len(cases)} cases"
    if rows:
        s = summary(rows)
        values = ", ".join(
            f"{lv} {_cm(s[(lv, 'fht')]['ate_median'])} / {_cm(s[(lv, 'fht')]['ate_max'])}"
            for lv in ("low", "medium", "high")
            if (lv, "fht") in s
        )
        done += f"; FH-SLAM (paper) median / max: {values}, as in the table"
    return done


# ------------------------------------------------------------------------- exercise 7.3

#: Exercise 7.3's readings of FH-SLAM against FH-SLAM + classical Hough.
READINGS = {
    "a": "FH-SLAM's median ATE is at least 2 times lower than with classical Hough at every level",
    "b": "FH-SLAM's median is the lower at most levels but not 2 times lower at every level; "
    "classical Hough's worst run is at least 1.5 times FH-SLAM's at every level",
    "c": "classical Hough has the lower median ATE at most levels",
    "d": "FH-SLAM's median is the lower at most levels but not 2 times lower at every level; "
    "the worst runs are within a factor 1.5 at some level",
}


def check_classical_reading(answer: Any, rows: Sequence[RunResult]) -> Feedback:
    """Exercise 7.3 (interpret): what the box plots say about the paper's claim that the fast
    Hough transform is more precise than the classical one, comparing FH-SLAM with FH-SLAM +
    classical Hough as Loop 1 at each level of the sweep ``rows``.

    The readings (:data:`READINGS`) are decided in turn, so exactly one is right: (a) if the
    ratio of the medians (classical / FH-SLAM) is 2 or more at every level; else (c) if it is
    below 1 at most levels; else (b) if the ratio of the worst runs is 1.5 or more at every
    level; else (d). The right reading's explanation gives the medians and the worst runs; a
    wrong one's is a hint (where to look and what to test there), without the numbers."""
    s = summary(rows)
    levels = [lv for lv in ("low", "medium", "high") if (lv, "fht") in s and (lv, "classical") in s]
    med = {lv: s[(lv, "classical")]["ate_median"] / s[(lv, "fht")]["ate_median"] for lv in levels}
    worst = {lv: s[(lv, "classical")]["ate_max"] / s[(lv, "fht")]["ate_max"] for lv in levels}
    all_twice = all(r >= 2 for r in med.values())
    classical_lower = [lv for lv in levels if med[lv] < 1]
    mostly_classical = len(classical_lower) > len(levels) / 2
    alike = [lv for lv in levels if worst[lv] < 1.5]
    if all_twice:
        right = "a"
    elif mostly_classical:
        right = "c"
    elif not alike:
        right = "b"
    else:
        right = "d"

    def pairs(key: str) -> str:
        return ", ".join(
            f"{lv} {_cm(s[(lv, 'fht')][key])} / {_cm(s[(lv, 'classical')][key])}" for lv in levels
        )

    def ratios(d: dict[str, float]) -> str:
        return ", ".join(f"{d[lv]:.2f}" for lv in levels)

    medians = f"median ATE FH-SLAM / classical: {pairs('ate_median')} (ratios {ratios(med)})"
    worsts = f"worst run: {pairs('ate_max')} (ratios {ratios(worst)})"
    beyond = {
        lv: sum(
            r.ate_rmse > s[(lv, "fht")]["ate_max"]
            for r in rows
            if (r.method, r.level) == ("classical", lv)
        )
        for lv in levels
    }
    counts = ", ".join(f"{lv} {beyond[lv]} of {s[(lv, 'classical')]['n']}" for lv in levels)
    lesson = {
        "a": "the faster Loop 1 is also the more precise one in the typical run.",
        "b": "the claim holds for the bad runs, not for the typical one: look at the upper "
        "quartiles and whiskers, not only at the median lines. Runs with classical Hough worse "
        f"than FH-SLAM's worst: {counts}; its less precise lines (section 1) let many runs "
        "drift a few centimetres further, which the median hides.",
        "c": "in SLAM the precision claim is reversed.",
        "d": "in SLAM this sweep does not tell the two extractors apart.",
    }
    # a wrong reading gets a hint, not the numbers: where in the box plots and the table to
    # look, and the test to make there. (b) and (d) differ only in the worst runs, so their hint
    # names both of their parts, whichever one fails: naming it would settle the other reading.
    look_medians = (
        "compare the median lines (the table's ATE median) of FH-SLAM (paper) and FH-SLAM + "
        "classical Hough at each level"
    )
    look_worst = (
        "the worst runs (the table's ATE max, the highest point of each box plot) at each level"
    )
    both = f"check both of its parts: {look_medians}, then {look_worst}, as ratios"
    both += " classical / FH-SLAM"
    wrong = {
        "a": f"{look_medians}: is classical Hough's at least 2 times FH-SLAM's at every level?",
        "b": both,
        "c": f"{look_medians}: at how many of the levels is classical Hough's the lower?",
        "d": both,
    }
    facts = {"a": medians, "b": f"{medians}; {worsts}", "c": medians, "d": f"{medians}; {worsts}"}
    why = {}
    for letter, reading in READINGS.items():
        if letter == right:
            why[letter] = f"{reading}: {facts[letter]} — {lesson[letter]}"
        else:
            why[letter] = f"not so; {wrong[letter]}"
    return check_choice(answer, right, why, what="my_answer")
