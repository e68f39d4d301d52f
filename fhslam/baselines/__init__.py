"""Baseline line extractors the paper's fast Hough transform is compared with.

All share the call shape of the main extractor: ``f(points, params=None, pose=None)``
returning a list of :class:`fhslam.lines.Line` whose ``inliers`` index ``points``.
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
