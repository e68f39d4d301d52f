"""The package's errors for bad input: what a user hands it, as opposed to a bug.

Every reader, name lookup and writer of :mod:`fhslam` reports bad input by raising an
:class:`InputError` (a :class:`ValueError`) whose message names the file and, where it
applies, the line: ``"{path}:{line}: {what is wrong}"``. The ``fhslam`` command prints such an
error as one line and exits with status 2. An exception of any other type is a bug inside the
package: the command prints it as one line, ``fhslam: internal error: ...``, and exits with
status 1 (``fhslam --debug`` shows its traceback).

A dataclass of parameters checks its numbers when it is made: a value out of its
:class:`Range` raises a :class:`ParameterError` (a :class:`ValueError`: a program's argument,
not a file) naming the class, the field, the range and the value (:func:`check_ranges`); the
command names the option that set it (``fhslam slam --set``).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

__all__ = [
    "InputError",
    "InputWarning",
    "MissingInputError",
    "ParameterError",
    "Range",
    "Ranged",
    "check_ranges",
]


class InputError(ValueError):
    """Bad input: a malformed or unreadable file, an unknown name, an output that cannot be
    written. The message names what and where."""


class MissingInputError(FileNotFoundError, InputError):
    """An input file (or dataset) that does not exist. Also a :class:`FileNotFoundError`,
    with ``filename`` set where one is known."""

    def __init__(self, message: str, filename: str | None = None) -> None:
        super().__init__(message)
        self.filename = filename

    def __str__(self) -> str:  # the message, not OSError's "[Errno ...] ..." layout
        return str(self.args[0])


class InputWarning(UserWarning):
    """Readable but implausible input, read as documented (time running backwards, an
    odometry jump, readings no laser gives, a scan without a return). The message names the
    file and, where it applies, the line; the ``fhslam`` command prints it as one line
    ``fhslam: warning: ...`` and goes on."""


class ParameterError(ValueError):
    """A parameter out of its range, refused when its dataclass of parameters is made
    (:func:`check_ranges`). The message names the class, the field, the range allowed and
    the value given: ``"TrackerParams.window must be >= 0 and at most 10 m, got -1.0"``;
    the attributes ``owner`` (the class's name), ``name`` (the field's), ``value`` and
    ``allowed`` hold the parts."""

    def __init__(self, owner: str, name: str, value: object, allowed: str) -> None:
        super().__init__(f"{owner}.{name} must be {allowed}, got {value!r}")
        self.owner, self.name, self.value, self.allowed = owner, name, value, allowed


@dataclass(frozen=True)
class Range:
    """The values a numeric parameter may take, for :func:`check_ranges`.

    ``low`` to ``high``, both included unless ``open_low`` (then ``low`` itself is not).
    ``cap``: the upper bound is a limit of plausibility, not of meaning (a window of
    ``1e308`` m is no window: it overflows the search or never ends); the message then reads
    ``">= 0 and at most 10 m"`` instead of ``"in [0, 1]"``. ``integer``: whole numbers only
    (a Python or NumPy integer; not a bool, not ``5.0``); else any finite real number (not a
    bool). ``items``: the value is a tuple (or list) of this many numbers, each in the
    range. ``optional``: ``None`` is allowed too. ``unit`` is named in the message.
    """

    low: float
    high: float
    open_low: bool = False
    cap: bool = True
    integer: bool = False
    items: int = 0
    optional: bool = False
    unit: str = ""

    def describe(self) -> str:
        """The range in words, as a :class:`ParameterError` names it."""
        unit = f" {self.unit}" if self.unit else ""
        if self.cap:
            text = f"{'>' if self.open_low else '>='} {self.low:g} and at most {self.high:g}{unit}"
        else:
            text = f"in {'(' if self.open_low else '['}{self.low:g}, {self.high:g}]{unit}"
        if self.integer:
            text += " (a whole number)"
        if self.items:
            text = f"{_COUNTS.get(self.items, self.items)} values {text}"
        if self.optional:
            text += ", or None"
        return text

    def holds(self, value: object) -> bool:
        """Whether one number ``value`` is in the range (the type included)."""
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            return False  # also NumPy's bool_, which is no numbers.Real
        if self.integer and not isinstance(value, numbers.Integral):
            return False
        if not math.isfinite(value):  # NaN fails every comparison below too
            return False
        low_ok = value > self.low if self.open_low else value >= self.low
        return low_ok and value <= self.high

    def check(self, owner: str, name: str, value: object) -> None:
        """Raise :class:`ParameterError` unless ``value`` is in the range."""
        if value is None and self.optional:
            return
        if self.items:
            ok = (
                isinstance(value, tuple | list)
                and len(value) == self.items
                and all(self.holds(v) for v in value)
            )
        else:
            ok = self.holds(value)
        if not ok:
            raise ParameterError(owner, name, value, self.describe())


_COUNTS = {2: "two", 3: "three"}


def check_ranges(params: object, ranges: Mapping[str, Range]) -> None:
    """Check each named field of a dataclass of parameters against its :class:`Range`
    (in the order given), raising :class:`ParameterError` for the first one out of it."""
    owner = type(params).__name__
    for name, allowed in ranges.items():
        allowed.check(owner, name, getattr(params, name))


class Ranged:
    """A base of frozen dataclasses of parameters whose numbers are all checked against the
    class's ``RANGES`` (:func:`check_ranges`) when an instance is made."""

    RANGES: ClassVar[dict[str, Range]] = {}

    def __post_init__(self) -> None:
        check_ranges(self, self.RANGES)
