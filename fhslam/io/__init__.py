"""Reading and writing logs and trajectories: CARMEN text logs, trajectory text files."""

from fhslam.io.carmen import CarmenFormatError, flaser_angles, read_carmen, write_carmen
from fhslam.io.log import Log
from fhslam.io.trajectory import TrajectoryFormatError, read_trajectory, write_trajectory

__all__ = [
    "CarmenFormatError",
    "Log",
    "TrajectoryFormatError",
    "flaser_angles",
    "read_carmen",
    "read_trajectory",
    "write_carmen",
    "write_trajectory",
]
