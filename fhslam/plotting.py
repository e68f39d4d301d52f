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
from matplotlib.cbook import normalize_kwargs
from matplotlib.collections import LineCollection
from matplotlib.lines import Line2D
from matplotlib.patches import Arc, Circle, FancyArrowPatch, Polygon, Wedge
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


def plot_lines(
    lines: Sequence[Line],
    ax: Axes | None = None,
    labels: bool = False,
    markers: bool = True,
    **kw,
) -> Axes:
    """Draw line segments from ``sp`` to ``ep``, with their endpoints marked unless
    ``markers=False`` (for maps of hundreds of lines); ``kw`` go to ``Axes.plot``."""
    ax = _axes(ax)
    style = {"color": LINE_COLOR, "linewidth": 2.5, "zorder": 4} | normalize_kwargs(kw, Line2D)
    for i, line in enumerate(lines):
        xs, ys = zip(line.sp, line.ep, strict=True)
        ax.plot(xs, ys, solid_capstyle="round", **(style | {"label": None}))
        if markers:
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
    ax.plot(p[:, 0], p[:, 1], **({"linewidth": 1.5} | normalize_kwargs(kw, Line2D)))
    return ax


def plot_angle_arc(
    center: ArrayLike,
    radius: float,
    start: float,
    end: float,
    ax: Axes | None = None,
    label: str | None = None,
    label_radius: float | None = None,
    **kw,
) -> Axes:
    """Draw an angle as a counter-clockwise arc with an arrow head at ``end``.

    Parameters
    ----------
    center : array-like, shape (2,)
        Vertex of the angle.
    radius : float
        Arc radius, data units.
    start, end : float
        First and last direction of the arc, radians (counter-clockwise from +x).
    label : str, optional
        Written at the middle of the arc, ``label_radius`` (default 1.35 radius) from the vertex.
    """
    ax = _axes(ax)
    c = np.asarray(center, dtype=float)
    style = {"color": "k", "lw": 1.0} | kw
    ax.add_patch(
        Arc(c, 2 * radius, 2 * radius, theta1=np.degrees(start), theta2=np.degrees(end), **style)
    )
    tip = c + radius * np.array([np.cos(end), np.sin(end)])
    back = end - min(0.25, 0.3 * abs(end - start))
    tail = c + radius * np.array([np.cos(back), np.sin(back)])
    ax.add_patch(FancyArrowPatch(tail, tip, arrowstyle="-|>", mutation_scale=10, **style))
    if label:
        mid = 0.5 * (start + end)
        r = label_radius if label_radius is not None else 1.35 * radius
        ax.text(*(c + r * np.array([np.cos(mid), np.sin(mid)])), label, ha="center", va="center")
    return ax


def plot_dimension(
    p: ArrayLike,
    q: ArrayLike,
    ax: Axes | None = None,
    label: str | None = None,
    offset: float = 0.0,
    text_offset: float = 0.12,
    **kw,
) -> Axes:
    """Draw a dimension line (double arrow with extension lines) from ``p`` to ``q``.

    ``offset`` shifts the arrow sideways (to the left of p -> q when positive), data units;
    the label sits ``text_offset`` further out, rotated along the arrow.
    """
    ax = _axes(ax)
    p, q = np.asarray(p, dtype=float), np.asarray(q, dtype=float)
    u = (q - p) / np.linalg.norm(q - p)
    n = np.array([-u[1], u[0]])
    a, b = p + offset * n, q + offset * n
    style = {"color": "0.2", "lw": 0.9} | kw
    ax.add_patch(FancyArrowPatch(a, b, arrowstyle="<|-|>", mutation_scale=10, **style))
    if offset:
        for end, base in ((a, p), (b, q)):
            ax.plot(*np.c_[base + 0.15 * (end - base), end + 0.08 * np.sign(offset) * n], **style)
    if label:
        angle = np.degrees(np.arctan2(u[1], u[0]))
        if angle > 90 or angle < -90:
            angle -= 180 * np.sign(angle)
        side = np.sign(offset) if offset else 1.0
        m = 0.5 * (a + b) + side * text_offset * n
        ax.text(*m, label, ha="center", va="center", rotation=angle, rotation_mode="anchor")
    return ax


def plot_right_angle(
    corner: ArrayLike, d1: ArrayLike, d2: ArrayLike, size: float, ax: Axes | None = None, **kw
) -> Axes:
    """Mark a right angle at ``corner`` between the unit directions ``d1`` and ``d2``."""
    ax = _axes(ax)
    c = np.asarray(corner, dtype=float)
    a, b = size * np.asarray(d1, dtype=float), size * np.asarray(d2, dtype=float)
    ax.plot(*np.array([c + a, c + a + b, c + b]).T, **({"color": "k", "lw": 0.8} | kw))
    return ax


