"""`Log`: a sequence of laser scans with odometry, the one input format of the SLAM loops.

Both the simulator (:func:`fhslam.sim.simulate`) and the file readers
(:func:`fhslam.io.read_carmen`, ...) produce a :class:`Log`, so everything downstream works
the same on simulated and real data.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from os import PathLike
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.errors import InputError, InputWarning
from fhslam.geometry import wrap_angle
from fhslam.io.files import input_path, reading
from fhslam.scan import Scan


@dataclass(eq=False)
class Log:
    """Laser scans with the odometry pose at each scan, and optionally the ground truth.

    Attributes
    ----------
    name : str
        A label, e.g. the world name or the log file's stem.
    timestamps : ndarray, shape (T,)
        Time of each scan in seconds (CARMEN: the ``ipc_timestamp``).
    ranges : ndarray, shape (T, B)
        Measured range of every beam, metres. A beam with no return reads ``max_range``
        (or more, in real logs); such beams are invalid and are dropped before extraction.
    angles : ndarray, shape (B,)
        Bearing of each beam in the laser frame, radians, counter-clockwise from straight
        ahead (the same for every scan).
    odometry : ndarray, shape (T, 3)
        Odometry pose ``(x, y, theta)`` of the robot at each scan, in the odometry frame.
        ``theta`` is wrapped to (-pi, pi] on construction, whatever the source states (a
        CARMEN log may count the turns: 2 pi + 0.1); one already in it is kept as given.
    max_range : float
        Largest range the laser reports, metres; readings ``>= max_range`` mean "no return".
    truth : ndarray, shape (T, 3), or None
        Ground-truth pose at each scan (simulated logs only); ``theta`` wrapped as for
        ``odometry``.
    hits : ndarray of int, shape (T, B), or None
        Index of the wall of ``world`` hit by each beam, -1 for no return (simulated only).
    world : fhslam.sim.World or None
        The world the log was simulated in (typed loosely: :mod:`fhslam.io` sits below
        :mod:`fhslam.sim` and never imports it).
    laser_offset : ndarray, shape (3,)
        Pose of the laser on the robot, ``robot_T_laser`` (zero: the laser at the robot's
        origin). SLAM estimates laser poses ``odometry ⊕ laser_offset`` and reports robot
        poses. Its angle is wrapped as ``odometry``'s.
    angle_offsets : ndarray, shape (T,), or None
        Per-scan offset added to ``angles``, radians (an interlaced laser whose successive
        scans start a quarter of a beam apart, as in the Freiburg hospital log); ``None``:
        every scan uses ``angles``. Read scans through :meth:`scan`.
    laser_offset_source : str or None
        Where the reader found ``laser_offset``: for a CARMEN log ``"PARAM"``,
        ``"laser pose"`` or ``"none"`` (:func:`fhslam.io.read_carmen`), for a bag
        ``"tf_static"``; ``None``: not recorded (simulated logs).
    stated_max_range : float or None
        The maximum range the file itself states, metres (a bag's ``range_max``, a
        ``ROBOTLASER1`` line's ``maximum_range``); ``None``: the file states none (``FLASER``,
        simulated logs). It bounds the search for the no-return code
        (:func:`no_return_reading`); ``max_range`` is the range in use.
    """

    name: str
    timestamps: NDArray[np.float64]
    ranges: NDArray[np.float64]
    angles: NDArray[np.float64]
    odometry: NDArray[np.float64]
    max_range: float
    truth: NDArray[np.float64] | None = None
    hits: NDArray[np.intp] | None = None
    world: Any = None
    laser_offset: NDArray[np.float64] | None = None
    angle_offsets: NDArray[np.float64] | None = None
    laser_offset_source: str | None = None
    stated_max_range: float | None = None

    def __post_init__(self) -> None:
        self.laser_offset = (
            np.zeros(3) if self.laser_offset is None else np.asarray(self.laser_offset, float)
        )
        if self.laser_offset.shape != (3,) or not np.all(np.isfinite(self.laser_offset)):
            raise ValueError(f"Log.laser_offset must be 3 finite numbers, got {self.laser_offset}")
        self.laser_offset = _wrap_headings(self.laser_offset)
        self.timestamps = np.asarray(self.timestamps, dtype=float)
        self.ranges = np.asarray(self.ranges, dtype=float)
        self.angles = np.asarray(self.angles, dtype=float)
        self.odometry = np.asarray(self.odometry, dtype=float)
        self.max_range = float(self.max_range)
        t = len(self.timestamps)
        if self.timestamps.ndim != 1:
            raise ValueError(f"Log.timestamps must have shape (T,), got {self.timestamps.shape}")
        if self.angles.ndim != 1:
            raise ValueError(f"Log.angles must have shape (B,), got {self.angles.shape}")
        b = len(self.angles)
        if self.ranges.shape != (t, b):
            raise ValueError(
                f"Log.ranges must have shape (T, B) = ({t}, {b}), got {self.ranges.shape}"
            )
        if self.odometry.shape != (t, 3):
            raise ValueError(f"Log.odometry must have shape ({t}, 3), got {self.odometry.shape}")
        self.odometry = _wrap_headings(self.odometry)
        if not self.max_range > 0:
            raise ValueError(f"Log.max_range must be positive, got {self.max_range}")
        if self.truth is not None:
            self.truth = np.asarray(self.truth, dtype=float)
            if self.truth.shape != (t, 3):
                raise ValueError(f"Log.truth must have shape ({t}, 3), got {self.truth.shape}")
            self.truth = _wrap_headings(self.truth)
        if self.angle_offsets is not None:
            self.angle_offsets = np.asarray(self.angle_offsets, dtype=float)
            if self.angle_offsets.shape != (t,) or not np.all(np.isfinite(self.angle_offsets)):
                raise ValueError(
                    f"Log.angle_offsets must be {t} finite numbers, got shape "
                    f"{self.angle_offsets.shape}"
                )
        if self.hits is not None:
            self.hits = np.asarray(self.hits, dtype=np.intp)
            if self.hits.shape != (t, b):
                raise ValueError(f"Log.hits must have shape ({t}, {b}), got {self.hits.shape}")

    def __len__(self) -> int:
        """Number of scans T."""
        return len(self.timestamps)

    @property
    def n_beams(self) -> int:
        """Number of beams per scan B."""
        return len(self.angles)

    def scan(self, k: int) -> Scan:
        """Scan ``k`` in the laser frame, with the log's ``max_range`` (its bearings are
        ``angles`` plus the scan's ``angle_offsets`` entry, if any)."""
        angles = self.angles if self.angle_offsets is None else self.angles + self.angle_offsets[k]
        return Scan(self.ranges[k], angles, self.max_range)

    def __repr__(self) -> str:
        duration = self.timestamps[-1] - self.timestamps[0] if len(self) else 0.0
        extras = [s for s, v in (("truth", self.truth), ("world", self.world)) if v is not None]
        return (
            f"Log({self.name!r}: {len(self)} scans x {self.n_beams} beams, {duration:.1f} s, "
            f"max_range={self.max_range:g} m{', with ' + ' and '.join(extras) if extras else ''})"
        )


