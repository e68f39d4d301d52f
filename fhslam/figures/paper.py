"""The paper's figures drawn: one function per figure (Figs. 1-14), and :func:`reproduce`.

The data each figure shows comes from :mod:`fhslam.figures.scenes`; this module only draws.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

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
from fhslam.figures.scenes import (
    SEED,
    _fig06_points,
    figure_scan,
    line_attributes_example,
    merging_example,
    paper_log,
    similarity_examples,
    slam_log,
)
from fhslam.geometry import transform_points
from fhslam.io import Log
from fhslam.matching import MatchParams, Similarity, merge, similarity
from fhslam.pipeline import SlamResult, run_slam
from fhslam.scan import scan_to_points
from fhslam.sim import World, paper_world


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


def fig06_line_attributes() -> Figure:
    """Fig. 6: the attributes (ρ, θ, n, l, sp, ep, dir, d) of a feature line AB and a robot."""
    line, pose = line_attributes_example()
    pts = _fig06_points()
    nrm, u = line.normal, np.array([-line.normal[1], line.normal[0]])
    P = line.rho * nrm
    x, y, _ = pose
    foot = np.array([x, y]) + line.d * nrm
    fig, ax = plt.subplots(figsize=(10, 7.5))
    ax.annotate("", (4.3, 0), (-0.6, 0), arrowprops={"arrowstyle": "-|>", "color": "0.5"})
    ax.annotate("", (0, 3.55), (0, -0.5), arrowprops={"arrowstyle": "-|>", "color": "0.5"})
    ax.text(4.3, -0.12, "x", ha="right", va="top", color="0.4")
    ax.text(-0.08, 3.55, "y", ha="right", va="top", color="0.4")
    # the infinite line, the segment AB and its points
    far = P + np.array([-2.2, 2.6])[:, None] * u
    ax.plot(*far.T, ":", color=plotting.LINE_COLOR, lw=1)
    plotting.plot_lines([line], ax=ax, label="feature line AB")
    plotting.plot_scan(pts, ax=ax, s=22, label=f"n = {line.n} scan points")
    for name, q, off, ha in (
        ("A = sp", line.sp, (8, -6), "left"),
        ("B = ep", line.ep, (-8, -6), "right"),
    ):
        ax.annotate(name, q, xytext=off, textcoords="offset points", fontsize=11, ha=ha)
    plotting.plot_dimension(
        line.sp, line.ep, ax=ax, label=f"l = {line.length:.2f} m", offset=-0.3, text_offset=0.13
    )
    # O, P, rho and theta
    ax.plot(*np.c_[[0.0, 0.0], P], "k--", lw=1.2)
    ax.plot(0, 0, "ko", ms=4)
    ax.annotate("O", (0, 0), xytext=(-13, -14), textcoords="offset points", fontsize=12)
    ax.annotate("P", P, xytext=(8, -16), textcoords="offset points", fontsize=12, ha="left")
    plotting.plot_right_angle(P, -nrm, u, 0.14, ax=ax)
    ax.text(
        *(0.55 * P - 0.2 * u),
        rf"$\rho$ = {line.rho:.2f} m",
        rotation=np.degrees(line.theta),
        rotation_mode="anchor",
        ha="center",
        va="bottom",
    )
    plotting.plot_angle_arc(
        (0, 0), 0.55, 0.0, line.theta, ax=ax, label=rf"$\theta$ = {np.degrees(line.theta):.1f}°",
        label_radius=0.95,
    )  # fmt: skip
    # the robot, d and dir
    plotting.plot_robot(pose, ax=ax, size=0.3)
    ax.annotate(
        f"robot (x, y, φ) = ({x:.2f}, {y:.2f}, {np.degrees(pose[2]):.0f}°)",
        (x, y),
        xytext=(14, -20),
        textcoords="offset points",
        fontsize=10,
    )
    ax.plot(*np.c_[[x, y], foot], color=plotting.ROBOT_COLOR, lw=1.6, ls="--")
    plotting.plot_right_angle(foot, -nrm, -u, 0.12, ax=ax, color=plotting.ROBOT_COLOR)
    ax.text(
        *(0.5 * (np.array([x, y]) + foot) + 0.1 * u),
        f"d = {line.d:.2f} m",
        rotation=np.degrees(line.theta),
        rotation_mode="anchor",
        ha="center",
        va="bottom",
        color="darkgreen",
    )
    s = line.rho - x * np.cos(line.theta) - y * np.sin(line.theta)
    box = "\n".join(
        [
            "Line.observed_from(pose):",
            rf"  $\rho$  = {line.rho:.3f} m",
            rf"  $\theta$  = {np.degrees(line.theta):.2f}°",
            f"  n  = {line.n}",
            f"  l  = {line.length:.3f} m",
            f"  sp = ({line.sp[0]:.2f}, {line.sp[1]:.2f})",
            f"  ep = ({line.ep[0]:.2f}, {line.ep[1]:.2f})",
            f"  dir = {line.dir:+d}",
            f"  d  = {line.d:.3f} m",
            "",
            r"dir = sign($\rho$ − x cos$\theta$ − y sin$\theta$)",
            f"     = sign({line.rho:.2f} − {x:.2f}·{np.cos(line.theta):.2f}"
            f" − {y:.2f}·{np.sin(line.theta):.2f})",
            f"     = sign({s:+.2f}) = {line.dir:+d}",
            "(robot on the origin's side of AB)",
        ]
    )
    ax.text(
        0.985, 0.97, box, transform=ax.transAxes, ha="right", va="top", fontsize=10,
        multialignment="left",
        bbox={"boxstyle": "round", "facecolor": "white", "edgecolor": "0.6"},
    )  # fmt: skip
    ax.set_aspect("equal", adjustable="box")
    ax.set(xlim=(-0.7, 6.2), ylim=(-0.6, 3.7), xlabel="x [m]", ylabel="y [m]")
    ax.legend(loc="lower right")
    ax.set_title("Fig. 6  The sketch of observation direction for feature line")
    return fig


SIMILARITY_CAPTIONS = {
    7: "Both lines are similar",
    8: "Both lines are not similar",
    9: "Both lines are not similar",
    10: "Both lines are not similar",
}
"""The paper's captions of Figs. 7-10."""


