"""The contract every SLAM back end keeps, so that one pipeline runs them all.

A back end is fed one scan at a time with the odometry pose at that scan
(:meth:`Backend.step`) and is asked for its final estimate at the end (:meth:`Backend.finish`).
It never sees a file, a log or a progress bar: :func:`fhslam.pipeline.run_slam` reads the
log, applies the laser's mount on the robot, hands over dropped scans as ``None`` and
collects the results (after KISS-ICP's ``pipeline.py``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.lines import Line
from fhslam.scan import Scan

__all__ = ["Backend", "FinalEstimate", "StepResult"]


@dataclass
class StepResult:
    """What one SLAM step did."""

    pose: NDArray[np.float64]
    """The pose estimate after the step, ``(x, y, theta)`` (laser frame in the map)."""
    n_lines: int
    """Lines extracted from the scan (Loop 1)."""
    n_matched: int
    """... of them matched to the map (Loop 2)."""
    n_added: int
    """New lines added to the map."""
    corrected: bool
    """Whether the pose was corrected from the map (Loop 3), not only predicted."""
    lines: list[Line] = field(default_factory=list, repr=False)
    """The scan's lines in the robot frame (Loop 1's output)."""


@dataclass(frozen=True)
class FinalEstimate:
    """A back end's estimate once the log is over."""

    map: list[Line]
    """The map: reference lines in the world frame."""
    poses: NDArray[np.float64] | None = None
    """Every step's pose revised after the fact (shape (T, 3)), as a pose graph does; ``None``
    when the poses the steps returned stand."""


@runtime_checkable
class Backend(Protocol):
    """A SLAM method as :func:`fhslam.pipeline.run_slam` drives it."""

    def step(self, scan: Scan | None, odometry: ArrayLike) -> StepResult:
        """Process one scan (``None``: the scan was dropped) taken at the odometry pose
        ``odometry`` (x, y, theta, in the odometry frame)."""
        ...

    def finish(self) -> FinalEstimate:
        """End the run: the map and, if revised, every step's pose."""
        ...
