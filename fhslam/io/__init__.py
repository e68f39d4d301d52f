"""Reading and writing logs, trajectories and maps: CARMEN logs, trajectory files, map JSON."""

from fhslam.io.carmen import CarmenFormatError, flaser_angles, read_carmen, write_carmen
from fhslam.io.log import Log
from fhslam.io.mapfile import MapFormatError, lines_from_segments, read_map, write_map
from fhslam.io.trajectory import TrajectoryFormatError, read_trajectory, write_trajectory

__all__ = [
    "CarmenFormatError",
    "Log",
    "MapFormatError",
    "TrajectoryFormatError",
    "flaser_angles",
    "lines_from_segments",
    "read_carmen",
    "read_map",
    "read_trajectory",
    "write_carmen",
    "write_map",
    "write_trajectory",
]