def _conditions_text(sim: Similarity, params: MatchParams, dirs: tuple[int, int]) -> str:
    """The four conditions as a small fixed-width table: value, criterion, ✓/✗."""
    mark = {True: "✓", False: "✗"}
    rows = [
        ("(a) observation dir", f"{dirs[0]:+d} / {dirs[1]:+d}", "equal", sim.same_direction),
        ("(b) angle", f"{sim.angle_deg:.1f}°", f"≤ {params.max_angle_deg:g}°", sim.angle_ok),
        (
            "(c) endpoint distance",
            f"{sim.distance:.2f} m",
            f"≤ {params.max_distance:g} m",
            sim.distance_ok,
        ),
        (
            "(d) projection overlap",
            f"{sim.overlap:+.2f} m",
            f"≥ {params.min_overlap:g} m",
            sim.overlap_ok,
        ),
    ]
    return "\n".join(f"{a:<23}{v:>8}  {c:<10}{mark[ok]}" for a, v, c, ok in rows)


def fig07_to_10_similarity(params: MatchParams | None = None) -> Figure:
    """Figs. 7-10: four pairs of lines and the four similarity conditions (a)-(d) of each.

    The reference segment is red, the new one purple; the dotted red line is the reference's
    infinite line, and the purple band on it is the new segment's projection (condition (d)).
    """
    params = params or MatchParams()
    new_color = "tab:purple"
    fig, axes = plt.subplots(2, 2, figsize=(11, 10), layout="constrained")
    for ax, (k, (ref, new, pose)) in zip(axes.flat, similarity_examples().items(), strict=True):
        sim = similarity(ref, new, params, pose=pose)
        u = np.array([-ref.normal[1], ref.normal[0]])
        base = ref.rho * ref.normal
        ax.plot(*(base + np.array([-5.0, 5.0])[:, None] * u).T, ":", color="tab:red", lw=0.8)
        proj = base + np.array([new.sp @ u, new.ep @ u])[:, None] * u
        ax.plot(*proj.T, color=new_color, lw=9, alpha=0.18, solid_capstyle="butt")
        for q, c in zip((new.sp, new.ep), proj, strict=True):
            ax.plot(*np.c_[q, c], ":", color=new_color, lw=0.9)
        plotting.plot_lines([ref], ax=ax, label="reference line")
        plotting.plot_lines([new], ax=ax, color=new_color, label="new line")
        plotting.plot_robot(pose, ax=ax, size=0.2)
        if k == 7:
            ax.plot([], [], color=new_color, lw=9, alpha=0.18, label="projection of new line")
            ax.plot([], [], "^", color=plotting.ROBOT_COLOR, mec="k", label="robot (same pose)")
            ax.legend(loc="lower left", fontsize=8)
        ax.set_aspect("equal", adjustable="box")
        ax.set(xlim=(-1.6, 1.8), ylim=(0.7, 2.8))
        ax.tick_params(labelsize=8)
        ax.set_ylabel("y [m]" if k in (7, 9) else "", fontsize=9)
        ax.set_title(f"Fig. {k}  {SIMILARITY_CAPTIONS[k]}", fontsize=11)
        dirs = (ref.observed_from(pose).dir, new.observed_from(pose).dir)
        table = ax.annotate(
            _conditions_text(sim, params, dirs), (0.5, -0.1), xycoords="axes fraction",
            ha="center", va="top", family="DejaVu Sans Mono", fontsize=9.5,
        )  # fmt: skip
        ax.annotate(
            "→ similar" if sim.similar else "→ not similar", (0.5, -0.25), xycoords=table,
            ha="center", va="top", fontsize=11, fontweight="bold",
            color="darkgreen" if sim.similar else "darkred",
        )  # fmt: skip
    fig.suptitle(
        "Figs. 7–10  Both lines are similar (Fig. 7) / not similar (Figs. 8–10): "
        f"conditions (a)–(d) with thresholds {params.max_angle_deg:g}°, "
        f"{params.max_distance:g} m, overlap ≥ {params.min_overlap:g} m",
        fontsize=12,
    )
    fig.get_layout_engine().set(h_pad=0.3, hspace=0.0)
    return fig


