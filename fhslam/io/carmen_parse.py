"""Parsing the lines of a CARMEN text log: the laser messages and the ``PARAM`` lines the
reader uses.

A laser line becomes ``(ipc_timestamp, ranges, odometry, laser_pose, geometry)``
(:data:`_PARSERS`, by message name); a ``PARAM`` line of the laser's mount or beam layout
is recorded with its line (:func:`_read_param`), every other ``PARAM`` ignored. Formats
(CARMEN logger documentation; see ``data/SOURCES.md``)::

    PARAM name value ipc_timestamp hostname logger_timestamp
    FLASER n r_1 ... r_n x y theta odom_x odom_y odom_theta ipc_timestamp hostname logger_ts
    ROBOTLASER1 laser_type start_angle field_of_view angular_resolution maximum_range
        accuracy remission_mode n r_1 ... r_n num_remissions [remissions]
        laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv
        forward_safety_dist side_safety_dist turn_axis ipc_timestamp hostname logger_ts

(``ROBOTLASER1``'s remission block is optional: older CARMEN versions write the message
without it.)

Bad input is a :class:`~fhslam.io.carmen_format.CarmenFormatError` naming the line
(``"{path}:{lineno}: ..."``): a truncated laser line, a non-numeric field, a reading count
that does not match the readings, a non-finite pose or timestamp; a ``ROBOTLASER1`` header
no laser states -- a non-finite value, a ``start_angle`` beyond ±2π (radians, not
degrees), an ``angular_resolution`` that is not positive or that spreads the beams over
more than 360°, a ``maximum_range`` that is not a positive number of metres below 1000 m
(:func:`fhslam.io.plausibility.stated_range_problem`); a ``PARAM`` of the mount or layout
without a value, with a non-numeric or non-finite value, with an angle out of range (a
resolution or field of view outside (0°, 360°], an angular offset beyond ±2π, i.e. given in
degrees), or stated twice with different values.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from fhslam.io.carmen_format import (
    FOV_PARAM,
    MOUNT_PARAMS,
    RESOLUTION_PARAM,
    CarmenFormatError,
)
from fhslam.io.log import is_number
from fhslam.io.plausibility import stated_range_problem

_UNITS = dict.fromkeys(MOUNT_PARAMS[:2], "metres") | {
    MOUNT_PARAMS[2]: "radians",
    RESOLUTION_PARAM: "degrees",
    FOV_PARAM: "degrees",
}


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


_PARSERS = {"FLASER": _parse_flaser, "ROBOTLASER1": _parse_robotlaser1}
