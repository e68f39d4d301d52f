"""Plausibility checks the log readers share: what no laser or odometry gives.

A reader reads its file as it is. Content that can be read but is implausible is read as
documented and reported, one warning per kind of finding (a subclass of
:class:`fhslam.errors.InputWarning` the reader chooses), naming the file and the first line
or scan, and how many more:

- :func:`check_sequence`: time running backwards, repeating or leaping forward more than
  :data:`TIME_JUMP` (a day); odometry jumping further than :data:`ODOMETRY_JUMP`; scans
  further apart than :data:`SCAN_INTERVAL_MAX` or closer than :data:`SCAN_INTERVAL_MIN` as
  the median (timestamps in another unit than seconds);
- :func:`check_readings`: readings that are negative, NaN, infinite or at or beyond
  :data:`IMPLAUSIBLE_RANGE` (read as no return), scans without a return, more beams per
  scan than :data:`PLAUSIBLE_BEAMS`.

A maximum range a file states that no laser has is refused by the readers (as their own
:class:`~fhslam.errors.InputError`); :func:`stated_range_problem` says why.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from os import PathLike

import numpy as np
from numpy.typing import NDArray

from fhslam.errors import InputWarning

IMPLAUSIBLE_RANGE = 1000.0
"""No 2D laser scanner measures this far, metres (the longest-range ones reach a few hundred):
a reading at or beyond it is no measurement. A log's maximum range never exceeds it, so such
readings count as no return; the readers warn of them (:func:`check_readings`)."""

PLAUSIBLE_BEAMS = 10_000
"""More beams per scan than any 2D laser scanner gives (the densest give a few thousand): a
log with more is read, with a warning (its ranges alone take 80 kB per scan)."""

ODOMETRY_JUMP = 10.0
"""An odometry step longer than this between two scans, metres, is implausible: warned."""

TIME_JUMP = 86_400.0
"""A step forward in time longer than this between two scans, seconds (a day), is
implausible: no log records a day without a scan (the five Freiburg logs' longest gap is
198 s), so it is a corrupt timestamp, warned as time running backwards is."""

SCAN_INTERVAL_MAX = 10.0
"""A log whose scans are more than this apart, seconds, as the median interval, is
implausible: lasers scan 5 to 100 times a second (the Freiburg, Intel, ACES and MIT logs:
0.1 to 0.6 s apart), and a log kept for SLAM records them as they come. Timestamps in
milliseconds read as seconds put scans 0.2 s apart at 200 s: warned."""

SCAN_INTERVAL_MIN = 1e-4
"""A log whose scans are less than this apart, seconds, as the median interval (10,000 scans
a second, far beyond the fastest 2D laser scanner's few hundred), is implausible:
timestamps in another unit than seconds, warned."""


def stated_range_problem(value: float) -> str | None:
    """Why ``value`` cannot be the maximum range a laser states, or ``None`` if it can: it
    must be a positive number of metres below :data:`IMPLAUSIBLE_RANGE` (NaN, 0, -1, inf and
    1e308 are no laser's range). For the readers' messages."""
    value = float(value)
    if not np.isfinite(value) or value <= 0:
        return f"{value:g} m is no laser's range: it must be a positive number of metres"
    if value >= IMPLAUSIBLE_RANGE:
        return (
            f"{value:g} m is no laser's range: it must be below {IMPLAUSIBLE_RANGE:g} m "
            "(no 2D laser measures that far)"
        )
    return None


def plural(n: int, noun: str) -> str:
    """``"1 scan"``, ``"2 scans"``: a count for a message."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def check_sequence(
    path: str | PathLike[str],
    t: NDArray[np.float64],
    odometry: NDArray[np.float64] | None,
    lines: Sequence[int] | None,
    category: type[InputWarning] = InputWarning,
    noun: str = "scan",
) -> None:
    """Warn where successive rows' time runs backwards, stands still or leaps forward more
    than :data:`TIME_JUMP` (a day), or (``odometry`` given) the odometry jumps further than
    :data:`ODOMETRY_JUMP`: one warning of ``category`` per kind of finding, naming the file,
    the first place and how many more. For scans (``noun`` ``"scan"``), also when the
    median interval between them (over the steps forward in time) is beyond
    :data:`SCAN_INTERVAL_MAX` or below :data:`SCAN_INTERVAL_MIN`: no laser scans at that
    rate, the timestamps are in another unit (one warning naming the file and the median).

    ``lines`` is the file line of each row (``None``: rows are named by their index, e.g.
    ``scan 4``). Nothing is changed: the caller reads the input as it is and says so.
    """
    t = np.asarray(t, dtype=float)
    dt = np.diff(t)
    checks = [
        (dt < 0, "time goes backwards"),
        (dt == 0, "the timestamp repeats"),
        (dt > TIME_JUMP, f"time leaps forward more than a day ({TIME_JUMP:g} s)"),
    ]
    if odometry is not None:
        step = np.hypot(*np.diff(np.asarray(odometry)[:, :2], axis=0).T)
        checks.append((step > ODOMETRY_JUMP, f"the odometry jumps more than {ODOMETRY_JUMP:g} m"))
    for bad, what in checks:
        if not bad.any():
            continue
        k = int(np.flatnonzero(bad)[0])
        more = f" (and at {plural(int(bad.sum()) - 1, 'more ' + noun)})" if bad.sum() > 1 else ""
        detail = (
            f"{step[k]:.6g} m" if "odometry" in what else f"{float(t[k])!r} -> {float(t[k + 1])!r}"
        )
        if lines is None:
            where = f"{path}: {noun} {k + 1}: {what} from {noun} {k}"
        else:
            where = f"{path}:{lines[k + 1]}: {what} from the {noun} on line {lines[k]}"
        warnings.warn(f"{where} ({detail}){more}; read as it is", category, stacklevel=3)
    forward = dt[dt > 0]
    if noun == "scan" and forward.size:
        median = float(np.median(forward))
        if median > SCAN_INTERVAL_MAX:
            why = (
                f"more than any laser takes ({SCAN_INTERVAL_MAX:g} s at most): timestamps "
                "in milliseconds read as seconds?"
            )
        elif median < SCAN_INTERVAL_MIN:
            why = (
                f"less than any laser takes ({SCAN_INTERVAL_MIN:g} s at least): timestamps "
                "in another unit than seconds?"
            )
        else:
            return
        warnings.warn(
            f"{path}: the scans are {median:.6g} s apart (the median of "
            f"{plural(forward.size, 'step')} forward in time), {why} Read as it is",
            category,
            stacklevel=3,
        )


def check_readings(
    path: str | PathLike[str],
    ranges: NDArray[np.float64],
    max_range: float,
    lines: Sequence[int] | None,
    category: type[InputWarning] = InputWarning,
    non_finite: bool = True,
) -> None:
    """Warn of a log's implausible readings and of scans without a single return.

    One warning of ``category`` for each of: readings that are negative, at or beyond
    :data:`IMPLAUSIBLE_RANGE`, or (``non_finite``; ROS bags code no return as +inf, too close
    as -inf and invalid as NaN, REP 117, so they pass ``False`` and these go unwarned) NaN or
    infinite, all read as no return; scans
    in which no beam returns (nothing to extract or match: SLAM carries the odometry
    across them); and more beams per scan than :data:`PLAUSIBLE_BEAMS`. Each names the file
    and the first scan (its file line, or its index when ``lines`` is ``None``).
    """
    r = np.asarray(ranges, dtype=float)

    def first(rows: NDArray[np.bool_]) -> str:
        k = int(np.flatnonzero(rows)[0])
        return f"{path}:{lines[k]}" if lines is not None else f"{path}: scan {k}"

    with np.errstate(invalid="ignore"):
        odd = (r < 0) | (r >= IMPLAUSIBLE_RANGE)
        odd = odd | ~np.isfinite(r) if non_finite else odd & np.isfinite(r)  # ±inf: REP 117
        empty = ~np.any(np.isfinite(r) & (r > 0) & (r < max_range), axis=1)
    if odd.any():
        rows = odd.any(axis=1)
        kinds = "negative, NaN, infinite or" if non_finite else "negative or"
        n, verb = int(odd.sum()), "is" if odd.sum() == 1 else "are"
        warnings.warn(
            f"{first(rows)}: {plural(n, 'reading')} in {plural(int(rows.sum()), 'scan')} "
            f"{verb} {kinds} beyond {IMPLAUSIBLE_RANGE:g} m (no laser measures that): read as "
            "no return",
            category,
            stacklevel=3,
        )
    if empty.any():
        n = int(empty.sum())
        which = "no scan has a return" if n == len(r) else f"{n} of {len(r)} scans have no return"
        warnings.warn(
            f"{first(empty)}: {which} below the maximum range {max_range:g} m: "
            "nothing to match there, SLAM carries the odometry across",
            category,
            stacklevel=3,
        )
    if r.shape[1] > PLAUSIBLE_BEAMS:
        warnings.warn(
            f"{path}: {r.shape[1]} beams per scan, more than any 2D laser scanner gives "
            f"(> {PLAUSIBLE_BEAMS:,}); read as it is",
            category,
            stacklevel=3,
        )
