"""The scan explorers of notebooks 02 and 03: the clusters of a scan as the gap between
neighbours changes (:func:`clustering_explorer`), and its lines under the thresholds of the
fast Hough extraction (:func:`extraction_explorer`).
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from fhslam import plotting
from fhslam.extraction import ExtractionParams, cluster_scan, extract_lines
from fhslam.figures.explorer_base import Explorer, slider
from fhslam.figures.scan_panels import axes_labels, gap_panel, support_panel, window_panel
from fhslam.io.log import Log


def clustering_explorer(log: Log, k: int, min_points: int = ExtractionParams().min_points):
    """Notebook 02: the clusters of scan ``k`` as the gap between neighbours changes.

    Left: the scan's points coloured by cluster. Right: the gap from each point to the next,
    along the scan, with the slider's gap drawn across it: every gap above it (shaded) starts a
    new cluster (black crosses)."""

    def draw(cluster_gap: float, scan: int) -> Figure:
        pts, beams = log.scan(scan).points()
        labels = cluster_scan(pts, cluster_gap)
        sizes = np.bincount(labels) if len(labels) else np.zeros(0, int)
        fig, (ax, gap_ax) = plt.subplots(
            1, 2, figsize=(11.5, 4.5), gridspec_kw={"width_ratios": [1.3, 1]}
        )
        fig.subplots_adjust(left=0.06, right=0.98, bottom=0.12, top=0.92, wspace=0.22)
        plotting.plot_clusters(pts, labels, ax=ax)
        ax.plot(0, 0, "k^", ms=9, label="robot")
        axes_labels(ax)
        ax.set_title(
            f"scan {scan}, gap {cluster_gap:.2f} m: {len(sizes)} clusters, "
            f"{int((sizes >= min_points).sum())} with ≥ {min_points} points"
        )
        gap_panel(gap_ax, pts, beams, labels, cluster_gap, top=2.2)
        gap_ax.set_title(f"{int((np.diff(labels) > 0).sum())} gaps above {cluster_gap:.2f} m")
        return fig

    return Explorer(
        draw,
        {
            "cluster_gap": slider(0.3, 0.02, 2.0, 0.02, "cluster gap [m]"),
            "scan": slider(int(k), 0, len(log) - 1, 1, "scan"),
        },
        "Clustering: a new cluster where neighbours are farther apart than the gap",
    )


def _lines_panel(ax, pts, labels, found, densify_step: float) -> None:
    """The lines found, each marked with its number and its support (scan points), on the
    clusters and the points densification adds (grey dots; they only vote)."""
    from fhslam.extraction import densify

    plotting.plot_clusters(pts, labels, ax=ax)
    if densify_step > 0 and len(pts):
        dense, _, source = densify(pts, labels, densify_step)
        added = dense[source < 0]
        ax.scatter(*added.T, s=2, c="0.45", zorder=2, lw=0)
    plotting.plot_lines(found, ax=ax)
    for i, line in enumerate(found, 1):
        ax.annotate(
            f"l{i} ({line.n})",
            line.midpoint,
            xytext=(4, -12),
            textcoords="offset points",
            fontsize=8,
            color="0.15",
        )
    ax.plot(0, 0, "k^", ms=9)
    axes_labels(ax)


def _extraction_controls(log: Log, k: int) -> dict:
    """The sliders of :func:`extraction_explorer`, the support threshold first."""
    d = ExtractionParams()
    return {
        "min_points": slider(int(d.min_points), 2, 64, 1, "support threshold [points]"),
        "window_deg": slider(d.window_deg, 0.0, 20.0, 0.5, "Hough window ± [°]"),
        "inlier_dist": slider(
            d.inlier_dist, 0.005, 0.15, 0.005, "inlier distance [m]", readout_format=".3f"
        ),
        "cluster_gap": slider(d.cluster_gap, 0.05, 1.5, 0.05, "cluster gap [m]"),
        "densify_step": slider(d.densify_step, 0.0, 0.3, 0.01, "densify step [m]"),
        "scan": slider(int(k), 0, len(log) - 1, 1, "scan"),
    }


def extraction_explorer(log: Log, k: int):
    """Notebook 03: the lines of scan ``k`` under the extraction's thresholds, the support
    threshold first (the paper's "until the number to support a certain slope is lower than
    the threshold"). Left: the lines, each marked with its number and its support (scan
    points), on the clusters and the points densification adds (grey dots; they only vote);
    the title gives the count of lines and the thresholds.

    Right, each other threshold drawn where it acts: the gaps between neighbouring points with
    the cluster gap and the densify step (:func:`~fhslam.figures.scan_panels.gap_panel`); the
    pair directions of each cluster around its dominant one, with the Hough window
    (:func:`~fhslam.figures.scan_panels.window_panel`); and each point's distance to the
    nearest line, with the inlier distance (:func:`~fhslam.figures.scan_panels.support_panel`).
    """

    def draw(min_points, window_deg, inlier_dist, cluster_gap, densify_step, scan) -> Figure:
        pts, beams = log.scan(scan).points()
        p = ExtractionParams(
            cluster_gap=cluster_gap,
            window_deg=window_deg,
            inlier_dist=inlier_dist,
            min_points=min_points,
            densify_step=densify_step,
        )
        found = extract_lines(pts, p)
        labels = cluster_scan(pts, cluster_gap)
        fig = plt.figure(figsize=(13, 7.5))
        grid = fig.add_gridspec(
            3, 2, width_ratios=[1.35, 1], left=0.05, right=0.98, bottom=0.07, top=0.92
        )
        grid.update(wspace=0.18, hspace=0.55)
        ax = fig.add_subplot(grid[:, 0])
        gap_ax, window_ax, support_ax = (fig.add_subplot(grid[i, 1]) for i in range(3))
        _lines_panel(ax, pts, labels, found, densify_step)
        ax.set_title(
            f"scan {scan}: {len(found)} lines with ≥ {min_points} points (in parentheses)\n"
            f"window ±{window_deg:g}°, inliers within {100 * inlier_dist:g} cm, "
            f"gap {cluster_gap:.2f} m, densify {densify_step:.2f} m",
            fontsize=10,
        )
        gap_panel(gap_ax, pts, beams, labels, cluster_gap, top=1.6, densify_step=densify_step)
        gap_ax.set_title("clustering and densification", fontsize=10)
        window_panel(window_ax, pts, p)
        window_ax.set_title("the Hough window on the slope histogram", fontsize=10)
        support_panel(support_ax, pts, beams, found, inlier_dist, top=0.16)
        support_ax.set_title("the support of the lines", fontsize=10)
        return fig

    return Explorer(draw, _extraction_controls(log, k), "Fast Hough extraction: the thresholds")
