"""CARMEN text logs: one message per line, ``NAME [contents] ipc_timestamp host logger_timestamp``.

Read: ``FLASER`` (old format) and ``ROBOTLASER1`` laser messages become the scans of a
:class:`~fhslam.io.log.Log`; ``PARAM`` lines are read for the laser's mount and beam
layout (below); ``#`` comments, blank lines and every other message (``ODOM``, ``SYNC``,
``TRUEPOS``, ...) are skipped, since the laser messages carry the odometry pose themselves.

The file is read as a stream of UTF-8 text lines (``\\n``, ``\\r\\n`` or ``\\r`` ending a
line), in pieces of at most :data:`MAX_LINE` characters, so that memory follows the scans
kept, not the size of the file; a byte-order mark at its start is skipped. A line that is
not text -- holding NUL bytes or bytes that are not UTF-8, or longer than :data:`MAX_LINE`
(a stretch of binary data; the NUL bytes a crash leaves at the end of a file) -- is skipped,
and the lines after it are read: one :class:`CarmenWarning` names the file, the line and
byte where the first such line starts, how many bytes were skipped and up to where. A file
without a laser message that has such lines is not a CARMEN text log (a
:class:`CarmenFormatError`). A gzip-compressed log (``fr101.carmen.log.gz``) is read as it
is, decompressed as a stream; damaged compressed data is a :class:`CarmenFormatError` naming
the file.

Write: one ``ODOM`` and one ``FLASER`` line per scan, every number as Python's shortest
round-trip ``repr``, so reading the file back gives exactly the same floats. The odometry
triple of a written laser line is the *odometry*, its laser-pose triple the odometry ⊕
``log.laser_offset``, and three ``PARAM`` lines state the mount; ground truth never goes
into a log.

Formats (CARMEN logger documentation; see ``data/SOURCES.md``)::

    PARAM name value ipc_timestamp hostname logger_timestamp
    ODOM x y theta tv rv accel ipc_timestamp hostname logger_timestamp
    FLASER n r_1 ... r_n x y theta odom_x odom_y odom_theta ipc_timestamp hostname logger_ts
    ROBOTLASER1 laser_type start_angle field_of_view angular_resolution maximum_range
        accuracy remission_mode n r_1 ... r_n num_remissions [remissions]
        laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv
        forward_safety_dist side_safety_dist turn_axis ipc_timestamp hostname logger_ts

Conventions, from CARMEN's source: its log reader (``readlog.c``,
``carmen_string_to_robot_laser_message_orig``) reads the ``FLASER`` triple ``x y theta``
into the message's ``laser_pose`` and ``odom_x odom_y odom_theta`` into its ``robot_pose``
(``ROBOTLASER1`` names them itself); the robot module that publishes these messages sets
``laser_pose = robot_pose ⊕ (robot_frontlaser_offset, robot_frontlaser_side_offset,
robot_frontlaser_angular_offset)`` (older versions: ``odom + offset·(cos θ, sin θ)``, the
heading unchanged); the laser module's ``laser_front_laser_resolution`` and
``laser_front_laser_fov`` are in degrees. The logger writes every parameter as
``PARAM module_variable value ...``.

The laser's mount, :attr:`Log.laser_offset <fhslam.io.log.Log>` (``robot_T_laser``, the
laser's pose in the robot frame), comes from

1. ``PARAM robot_frontlaser_offset`` (metres forward), ``robot_frontlaser_side_offset``
   (metres to the left) and ``robot_frontlaser_angular_offset`` (radians counter-
   clockwise) when the log states any of them (an unstated one is 0, CARMEN's default);
2. else the laser poses, when ``relative(odometry, laser_pose)`` is one constant (within
   :data:`MOUNT_TOLERANCE`) over every laser line of the log: then it is the mount. Logs
   whose laser pose is a *corrected* pose (scan-matched, or the true pose) give an offset
   that drifts with the correction, which says nothing about the mount; it is not used;
3. else none: the laser at the robot's origin.

When both ``PARAM`` lines and a constant laser-pose offset exist and differ (by more than
the tolerance), the ``PARAM`` values win and a :class:`CarmenWarning` names the file and
both values. The ``PARAM`` lines are the mount the robot was configured with, from which
CARMEN's robot module computed the laser poses; laser poses that disagree were written by
another program, and programs that rewrite CARMEN logs may copy the odometry into both
triples: a zero offset that states nothing.
``Log.laser_offset_source`` records the outcome: ``"PARAM"``, ``"laser pose"`` or
``"none"``.

The bearings of a ``FLASER`` scan: the line carries none. Without ``PARAM`` lines, CARMEN's
reader's guess applies (:func:`flaser_angles`). With ``PARAM laser_front_laser_resolution``
(degrees between beams) and/or ``laser_front_laser_fov`` (degrees), the scan is laid out
as CARMEN's laser driver does, centred on the laser's heading (see :func:`flaser_angles`);
the resolution times ``n − 1`` must not exceed 360°, and with both stated the beam count
must be ``fov / resolution + 1`` (or one less: the last beam dropped). ``ROBOTLASER1``
lines state their own start angle and resolution, which these ``PARAM`` lines do not
override.

A ``ROBOTLASER1`` line states what no laser has, and is a :class:`CarmenFormatError` naming
the line, if its header holds a non-finite value, a ``start_angle`` beyond ±2π (radians,
not degrees), an ``angular_resolution`` that is not positive or that spreads the beams over
more than 360°, or a ``maximum_range`` that is not a positive number of metres below
1000 m (:func:`fhslam.io.log.stated_range_problem`): such a line is corrupt, and ignoring
the one field would only hide it.

The maximum range in use (``Log.max_range``; readings at or beyond it are no returns): the
log's no-return code, the value read over and over at the top of the readings
(:func:`fhslam.io.log.no_return_reading`, e.g. 81.91 m in mit-csail); for ``ROBOTLASER1``
its stated ``maximum_range`` if that is smaller, and the code is only sought in the upper
half of the stated range (a value read over and over far below it is a distance measured
often, not a code). A ``FLASER`` log without a code gets CARMEN's assumption, 80 m (or
more, above its largest reading).

A ``PARAM`` of one of these five names without a value, with a non-numeric or non-finite
value, with an angle out of range (a resolution or field of view outside (0°, 360°], an
angular offset beyond ±2π, i.e. given in degrees), or stated twice with different values
is a :class:`CarmenFormatError`; every other ``PARAM`` (many hold strings) is ignored.
"""

