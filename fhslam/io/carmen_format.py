"""CARMEN log conventions the reader and the writer share.

The errors and warnings of a CARMEN log (:class:`CarmenFormatError`, a malformed log, the
message naming the file and line; :class:`CarmenWarning`, a log read as documented that
contradicts itself or holds implausible content); the names of the ``PARAM`` lines that
state the front laser's mount (:data:`MOUNT_PARAMS`: metres forward, metres to the left,
radians counter-clockwise) and its beam layout (:data:`RESOLUTION_PARAM`,
:data:`FOV_PARAM`: degrees); and the bearings of an old-format ``FLASER`` scan, which the
line does not state (:func:`flaser_angles`: CARMEN's log reader's guess, or its laser
driver's layout where the ``PARAM`` lines state one). The format and the reader's rules are
described in :mod:`fhslam.io.carmen`.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from fhslam.errors import InputError, InputWarning


class CarmenFormatError(InputError):
    """A malformed CARMEN log. The message reads ``"{path}:{lineno}: {what is wrong}"``."""


class CarmenWarning(InputWarning):
    """A CARMEN log that contradicts itself, e.g. a ``PARAM`` mount its laser poses disagree
    with (the reader goes on with the rule of :mod:`fhslam.io.carmen`)."""


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
