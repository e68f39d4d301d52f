"""Figures 12-14: the robot, the map it builds and the SLAM result (Loop 3); and the picture
of a SLAM run on any log that ``fhslam slam --plot`` writes (:func:`slam_run_figure`)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure

from fhslam import plotting
from fhslam.io import KeyframeGraph, Log
from fhslam.pipeline import SlamResult
from fhslam.sim import World, paper_world


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


def slam_run_figure(
    log: Log, result: SlamResult, method: str, graph: KeyframeGraph | None = None
) -> Figure:
    """A SLAM run on any log, as ``fhslam slam --plot`` draws it: the map of reference lines,
    the estimated trajectory from S to E and the odometry (dead reckoning from the same first
    pose; the view is the run's, so a drift of tens of metres leaves it), the
    true walls and trajectory where the log has them, and for a graph run each loop closure
    still in the graph as a thin line between its two keyframes.

    Parameters
    ----------
    log : Log
        The log the run was made on.
    result : SlamResult
        The run (:func:`fhslam.pipeline.run_slam`).
    method : str
        The method's name, for the title and the legend.
    graph : KeyframeGraph, optional
        The run's keyframes and loop closures (:func:`fhslam.pipeline.keyframe_graph`).
    """
    fig, ax = plt.subplots(figsize=(10, 7.5))
    if log.world is not None:
        plotting.plot_walls(log.world.walls, ax=ax, colors="0.8", linewidths=4, label="true walls")
    plotting.plot_lines(
        result.map,
        ax=ax,
        linewidth=1.2,
        markers=False,
        label=f"map ({len(result.map)} reference lines)",
    )
    plotting.plot_trajectory(
        log.odometry, ax=ax, color="tab:orange", linewidth=0.8, label="odometry"
    )
    title = f"{log.name or 'log'}: {method}, {len(log)} scans"
    if log.truth is not None:
        plotting.plot_trajectory(log.truth, ax=ax, color="k", ls="--", label="truth")
        err = np.hypot(*(result.poses[:, :2] - log.truth[:, :2]).T)
        title += f", ATE {np.sqrt(np.mean(err**2)):.3f} m"
    plotting.plot_trajectory(result.poses, ax=ax, color="tab:blue", linewidth=1.0, label=method)
    if graph is not None:
        kept = graph.loops[graph.active]
        if len(kept):
            ends = graph.poses[kept][:, :, :2]  # (L, 2 keyframes, xy)
            ax.add_collection(LineCollection(ends, colors="tab:green", linewidths=0.6, zorder=3))
        ax.plot([], [], color="tab:green", linewidth=0.6, label=f"{len(kept)} loop closures")
        title += f", {len(graph)} keyframes"
    for label, (x, y) in (("S", result.poses[0, :2]), ("E", result.poses[-1, :2])):
        ax.annotate(label, (x, y), xytext=(6, 4), textcoords="offset points", fontsize=12)
    # the view: the run, its map and the truth, not the odometry's drift
    seen = [result.poses[:, :2], *([line.sp, line.ep] for line in result.map)]
    if log.truth is not None:
        seen.append(log.truth[:, :2])
    if log.world is not None:
        seen.append(np.reshape(log.world.walls, (-1, 2)))
    lo, hi = np.min(np.vstack(seen), axis=0), np.max(np.vstack(seen), axis=0)
    pad = 0.05 * (hi - lo).max() + 0.5
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_title(title)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="best", fontsize=9)
    return fig