from __future__ import annotations

import codecs
import gzip
import io
import math
import warnings
import zlib
from collections.abc import Iterator
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import IO

import numpy as np
from numpy.typing import NDArray

from fhslam.errors import InputError, InputWarning
from fhslam.geometry import compose, relative, wrap_angle
from fhslam.io.files import atomic_output, input_path, reading
from fhslam.io.log import (
    Log,
    check_readings,
    check_sequence,
    effective_max_range,
    is_number,
    stated_range_problem,
)

HOSTNAME = "fhslam"
FLASER_MAX_RANGE = 80.0
"""CARMEN's assumed maximum range of an old ``FLASER`` laser, metres."""


class CarmenFormatError(InputError):
    """A malformed CARMEN log. The message reads ``"{path}:{lineno}: {what is wrong}"``."""


class CarmenWarning(InputWarning):
    """A CARMEN log that contradicts itself, e.g. a ``PARAM`` mount its laser poses disagree
    with (the reader goes on with the rule of the module docstring)."""


MOUNT_TOLERANCE = (1e-3, 1e-3)
"""How far (metres, radians) the laser-pose offsets of a log may scatter and still count as
one constant mount, and how far the ``PARAM`` mount and that offset may differ and still
agree. CARMEN prints poses to 1e-6 (``%f``), a thousandth of this."""

MOUNT_PARAMS = (
    "robot_frontlaser_offset",
    "robot_frontlaser_side_offset",
    "robot_frontlaser_angular_offset",
)
"""The ``PARAM`` names of the front laser's mount ``(x, y, theta)``: metres, metres, radians."""

RESOLUTION_PARAM = "laser_front_laser_resolution"
"""The ``PARAM`` of the front laser's angle between beams, degrees."""

FOV_PARAM = "laser_front_laser_fov"
"""The ``PARAM`` of the front laser's field of view, degrees."""

_UNITS = dict.fromkeys(MOUNT_PARAMS[:2], "metres") | {
    MOUNT_PARAMS[2]: "radians",
    RESOLUTION_PARAM: "degrees",
    FOV_PARAM: "degrees",
}


_GUESSED_INCREMENT = {180: 1.0, 181: 1.0, 360: 0.5, 361: 0.5, 400: 0.25, 401: 0.25}
"""CARMEN's ``carmen_laser_guess_angle_increment``: degrees between beams by beam count."""


