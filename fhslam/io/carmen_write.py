"""Writing a :class:`~fhslam.io.log.Log` as a CARMEN text log (:func:`write_carmen`).

One ``ODOM`` and one laser line per scan, after a ``#`` header and three ``PARAM`` lines
stating the laser's mount (:data:`~fhslam.io.carmen_format.MOUNT_PARAMS`). Every number is
Python's shortest round-trip ``repr``, so reading the file back
(:func:`fhslam.io.read_carmen`) gives exactly the same floats. The odometry triple of a
written laser line is the *odometry*, its laser-pose triple the odometry ⊕
``log.laser_offset``; ground truth never goes into a log. Scans whose bearings follow
:func:`~fhslam.io.carmen_format.flaser_angles` are written as old-format ``FLASER`` lines,
other evenly spaced bearings as ``ROBOTLASER1`` (which states its start angle and
resolution); uneven bearings and per-scan bearing offsets cannot be written (a
:class:`ValueError`). The output is written atomically (:func:`fhslam.io.files.atomic_output`).

Lines written (CARMEN logger documentation)::

    PARAM name value ipc_timestamp hostname logger_timestamp
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

from fhslam.geometry import compose, relative, wrap_angle
from fhslam.io.carmen_format import MOUNT_PARAMS, flaser_angles
from fhslam.io.files import atomic_output
from fhslam.io.log import Log

HOSTNAME = "fhslam"
"""The host name of the lines written."""


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
    ``robot_frontlaser_angular_offset``, so :func:`~fhslam.io.carmen.read_carmen` gets
    ``laser_offset`` back exactly. ``log.truth`` is not written (use
    :func:`fhslam.io.write_trajectory` for it).
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
