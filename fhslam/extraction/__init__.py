"""Loop 1 of the paper: straight wall lines from one laser scan by the fast Hough transform.

:mod:`fhslam.extraction.fast_hough` holds the steps (clustering, "extending" the points,
the slope histogram, the restricted Hough vote) and :func:`extract_lines`, the whole loop;
:mod:`fhslam.extraction._kernels` their compiled (numba) per-cluster kernels;
:mod:`fhslam.extraction.params` the thresholds.
"""

from fhslam.extraction.fast_hough import (
    ExtractionParams,
    HoughPeaks,
    cluster_scan,
    densify,
    dominant_angle,
    extract_lines,
    extract_lines_from_scan,
    lone_points,
    restricted_hough,
    slope_histogram,
)

__all__ = [
    "ExtractionParams",
    "HoughPeaks",
    "cluster_scan",
    "densify",
    "dominant_angle",
    "extract_lines",
    "extract_lines_from_scan",
    "lone_points",
    "restricted_hough",
    "slope_histogram",
]