def _wrap_headings(poses: NDArray[np.float64]) -> NDArray[np.float64]:
    """``poses`` (shape (..., 3)) with every angle ``theta`` wrapped to (-pi, pi].

    Only the angles outside the interval change (:func:`~fhslam.geometry.wrap_angle`); one
    inside it is kept bit for bit, and ``poses`` itself is never written to (a changed copy
    is returned). Non-finite angles are left alone.
    """
    theta = poses[..., 2]
    bad = np.isfinite(theta) & ((theta <= -np.pi) | (theta > np.pi))
    if not bad.any():
        return poses
    poses = poses.copy()
    theta = poses[..., 2]  # a view of the copy
    theta[bad] = wrap_angle(theta[bad])
    return poses


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
        The maximum range the file states (:attr:`Log.stated_max_range`), metres.

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
    (``stated``, e.g. a bag's ``range_max``; a plausible one, :func:`stated_range_problem`)
    and its detected no-return code (:func:`no_return_reading`, searched near ``stated``:
    never far below it); with neither, ``default``, raised above the largest reading
    if needed so that no real reading is dropped. Never more than :data:`IMPLAUSIBLE_RANGE`:
    a reading that far is no measurement (:func:`check_readings` warns of it). Returns
    ``(max_range, code)``.

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


def is_number(token: str) -> bool:
    """Whether a text field of a log or trajectory file parses as a float."""
    try:
        float(token)
    except ValueError:
        return False
    return True


def read_numeric_table(
    path: str | PathLike[str],
    columns: str,
    error: type[InputError],
    what: str,
    check: Callable[[list[float], str], None] | None = None,
    with_lines: bool = False,
) -> NDArray[np.float64] | tuple[NDArray[np.float64], list[int]]:
    """Rows of a whitespace-separated text file of numbers (``#`` comments, blank lines).

    Parameters
    ----------
    path : path-like
    columns : str
        The expected fields, e.g. ``"timestamp x y theta"``; each row must have as many.
    error : type
        The :class:`~fhslam.errors.InputError` subclass to raise, with ``"{path}:{lineno}: ..."``.
    what : str
        What a row is, for the message of an empty file (e.g. ``"poses"``).
    check : callable, optional
        ``check(row, where)`` raising ``error`` for a row that is wrong in a file-specific way.

    with_lines : bool
        Also return the file line of each row.

    Returns
    -------
    ndarray, shape (R, len(columns.split()))
        And, with ``with_lines``, the list of the rows' line numbers.
    """
    path = input_path(path)
    n = len(columns.split())
    rows: list[list[float]] = []
    linenos: list[int] = []
    try:
        with reading(path), path.open(encoding="utf-8") as f:
            for lineno, line in enumerate(f, start=1):
                fields = line.split()
                if not fields or fields[0].startswith("#"):
                    continue
                where = f"{path}:{lineno}"
                if len(fields) != n:
                    raise error(f"{where}: expected {n} fields '{columns}', found {len(fields)}")
                try:
                    row = [float(v) for v in fields]
                except ValueError:
                    bad = next(v for v in fields if not is_number(v))
                    raise error(f"{where}: non-numeric value {bad!r}") from None
                if not all(np.isfinite(row)):
                    raise error(f"{where}: non-finite value in {fields}")
                if check is not None:
                    check(row, where)
                rows.append(row)
                linenos.append(lineno)
    except UnicodeDecodeError as e:
        raise error(f"{path}: not a text file ({e.reason})") from None
    if not rows:
        raise error(f"{path}: no {what} found")
    return (np.array(rows), linenos) if with_lines else np.array(rows)


def scan_of(log, k: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Scan ``k`` of ``log`` as ``(ranges, angles)``: :meth:`Log.scan` for a :class:`Log`,
    ``(log.ranges[k], log.angles)`` for any other object with those attributes."""
    scan = getattr(log, "scan", None)
    if not callable(scan):
        return log.ranges[k], log.angles
    s = scan(k)
    return s.ranges, s.angles