def flaser_angles(
    n: int, resolution: float | None = None, fov: float | None = None
) -> NDArray[np.float64]:
    """Bearings of an old-format ``FLASER`` scan of ``n`` beams, by CARMEN's own rule.

    The message carries no angles. CARMEN's log reader (``carmen_string_to_robot_laser_
    message_orig``: ``start_angle = -M_PI / 2`` and ``carmen_laser_guess_angle_increment``)
    assumes a scan starting at -90° (the right) in steps of 1° for 180 or 181 beams, 0.5° for
    360 or 361 and 0.25° for 400 or 401; any other count spreads over 180°, both ends
    included. So 181 beams span -90°..+90°, but 180 beams -90°..+89° (the last beam of a
    180° scan is not sent), not 180° in steps of 180°/179.

    The same rule reads bags converted from such logs (:func:`fhslam.io.read_bag`), whose
    converter wrote ``angle_increment = π/(n−1)`` without knowing better.

    Where the log states the laser's ``resolution`` and/or ``fov`` (``PARAM
    laser_front_laser_resolution`` / ``laser_front_laser_fov``, degrees), the scan is laid
    out as CARMEN's laser driver does (``laser_main.c``, ``set_laser_config_structure``):
    ``resolution`` apart, starting at ``-fov / 2``. An unstated ``fov`` is ``n × resolution``
    when that is one of the SICK's fields of view, 100° or 180° (the driver drops the last
    beam of such a scan: 180 beams at 1° start at -90°), else ``(n − 1) × resolution``
    (centred). An unstated ``resolution`` is the guess above where it fits ``fov`` (``n`` is
    ``fov / step`` or one more), else ``fov / (n − 1)``. Without either, the reader's rule.

    Raises
    ------
    ValueError
        For a non-positive ``resolution`` or ``fov``, or a layout spanning more than 360°.
    """
    if resolution is None and fov is None:
        step = _GUESSED_INCREMENT.get(n)
        span = np.pi if step is None else np.radians(step) * (n - 1)
        if n in (181, 361):
            span = np.pi  # exactly: the last bearing is +90°
        return np.linspace(-np.pi / 2, -np.pi / 2 + span, n)
    for name, value in (("resolution", resolution), ("fov", fov)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise ValueError(f"flaser_angles: {name} must be a positive number, got {value}")
    if resolution is None:
        guess = _GUESSED_INCREMENT.get(n)
        fits = guess is not None and any(math.isclose(fov / guess, k) for k in (n, n - 1))
        resolution = guess if fits else fov / max(n - 1, 1)
    if fov is None:
        whole = n * resolution
        fov = whole if any(math.isclose(whole, f) for f in (100.0, 180.0)) else (n - 1) * resolution
    if (n - 1) * resolution > 360.0 + 1e-9:
        raise ValueError(
            f"flaser_angles: {n} beams {resolution:g}° apart span {(n - 1) * resolution:g}°, "
            "more than a full turn"
        )
    return np.radians(-fov / 2) + np.radians(resolution) * np.arange(n)


# ----------------------------------------------------------------------------------- writing


def _fmt(values: NDArray | list[float]) -> str:
    """Space-separated shortest round-trip reprs of floats."""
    return " ".join(repr(float(v)) for v in np.asarray(values, dtype=float).ravel())


def write_carmen(log: Log, path: str | PathLike[str]) -> None:
    """Write ``log`` as a CARMEN text log: a ``#`` header, three ``PARAM`` lines stating the
    laser's mount, then ``ODOM`` + laser line per scan.

    Scans whose bearings follow :func:`flaser_angles` are written as old-format ``FLASER``;
    any other evenly spaced bearings as ``ROBOTLASER1`` (which records start angle and
    resolution). The poses written are ``log.odometry`` (``ODOM`` and the laser lines'
    odometry/robot triple) and, as CARMEN's robot module writes it, the laser pose
    ``log.odometry ⊕ log.laser_offset``; the mount itself goes into ``PARAM
    robot_frontlaser_offset``, ``robot_frontlaser_side_offset`` and
    ``robot_frontlaser_angular_offset``, so :func:`read_carmen` gets ``laser_offset`` back
    exactly. ``log.truth`` is not written (use :func:`fhslam.io.write_trajectory` for it).
    ``tv``/``rv`` in ``ODOM`` are finite differences of the odometry; ``accel`` is 0.

    Parameters
    ----------
    log : Log
    path : str or path-like
        Output file, overwritten.

    Raises
    ------
    ValueError
        If the bearings are not evenly spaced (no CARMEN message can describe them).
    """
    if log.angle_offsets is not None and np.any(log.angle_offsets != 0):
        raise ValueError(
            f"write_carmen: log {log.name!r} has per-scan bearing offsets (an interlaced "
            "laser), which CARMEN lines cannot describe"
        )
    n = log.n_beams
    angles = log.angles
    use_flaser = n >= 2 and np.allclose(angles, flaser_angles(n), rtol=0, atol=1e-12)
    if not use_flaser:
        res = (angles[-1] - angles[0]) / (n - 1) if n > 1 else 0.0
        if not np.allclose(angles, angles[0] + np.arange(n) * res, rtol=0, atol=1e-9):
            raise ValueError(
                f"write_carmen: log {log.name!r} has unevenly spaced beam angles, which "
                "neither FLASER nor ROBOTLASER1 can describe"
            )

    odom = log.odometry
    dt = np.diff(log.timestamps)
    step = relative(odom[:-1], odom[1:])
    ok = dt > 0
    tv = np.zeros(len(log))
    rv = np.zeros(len(log))
    tv[1:][ok] = np.sign(step[ok, 0]) * np.hypot(step[ok, 0], step[ok, 1]) / dt[ok]
    rv[1:][ok] = wrap_angle(step[ok, 2]) / dt[ok]

    laser = "FLASER" if use_flaser else "ROBOTLASER1"
    mount = np.asarray(log.laser_offset, dtype=float)
    mounted = bool(np.any(mount != 0))
    laser_poses = compose(odom, mount) if mounted else odom
    header = [
        f"# CARMEN log written by fhslam: {log.name}, {len(log)} scans of {n} beams, "
        f"max range {log.max_range!r} m",
        "# PARAM param_name param_value ipc_timestamp ipc_hostname logger_timestamp",
        "# ODOM x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp",
        "# FLASER num_readings [range_readings] x y theta odom_x odom_y odom_theta "
        "ipc_timestamp ipc_hostname logger_timestamp",
        f"# {laser} poses: the laser's (odometry + mount), then the odometry; "
        "no ground truth is stored in this file",
    ]
    t0 = repr(float(log.timestamps[0])) if len(log) else "0.0"
    params = [
        f"PARAM {name} {value!r} {t0} {HOSTNAME} {t0}"
        for name, value in zip(MOUNT_PARAMS, map(float, mount), strict=True)
    ]
    with atomic_output(path) as f:
        f.write("\n".join(header + params) + "\n")
        for k in range(len(log)):
            ts = repr(float(log.timestamps[k]))
            tail = f"{ts} {HOSTNAME} {ts}"
            pose = _fmt(odom[k])
            poses = f"{_fmt(laser_poses[k])} {pose}"
            f.write(f"ODOM {pose} {_fmt([tv[k], rv[k], 0.0])} {tail}\n")
            ranges = _fmt(log.ranges[k])
            if use_flaser:
                f.write(f"FLASER {n} {ranges} {poses} {tail}\n")
            else:
                fov, res = angles[-1] - angles[0], (angles[-1] - angles[0]) / (n - 1)
                head = _fmt([angles[0], fov, res, log.max_range, 0.01])
                f.write(
                    f"ROBOTLASER1 0 {head} 0 {n} {ranges} 0 {poses} "
                    f"{_fmt([tv[k], rv[k], 0.0, 0.0, 0.0])} {tail}\n"
                )


# ----------------------------------------------------------------------------------- reading


def _floats(tokens: list[str], what: str, where: str) -> NDArray[np.float64]:
    """Parse tokens as floats; a bad token raises :class:`CarmenFormatError` naming it."""
    try:
        return np.array(tokens, dtype=float)
    except ValueError:
        for i, tok in enumerate(tokens):
            try:
                float(tok)
            except ValueError:
                raise CarmenFormatError(
                    f"{where}: non-numeric {what} {tok!r} (item {i + 1} of {len(tokens)})"
                ) from None
        raise  # pragma: no cover (numpy refused a list Python accepts)


def _count(token: str, what: str, where: str) -> int:
    """Parse a non-negative integer count field."""
    try:
        value = int(token)
    except ValueError:
        raise CarmenFormatError(f"{where}: {what} must be an integer, got {token!r}") from None
    if value < 0:
        raise CarmenFormatError(f"{where}: {what} must be >= 0, got {value}")
    return value


def _check_finite(values: NDArray[np.float64], what: str, where: str) -> None:
    if not np.all(np.isfinite(values)):
        raise CarmenFormatError(f"{where}: non-finite {what} {values.tolist()}")


_Parsed = tuple[float, NDArray, NDArray, NDArray, NDArray | None]
"""What a laser-line parser returns: ``(ipc_timestamp, ranges, odometry, laser_pose,
geometry)``; ``geometry`` is ``[start_angle, resolution, max_range]`` or ``None``."""


def _parse_flaser(fields: list[str], where: str) -> _Parsed:
    """``FLASER n r_1..r_n x y theta odom_x odom_y odom_theta ipc_ts host logger_ts``."""
    if len(fields) < 2:
        raise CarmenFormatError(f"{where}: truncated FLASER line (no num_readings)")
    n = _count(fields[1], "FLASER num_readings", where)
    expected = n + 11
    if len(fields) != expected:
        # A complete line ends with "... ipc_timestamp hostname logger_timestamp".
        complete = len(fields) >= 11 and not is_number(fields[-2])
        if complete:
            raise CarmenFormatError(
                f"{where}: wrong reading count: FLASER num_readings is {n} but the line "
                f"holds {len(fields) - 11} readings"
            )
        raise CarmenFormatError(
            f"{where}: truncated FLASER line: num_readings {n} needs {expected} fields, "
            f"found {len(fields)}"
        )
    ranges = _floats(fields[2 : 2 + n], "range reading", where)
    poses = _floats(fields[2 + n : 8 + n], "pose value", where)
    _check_finite(poses, "pose", where)
    stamp = _floats([fields[8 + n]], "ipc_timestamp", where)
    _check_finite(stamp, "ipc_timestamp", where)
    return float(stamp[0]), ranges, poses[3:6], poses[0:3], None


def _parse_robotlaser1(fields: list[str], where: str) -> _Parsed:
    """``ROBOTLASER1`` (see the module docstring); returns the robot pose as odometry.

    The remission block ``num_remissions [remissions]`` is optional (older CARMEN versions
    write the message without it).
    """
    if len(fields) < 9:
        raise CarmenFormatError(f"{where}: truncated ROBOTLASER1 line ({len(fields)} fields)")
    head = _floats(fields[2:7], "ROBOTLASER1 header value", where)
    _check_finite(head, "ROBOTLASER1 start_angle/fov/resolution/max_range/accuracy", where)
    start, _fov, res, max_range, _acc = head
    n = _count(fields[8], "ROBOTLASER1 num_readings", where)
    if len(fields) == 23 + n:  # no remission block
        tail = fields[9 + n :]
    else:
        if len(fields) < 10 + n:
            raise CarmenFormatError(
                f"{where}: truncated ROBOTLASER1 line: num_readings {n} needs at least "
                f"{23 + n} fields, found {len(fields)}"
            )
        m = _count(fields[9 + n], "ROBOTLASER1 num_remissions", where)
        if len(fields) != 24 + n + m:
            raise CarmenFormatError(
                f"{where}: ROBOTLASER1 with {n} readings and {m} remissions needs "
                f"{24 + n + m} fields, found {len(fields)} (truncated line or wrong count)"
            )
        tail = fields[10 + n + m :]
    _check_robotlaser1_head(start, res, max_range, n, where)
    ranges = _floats(fields[9 : 9 + n], "range reading", where)
    poses = _floats(tail[0:6], "pose value", where)
    _check_finite(poses, "pose", where)
    stamp = _floats([tail[11]], "ipc_timestamp", where)
    _check_finite(stamp, "ipc_timestamp", where)
    return float(stamp[0]), ranges, poses[3:6], poses[0:3], np.array([start, res, max_range])


def _check_robotlaser1_head(start: float, res: float, max_range: float, n: int, where: str):
    """Refuse a ``ROBOTLASER1`` header no laser states (see the module docstring)."""
    if abs(start) > 2 * math.pi:
        raise CarmenFormatError(
            f"{where}: ROBOTLASER1 start_angle {start:g} is more than a full turn: CARMEN "
            "states it in radians, not degrees"
        )
    if res <= 0:
        raise CarmenFormatError(
            f"{where}: ROBOTLASER1 angular_resolution {res:g} rad: the angle between beams "
            "must be positive"
        )
    if (n - 1) * res > 2 * math.pi + 1e-9:
        raise CarmenFormatError(
            f"{where}: ROBOTLASER1 angular_resolution {res:g} rad spreads its {n} beams over "
            f"{math.degrees((n - 1) * res):g} degrees, more than a full turn"
        )
    problem = stated_range_problem(max_range)
    if problem is not None:
        raise CarmenFormatError(f"{where}: ROBOTLASER1 maximum_range {problem}")


@dataclass(frozen=True)
class _Param:
    value: float
    lineno: int


def _read_param(fields: list[str], where: str, lineno: int, params: dict[str, _Param]) -> None:
    """Record a ``PARAM name value ...`` line of one of the names this reader uses; ignore
    every other name (a value may be any string)."""
    if len(fields) < 2:
        raise CarmenFormatError(f"{where}: PARAM line without a parameter name")
    name = fields[1]
    unit = _UNITS.get(name)
    if unit is None:
        return
    if len(fields) < 3:
        raise CarmenFormatError(f"{where}: PARAM {name} has no value (a number of {unit})")
    try:
        value = float(fields[2])
    except ValueError:
        raise CarmenFormatError(
            f"{where}: PARAM {name} value {fields[2]!r} is not a number (of {unit})"
        ) from None
    if not math.isfinite(value):
        raise CarmenFormatError(f"{where}: PARAM {name} value {fields[2]!r} is not finite")
    if name in (RESOLUTION_PARAM, FOV_PARAM) and not 0 < value <= 360:
        raise CarmenFormatError(
            f"{where}: PARAM {name} {value:g} is not an angle in degrees in (0, 360]"
        )
    if name == MOUNT_PARAMS[2] and abs(value) > 2 * math.pi:
        raise CarmenFormatError(
            f"{where}: PARAM {name} {value:g} is more than a full turn: CARMEN states it in "
            "radians, not degrees"
        )
    seen = params.get(name)
    if seen is not None and seen.value != value:
        raise CarmenFormatError(
            f"{where}: PARAM {name} {value:g} contradicts line {seen.lineno}, which states "
            f"{seen.value:g}; a log whose laser changes is not supported"
        )
    if seen is None:
        params[name] = _Param(value, lineno)


def _fmt_pose(pose: NDArray) -> str:
    return f"(x {pose[0]:.6g} m, y {pose[1]:.6g} m, theta {pose[2]:.6g} rad)"


def _constant_offset(odometry: NDArray, laser_poses: NDArray) -> NDArray[np.float64] | None:
    """``relative(odometry, laser_pose)`` if it is one constant over the log (within
    :data:`MOUNT_TOLERANCE`), else ``None`` (corrected laser poses)."""
    if np.array_equal(odometry, laser_poses):
        return np.zeros(3)
    rel = relative(odometry, laser_poses)
    dev = rel - rel[0]
    dev[:, 2] = wrap_angle(dev[:, 2])
    tol_xy, tol_theta = MOUNT_TOLERANCE
    if np.abs(dev[:, :2]).max() > tol_xy or np.abs(dev[:, 2]).max() > tol_theta:
        return None
    offset = rel[0] + np.median(dev, axis=0)
    offset[2] = wrap_angle(offset[2])
    offset[np.abs(offset) < 1e-9] = 0.0  # below any log's print precision: exactly none
    return offset


def _laser_mount(
    path, kind: str, params: dict[str, _Param], odometry: NDArray, laser_poses: NDArray
) -> tuple[NDArray[np.float64], str]:
    """The laser's mount and where it came from (the rule of the module docstring)."""
    from_poses = _constant_offset(odometry, laser_poses)
    stated = [params.get(name) for name in MOUNT_PARAMS]
    if all(p is None for p in stated):
        if from_poses is not None:
            return from_poses, "laser pose"
        return np.zeros(3), "none"
    from_params = np.array([0.0 if p is None else p.value for p in stated])
    if from_poses is not None:
        diff = from_params - from_poses
        diff[2] = wrap_angle(diff[2])
        tol_xy, tol_theta = MOUNT_TOLERANCE
        if np.abs(diff[:2]).max() > tol_xy or abs(diff[2]) > tol_theta:
            linenos = [str(p.lineno) for p in stated if p is not None]
            lines = f"line{'s' if len(linenos) > 1 else ''} {', '.join(linenos)}"
            warnings.warn(
                f"{path}: PARAM lines ({lines}) state the laser mount "
                f"{_fmt_pose(from_params)}, but the laser poses of its {kind} lines sit at "
                f"{_fmt_pose(from_poses)} from the odometry; using the PARAM values",
                CarmenWarning,
                stacklevel=3,
            )
    return from_params, "PARAM"


def _flaser_layout(path, params: dict[str, _Param], n: int, first: int) -> NDArray[np.float64]:
    """The bearings of the ``FLASER`` scans of ``n`` beams (first line ``first``), from the
    resolution and field-of-view ``PARAM`` lines if stated (:func:`flaser_angles`)."""
    res, fov = params.get(RESOLUTION_PARAM), params.get(FOV_PARAM)
    if res is not None and (n - 1) * res.value > 360.0 + 1e-9:
        raise CarmenFormatError(
            f"{path}:{res.lineno}: PARAM {RESOLUTION_PARAM} {res.value:g} degrees gives the "
            f"{n} beams of the FLASER lines (first: line {first}) a field of view of "
            f"{(n - 1) * res.value:g} degrees, more than a full turn"
        )
    if res is not None and fov is not None:
        k = fov.value / res.value
        if not any(math.isclose(k, m, rel_tol=0, abs_tol=1e-6) for m in (n, n - 1)):
            raise CarmenFormatError(
                f"{path}:{res.lineno}: PARAM {RESOLUTION_PARAM} {res.value:g} and {FOV_PARAM} "
                f"{fov.value:g} (line {fov.lineno}) make scans of {k + 1:g} beams (or {k:g} "
                f"without the last), but the FLASER lines (first: line {first}) hold {n}"
            )
    return flaser_angles(
        n,
        resolution=None if res is None else res.value,
        fov=None if fov is None else fov.value,
    )


_PARSERS = {"FLASER": _parse_flaser, "ROBOTLASER1": _parse_robotlaser1}

MAX_LINE = 1 << 20
"""The longest line read, in characters (1 MiB of text; a laser line of 100,000 beams is
about 400 kB). A longer stretch without a line break is not a CARMEN line: it is skipped as
unreadable, read in pieces of this size, so that no more of it is ever held in memory."""


@dataclass
class _Unreadable:
    """The lines of a file that are not text (see :func:`_text_lines`), for one warning."""

    lines: int = 0
    nbytes: int = 0
    first_line: int = 0
    start: int = 0  # byte offset of the first unreadable line
    last_line: int = 0
    end: int = 0  # byte offset just past the last one
    reasons: set[str] = field(default_factory=set)
    size: int = 0  # bytes read in all
    gzip: bool = False  # the file starts with gzip's magic bytes

    def add(self, lineno: int, start: int, end: int, reason: str) -> None:
        if self.last_line != lineno:
            self.lines += 1
        if not self.first_line:
            self.first_line, self.start = lineno, start
        self.last_line, self.end = lineno, end
        self.nbytes += end - start
        self.reasons.add(reason)

    def describe(self) -> str:
        """``"N bytes that are not text (why) from byte X (line A) to ..."``."""
        why = ", ".join(sorted(self.reasons))
        end = "the end of the file" if self.end == self.size else f"byte {self.end}"
        if self.lines == 1:
            where = f"from byte {self.start} (line {self.first_line}) to {end}"
        else:
            where = (
                f"in {self.lines} lines from byte {self.start} (line {self.first_line}) to "
                f"{end} (line {self.last_line})"
            )
        return f"{self.nbytes} bytes that are not text ({why}) {where}"


class _Gunzipped(gzip.GzipFile):
    """A gzip-compressed file read as its text: damaged or cut compressed data is a
    :class:`CarmenFormatError` naming the file and how far it was read."""

    def __init__(self, raw: IO[bytes], path: Path) -> None:
        super().__init__(fileobj=raw, mode="rb")
        self._path, self._raw = path, raw

    def read(self, size: int = -1) -> bytes:
        return self._named(super().read, size)

    def read1(self, size: int = -1) -> bytes:
        return self._named(super().read1, size)

    def _named(self, read, size: int) -> bytes:
        try:
            return read(size)
        except (EOFError, OSError, zlib.error) as e:
            raise CarmenFormatError(
                f"{self._path}: damaged gzip data at about byte {self._raw.tell()} of the "
                f"compressed file ({e}); the log cannot be read past it"
            ) from None


def _text_lines(path: Path, junk: _Unreadable) -> Iterator[tuple[int, str]]:
    """The lines of the file ``path`` that are text, as ``(line number, line)``: decoded as
    UTF-8 (after gzip's decompression where the file starts with its magic bytes; byte
    offsets are then those of the decompressed text), a byte-order mark at the start
    skipped, any line break (``\\n``, ``\\r\\n``, ``\\r``) ending a line, as a text file
    is read. A line holding NUL bytes or bytes that are
    not UTF-8, or longer than :data:`MAX_LINE`, is not yielded but recorded in ``junk``. The
    file is read in pieces of at most :data:`MAX_LINE` characters."""
    with path.open("rb") as raw:
        junk.gzip = raw.read(2) == b"\x1f\x8b"
        raw.seek(0)
        f = _Gunzipped(raw, path) if junk.gzip else raw
        head = f.read(3)
        offset = 3 if head == codecs.BOM_UTF8 else 0
        f.seek(offset)
        text = io.TextIOWrapper(f, encoding="utf-8", errors="surrogateescape", newline="")
        with text:
            readline = text.readline
            lineno = 0
            long_line = False  # the last piece was cut at MAX_LINE: this one continues it
            while piece := readline(MAX_LINE):
                start = offset
                if piece.isascii():
                    offset += len(piece)
                    reason = "NUL bytes" if "\x00" in piece else None
                else:
                    try:
                        offset += len(piece.encode("utf-8"))
                        reason = "NUL bytes" if "\x00" in piece else None
                    except UnicodeEncodeError:  # a byte that is not UTF-8, as a surrogate
                        offset += len(piece.encode("utf-8", "surrogateescape"))
                        reason = "bytes that are not UTF-8"
                if not long_line:
                    lineno += 1
                cut = len(piece) == MAX_LINE and piece[-1] not in "\r\n"
                if long_line or cut:
                    reason = reason or f"a line of more than {MAX_LINE} characters"
                long_line = cut
                if reason is None:
                    yield lineno, piece
                else:
                    junk.add(lineno, start, offset, reason)
    junk.size = offset


def read_carmen(path: str | PathLike[str], max_range: float | None = None) -> Log:
    """Read the laser scans, their odometry and the laser's mount from a CARMEN text log.

    Parameters
    ----------
    path : str or path-like
        The ``.clf``/``.log`` file (UTF-8 text), or the same compressed with gzip.
    max_range : float, optional
        The laser's maximum range in metres (readings at or beyond it mean "no return").
        Default: the log's "no return" code (:func:`fhslam.io.log.no_return_reading`, e.g.
        81.91 m in mit-csail), or for ``ROBOTLASER1`` its ``maximum_range`` field if that is
        smaller (a code far below that field is none); a ``FLASER`` log without a code gets
        CARMEN's assumption for ``FLASER``, 80 m (or more, above its largest reading).

    Returns
    -------
    Log
        ``name`` is the file's stem; ``timestamps`` the ``ipc_timestamp`` of each scan;
        ``odometry`` the ``odom_x odom_y odom_theta`` triple of ``FLASER`` (the
        ``robot_pose`` of ``ROBOTLASER1``), its heading wrapped to (-pi, pi] (by
        :class:`~fhslam.io.log.Log`; a heading already in it is kept as written);
        ``angles`` :func:`flaser_angles` for ``FLASER`` (with the log's resolution and
        field-of-view ``PARAM`` lines, if any),
        ``start_angle + k * angular_resolution`` for ``ROBOTLASER1``; ``laser_offset`` the
        laser's mount and ``laser_offset_source`` where it came from, ``"PARAM"``,
        ``"laser pose"`` or ``"none"`` (the rule is in the module docstring);
        ``stated_max_range`` the ``maximum_range`` of the first ``ROBOTLASER1`` line. No truth.

    Raises
    ------
    MissingInputError
        If ``path`` does not exist.
    CarmenFormatError
        ``"{path}:{lineno}: ..."`` for a malformed laser line (truncated, non-numeric field,
        wrong reading count, non-finite pose), a ``ROBOTLASER1`` header no laser states (a
        start angle beyond ±2π, a resolution that is not positive or spans more than 360°, a
        maximum range that is not a positive number below 1000 m), a beam count differing
        from the first scan's,
        a malformed or contradictory ``PARAM`` of the mount or beam layout, a resolution
        that spreads the beams over more than 360° (or that contradicts the stated field of
        view), or a file with no laser messages (``"{path}: not a CARMEN text log: ..."``
        if it has lines that are not text) or with both FLASER and ROBOTLASER1.

    Warns
    -----
    CarmenWarning
        For lines that are not text (NUL bytes, bytes that are not UTF-8, longer than
        :data:`MAX_LINE`), skipped: one warning naming the line and byte where they start
        and how many bytes (the module docstring);
        when the ``PARAM`` mount and the constant offset of the laser poses disagree; where
        the scans' time runs backwards, repeats or leaps forward more than a day, or the
        odometry jumps
        (:func:`fhslam.io.log.check_sequence`); for readings that are negative, NaN,
        infinite or beyond 1000 m (read as no return), scans without a return, more than
        10,000 beams (:func:`fhslam.io.log.check_readings`). Each names the file and line.
        Without ``max_range``: when the maximum range found is well below readings the log
        repeats, which are then read as no return
        (:func:`fhslam.io.log.effective_max_range`).
    """
    path = input_path(path, "CARMEN log")
    stamps: list[float] = []
    scan_lines: list[int] = []  # the line of each scan, for warnings
    ranges: list[NDArray] = []
    odometry: list[NDArray] = []
    laser_poses: list[NDArray] = []
    params: dict[str, _Param] = {}
    first: tuple[str, int, int, NDArray | None] | None = None  # kind, lineno, n, geometry
    junk = _Unreadable()
    with reading(path):
        for lineno, line in _text_lines(path, junk):
            fields = line.split()
            if not fields or fields[0].startswith("#"):
                continue
            if fields[0] == "PARAM":
                _read_param(fields, f"{path}:{lineno}", lineno, params)
                continue
            if fields[0] not in _PARSERS:
                continue
            kind, where = fields[0], f"{path}:{lineno}"
            stamp, r, odom, laser_pose, geom = _PARSERS[kind](fields, where)
            if first is None:
                first = (kind, lineno, len(r), geom)
                if len(r) == 0:
                    raise CarmenFormatError(f"{where}: {kind} scan has no readings")
            elif kind != first[0]:
                raise CarmenFormatError(
                    f"{where}: {kind} after {first[0]} messages (line {first[1]}); logs "
                    "mixing both laser messages are not supported"
                )
            elif len(r) != first[2]:
                raise CarmenFormatError(
                    f"{where}: {kind} has {len(r)} readings but the first scan (line "
                    f"{first[1]}) has {first[2]}; varying beam counts are not supported"
                )
            elif geom is not None and not np.allclose(geom[:2], first[3][:2]):
                raise CarmenFormatError(
                    f"{where}: ROBOTLASER1 start_angle/angular_resolution {geom[:2]} differ"
                    f" from the first scan's {first[3][:2]} (line {first[1]})"
                )
            stamps.append(stamp)
            scan_lines.append(lineno)
            ranges.append(r)
            odometry.append(odom)
            laser_poses.append(laser_pose)
    if first is None:
        if junk.lines:
            gz = "gzip-compressed, and its text " if junk.gzip else ""
            raise CarmenFormatError(
                f"{path}: not a CARMEN text log: {gz}{junk.describe()}, and no FLASER or "
                "ROBOTLASER1 laser messages"
            )
        raise CarmenFormatError(f"{path}: no FLASER or ROBOTLASER1 laser messages found")
    if junk.lines:
        warnings.warn(
            f"{path}:{junk.first_line}: skipped {junk.describe()}; read the {len(stamps)} "
            "laser scans of the other lines",
            CarmenWarning,
            stacklevel=2,
        )

    kind, first_line, n, geom = first
    r = np.vstack(ranges)
    stated = None if kind == "FLASER" else float(geom[2])
    if kind == "FLASER":
        angles = _flaser_layout(path, params, n, first_line)
    else:
        angles = geom[0] + np.arange(n) * geom[1]
    if max_range is None:
        default = FLASER_MAX_RANGE if stated is None else stated
        max_range, _ = effective_max_range(r, stated, default, path, CarmenWarning)
    else:
        max_range = float(max_range)
    odo = np.vstack(odometry)
    check_sequence(path, np.array(stamps), odo, scan_lines, CarmenWarning)
    check_readings(path, r, max_range, scan_lines, CarmenWarning)
    mount, source = _laser_mount(path, kind, params, odo, np.vstack(laser_poses))
    return Log(
        name=path.stem,
        timestamps=np.array(stamps),
        ranges=r,
        angles=angles,
        odometry=odo,
        max_range=max_range,
        laser_offset=mount,
        laser_offset_source=source,
        stated_max_range=stated,
    )
