"""CARMEN text logs: one message per line, ``NAME [contents] ipc_timestamp host logger_timestamp``.

Read: ``FLASER`` (old format) and ``ROBOTLASER1`` laser messages become the scans of a
:class:`~fhslam.io.log.Log`; ``#`` comments, blank lines and every other message (``ODOM``,
``PARAM``, ``SYNC``, ``TRUEPOS``, ...) are skipped, since the laser messages carry the
odometry pose themselves.

Write: one ``ODOM`` and one ``FLASER`` line per scan, every number as Python's shortest
round-trip ``repr``, so reading the file back gives exactly the same floats. Both pose
triples of a written ``FLASER`` line are the *odometry*; ground truth never goes into a log.

Formats (CARMEN logger documentation; see ``data/SOURCES.md``)::

    ODOM x y theta tv rv accel ipc_timestamp hostname logger_timestamp
    FLASER n r_1 ... r_n x y theta odom_x odom_y odom_theta ipc_timestamp hostname logger_ts
    ROBOTLASER1 laser_type start_angle field_of_view angular_resolution maximum_range
        accuracy remission_mode n r_1 ... r_n num_remissions [remissions]
        laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv
        forward_safety_dist side_safety_dist turn_axis ipc_timestamp hostname logger_ts
"""

from __future__ import annotations

from os import PathLike

import numpy as np
from numpy.typing import NDArray

from fhslam.errors import InputError
from fhslam.geometry import relative, wrap_angle
from fhslam.io.files import atomic_output, input_path, reading
from fhslam.io.log import Log, effective_max_range, is_number

HOSTNAME = "fhslam"
FLASER_MAX_RANGE = 80.0
"""CARMEN's assumed maximum range of an old ``FLASER`` laser, metres."""


class CarmenFormatError(InputError):
    """A malformed CARMEN log. The message reads ``"{path}:{lineno}: {what is wrong}"``."""


_GUESSED_INCREMENT = {180: 1.0, 181: 1.0, 360: 0.5, 361: 0.5, 400: 0.25, 401: 0.25}
"""CARMEN's ``carmen_laser_guess_angle_increment``: degrees between beams by beam count."""


def flaser_angles(n: int) -> NDArray[np.float64]:
    """Bearings of an old-format ``FLASER`` scan of ``n`` beams, by CARMEN's own rule.

    The message carries no angles. CARMEN's log reader (``carmen_string_to_robot_laser_
    message_orig``: ``start_angle = -M_PI / 2`` and ``carmen_laser_guess_angle_increment``)
    assumes a scan starting at -90° (the right) in steps of 1° for 180 or 181 beams, 0.5° for
    360 or 361 and 0.25° for 400 or 401; any other count spreads over 180°, both ends
    included. So 181 beams span -90°..+90°, but 180 beams -90°..+89° (the last beam of a
    180° scan is not sent), not 180° in steps of 180°/179.

    The same rule reads bags converted from such logs (:func:`fhslam.io.read_bag`), whose
    converter wrote ``angle_increment = π/(n−1)`` without knowing better.
    """
    step = _GUESSED_INCREMENT.get(n)
    span = np.pi if step is None else np.radians(step) * (n - 1)
    if n in (181, 361):
        span = np.pi  # exactly: the last bearing is +90°
    return np.linspace(-np.pi / 2, -np.pi / 2 + span, n)


# ----------------------------------------------------------------------------------- writing


def _fmt(values: NDArray | list[float]) -> str:
    """Space-separated shortest round-trip reprs of floats."""
    return " ".join(repr(float(v)) for v in np.asarray(values, dtype=float).ravel())


