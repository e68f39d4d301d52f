"""One laser scan, and the one rule that turns its beams into points.

A scan is what the laser reports at one instant: a range per beam and the beams' bearings in
the laser frame (counter-clockwise from straight ahead, radians). A beam without a return
(its range NaN, infinite, not positive, or at or beyond the laser's maximum range) is
*dropped* by :func:`scan_to_points`, never turned into a point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.geometry import polar_to_points

__all__ = ["Scan", "scan_to_points"]


def scan_to_points(
    ranges: ArrayLike,
    angles: ArrayLike,
    max_range: float | None = None,
    min_range: float = 0.0,
) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """Turn one scan into points in the laser frame, dropping invalid beams.

    A beam is invalid when its range is NaN, infinite, ``<= min_range`` or ``>= max_range``
    ("no return"); it is dropped, never turned into a point.

    Parameters
    ----------
    ranges, angles : array-like, shape (B,)
        Ranges (metres) and bearings (radians) of the beams, in scan order.
    max_range : float, optional
        The sensor's maximum range; readings at or beyond it mean "no return".
    min_range : float
        Readings at or below it are dropped too, metres.

    Returns
    -------
    points : ndarray, shape (N, 2)
    beams : ndarray of int, shape (N,)
        Index of the beam each point came from.
    """
    r = np.asarray(ranges, dtype=float)
    a = np.asarray(angles, dtype=float)
    if r.ndim != 1 or r.shape != a.shape:
        raise ValueError(
            f"ranges and angles must be 1-D arrays of equal length, got {r.shape} and {a.shape}"
        )
    if not np.all(np.isfinite(a)):
        raise ValueError("angles contain NaN or inf")
    valid = np.isfinite(r) & (r > min_range)
    if max_range is not None:
        valid &= r < max_range
    beams = np.flatnonzero(valid)
    return polar_to_points(r[beams], a[beams]), beams


@dataclass(frozen=True, eq=False)
class Scan:
    """One laser scan in the laser frame.

    Attributes
    ----------
    ranges : ndarray, shape (B,)
        Range of each beam, metres; NaN, inf and readings ``>= max_range`` mean no return.
    angles : ndarray, shape (B,)
        Bearing of each beam, radians, counter-clockwise from straight ahead.
    max_range : float or None
        The laser's maximum range, metres (``None``: only NaN/inf/non-positive are invalid).
    """

    ranges: NDArray[np.float64]
    angles: NDArray[np.float64]
    max_range: float | None = None

    def __post_init__(self) -> None:
        r = np.asarray(self.ranges, dtype=float)
        a = np.asarray(self.angles, dtype=float)
        if r.ndim != 1 or r.shape != a.shape:
            raise ValueError(
                f"Scan: ranges and angles must be 1-D of equal length, got {r.shape} and {a.shape}"
            )
        object.__setattr__(self, "ranges", r)
        object.__setattr__(self, "angles", a)
        if self.max_range is not None and not self.max_range > 0:
            raise ValueError(f"Scan: max_range must be positive, got {self.max_range}")

    def __len__(self) -> int:
        """Number of beams B."""
        return len(self.ranges)

    def points(
        self, max_range: float | None = None
    ) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
        """:func:`scan_to_points` of this scan: points (N, 2) and their beam indices (N,).

        ``max_range`` lowers the cut-off below the laser's own (e.g. to keep far, sparse
        returns out of a point cloud)."""
        cap = self.max_range
        if max_range is not None:
            cap = max_range if cap is None else min(cap, max_range)
        return scan_to_points(self.ranges, self.angles, max_range=cap)
