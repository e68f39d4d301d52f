"""The paper's figures, reproduced: one function per figure, and :func:`reproduce`.

Every figure is computed from the built-in ``paper`` world simulated with :data:`SEED`, so
``fhslam reproduce`` always writes the same pictures. Figures 1-5 belong to Loop 1
(feature extraction); Figures 6-11 are the paper's sketches of Loop 2 (line attributes, the
four similarity conditions, merging), drawn from small hand-made examples whose numbers are
computed by :mod:`fhslam.lines` and :mod:`fhslam.matching`; Figure 12 is a schematic of the
robot.

The package keeps the scenes apart from the drawing: :mod:`fhslam.figures.scenes` builds the
data (the simulated logs, the scan shown, the worked examples of Figs. 6-11) without
Matplotlib; :mod:`fhslam.figures.loop1` (Figs. 1-5), :mod:`fhslam.figures.loop2` (Figs.
6-11) and :mod:`fhslam.figures.slam` (Figs. 12-14) draw them, and :mod:`fhslam.figures.paper`
writes them all (:func:`reproduce`). Everything is
re-exported here, so ``from fhslam.figures import ...`` works for both.
"""

from fhslam.figures.errors import pose_errors_figure, relation_errors_figure, sweep_errors_figure
from fhslam.figures.loop1 import (
    fig01_hough_principle,
    fig02_environment,
    fig03_extended_points,
    fig04_clusters,
    fig05_lines,
)
from fhslam.figures.loop2 import (
    SIMILARITY_CAPTIONS,
    fig06_line_attributes,
    fig07_to_10_similarity,
    fig11_merging,
)
from fhslam.figures.paper import reproduce
from fhslam.figures.scenes import (
    SEED,
    SIMILARITY_POSE,
    Pose,
    figure_scan,
    line_attributes_example,
    merging_example,
    paper_log,
    similarity_examples,
    slam_log,
)
from fhslam.figures.slam import (
    fig12_pioneer,
    fig13_environment_map,
    fig14_slam_result,
    slam_run_figure,
)

__all__ = [
    "SEED",
    "SIMILARITY_CAPTIONS",
    "SIMILARITY_POSE",
    "Pose",
    "fig01_hough_principle",
    "fig02_environment",
    "fig03_extended_points",
    "fig04_clusters",
    "fig05_lines",
    "fig06_line_attributes",
    "fig07_to_10_similarity",
    "fig11_merging",
    "fig12_pioneer",
    "fig13_environment_map",
    "fig14_slam_result",
    "figure_scan",
    "line_attributes_example",
    "merging_example",
    "paper_log",
    "pose_errors_figure",
    "relation_errors_figure",
    "reproduce",
    "similarity_examples",
    "slam_log",
    "slam_run_figure",
    "sweep_errors_figure",
]
