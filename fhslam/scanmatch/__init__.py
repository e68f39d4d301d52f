"""Correlative scan matching (Olson 2009): the pose of one point cloud in another's frame.

The target cloud is rasterised into a *likelihood grid*: each cell holds
``exp(-d² / 2σ²)`` of its distance ``d`` to the nearest target point (an exact Euclidean
distance transform, compiled). A candidate pose scores the mean likelihood of the query
points it places in the grid. :func:`match_clouds` searches exhaustively, first on a coarse
grid (10 cm, 1° steps) over the whole search window, then on a fine grid (2 cm, 0.1°) around
the coarse optimum. An exhaustive search cannot be caught by a local minimum, which is what a
loop closure after a long drift needs; the score says how well the clouds agree, which is
what decides whether to trust the match.

Used by :mod:`fhslam.slam.graph`; depends only on :mod:`fhslam.geometry`. The inner loop is a
``numba`` kernel (one pass over angles × shifts × points).

The modules, by job: :mod:`fhslam.scanmatch.clouds` makes a scan a cloud (voxel thinning,
normals, smoothing, densifying); :mod:`fhslam.scanmatch.grids` makes a target cloud ready
to match (:class:`LikelihoodGrid`, :class:`PointMap`); :mod:`fhslam.scanmatch.search` the
correlative and branch-and-bound searches and :func:`match_clouds`;
:mod:`fhslam.scanmatch.refinement` the point-to-line refinement (:func:`refine`).
"""

from fhslam.scanmatch.clouds import (
    densify,
    scan_normals,
    smooth_scan,
    voxel_downsample,
    voxel_index,
)
from fhslam.scanmatch.grids import LikelihoodGrid, PointMap
from fhslam.scanmatch.refinement import Refinement, refine
from fhslam.scanmatch.search import MatchResult, correlative_search, match_clouds

__all__ = [
    "LikelihoodGrid",
    "MatchResult",
    "PointMap",
    "Refinement",
    "correlative_search",
    "densify",
    "match_clouds",
    "refine",
    "scan_normals",
    "smooth_scan",
    "voxel_downsample",
    "voxel_index",
]
