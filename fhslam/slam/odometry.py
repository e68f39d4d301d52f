"""Dead reckoning as a SLAM back end: the baseline every method must beat."""

from __future__ import annotations

from numpy.typing import ArrayLike

from fhslam.geometry import as_pose
from fhslam.scan import Scan
from fhslam.slam.base import FinalEstimate, StepResult

__all__ = ["OdometryOnly"]


class OdometryOnly:
    """The odometry pose as the estimate, no map: what the robot knows without its laser."""

    def step(self, scan: Scan | None, odometry: ArrayLike) -> StepResult:
        """Take the odometry pose as it is; the scan is not used."""
        return StepResult(as_pose(odometry, "odometry").copy(), 0, 0, 0, False)

    def finish(self) -> FinalEstimate:
        """No map."""
        return FinalEstimate([])
