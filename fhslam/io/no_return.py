"""The "no return" code and the maximum range of a laser log.

A laser reports a beam without an echo as one fixed reading, and a log does not always say
which: a CARMEN ``FLASER`` line never does, a bag's ``range_max`` may be longer than the
code (the Freiburg hospital bag states 81.9 m and codes 81.83 and 81.91 m).
:func:`no_return_reading` finds the code at the top of the histogram of the log's readings,
counted over the run as the scans change (:func:`counted_readings`: a robot standing still
counts once); :func:`effective_max_range` gives the maximum range a reader uses -- the
smaller of the range the file states and the code, else a default above every reading,
never beyond :data:`~fhslam.io.plausibility.IMPLAUSIBLE_RANGE` -- and warns, naming the
file, where that range is well below readings the log repeats. Readings at or above the
maximum range are no returns. NaN, infinite and non-positive readings never count.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from os import PathLike

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.errors import InputWarning
from fhslam.io.plausibility import IMPLAUSIBLE_RANGE, plural

NO_RETURN_MIN_SHARE = 1e-3
"""Smallest share of a log's counted readings (:func:`no_return_reading`) that must read one
exact value for it to be taken as the "no return" code; never fewer than
:data:`NO_RETURN_MIN_COUNT` readings."""

NO_RETURN_MIN_COUNT = 20
"""Fewest counted readings of one value that make it a "no return" code (short logs)."""

NO_RETURN_MIN_BEAMS = 3
"""Fewest beams that must read a value for it to be a "no return" code: a value one or two
beams read over and over is a distance they see, not the laser's code."""

NO_RETURN_PEAK = 5.0
"""How many times more often a "no return" code is read than any other value within
:data:`NO_RETURN_WINDOW` of it: a code is one exact value, while a distance the laser
measures often (a wall, readings rounded to 1 cm) is read about as often as its
neighbours."""

NO_RETURN_WINDOW = 0.02
"""Half-width of the neighbourhood a code must stand out in, relative to the value (2 %:
±1.6 m around 81.91 m); at least :data:`NO_RETURN_WINDOW_MIN`."""

NO_RETURN_WINDOW_MIN = 0.05
"""Smallest half-width of that neighbourhood, metres (five 1-cm steps)."""

REPEATED_SCAN_SHARE = 0.9
"""A scan whose beams read, on at least this share of them, what they read in the scan
before (within :data:`REPEATED_SCAN_TOLERANCE`) repeats it: a robot standing still. Its
unchanged readings are not counted again when a log's no-return code is sought, so a long
stop does not turn the distances it sees into codes. In the real logs these are the
robot's stops: none in ACES, the Freiburg hospital and MIT Killian, up to 980 of 4758 scans
in Freiburg 101; their codes come out the same counted either way."""

REPEATED_SCAN_TOLERANCE = 0.03
"""How far a beam's reading may move, metres, and still count as unchanged from the scan
before (three times the 1 cm range noise of the simulated laser,
:class:`fhslam.sim.LaserParams`, and of a SICK LMS)."""

DROPPED_RANGE_MARGIN = 0.05
"""Readings at least this share beyond the maximum range in use count as dropped ones for
the warning of :func:`effective_max_range` (the jitter of a code just above it does not)."""


def _as_scans(ranges: ArrayLike) -> NDArray[np.float64]:
    """``ranges`` as an array of scans (T, B): a flat array is one scan."""
    r = np.asarray(ranges, dtype=float)
    if r.ndim < 2:
        return r.reshape(1, -1)
    return r.reshape(-1, r.shape[-1]) if r.ndim > 2 else r


