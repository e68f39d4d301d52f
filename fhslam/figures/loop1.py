"""Figures 1-5: Loop 1, the fast Hough transform on one scan of the paper world."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from fhslam import plotting
from fhslam.extraction import (
    ExtractionParams,
    cluster_scan,
    densify,
    extract_lines,
)
from fhslam.geometry import transform_points
from fhslam.io import Log
from fhslam.scan import scan_to_points


def fig01_hough_principle() -> Figure:
    """Fig. 1: points on a line map to sinusoids that cross at the line's (ρ, θ) (eq. (1))."""
    rho0, theta0 = 2.0, np.radians(60.0)
    n = np.array([np.cos(theta0), np.sin(theta0)])
    u = np.array([-n[1], n[0]])
    t = np.array([-1.5, -0.5, 0.6, 1.6])
    pts = rho0 * n + t[:, None] * u
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.5))
    ax1.set_aspect("equal")
    ext = rho0 * n + np.array([-2.5, 2.5])[:, None] * u
    ax1.plot(*ext.T, color=plotting.LINE_COLOR, label="line")
    ax1.scatter(*pts.T, color=plotting.POINT_COLOR, zorder=3, label="points (x, y)")
    ax1.plot([0, rho0 * n[0]], [0, rho0 * n[1]], "k--", lw=1)
    ax1.annotate("O", (0, 0), xytext=(-12, -12), textcoords="offset points")
    ax1.annotate("P", rho0 * n, xytext=(6, 0), textcoords="offset points")
    ax1.annotate(r"$\rho$", 0.5 * rho0 * n, xytext=(-14, 4), textcoords="offset points")
    ax1.annotate(r"$\theta$", (0.35, 0.2))
    ax1.axhline(0, color="0.7", lw=0.8)
    ax1.axvline(0, color="0.7", lw=0.8)
    ax1.set(xlabel="x [m]", ylabel="y [m]", title="image space", xlim=(-1.5, 3.5), ylim=(-0.5, 3.5))
    ax1.legend(loc="upper right")
    th = np.linspace(0, np.pi, 361)
    for i, (x, y) in enumerate(pts):
        ax2.plot(np.degrees(th), x * np.cos(th) + y * np.sin(th), label=f"point {i + 1}")
    ax2.plot(np.degrees(theta0), rho0, "ko", ms=9, mfc="none", mew=2)
    ax2.annotate(
        rf"common point ($\rho$={rho0:.1f} m, $\theta$={np.degrees(theta0):.0f}°)",
        (np.degrees(theta0), rho0),
        xytext=(10, 14),
        textcoords="offset points",
    )
    ax2.set(
        xlabel=r"$\theta$ [deg]",
        ylabel=r"$\rho$ [m]",
        title=r"Hough space: $\rho = x\cos\theta + y\sin\theta$",
    )
    ax2.legend(loc="lower left", fontsize=8)
    fig.suptitle("Fig. 1  Principle of the Hough transform")
    fig.tight_layout()
    return fig


def fig02_environment(log: Log, k: int) -> Figure:
    """Fig. 2: the environment and one laser scan taken in it."""
    fig, ax = plt.subplots(figsize=(9, 7))
    pose = log.truth[k]
    pts, _ = scan_to_points(log.ranges[k], log.angles, max_range=log.max_range)
    world_pts = transform_points(pose, pts)
    plotting.plot_walls(log.world.walls, ax=ax)
    plotting.plot_rays(pose, world_pts, ax=ax)
    plotting.plot_scan(world_pts, ax=ax)
    plotting.plot_robot(pose, ax=ax)
    ax.set_title(f"Fig. 2  The environment and scan {k} ({len(pts)} of {len(log.angles)} beams)")
    ax.legend(loc="upper right")
    return fig


def fig03_extended_points(log: Log, k: int, params: ExtractionParams | None = None) -> Figure:
    """Fig. 3: scan points A, B, C, ... and the points added between them ("extend")."""
    params = params or ExtractionParams()
    pts, _ = scan_to_points(log.ranges[k], log.angles, max_range=log.max_range)
    labels = cluster_scan(pts, params.cluster_gap)
    # A stretch of 14 points around the first gap between clusters: both sides of a break.
    brk = np.flatnonzero(np.diff(labels))
    mid = int(brk[0]) if len(brk) else len(pts) // 2
    sl = slice(max(mid - 6, 0), min(mid + 8, len(pts)))
    sub, sub_lab = pts[sl], labels[sl]
    dense, _, source = densify(sub, sub_lab, params.densify_step)
    fig, ax = plt.subplots(figsize=(9, 6))
    ax.set_aspect("equal", adjustable="datalim")
    added = dense[source < 0]
    ax.scatter(
        *added.T, s=6, color="0.55", label=f"added every ≤{params.densify_step * 100:.0f} cm"
    )
    ax.scatter(*sub.T, s=40, color=plotting.POINT_COLOR, zorder=3, label="scan points")
    for i, p in enumerate(sub):
        ax.annotate(chr(ord("A") + i), p, xytext=(5, 5), textcoords="offset points")
    ax.set(xlabel="x [m] (laser frame)", ylabel="y [m]")
    ax.set_title("Fig. 3  Extend laser scan points (points are added only inside a cluster)")
    ax.legend()
    return fig


def fig04_clusters(log: Log, k: int, params: ExtractionParams | None = None) -> Figure:
    """Fig. 4: the scan clustered by the distance between neighbouring points."""
    params = params or ExtractionParams()
    pts, _ = scan_to_points(log.ranges[k], log.angles, max_range=log.max_range)
    labels = cluster_scan(pts, params.cluster_gap)
    keep = np.bincount(labels)[labels] >= params.min_points
    fig, ax = plt.subplots(figsize=(8, 7))
    plotting.plot_clusters(pts[keep], labels[keep], ax=ax)
    ax.scatter(*pts[~keep].T, s=8, color="0.6", marker="x", label="too small to hold a line")
    plotting.plot_robot((0, 0, 0), ax=ax)
    n = len(np.unique(labels[keep]))
    ax.set_title(f"Fig. 4  Cluster all points into {n} classes (gap > {params.cluster_gap} m)")
    ax.set(xlabel="x [m] (laser frame)", ylabel="y [m]")
    if (~keep).any():
        ax.legend()
    return fig


def fig05_lines(log: Log, k: int, params: ExtractionParams | None = None) -> Figure:
    """Fig. 5: the lines picked up by the fast Hough transform, over the scan points."""
    pts, _ = scan_to_points(log.ranges[k], log.angles, max_range=log.max_range)
    lines = extract_lines(pts, params, pose=(0.0, 0.0, 0.0))
    fig, ax = plt.subplots(figsize=(8, 7))
    plotting.plot_scan(pts, ax=ax, color="0.6")
    plotting.plot_lines(lines, ax=ax, labels=True, label="fast Hough lines")
    plotting.plot_robot((0, 0, 0), ax=ax)
    ax.set_title(f"Fig. 5  Pick-up features of the outline: {len(lines)} lines")
    ax.set(xlabel="x [m] (laser frame)", ylabel="y [m]")
    ax.legend()
    return fig
