"""Pose-graph SLAM with a map of fast Hough lines: the package's default method.

On a simulated world the paper's step-by-step calibration keeps the pose within centimetres
(:mod:`fhslam.slam.fht`). Real logs need more: odometry that glitches (an 85° heading jump
between two scans), rooms visited again after hundreds of metres, clutter that no straight
line describes. What this package adds (parameters: :mod:`~fhslam.slam.graph.params`):

1. **Scan-to-map tracking** (:mod:`~fhslam.slam.graph.tracker`): every scan is placed against
   the points of the last ``keyframes.submap`` keyframes by an exhaustive correlative search
   around the odometry prediction, refined point-to-line; a search around the previous pose
   competes when the odometry looks wrong.
2. **Keyframes** (:mod:`~fhslam.slam.graph.slam`). Every ``keyframes.distance`` metres or
   ``keyframes.angle_deg`` degrees of travel a keyframe starts; the scans until the next one
   are attached to it with their tracked poses relative to it, and their points (smoothed
   along straight surfaces, filled in between beams) form its cloud. The keyframe's fast
   Hough lines (Loop 1) are kept for the map.
3. **Edges weighted by their information.** An edge between consecutive keyframes carries
   the point-to-line refinement's information (its 3 x 3 Hessian, scaled to ``edges.points``
   independent points of ``edges.sigma``) plus a weak odometry prior; in a corridor the scan
   constrains nothing along the axis and the edge says so. An edge across a doubtful scan
   carries the odometry alone: its information and its measurement, unless the odometry
   glitched on the way.
4. **Verified loop closures** (:mod:`~fhslam.slam.graph.closure`), held until confirmed when
   they would move their keyframe far or are not unique; inconsistent ones are switched off
   after each optimisation (:class:`fhslam.posegraph.PoseGraph`, Gauss-Newton with a Cauchy
   kernel on loop edges).
5. **A global search** (:mod:`~fhslam.slam.graph.search`) after a long stretch without a
   closure, around the graph's estimate and around where the odometry puts the robot.
6. **The map of reference lines** is built at the end by Loop 2 itself: each keyframe's fast
   Hough lines, placed at its optimised pose, are matched with and merged into the map
   (Fig. 11) - the paper's map, from better poses.

Each scan's pose is its keyframe's optimised pose composed with the scan's tracked pose
relative to the keyframe. Everything runs in the first scan's frame, so where the world
frame lies changes nothing but the final composition.

**Two threads** (:mod:`~fhslam.slam.graph.worker`). The front end (tracking, keyframes, their
clouds and lines) never reads the graph: it tracks in its own frame. So the back end (adding
each keyframe to the graph, its loop closures, the optimisations) runs on a thread of its
own, a keyframe behind, while the front end tracks the next scans; the compiled kernels
release the GIL, so on two cores the halves overlap. The back end gets the same calls in the
same order either way, and the results are the same bit for bit (``background=False`` runs
it in turn).

``fhslam slam LOG`` runs it (``method="graph"`` in :func:`fhslam.pipeline.run_slam`);
``method="fht"`` stays the paper's procedure.

Layers inside the package (import-linter): ``slam`` above ``closure`` / ``search`` above
``params`` / ``worker`` above ``tracker``; the scan matcher (:mod:`fhslam.scanmatch`) and the
pose graph (:mod:`fhslam.posegraph`) are the layer below.
"""

from fhslam.slam.graph.closure import LoopClosure
from fhslam.slam.graph.params import (
    EdgeParams,
    GlobalSearchParams,
    GraphSlamParams,
    KeyframeParams,
    LoopParams,
    OptimiserParams,
    count_parameters,
)
from fhslam.slam.graph.slam import GraphFastHoughSLAM, scan_cloud
from fhslam.slam.graph.tracker import ScanTracker, Track, TrackerParams
from fhslam.slam.graph.worker import LoopTargetCache

__all__ = [
    "EdgeParams",
    "GlobalSearchParams",
    "GraphFastHoughSLAM",
    "GraphSlamParams",
    "KeyframeParams",
    "LoopClosure",
    "LoopParams",
    "LoopTargetCache",
    "OptimiserParams",
    "ScanTracker",
    "Track",
    "TrackerParams",
    "count_parameters",
    "scan_cloud",
]
