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

The reader is this module (:func:`read_carmen`, and the rules above for the mount, the
bearings and the maximum range); the line reader, the line parsers, the writer and the
conventions they share are modules of their own (:mod:`fhslam.io.carmen_lines`,
:mod:`fhslam.io.carmen_parse`, :mod:`fhslam.io.carmen_write`,
:mod:`fhslam.io.carmen_format`), their public names importable from here too.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from fhslam.geometry import relative, wrap_angle
from fhslam.io.carmen_format import (
    FOV_PARAM,
    MOUNT_PARAMS,
    RESOLUTION_PARAM,
    CarmenFormatError,
    CarmenWarning,
    flaser_angles,
)
from fhslam.io.carmen_lines import MAX_LINE, _text_lines, _Unreadable
from fhslam.io.carmen_parse import _PARSERS, _Param, _Parsed, _read_param
from fhslam.io.carmen_write import HOSTNAME, write_carmen
from fhslam.io.files import input_path, reading
from fhslam.io.log import Log, check_readings, check_sequence, effective_max_range

__all__ = [
    "FLASER_MAX_RANGE",
    "FOV_PARAM",
    "HOSTNAME",
    "MAX_LINE",
    "MOUNT_PARAMS",
    "MOUNT_TOLERANCE",
    "RESOLUTION_PARAM",
    "CarmenFormatError",
    "CarmenWarning",
    "flaser_angles",
    "read_carmen",
    "write_carmen",
]

FLASER_MAX_RANGE = 80.0
"""CARMEN's assumed maximum range of an old ``FLASER`` laser, metres."""

MOUNT_TOLERANCE = (1e-3, 1e-3)
"""How far (metres, radians) the laser-pose offsets of a log may scatter and still count as
one constant mount, and how far the ``PARAM`` mount and that offset may differ and still
agree. CARMEN prints poses to 1e-6 (``%f``), a thousandth of this."""


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


@dataclass
class _Scans:
    """The laser lines of a CARMEN log as read (:func:`_read_scans`), with its mount and
    layout ``PARAM`` lines and the lines that are not text."""

    stamps: list[float] = field(default_factory=list)
    lines: list[int] = field(default_factory=list)  # the line of each scan, for warnings
    ranges: list[NDArray] = field(default_factory=list)
    odometry: list[NDArray] = field(default_factory=list)
    laser_poses: list[NDArray] = field(default_factory=list)
    params: dict[str, _Param] = field(default_factory=dict)
    first: tuple[str, int, int, NDArray | None] | None = None  # kind, lineno, n, geometry
    junk: _Unreadable = field(default_factory=_Unreadable)

    def add(self, kind: str, lineno: int, where: str, parsed: _Parsed) -> None:
        """Keep the laser line ``lineno`` (``where``: ``"{path}:{lineno}"``), parsed; one
        that does not fit the first scan (message, beam count, layout) is refused."""
        stamp, r, odom, laser_pose, geom = parsed
        first = self.first
        if first is None:
            self.first = (kind, lineno, len(r), geom)
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
        self.stamps.append(stamp)
        self.lines.append(lineno)
        self.ranges.append(r)
        self.odometry.append(odom)
        self.laser_poses.append(laser_pose)


def _read_scans(path: Path) -> _Scans:
    """The laser lines and the mount and layout ``PARAM`` lines of the log ``path``, every
    other line skipped; a log without a laser line is a :class:`CarmenFormatError`."""
    scans = _Scans()
    with reading(path):
        for lineno, line in _text_lines(path, scans.junk):
            fields = line.split()
            if not fields or fields[0].startswith("#"):
                continue
            if fields[0] == "PARAM":
                _read_param(fields, f"{path}:{lineno}", lineno, scans.params)
                continue
            if fields[0] not in _PARSERS:
                continue
            kind, where = fields[0], f"{path}:{lineno}"
            scans.add(kind, lineno, where, _PARSERS[kind](fields, where))
    if scans.first is None:
        junk = scans.junk
        if junk.lines:
            gz = "gzip-compressed, and its text " if junk.gzip else ""
            raise CarmenFormatError(
                f"{path}: not a CARMEN text log: {gz}{junk.describe()}, and no FLASER or "
                "ROBOTLASER1 laser messages"
            )
        raise CarmenFormatError(f"{path}: no FLASER or ROBOTLASER1 laser messages found")
    return scans


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
    scans = _read_scans(path)
    junk = scans.junk
    if junk.lines:
        warnings.warn(
            f"{path}:{junk.first_line}: skipped {junk.describe()}; read the "
            f"{len(scans.stamps)} laser scans of the other lines",
            CarmenWarning,
            stacklevel=2,
        )
    kind, first_line, n, geom = scans.first
    r = np.vstack(scans.ranges)
    stated = None if kind == "FLASER" else float(geom[2])
    if kind == "FLASER":
        angles = _flaser_layout(path, scans.params, n, first_line)
    else:
        angles = geom[0] + np.arange(n) * geom[1]
    if max_range is None:
        default = FLASER_MAX_RANGE if stated is None else stated
        max_range, _ = effective_max_range(r, stated, default, path, CarmenWarning)
    else:
        max_range = float(max_range)
    odo = np.vstack(scans.odometry)
    check_sequence(path, np.array(scans.stamps), odo, scans.lines, CarmenWarning)
    check_readings(path, r, max_range, scans.lines, CarmenWarning)
    mount, source = _laser_mount(path, kind, scans.params, odo, np.vstack(scans.laser_poses))
    return Log(
        name=path.stem,
        timestamps=np.array(scans.stamps),
        ranges=r,
        angles=angles,
        odometry=odo,
        max_range=max_range,
        laser_offset=mount,
        laser_offset_source=source,
        stated_max_range=stated,
    )