def fig11_merging() -> Figure:
    """Fig. 11: merging a new segment AB into the similar reference segment EF.

    AB is projected onto EF's line (C, D); the four endpoints are sorted along the line
    (C, E, D, F); since CM > EM (M the midpoint of EF) EF is extended to C, giving CF.
    ``merge(ref, new)`` also refits the line to both segments, weighted by their support n.
    """
    ef, ab = merging_example()
    merged = merge(ef, ab)
    u = np.array([-ef.normal[1], ef.normal[0]])
    base = ef.rho * ef.normal
    C, D = (base + (q @ u) * u for q in (ab.sp, ab.ep))
    E, F = ef.sp, ef.ep
    M = ef.midpoint
    cm, em = float(np.linalg.norm(C - M)), float(np.linalg.norm(E - M))
    new_color, merged_color = "tab:purple", "tab:green"
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(10, 6.2), sharex=True)
    ax1.plot(*(base + np.array([-3.0, 3.0])[:, None] * u).T, ":", color="tab:red", lw=0.8)
    plotting.plot_lines([ef], ax=ax1, label="reference EF")
    plotting.plot_lines([ab], ax=ax1, color=new_color, label="new AB")
    for q, c in ((ab.sp, C), (ab.ep, D)):
        ax1.plot(*np.c_[q, c], "--", color=new_color, lw=0.9)
    ax1.plot(*np.c_[C, D], color=new_color, lw=7, alpha=0.2, solid_capstyle="butt",
             label="projection CD")  # fmt: skip
    ax1.plot(*M, "k|", ms=14, mew=2)
    below, above = (0, -15), (0, 8)
    for name, q, off in (
        ("E", E, below), ("F", F, below), ("M", M, below), ("C", C, below), ("D", D, below),
        ("A", ab.sp, above), ("B", ab.ep, above),
    ):  # fmt: skip
        ax1.annotate(name, q, xytext=off, textcoords="offset points", ha="center",
                     va="center", fontsize=12, fontweight="bold")  # fmt: skip
    ax1.annotate(
        f"sorted along EF: C, E, D, F\nCM = {cm:.2f} m > EM = {em:.2f} m  →  extend EF to C",
        (0.99, 0.95), xycoords="axes fraction", ha="right", va="top", fontsize=10,
        bbox={"boxstyle": "round", "facecolor": "white", "edgecolor": "0.6"},
    )  # fmt: skip
    for name, p, yd in (("CM", C, 0.935), ("EM", E, 0.885)):
        plotting.plot_dimension((p[0], yd), (M[0], yd), ax=ax1)
        ax1.text(
            0.5 * (p[0] + M[0]), yd, f"{name} = {np.linalg.norm(p - M):.2f} m", ha="center",
            va="center", fontsize=9, bbox={"facecolor": "white", "edgecolor": "none", "pad": 1},
        )  # fmt: skip
    ax1.legend(loc="upper left", fontsize=8)
    ax1.set_title("before: project the new segment AB onto the reference line EF", fontsize=10)
    plotting.plot_lines([ef], ax=ax2, alpha=0.3)
    plotting.plot_lines([ab], ax=ax2, color=new_color, alpha=0.3)
    plotting.plot_lines([merged], ax=ax2, color=merged_color, label="merged CF")
    for name, q in (("C", merged.sp), ("F", merged.ep)):
        ax2.annotate(name, q, xytext=(0, -15), textcoords="offset points", ha="center",
                     va="center", fontsize=12, fontweight="bold")  # fmt: skip
    ax2.annotate(
        f"merge(EF, AB): n = {ef.n} + {ab.n} = {merged.n},  l = {merged.length:.2f} m\n"
        f"refit: ρ = {merged.rho:.3f} m, θ = {np.degrees(merged.theta):.2f}°"
        f"  (EF: ρ = {ef.rho:.3f} m, θ = {np.degrees(ef.theta):.2f}°)",
        (0.99, 0.95), xycoords="axes fraction", ha="right", va="top", fontsize=10,
        bbox={"boxstyle": "round", "facecolor": "white", "edgecolor": "0.6"},
    )  # fmt: skip
    ax2.legend(loc="lower right", fontsize=9)
    ax2.set_title("after: EF extended to C and refitted to both segments", fontsize=10)
    ax2.set_xlabel("x [m]")
    for ax in (ax1, ax2):
        ax.set_aspect(5.0, adjustable="box")
        ax.set(xlim=(-1.0, 4.6), ylim=(0.84, 1.22), ylabel="y [m]  (vertical ×5)")
    fig.suptitle("Fig. 11  The sketch of mergence of two similar straight line segments")
    fig.tight_layout()
    return fig