def write_carmen(log: Log, path: str | PathLike[str]) -> None:
    """Write ``log`` as a CARMEN text log: a ``#`` header, then ``ODOM`` + laser line per scan.

    Scans whose bearings follow :func:`flaser_angles` are written as old-format ``FLASER``;
    any other evenly spaced bearings as ``ROBOTLASER1`` (which records start angle and
    resolution). The poses written are ``log.odometry``; ``log.truth`` is not written (use
    :func:`fhslam.io.write_trajectory` for it). ``tv``/``rv`` in ``ODOM`` are finite
    differences of the odometry; ``accel`` is 0.

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
    header = [
        f"# CARMEN log written by fhslam: {log.name}, {len(log)} scans of {n} beams, "
        f"max range {log.max_range!r} m",
        "# ODOM x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp",
        "# FLASER num_readings [range_readings] x y theta odom_x odom_y odom_theta "
        "ipc_timestamp ipc_hostname logger_timestamp",
        f"# {laser} poses are odometry; no ground truth is stored in this file",
    ]
    with atomic_output(path) as f:
        f.write("\n".join(header) + "\n")
        for k in range(len(log)):
            ts = repr(float(log.timestamps[k]))
            tail = f"{ts} {HOSTNAME} {ts}"
            pose = _fmt(odom[k])
            f.write(f"ODOM {pose} {_fmt([tv[k], rv[k], 0.0])} {tail}\n")
            ranges = _fmt(log.ranges[k])
            if use_flaser:
                f.write(f"FLASER {n} {ranges} {pose} {pose} {tail}\n")
            else:
                fov, res = angles[-1] - angles[0], (angles[-1] - angles[0]) / (n - 1)
                head = _fmt([angles[0], fov, res, log.max_range, 0.01])
                f.write(
                    f"ROBOTLASER1 0 {head} 0 {n} {ranges} 0 {pose} {pose} "
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


def _parse_flaser(fields: list[str], where: str) -> tuple[float, NDArray, NDArray, None]:
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
    return float(stamp[0]), ranges, poses[3:6], None


def _parse_robotlaser1(
    fields: list[str], where: str
) -> tuple[float, NDArray, NDArray, NDArray[np.float64]]:
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
    ranges = _floats(fields[9 : 9 + n], "range reading", where)
    poses = _floats(tail[0:6], "pose value", where)
    _check_finite(poses, "pose", where)
    stamp = _floats([tail[11]], "ipc_timestamp", where)
    _check_finite(stamp, "ipc_timestamp", where)
    return float(stamp[0]), ranges, poses[3:6], np.array([start, res, max_range])


_PARSERS = {"FLASER": _parse_flaser, "ROBOTLASER1": _parse_robotlaser1}


def read_carmen(path: str | PathLike[str], max_range: float | None = None) -> Log:
    """Read the laser scans and their odometry from a CARMEN text log.

    Parameters
    ----------
    path : str or path-like
        The ``.clf``/``.log`` file.
    max_range : float, optional
        The laser's maximum range in metres (readings at or beyond it mean "no return").
        Default: the log's "no return" code (:func:`fhslam.io.log.no_return_reading`, e.g.
        81.91 m in mit-csail), or for ``ROBOTLASER1`` its ``maximum_range`` field if that is
        smaller; a ``FLASER`` log without a code gets CARMEN's assumption for ``FLASER``,
        80 m (or more, above its largest reading).

    Returns
    -------
    Log
        ``name`` is the file's stem; ``timestamps`` the ``ipc_timestamp`` of each scan;
        ``odometry`` the ``odom_x odom_y odom_theta`` triple of ``FLASER`` (the
        ``robot_pose`` of ``ROBOTLASER1``); ``angles`` :func:`flaser_angles` for ``FLASER``,
        ``start_angle + k * angular_resolution`` for ``ROBOTLASER1``. No truth.

    Raises
    ------
    MissingInputError
        If ``path`` does not exist.
    CarmenFormatError
        ``"{path}:{lineno}: ..."`` for a malformed laser line (truncated, non-numeric field,
        wrong reading count, non-finite pose), a beam count differing from the first scan's,
        or a file with no laser messages or with both FLASER and ROBOTLASER1.
    """
    path = input_path(path, "CARMEN log")
    stamps: list[float] = []
    ranges: list[NDArray] = []
    odometry: list[NDArray] = []
    first: tuple[str, int, int, NDArray | None] | None = None  # kind, lineno, n, geometry
    try:
        with reading(path), path.open(encoding="utf-8") as f:
            for lineno, line in enumerate(f, start=1):
                fields = line.split()
                if not fields or fields[0].startswith("#") or fields[0] not in _PARSERS:
                    continue
                kind, where = fields[0], f"{path}:{lineno}"
                stamp, r, odom, geom = _PARSERS[kind](fields, where)
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
                ranges.append(r)
                odometry.append(odom)
    except UnicodeDecodeError as e:
        raise CarmenFormatError(f"{path}: not a CARMEN text log ({e.reason})") from None
    if first is None:
        raise CarmenFormatError(f"{path}: no FLASER or ROBOTLASER1 laser messages found")

    kind, _, n, geom = first
    r = np.vstack(ranges)
    if kind == "FLASER":
        angles = flaser_angles(n)
        inferred, _ = effective_max_range(r, None, FLASER_MAX_RANGE)
    else:
        angles = geom[0] + np.arange(n) * geom[1]
        inferred, _ = effective_max_range(r, float(geom[2]), float(geom[2]))
    return Log(
        name=path.stem,
        timestamps=np.array(stamps),
        ranges=r,
        angles=angles,
        odometry=np.vstack(odometry),
        max_range=inferred if max_range is None else float(max_range),
    )