def _place(shape: ArrayLike, pose: ArrayLike) -> np.ndarray:
    """Map points given in a robot frame (x forward, y left) to the world by ``pose``."""
    x, y, th = np.asarray(pose, dtype=float)
    c, s = np.cos(th), np.sin(th)
    return np.asarray(shape, dtype=float) @ np.array([[c, s], [-s, c]]) + [x, y]


def plot_pioneer(
    pose: ArrayLike = (0.0, 0.0, np.pi / 2),
    ax: Axes | None = None,
    length: float = 0.44,
    width: float = 0.38,
    laser: bool = True,
) -> Axes:
    """Draw a schematic top view of a Pioneer II robot (body, two drive wheels, caster, laser).

    Parameters
    ----------
    pose : array-like, shape (3,)
        Centre and heading of the robot (default: at the origin, facing +y).
    length, width : float
        Body size, metres (Pioneer II: about 0.44 m x 0.38 m).
    laser : bool
        Also draw the SICK LMS200 box on the front (its beam origin is
        ``laser_origin(pose, length)``).
    """
    ax = _axes(ax)
    hl, hw = length / 2, width / 2
    # An octagon with a blunt, rounded-looking nose: chamfers on every corner.
    cf, cr = 0.35 * hw, 0.22 * hw
    body = [
        (hl, -hw + cf), (hl, hw - cf), (hl - cf, hw), (-hl + cr, hw),
        (-hl, hw - cr), (-hl, -hw + cr), (-hl + cr, -hw), (hl - cf, -hw),
    ]  # fmt: skip
    ax.add_patch(
        Polygon(
            _place(body, pose), closed=True, facecolor="#d9534f", edgecolor="k", lw=1.2, zorder=3
        )
    )
    wl, ww = 0.19, 0.05  # drive wheels: 19 cm tyres, slightly outside the body
    for side in (1, -1):
        y0 = side * (hw + 0.005) - (ww if side < 0 else 0)
        wheel = [(-wl / 2, y0), (wl / 2, y0), (wl / 2, y0 + ww), (-wl / 2, y0 + ww)]
        ax.add_patch(
            Polygon(_place(wheel, pose), closed=True, facecolor="0.15", edgecolor="k", zorder=3)
        )
    cx, cy = _place([(-hl + 0.07, 0.0)], pose)[0]
    ax.add_patch(Circle((cx, cy), 0.03, facecolor="0.45", edgecolor="k", zorder=4))
    if laser:
        lx0, ld, lw = hl - 0.17, 0.155, 0.155  # SICK LMS200: 156 mm x 155 mm footprint
        box = [(lx0, -lw / 2), (lx0 + ld, -lw / 2), (lx0 + ld, lw / 2), (lx0, lw / 2)]
        ax.add_patch(
            Polygon(_place(box, pose), closed=True, facecolor="#4a7ab5", edgecolor="k", zorder=5)
        )
        ox, oy = laser_origin(pose, length)
        ax.add_patch(Circle((ox, oy), 0.02, facecolor="k", zorder=6))
    return ax


def laser_origin(pose: ArrayLike, length: float = 0.44) -> np.ndarray:
    """Where :func:`plot_pioneer` puts the laser's beam origin for a robot at ``pose``."""
    return _place([(length / 2 - 0.17 + 0.155 / 2 + 0.03, 0.0)], pose)[0]


def plot_laser_fan(
    origin: ArrayLike,
    heading: float,
    radius: float,
    ax: Axes | None = None,
    fov_deg: float = 180.0,
    n_rays: int = 19,
    **kw,
) -> Axes:
    """Draw a laser's field of view: a shaded fan of ``radius`` and ``n_rays`` evenly spread beams.

    The fan spans ``heading ± fov/2``; ``radius`` is the drawn (not necessarily the real)
    range.
    """
    ax = _axes(ax)
    o = np.asarray(origin, dtype=float)
    half = np.radians(fov_deg) / 2
    color = kw.pop("color", "tab:orange")
    ax.add_patch(
        Wedge(
            o, radius, np.degrees(heading - half), np.degrees(heading + half),
            facecolor=color, alpha=0.12, edgecolor=color, lw=1.0,
        )
    )  # fmt: skip
    a = heading + np.linspace(-half, half, n_rays)
    ends = o + radius * np.column_stack([np.cos(a), np.sin(a)])
    plot_rays(o, ends, ax=ax, colors=color, linewidths=0.8, alpha=0.8, **kw)
    return ax