def fig12_pioneer() -> Figure:
    """Fig. 12: a schematic top view of the Pioneer II and its 180° SICK laser.

    The paper shows a photograph; this is a to-scale sketch (body 0.44 m x 0.38 m). The
    laser's 8 m range is drawn shortened; its 0° beam points to the robot's right, 90°
    straight ahead and 180° to the left (the simulator's bearings -90°..+90°).
    """
    pose = (0.0, 0.0, np.pi / 2)
    reach = 1.1
    fig, ax = plt.subplots(figsize=(10, 7))
    o = plotting.laser_origin(pose)
    plotting.plot_laser_fan(o, pose[2], reach, ax=ax, n_rays=19)
    plotting.plot_pioneer(pose, ax=ax)
    for deg, ha, va in ((0, "left", "center"), (90, "center", "bottom"), (180, "right", "center")):
        a = np.radians(deg)
        q = o + (reach + 0.05) * np.array([np.cos(a), np.sin(a)])
        ax.text(*q, f"{deg}°", ha=ha, va=va, fontsize=12)
    a = np.radians(140.0)
    ax.annotate(
        "", o + reach * np.array([np.cos(a), np.sin(a)]), o,
        arrowprops={"arrowstyle": "-|>", "color": "tab:orange", "lw": 1.8},
    )  # fmt: skip
    ax.text(*(o + 0.62 * reach * np.array([np.cos(a), np.sin(a)]) + [-0.02, 0.07]),
            "8 m", rotation=140 - 180, ha="center", va="center", fontsize=12,
            color="saddlebrown")  # fmt: skip
    ax.text(0.0, -0.62, "beams every 10° drawn (the LMS200 gives 181, one per degree);\n"
            "max range 8 m, drawn shortened", ha="center", va="top", fontsize=9,
            color="0.3")  # fmt: skip
    plotting.plot_dimension((-0.19, -0.22), (0.19, -0.22), ax=ax, label="0.38 m", offset=-0.08,
                            text_offset=0.05)  # fmt: skip
    plotting.plot_dimension((-0.19, -0.22), (-0.19, 0.22), ax=ax, label="0.44 m", offset=0.12,
                            text_offset=0.05)  # fmt: skip
    arrow = {"arrowstyle": "->", "color": "0.2", "lw": 0.8}
    for text, xy, xytext in (
        ("SICK LMS200\nlaser range finder", (0.08, 0.12), (0.72, 0.08)),
        ("drive wheel", (0.245, 0.0), (0.72, -0.06)),
        ("caster", (0.03, -0.15), (0.72, -0.2)),
        ("Pioneer II body", (0.13, -0.2), (0.72, -0.36)),
    ):
        ax.annotate(text, xy, xytext=xytext, arrowprops=arrow, fontsize=10, va="center")
    ax.set_aspect("equal", adjustable="box")
    ax.set(xlim=(-1.45, 1.45), ylim=(-0.8, 1.42), xlabel="x [m]", ylabel="y [m]")
    ax.set_title(
        "Fig. 12  Pioneer II with a 180° laser range finder "
        "(schematic; the paper's photo cannot be reproduced)"
    )
    return fig


