"""`Log`: a sequence of laser scans with odometry, the one input format of the SLAM loops.

Both the simulator (:func:`fhslam.sim.simulate`) and the file readers
(:func:`fhslam.io.read_carmen`, ...) produce a :class:`Log`, so everything downstream works
the same on simulated and real data.

The no-return detection (:mod:`fhslam.io.no_return`) and the plausibility checks the
readers share (:mod:`fhslam.io.plausibility`) live in modules of their own; their public
names can be imported from here too.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from os import PathLike
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fhslam.errors import InputError
from fhslam.geometry import wrap_angle
from fhslam.io.files import input_path, reading
from fhslam.io.no_return import (
    DROPPED_RANGE_MARGIN,
    NO_RETURN_MIN_BEAMS,
    NO_RETURN_MIN_COUNT,
    NO_RETURN_MIN_SHARE,
    NO_RETURN_PEAK,
    NO_RETURN_WINDOW,
    NO_RETURN_WINDOW_MIN,
    REPEATED_SCAN_SHARE,
    REPEATED_SCAN_TOLERANCE,
    counted_readings,
    effective_max_range,
    no_return_reading,
)
from fhslam.io.plausibility import (
    IMPLAUSIBLE_RANGE,
    ODOMETRY_JUMP,
    PLAUSIBLE_BEAMS,
    SCAN_INTERVAL_MAX,
    SCAN_INTERVAL_MIN,
    TIME_JUMP,
    check_readings,
    check_sequence,
    plural,
    stated_range_problem,
)
from fhslam.scan import Scan

__all__ = [
    "DROPPED_RANGE_MARGIN",
    "IMPLAUSIBLE_RANGE",
    "NO_RETURN_MIN_BEAMS",
    "NO_RETURN_MIN_COUNT",
    "NO_RETURN_MIN_SHARE",
    "NO_RETURN_PEAK",
    "NO_RETURN_WINDOW",
    "NO_RETURN_WINDOW_MIN",
    "ODOMETRY_JUMP",
    "PLAUSIBLE_BEAMS",
    "REPEATED_SCAN_SHARE",
    "REPEATED_SCAN_TOLERANCE",
    "SCAN_INTERVAL_MAX",
    "SCAN_INTERVAL_MIN",
    "TIME_JUMP",
    "Log",
    "check_readings",
    "check_sequence",
    "counted_readings",
    "effective_max_range",
    "is_number",
    "no_return_reading",
    "plural",
    "read_numeric_table",
    "scan_of",
    "stated_range_problem",
]


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
