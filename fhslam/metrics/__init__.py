"""Measurement: line-detection scores, trajectory errors (ATE, RPE), map errors and the
relations metric, one submodule per family:

- :mod:`fhslam.metrics.detection`: line-detection scores (Nguyen et al. 2005) against the
  simulator's true lines (:func:`fhslam.sim.true_lines`);
- :mod:`fhslam.metrics.trajectory`: absolute and relative pose error (:func:`ate`,
  :func:`rpe`, after evo), timestamp association and SE(2) alignment;
- :mod:`fhslam.metrics.map`: the map's segments against the true walls (:func:`map_error`,
  :func:`map_coverage`);
- :mod:`fhslam.metrics.relations`: the relations metric of the Freiburg SLAM benchmark
  (Kümmerle et al. 2009).

Ground truth (true lines, observed wall points) comes from :mod:`fhslam.sim`; running a
method and scoring it is :mod:`fhslam.evaluate`.
"""

from fhslam.metrics.detection import (
    DetectionScores,
    HessianLine,
    detection_scores,
    line_difference,
    match_scan,
)
from fhslam.metrics.map import as_segments, map_coverage, map_error, sample_segments
from fhslam.metrics.relations import (
    RelationsError,
    extend_by_odometry,
    relations_error,
    relations_errors,
    sample_relations,
)
from fhslam.metrics.trajectory import (
    ErrorStats,
    align_se2,
    associate,
    ate,
    ate_errors,
    error_stats,
    rpe,
    rpe_errors,
    rpe_pairs,
    rpe_rot_deg,
)

__all__ = [
    "DetectionScores",
    "ErrorStats",
    "HessianLine",
    "RelationsError",
    "align_se2",
    "as_segments",
    "associate",
    "ate",
    "ate_errors",
    "detection_scores",
    "error_stats",
    "extend_by_odometry",
    "line_difference",
    "map_coverage",
    "map_error",
    "match_scan",
    "relations_error",
    "relations_errors",
    "rpe",
    "rpe_errors",
    "rpe_pairs",
    "rpe_rot_deg",
    "sample_relations",
    "sample_segments",
]