def fig13_environment_map(world: World | None = None) -> Figure:
    """Fig. 13: the original environment map, with the route from S to E."""
    world = world or paper_world()
    fig, ax = plt.subplots(figsize=(10, 7.5))
    plotting.plot_walls(world.walls, ax=ax)
    route = np.asarray(world.route)
    ax.plot(*route.T, ":", color="0.5", lw=1.2, label="route")
    for label, (x, y) in (("S", route[0]), ("E", route[-1])):
        ax.plot(x, y, "o", ms=10, color=plotting.ROBOT_COLOR, mec="k", zorder=6)
        ax.annotate(label, (x, y), xytext=(8, 6), textcoords="offset points", fontsize=14)
    x0, y0, x1, y1 = world.bounds
    ax.set_title(
        f"Fig. 13  Original environment map: {x1 - x0:.1f} × {y1 - y0:.1f} m, "
        f"{len(world.walls)} walls, route {world.route_length:.1f} m"
    )
    ax.legend(loc="upper right")
    return fig


def fig14_slam_result(log: Log, result: SlamResult) -> Figure:
    """Fig. 14: the SLAM result: reference-line map, estimated trajectory, truth, odometry."""
    fig, ax = plt.subplots(figsize=(10, 7.5))
    plotting.plot_walls(log.world.walls, ax=ax, colors="0.8", linewidths=4, label="true walls")
    plotting.plot_lines(result.map, ax=ax, linewidth=1.6, label="map (reference lines)")
    plotting.plot_trajectory(log.odometry, ax=ax, color="tab:orange", label="odometry")
    plotting.plot_trajectory(log.truth, ax=ax, color="k", ls="--", label="truth")
    plotting.plot_trajectory(result.poses, ax=ax, color="tab:blue", label="FH-SLAM")
    for label, (x, y) in (("S", log.truth[0, :2]), ("E", log.truth[-1, :2])):
        ax.annotate(label, (x, y), xytext=(8, 6), textcoords="offset points", fontsize=14)
    err = np.hypot(*(result.poses[:, :2] - log.truth[:, :2]).T)
    odo = np.hypot(*(log.odometry[:, :2] - log.truth[:, :2]).T)
    ax.set_title(
        f"Fig. 14  SLAM with the fast Hough transform: ATE {np.sqrt(np.mean(err**2)):.3f} m "
        f"(odometry {np.sqrt(np.mean(odo**2)):.2f} m), {len(result.map)} map lines"
    )
    ax.legend(loc="upper right", fontsize=9)
    return fig


def reproduce(out_dir: str | Path = "figures", seed: int = SEED) -> list[Path]:
    """Write the reproduced figures as PNG files into ``out_dir``; return their paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    log = paper_log(seed)
    drift_log = slam_log(seed)
    k = figure_scan(log)
    makers: dict[str, Callable[[], Figure]] = {
        "fig01_hough_principle": fig01_hough_principle,
        "fig02_environment": lambda: fig02_environment(log, k),
        "fig03_extended_points": lambda: fig03_extended_points(log, k),
        "fig04_clusters": lambda: fig04_clusters(log, k),
        "fig05_lines": lambda: fig05_lines(log, k),
        "fig06_line_attributes": fig06_line_attributes,
        "fig07_10_similarity": fig07_to_10_similarity,
        "fig11_merging": fig11_merging,
        "fig12_pioneer": fig12_pioneer,
        "fig13_environment_map": lambda: fig13_environment_map(log.world),
        "fig14_slam_result": lambda: fig14_slam_result(drift_log, run_slam(drift_log)),
    }
    paths = []
    for name, make in makers.items():
        fig = make()
        path = out / f"{name}.png"
        fig.savefig(path, dpi=110, bbox_inches="tight", metadata={"Software": None})
        plt.close(fig)
        paths.append(path)
    return paths
