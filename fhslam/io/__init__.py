"""Reading and writing logs, trajectories and maps: CARMEN logs, trajectory files, map JSON,
keyframe-graph JSON, benchmark relations files. Every reader reports bad input as a
:class:`fhslam.errors.InputError` naming the file (and line); every writer writes atomically
(:mod:`fhslam.io.files`). Input that is readable but implausible is read as documented with
a warning, a subclass of :class:`fhslam.errors.InputWarning` (``CarmenWarning``,
``BagWarning``, ``TrajectoryWarning``), naming the file and line."""

from fhslam.io.carmen import (
    CarmenFormatError,
    CarmenWarning,
    flaser_angles,
    read_carmen,
    write_carmen,
)
from fhslam.io.graphfile import GraphFormatError, KeyframeGraph, read_graph, write_graph
from fhslam.io.log import Log, effective_max_range, no_return_reading
from fhslam.io.mapfile import MapFormatError, lines_from_segments, read_map, write_map
from fhslam.io.relations import RelationsFormatError, read_relations, write_relations
from fhslam.io.rosbag import BagFormatError, BagWarning, is_bag, read_bag
from fhslam.io.trajectory import (
    TrajectoryFormatError,
    TrajectoryWarning,
    read_trajectory,
    write_trajectory,
)

__all__ = [
    "BagFormatError",
    "BagWarning",
    "CarmenFormatError",
    "CarmenWarning",
    "GraphFormatError",
    "KeyframeGraph",
    "Log",
    "MapFormatError",
    "RelationsFormatError",
    "TrajectoryFormatError",
    "TrajectoryWarning",
    "effective_max_range",
    "flaser_angles",
    "is_bag",
    "lines_from_segments",
    "no_return_reading",
    "read_bag",
    "read_carmen",
    "read_graph",
    "read_map",
    "read_relations",
    "read_trajectory",
    "write_carmen",
    "write_graph",
    "write_map",
    "write_relations",
    "write_trajectory",
]
