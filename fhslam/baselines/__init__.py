"""Baselines the paper's method is compared with.

Line extractors share the call shape of the main extractor: ``f(points, params=None,
pose=None)`` returning a list of :class:`fhslam.lines.Line` whose ``inliers`` index
``points``. :class:`EKFLineSLAM` is the EKF line-SLAM baseline (filterpy).
"""

from fhslam.baselines.classical import (
    ClassicalHoughParams,
    hough_accumulator,
    hough_numpy_accumulator,
    hough_opencv_pointset,
    hough_opencv_probabilistic,
    hough_opencv_raster,
)
from fhslam.baselines.ekf_slam import EKFLineSLAM, EKFParams
from fhslam.baselines.split_merge import SplitMergeParams, split_and_merge

__all__ = [
    "ClassicalHoughParams",
    "EKFLineSLAM",
    "EKFParams",
    "SplitMergeParams",
    "hough_accumulator",
    "hough_numpy_accumulator",
    "hough_opencv_pointset",
    "hough_opencv_probabilistic",
    "hough_opencv_raster",
    "split_and_merge",
]
