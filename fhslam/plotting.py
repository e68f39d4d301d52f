"""One plotting vocabulary for every notebook and figure.

Each function draws one kind of thing on a Matplotlib ``Axes`` (created when not given) and
returns the axes, so figures are built by layering: ``ax = plot_walls(world.walls);
plot_scan(points, ax=ax); plot_lines(lines, ax=ax)``.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection
from matplotlib.patches import Polygon
from numpy.typing import ArrayLike

from fhslam.lines import Line

WALL_COLOR = "0.25"
POINT_COLOR = "tab:blue"
LINE_COLOR = "tab:red"
ROBOT_COLOR = "tab:green"


@contextmanager
def figsize(width: float = 8.0, height: float = 5.0) -> Iterator[None]:
    """Temporarily change the default figure size (as in Labbe's book_plots)."""
    old = plt.rcParams["figure.figsize"]
    plt.rcParams["figure.figsize"] = (width, height)
    try:
        yield
    finally:
        plt.rcParams["figure.figsize"] = old


def _axes(ax: Axes | None, equal: bool = True) -> Axes:
    if ax is None:
        _, ax = plt.subplots()
    if equal:
        ax.set_aspect("equal", adjustable="datalim")
    return ax


def plot_walls(walls: ArrayLike, ax: Axes | None = None, **kw) -> Axes:
    """Draw wall segments, shape (M, 4) rows ``[x1, y1, x2, y2]``."""
    ax = _axes(ax)
    w = np.asarray(walls, dtype=float).reshape(-1, 2, 2)
    style = {"colors": WALL_COLOR, "linewidths": 2.0, "label": "walls"} | kw
    ax.add_collection(LineCollection(w, **style))
    ax.autoscale_view()
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    return ax


def plot_scan(points: ArrayLike, ax: Axes | None = None, **kw) -> Axes:
    """Draw scan points, shape (N, 2)."""
    ax = _axes(ax)
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    style = {"s": 6, "color": POINT_COLOR, "label": "scan points", "zorder": 3} | kw
    ax.scatter(p[:, 0], p[:, 1], **style)
    return ax


def plot_rays(origin: ArrayLike, points: ArrayLike, ax: Axes | None = None, **kw) -> Axes:
    """Draw laser beams from ``origin`` (2,) to ``points`` (N, 2)."""
    ax = _axes(ax)
    o = np.asarray(origin, dtype=float)[:2]
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    segs = np.stack([np.broadcast_to(o, p.shape), p], axis=1)
    style = {"colors": "tab:orange", "linewidths": 0.4, "alpha": 0.5} | kw
    ax.add_collection(LineCollection(segs, **style))
    return ax


def plot_clusters(points: ArrayLike, labels: ArrayLike, ax: Axes | None = None) -> Axes:
    """Draw scan points coloured by cluster, with the cluster number at each cluster's middle."""
    ax = _axes(ax)
    p = np.asarray(points, dtype=float)
    lab = np.asarray(labels)
    cmap = plt.get_cmap("tab10")
    for k, c in enumerate(np.unique(lab)):
        q = p[lab == c]
        ax.scatter(q[:, 0], q[:, 1], s=8, color=cmap(k % 10), zorder=3)
        m = q[len(q) // 2]
        ax.annotate(f"S{k + 1}", m, xytext=(4, 4), textcoords="offset points", fontsize=9)
    return ax


def plot_lines(lines: Sequence[Line], ax: Axes | None = None, labels: bool = False, **kw) -> Axes:
    """Draw line segments from ``sp`` to ``ep`` with their endpoints marked."""
    ax = _axes(ax)
    style = {"color": LINE_COLOR, "linewidth": 2.5, "zorder": 4} | kw
    for i, line in enumerate(lines):
        xs, ys = zip(line.sp, line.ep, strict=True)
        ax.plot(xs, ys, solid_capstyle="round", **(style | {"label": None}))
        ax.plot(xs, ys, "o", ms=4, color=style["color"], zorder=5)
        if labels:
            ax.annotate(f"l{i + 1}", line.midpoint, xytext=(3, 3), textcoords="offset points")
    if lines and "label" in kw:
        ax.plot([], [], color=style["color"], linewidth=2.5, label=kw["label"])
    return ax


def plot_robot(pose: ArrayLike, ax: Axes | None = None, size: float = 0.45, **kw) -> Axes:
    """Draw the robot as a triangle pointing along its heading."""
    ax = _axes(ax)
    x, y, th = np.asarray(pose, dtype=float)
    shape = np.array([[1.0, 0.0], [-0.6, 0.55], [-0.6, -0.55]]) * size
    c, s = np.cos(th), np.sin(th)
    pts = shape @ np.array([[c, s], [-s, c]]) + [x, y]
    style = {"facecolor": ROBOT_COLOR, "edgecolor": "k", "zorder": 6} | kw
    ax.add_patch(Polygon(pts, closed=True, **style))
    return ax


def plot_trajectory(poses: ArrayLike, ax: Axes | None = None, **kw) -> Axes:
    """Draw a trajectory, shape (T, 3) or (T, 2)."""
    ax = _axes(ax)
    p = np.asarray(poses, dtype=float)
    ax.plot(p[:, 0], p[:, 1], **({"linewidth": 1.5} | kw))
    return ax