def counted_readings(ranges: ArrayLike) -> NDArray[np.bool_]:
    """The readings of ``ranges`` (T, B) that count as evidence for a no-return code: the
    valid ones (finite, positive), except where a scan repeats the one before
    (:data:`REPEATED_SCAN_SHARE`): there only the beams whose reading changed count. A robot
    standing still for minutes then counts as one scan, not as thousands of readings of the
    same walls. Returns a boolean mask of the shape of ``_as_scans(ranges)``."""
    r = _as_scans(ranges)
    with np.errstate(invalid="ignore"):
        valid = np.isfinite(r) & (r > 0)
        same = np.zeros(r.shape, dtype=bool)
        same[1:] = (
            (np.abs(r[1:] - r[:-1]) <= REPEATED_SCAN_TOLERANCE)
            | (r[1:] == r[:-1])
            | (np.isnan(r[1:]) & np.isnan(r[:-1]))
        )
    if not r.shape[1]:
        return valid
    repeats = same.mean(axis=1) >= REPEATED_SCAN_SHARE
    return valid & ~(same & repeats[:, None])


@dataclass
class _RangeHistogram:
    """The counted readings of a log (:func:`counted_readings`) by value, with what
    :func:`no_return_reading` and :func:`effective_max_range` decide on."""

    values: NDArray[np.float64]  # distinct counted readings, ascending
    counts: NDArray[np.intp]  # how often each is read
    beams: NDArray[np.intp]  # by how many distinct beams (0 for the rare values)
    which: NDArray[np.intp]  # value index of each counted reading
    scan: NDArray[np.intp]  # its scan
    beam: NDArray[np.intp]  # its beam
    n_beams: int
    need: float  # counted readings a code needs
    lo: int  # index of the first value a code may be (half the stated range)
    code_like: NDArray[np.bool_]  # values that stand out as codes do

    @classmethod
    def of(cls, ranges: ArrayLike, min_share: float, stated: float | None) -> _RangeHistogram:
        r = _as_scans(ranges)
        use = counted_readings(r)
        scan, beam = np.nonzero(use)
        values, which, counts = np.unique(r[use], return_inverse=True, return_counts=True)
        need = max(NO_RETURN_MIN_COUNT, min_share * len(which))
        asked = counts >= need  # the beams are counted where they matter: frequent values
        asked[-1:] = True  # and the largest
        b = max(r.shape[1], 1)
        pairs = np.unique(which[asked[which]].astype(np.int64) * b + beam[asked[which]])
        h = cls(
            values=values,
            counts=counts,
            beams=np.bincount(pairs // b, minlength=len(values)),
            which=which,
            scan=scan,
            beam=beam,
            n_beams=r.shape[1],
            need=need,
            lo=int(np.searchsorted(values, 0.5 * stated)) if stated is not None else 0,
            code_like=np.zeros(len(values), dtype=bool),
        )
        h._find_code_like()
        return h

    def _window(self, i: int) -> NDArray[np.intp]:
        """Indices of the other values within the neighbourhood of value ``i``."""
        v = self.values[i]
        half = max(NO_RETURN_WINDOW * v, NO_RETURN_WINDOW_MIN)
        j0 = int(np.searchsorted(self.values, v - half, "left"))
        j1 = int(np.searchsorted(self.values, v + half, "right"))
        return np.r_[j0:i, i + 1 : j1]

    def _stands_out(self, i: int, ignore: NDArray[np.bool_] | None = None) -> bool:
        """Whether value ``i`` is read :data:`NO_RETURN_PEAK` times more often than any
        other value near it (those flagged in ``ignore`` aside)."""
        near = self._window(i)
        c = self.counts[near] if ignore is None else self.counts[near][~ignore[near]]
        return bool(self.counts[i] >= NO_RETURN_PEAK * (c.max() if c.size else 0))

    def _find_code_like(self) -> None:
        """Flag the values read like codes: often (``need``), by several beams, and far more
        often than the values near them. A second code near a stronger one (81.83 m beside
        81.91 m) stands out once the first is set aside. A value one rounding step below a
        stronger code, on top of the real readings, is the tail of those readings clipped
        below the code (a simulated laser's ``max_range - resolution``), not a code."""
        frequent = np.flatnonzero(
            (self.counts >= self.need)
            & (np.arange(len(self.values)) >= self.lo)
            & (self.beams >= min(NO_RETURN_MIN_BEAMS, self.n_beams))
        )
        spike = np.zeros(len(self.values), dtype=bool)
        spike[frequent] = [self._stands_out(i) for i in frequent]
        code_like = spike.copy()
        code_like[frequent] = [spike[i] or self._stands_out(i, spike) for i in frequent]
        for i in np.flatnonzero(code_like[:-1] & code_like[1:]):
            below = self._window(i)
            below = below[(below < i) & ~code_like[below]]
            step_below = self.values[i] - self.values[i - 1] if i else np.inf
            step_above = self.values[i + 1] - self.values[i]
            one_step = step_above <= 1.5 * step_below and step_below <= 1.5 * step_above
            dense = self.counts[below].sum() >= self.counts[i]
            if self.counts[i + 1] > self.counts[i] and (dense or one_step):
                code_like[i] = False
        self.code_like = code_like

    def _others_above(self, i: int) -> tuple[int, int]:
        """Readings above value ``i`` that are no codes: within its neighbourhood, beyond."""
        near = self._window(i)
        near = near[near > i]
        other = ~self.code_like
        beyond = near[-1] + 1 if near.size else i + 1
        n_near = int(self.counts[near][other[near]].sum())
        n_far = int(self.counts[beyond:][other[beyond:]].sum())
        return n_near, n_far

    def code(self) -> float | None:
        """The no-return code (:func:`no_return_reading`), or ``None``."""
        for i in np.flatnonzero(self.code_like):
            n_near, n_far = self._others_above(i)
            if n_near <= self.counts[i] and n_far <= self.need:
                return float(self.values[i])
        i = len(self.values) - 1
        if i < self.lo or self.counts[i] < 2 or self.beams[i] < 2:
            return None
        scans = np.unique(self.scan[self.which == i])
        return float(self.values[i]) if len(scans) >= 2 and self._stands_out(i) else None

    def dropped(self, max_range: float) -> tuple[int, int, int, float, float]:
        """Counted readings well beyond ``max_range`` (:data:`DROPPED_RANGE_MARGIN`) that are
        no codes: how many, in how many scans, by how many beams, smallest, largest."""
        i0 = int(np.searchsorted(self.values, max_range * (1 + DROPPED_RANGE_MARGIN)))
        keep = np.flatnonzero(~self.code_like[i0:]) + i0
        sel = np.isin(self.which, keep)
        if not sel.any():
            return 0, 0, 0, np.nan, np.nan
        v = self.values[self.which[sel]]
        return (
            int(sel.sum()),
            len(np.unique(self.scan[sel])),
            len(np.unique(self.beam[sel])),
            float(v.min()),
            float(v.max()),
        )


def no_return_reading(
    ranges: ArrayLike, min_share: float = NO_RETURN_MIN_SHARE, stated: float | None = None
) -> float | None:
    """The reading a log uses to say "no return", or ``None`` if it has none.

    A laser reports a beam without an echo as one fixed code, and a CARMEN ``FLASER`` line
    does not say which: 81.91 m (and 81.83 m) in the Freiburg logs of a SICK LMS in its
    80 m mode, 50.0 m in ACES, the maximum range in a simulated log. The code is the top of
    the readings' histogram: one exact value, read by many beams, far more often than any
    value near it, with (other codes aside) hardly a reading above it. A distance the laser
    measures often is none of that: readings rounded to 1 cm repeat each centimetre about
    as often as the next, a wall seen again and again has the readings of the rest of the
    run beyond it.

    The readings are counted over the run as the scans change (:func:`counted_readings`): a
    robot standing still repeats one scan for minutes, and its readings count once. Then
    the code is the smallest value that

    1. makes up at least ``min_share`` of the counted readings (and at least
       :data:`NO_RETURN_MIN_COUNT` of them), read by at least :data:`NO_RETURN_MIN_BEAMS`
       beams;
    2. is read :data:`NO_RETURN_PEAK` times more often than any other value within
       :data:`NO_RETURN_WINDOW` of it (a stronger code there aside: 81.83 m beside 81.91 m;
       a value one rounding step below a stronger code, on top of the real readings, is
       those readings clipped below it, no code);
    3. has few readings above it that are no codes: fewer than its own count within that
       window (the jitter of a code), and no more than rule 1's count beyond it (glitches).

    Failing that, the largest reading is the code if it is read in two scans by two beams
    and stands out as in rule 2 (a short log with few no-return beams). With none of it, a
    log has no code: every reading is a return.

    The ``stated`` range bounds the search from below: a value repeated far below it (less
    than half) is a distance the laser measured often, not its no-return code. So in a bag
    stating ``range_max`` 80 m, a wall at 2.0 m read in every beam of every scan is no code,
    while a SICK's 81.91 m and 81.83 m (the Freiburg bags state 80 m and 81.9 m) and ACES's
    50.0 m (it states 50 m) are.

    Parameters
    ----------
    ranges : array-like, shape (T, B)
        The log's readings, metres, scan by scan (NaN/inf and non-positive ones are
        ignored); a flat array is one scan.
    min_share : float
        See rule 1.
    stated : float, optional
        The maximum range the file states, metres
        (:attr:`Log.stated_max_range <fhslam.io.log.Log>`).

    Returns
    -------
    float or None
        The code; readings at or above it are "no return".
    """
    h = _RangeHistogram.of(ranges, min_share, stated)
    return h.code() if len(h.values) else None


def effective_max_range(
    ranges: ArrayLike,
    stated: float | None,
    default: float,
    path: str | PathLike[str] | None = None,
    category: type[InputWarning] = InputWarning,
) -> tuple[float, float | None]:
    """The maximum range a reader gives a log: the smaller of the range the file states
    (``stated``, e.g. a bag's ``range_max``; a plausible one,
    :func:`~fhslam.io.plausibility.stated_range_problem`) and its detected no-return code
    (:func:`no_return_reading`, searched near ``stated``: never far below it); with neither,
    ``default``, raised above the largest reading if needed so that no real reading is
    dropped. Never more than :data:`~fhslam.io.plausibility.IMPLAUSIBLE_RANGE`: a reading
    that far is no measurement (:func:`~fhslam.io.plausibility.check_readings` warns of it).
    Returns ``(max_range, code)``.

    With ``path``, one warning of ``category`` naming the file if the range so chosen is
    well below (:data:`DROPPED_RANGE_MARGIN`) readings the log repeats: as many as a code
    needs (rule 1 of :func:`no_return_reading`), from at least a tenth of the beams (and
    :data:`NO_RETURN_MIN_BEAMS`) and three scans, other codes aside. They are read as no
    return all the same (a ``range_max`` stated too short, say), and the message says how
    many, where, and how to keep them (a maximum range given explicitly).
    """
    r = np.asarray(ranges, dtype=float)
    with np.errstate(invalid="ignore"):
        r = np.where(np.isfinite(r) & (r < IMPLAUSIBLE_RANGE), r, np.nan)
    h = _RangeHistogram.of(r, NO_RETURN_MIN_SHARE, stated)
    code = h.code() if len(h.values) else None
    candidates = [v for v in (stated, code) if v is not None]
    if candidates:
        max_range = min(*candidates, IMPLAUSIBLE_RANGE)
    else:
        top = float(np.nanmax(r)) if np.isfinite(r).any() else 0.0
        max_range = min(
            default if default > top else float(np.nextafter(top, np.inf)), IMPLAUSIBLE_RANGE
        )
    if path is not None and len(h.values):
        n, scans, beams, lo, hi = h.dropped(max_range)
        spread = min(h.n_beams, max(NO_RETURN_MIN_BEAMS, int(np.ceil(0.1 * h.n_beams))))
        if n >= h.need and beams >= spread and scans >= 3:
            source = "the range the file states" if max_range == stated else "its no-return code"
            warnings.warn(
                f"{path}: the maximum range in use, {max_range:g} m ({source}), is well below "
                f"{plural(n, 'reading')} the log repeats from {lo:g} to {hi:g} m, in "
                f"{plural(scans, 'scan')} by {plural(beams, 'beam')}: all read as no return; "
                "give the laser's maximum range explicitly if they are returns",
                category,
                stacklevel=3,
            )
    return max_range, code
