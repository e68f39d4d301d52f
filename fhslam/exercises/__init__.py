"""The notebooks' exercises: checks that receive the student's answer and say, in one line,
whether it is right.

Every notebook has at least three exercises of three kinds — *predict-then-check* (a value or a
choice written down before running the code that shows it), *implement-a-step* (a function the
method needs) and *interpret-a-result* (a choice about what a figure or table means). Each has
a check here, ``check_…(answer, ...)``, which returns a :class:`Feedback`, shown as one line:

- ``⏳ not attempted yet: ...`` while the template is unfilled (a function that still raises
  :class:`NotImplementedError`, a value left as ``...``), so that Run All completes;
- ``✅ correct: ...`` or ``❌ not yet: ...`` naming the case that failed and a hint.

A student's function that raises is reported the same way, in one line, never as a traceback.
A wrong prediction is told so with a hint, never with the numbers that decide it (those come in
the cell the student runs next, and in the message for the right answer).
The checks of notebook ``NN`` live in :mod:`fhslam.exercises.nbNN` (``from
fhslam.exercises.nb02 import check_clustering``); this module holds what they share.

In the notebooks an exercise is four cells: a markdown cell ``## Exercise N.k (kind) — title``
with the task; the student's cell (tag ``exercise``: a template that raises
:class:`NotImplementedError` or sets a value to ``...``); the check cell (tag ``check``,
calling the check on the student's answer); and the solution cell (tag ``solution``, its input
hidden until asked), which defines the solution — ``solution_x`` for the student's ``my_x`` —
and shows nothing: Run All gives away no verdict and no number of the solution's. The tests
run each notebook with the check called on every solution (``tests/test_exercises.py``).
``fhslam student-copy`` (:func:`fhslam.workbook.student_copy`) writes the notebooks without
their solution cells.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "Feedback",
    "Wrong",
    "call",
    "check_band",
    "check_choice",
    "check_value",
    "exercise",
]

_MARK = {"correct": "✅ correct", "wrong": "❌ not yet", "not attempted": "⏳ not attempted yet"}


@dataclass(frozen=True)
class Feedback:
    """The outcome of a check: ``status`` (``"correct"``, ``"wrong"`` or ``"not attempted"``)
    and a one-line ``message``. Shown as one line; true only when correct."""

    status: str
    message: str

    def __post_init__(self) -> None:
        if self.status not in _MARK:
            raise ValueError(f"status must be one of {sorted(_MARK)}, got {self.status!r}")

    def __str__(self) -> str:
        return f"{_MARK[self.status]}: {' '.join(self.message.split())}"

    __repr__ = __str__

    def __bool__(self) -> bool:
        return self.status == "correct"


class Wrong(Exception):
    """Raised inside a check: the answer is wrong; the message says where and why."""


class _NotAttempted(Exception):
    pass


def _unfilled(answer: Any) -> bool:
    return answer is ... or answer is None


def call(fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """Call the student's ``fn``: :class:`NotImplementedError` means the template is not
    filled in yet; any other exception becomes a :class:`Wrong` naming it (one line)."""
    try:
        result = fn(*args, **kwargs)
    except NotImplementedError:
        raise _NotAttempted from None
    except Exception as e:  # the student's code: reported, never a traceback
        name = getattr(fn, "__name__", "your function")
        raise Wrong(f"{name} raised {type(e).__name__}: {e}") from None
    if result is ...:
        raise _NotAttempted
    return result


def exercise(what: str) -> Callable[[Callable[..., str]], Callable[..., Feedback]]:
    """Turn ``check(answer, *args) -> str`` (the success message; raises :class:`Wrong`)
    into a check returning :class:`Feedback`. ``what`` says what the student fills in, for
    the "not attempted yet" line (e.g. ``"my_cluster"``)."""

    def wrap(check: Callable[..., str]) -> Callable[..., Feedback]:
        @functools.wraps(check)
        def run(answer: Any, *args: Any, **kwargs: Any) -> Feedback:
            todo = Feedback("not attempted", f"fill in {what} above, then run this cell again")
            if _unfilled(answer):
                return todo
            try:
                return Feedback("correct", check(answer, *args, **kwargs))
            except _NotAttempted:
                return todo
            except Wrong as e:
                return Feedback("wrong", str(e))

        return run

    return wrap


def check_value(
    answer: Any,
    expected: float,
    tolerance: float,
    what: str,
    unit: str = "",
    hint: str = "",
) -> Feedback:
    """A predicted number: right within ``tolerance`` of ``expected``; ``hint`` is shown
    when it is not."""

    @exercise(what)
    def check(answer: Any) -> str:
        try:
            value = float(answer)
        except (TypeError, ValueError):
            raise Wrong(f"{what} should be a number, got {answer!r}") from None
        if not abs(value - expected) <= tolerance:
            raise Wrong(
                f"{what} = {value:g}{unit} is more than {tolerance:g}{unit} off. {hint}".strip()
            )
        return f"{what} = {value:g}{unit} (the value: {expected:.4g}{unit})"

    return check(answer)


def check_choice(answer: Any, right: str, why: dict[str, str], what: str = "my_answer") -> Feedback:
    """A multiple-choice answer, a letter among ``why``'s keys: ``why[letter]`` explains each
    choice (shown for the one given, right or wrong)."""

    @exercise(what)
    def check(answer: Any) -> str:
        letter = str(answer).strip().lower().strip("()")
        if letter not in why:
            raise Wrong(f"answer with one of {', '.join(map(repr, why))}, got {answer!r}")
        if letter != right:
            raise Wrong(f"({letter}): {why[letter]}")
        return f"({letter}): {why[letter]}"

    return check(answer)


def check_band(
    answer: Any,
    value: float,
    bands: dict[str, tuple[float, float, str]],
    shown: str,
    right: str,
    too_low: str,
    too_high: str,
    what: str = "my_prediction",
) -> Feedback:
    """A predicted range, a letter among ``bands`` (letter -> (lowest, highest, wording), in
    increasing order, each from its lowest value up to the next one's): the right letter is
    the band holding ``value``. The right band is explained as its wording, ``shown`` (how
    ``value`` came about) and ``right``; a band below it gets ``too_low``, one above it
    ``too_high`` (why the value is not that small or large), without ``shown``: a prediction is
    made before the numbers are seen, and a wrong one must not give them away."""
    letters = list(bands)
    lows = [low for low, _, _ in bands.values()][1:]
    k = int(np.searchsorted(lows, value, side="right"))
    why = {}
    for i, (letter, (_, _, words)) in enumerate(bands.items()):
        if i == k:
            why[letter] = f"{words}: {shown}{right}"
        else:
            why[letter] = f"{words}: not so. {too_low if i < k else too_high}"
    return check_choice(answer, letters[k], why, what=what)
