"""The panels of the scan explorers (notebooks 02 and 03): each threshold of clustering and
extraction drawn where it acts, on the quantity it is compared with -- the gaps between
neighbouring points (:func:`gap_panel`), the pair directions around a cluster's dominant one
(:func:`window_panel`), each point's distance to the nearest line (:func:`support_panel`).
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from fhslam import plotting
from fhslam.extraction import ExtractionParams, cluster_scan


def axes_labels(ax) -> None:
    ax.set_xlabel("x [m] (robot frame)")
    ax.set_ylabel("y [m]")


def sqrt_scale(ax, top: float) -> None:
    """A square-root y axis from 0 to ``top`` metres: centimetre gaps stand apart near the
    bottom, and a threshold line still moves by a pixel or more at the top for a step of its
    slider."""
    ax.set_yscale("function", functions=(np.sqrt, np.square))
    ax.set_ylim(0.0, top)
    ticks = [t for t in (0.05, 0.1, 0.2, 0.5, 1.0, 2.0) if t < top]
    ax.set_yticks([0.0, *ticks], ["0", *(f"{t:g}" for t in ticks)])


def gap_panel(
    ax, pts, beams, labels, cluster_gap: float, top: float, densify_step: float | None = None
) -> None:
    """The distance between neighbouring scan points along the scan, each gap coloured as its
    cluster (the scan panel's colours): above ``cluster_gap`` (shaded) a new cluster starts,
    marked by a black cross. With ``densify_step``, a gap above it inside a cluster (shaded
    lighter) gets points added every ``densify_step``. Gaps above ``top`` are drawn at it."""
    cmap = plt.get_cmap("tab10")
    gaps = np.hypot(*np.diff(pts, axis=0).T) if len(pts) > 1 else np.zeros(0)
    at = 0.5 * (beams[1:] + beams[:-1])
    shown = np.minimum(gaps, top)
    split = gaps > cluster_gap
    ax.axhspan(cluster_gap, top, color="0.85", zorder=0, label="new cluster above the gap")
    ax.axhline(cluster_gap, color="k", lw=1.2, zorder=1)
    if densify_step:
        ax.axhspan(
            min(densify_step, cluster_gap),
            cluster_gap,
            color="tab:green",
            alpha=0.15,
            lw=0,
            zorder=0,
            label="points added (densify)",
        )
        ax.axhline(densify_step, color="tab:green", lw=1.2, ls="--", zorder=1)
    inside = ~split
    ax.scatter(
        at[inside], shown[inside], s=9, c=[cmap(lab % 10) for lab in labels[:-1][inside]], zorder=3
    )
    ax.scatter(at[split], shown[split], s=40, marker="x", c="k", zorder=4, clip_on=False)
    sqrt_scale(ax, top)
    ax.set_xlim(beams[0] - 2 if len(beams) else 0, beams[-1] + 2 if len(beams) else 1)
    ax.set_xlabel("beam (scan order)")
    ax.set_ylabel("gap to the next point [m]")
    ax.legend(loc="upper left", fontsize=7, framealpha=0.9)


def window_panel(ax, pts, p: ExtractionParams) -> None:
    """Step 2's window on step 1's histogram: the directions of the point pairs of each cluster
    (of at least ``p.min_points`` points, densified) relative to the cluster's dominant
    direction, summed over the clusters (the first line of each; the next ones are sought on
    the points left), with the window of ±``p.window_deg`` shaded and the directions the Hough
    vote tries (every ``p.theta_step_deg``) ticked under it."""
    from fhslam.extraction import densify, dominant_angle, lone_points, slope_histogram

    if p.drop_lone_points and len(pts) > 2:
        pts = pts[~lone_points(pts, p.cluster_gap)]
    labels = cluster_scan(pts, p.cluster_gap)
    n_bins = round(180.0 / p.angle_bin_deg)
    rel = np.zeros(n_bins)
    if len(pts):
        dense, dense_labels, _ = densify(pts, labels, p.densify_step)
        hist = slope_histogram(dense, dense_labels, p)
        phi, _ = dominant_angle(hist)
        big = np.bincount(labels) >= p.min_points
        for h, f in zip(hist[big], phi[big], strict=True):
            rel += np.roll(h, n_bins // 2 - int(f / np.radians(p.angle_bin_deg)))
    offsets = (np.arange(n_bins) - n_bins // 2) * p.angle_bin_deg
    ax.axvspan(-p.window_deg, p.window_deg, color="tab:blue", alpha=0.15, lw=0, label="window")
    edges = np.r_[offsets, offsets[-1] + p.angle_bin_deg] - 0.5 * p.angle_bin_deg
    ax.stairs(rel, edges, fill=True, color="0.35", label="point pairs")  # one artist: fast
    half = round(p.window_deg / p.theta_step_deg)
    tried = np.arange(-half, half + 1) * p.theta_step_deg
    ax.plot(
        tried,
        np.zeros_like(tried),
        "|",
        color="tab:blue",
        ms=10,
        mew=1.5,
        clip_on=False,
        label="directions voted",
    )
    ax.set_xlim(-30, 30)
    ax.set_ylim(0, max(1.0, 1.08 * rel.max()))
    ax.set_xlabel("pair direction − the cluster's dominant one [°]")
    ax.set_ylabel("pairs")
    ax.legend(loc="upper left", fontsize=7, framealpha=0.9)


def support_panel(ax, pts, beams, found, inlier_dist: float, top: float) -> None:
    """Each scan point's distance to the nearest line found, along the scan, with the inlier
    distance shaded: the points of a line (its support, red) lie within it, the others are
    grey. Distances above ``top`` are drawn at it."""
    d = np.full(len(pts), np.inf)
    for line in found:
        a, b = np.asarray(line.sp), np.asarray(line.ep)
        u = b - a
        t = np.clip(((pts - a) @ u) / max(float(u @ u), 1e-12), 0.0, 1.0)
        d = np.minimum(d, np.hypot(*(pts - a - t[:, None] * u).T))
    support = np.zeros(len(pts), bool)
    for line in found:
        support[line.inliers] = True
    shown = np.minimum(d, top)
    ax.axhspan(0.0, inlier_dist, color=plotting.LINE_COLOR, alpha=0.12, lw=0, label="inlier band")
    ax.axhline(inlier_dist, color=plotting.LINE_COLOR, lw=1.2)
    ax.scatter(beams[~support], shown[~support], s=9, c="0.55", zorder=3, clip_on=False)
    ax.scatter(
        beams[support],
        shown[support],
        s=9,
        c=plotting.LINE_COLOR,
        zorder=3,
        clip_on=False,
        label="supports a line",
    )
    ax.set_ylim(0.0, top)
    ax.set_xlim(beams[0] - 2 if len(beams) else 0, beams[-1] + 2 if len(beams) else 1)
    ax.set_xlabel("beam (scan order)")
    ax.set_ylabel("to the nearest line [m]")
    ax.legend(loc="upper left", fontsize=7, framealpha=0.9)
