"""Baselines the paper's method is compared with.

Line extractors share the call shape of the main extractor: ``f(points, params=None,
pose=None)`` returning a list of :class:`fhslam.lines.Line` whose ``inliers`` index
``points``. The SLAM baselines (EKF line SLAM, odometry) are back ends in
:mod:`fhslam.slam`.
"""

from fhslam.baselines.classical import (
    ClassicalHoughParams,
    hough_accumulator,
    hough_numpy_accumulator,
    hough_opencv_pointset,
    hough_opencv_probabilistic,
    hough_opencv_raster,
)
from fhslam.baselines.split_merge import SplitMergeParams, split_and_merge

__all__ = [
    "ClassicalHoughParams",
    "SplitMergeParams",
    "hough_accumulator",
    "hough_numpy_accumulator",
    "hough_opencv_pointset",
    "hough_opencv_probabilistic",
    "hough_opencv_raster",
    "split_and_merge",
]
