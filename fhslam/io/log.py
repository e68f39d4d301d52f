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
"""Smallest share of a log's valid beams that must read one exact value for
:func:`no_return_reading` to take it as the "no return" code."""


def no_return_reading(
    ranges: ArrayLike, min_share: float = NO_RETURN_MIN_SHARE, stated: float | None = None
) -> float | None:
    """The reading a log uses to say "no return", or ``None`` if it has none.

    A laser reports a beam without an echo as one fixed code, and a CARMEN ``FLASER`` line
    does not say which: 81.91 m (and 81.83 m) in the Freiburg logs of a SICK LMS in its
    80 m mode, 50.0 m in ACES, the maximum range in a simulated log. Real returns that far
    are sparse and scattered; a code is one exact value read over and over, at or near the
    laser's maximum range. Among the values in the upper half of the readings' scale (at
    least half the largest reading, or half the ``stated`` maximum range if that is more):

    1. the smallest value read by at least ``min_share`` of all valid beams (and by at least
       20) is the code;
    2. failing that, the largest reading is the code if it was read at least twice (a short
       log with few no-return beams; at worst a few real returns at the very top are lost).

    The largest reading alone is no evidence: a few long noisy returns beyond the code would
    turn every no-return beam into a phantom point.

    The ``stated`` range bounds the search from below: a value repeated far below it (less
    than half) is a distance the laser measured often, not its no-return code. So in a bag
    stating ``range_max`` 80 m whose scans repeat (a robot standing before a wall), a
    wall at 2.0 m read in every scan is no code, while a SICK's 81.91 m and 81.83 m (the
    Freiburg bags state 80 m and 81.9 m) and ACES's 50.0 m (it states 50 m) are.

    Parameters
    ----------
    ranges : array-like
        Every reading of the log, metres (NaN/inf and non-positive ones are ignored).
    min_share : float
        See above.
    stated : float, optional
        The maximum range the file states (:attr:`Log.stated_max_range`), metres.

    Returns
    -------
    float or None
        The code; readings at or above it are "no return".
    """
    r = np.asarray(ranges, dtype=float).ravel()
    r = r[np.isfinite(r) & (r > 0)]
    if r.size == 0:
        return None
    scale = r.max() if stated is None else max(r.max(), stated)
    values, counts = np.unique(r[r >= 0.5 * scale], return_counts=True)
    if values.size == 0:
        return None
    spikes = values[counts >= max(20.0, min_share * r.size)]
    if spikes.size:
        return float(spikes[0])
    if counts[-1] >= 2:
        return float(values[-1])
    return None


def effective_max_range(
    ranges: ArrayLike, stated: float | None, default: float
) -> tuple[float, float | None]:
    """The maximum range a reader gives a log: the smaller of the range the file states
    (``stated``, e.g. a bag's ``range_max``; a plausible one, :func:`stated_range_problem`)
    and its detected no-return code (:func:`no_return_reading`, searched near ``stated``:
    never far below it); with neither, ``default``, raised above the largest reading
    if needed so that no real reading is dropped. Never more than :data:`IMPLAUSIBLE_RANGE`:
    a reading that far is no measurement (:func:`check_readings` warns of it). Returns
    ``(max_range, code)``."""
    r = np.asarray(ranges, dtype=float)
    r = r[np.isfinite(r) & (r < IMPLAUSIBLE_RANGE)]
    code = no_return_reading(r, stated=stated)
    candidates = [v for v in (stated, code) if v is not None]
    if candidates:
        return min(*candidates, IMPLAUSIBLE_RANGE), code
    top = float(r.max()) if r.size else 0.0
    return min(
        default if default > top else float(np.nextafter(top, np.inf)), IMPLAUSIBLE_RANGE
    ), None


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
    the first place and how many more.

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
