"""Interactive explorers for the notebooks: sliders for a threshold or a parameter, and one
figure that follows them.

An explorer shows its figure as an ordinary image output, updated in place when a slider
moves, so that the notebook as saved shows the last figure — useful before the kernel runs,
in a static viewer, on GitHub — and the sliders (ipywidgets) under it with a plain-text line
saying to run the cell, instead of ``interactive(children=(IntSlider(...``. Sliders act when
released (``continuous_update=False``); every redraw takes well under a second on a 2-core
machine (each explorer's work is one scan, one pair of lines or one short run).

Every control changes what its figure draws in one step from its default, up (down from the
top), not only a number in a title: a threshold is drawn where it acts (a line across the
quantity it is compared with, a band, a window, a box), the iterations by what each one does
(the tests move every control and compare the figures with their texts blanked; the browser
test moves each explorer's first). Each
``*_explorer`` function returns the :class:`Explorer`; ``explorer.set(name=value)`` moves
a control from code (what the tests do) and ``explorer.figure()`` draws the current state.
"""

from __future__ import annotations

import io
import time
from collections.abc import Callable
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from fhslam import plotting
from fhslam.extraction import ExtractionParams, cluster_scan, extract_lines
from fhslam.io.log import Log

__all__ = [
    "Explorer",
    "calibration_explorer",
    "clustering_explorer",
    "extraction_explorer",
    "similarity_explorer",
    "slam_noise_explorer",
    "slider",
]

FIGSIZE = (7.5, 4.5)


def slider(value: float, low: float, high: float, step: float, description: str, **kw: Any):
    """A labelled slider that acts when released, its whole name shown."""
    import ipywidgets as widgets

    cls = (
        widgets.IntSlider
        if all(isinstance(v, int) for v in (value, low, high, step))
        else (widgets.FloatSlider)
    )
    return cls(
        value=value,
        min=low,
        max=high,
        step=step,
        description=description,
        continuous_update=False,
        style={"description_width": "initial"},
        layout={"width": "460px"},
        **kw,
    )


class Explorer:
    """A figure drawn by ``draw(**values)`` from named controls (ipywidgets).

    Parameters
    ----------
    draw : callable
        ``draw(**{name: value}) -> Figure``; the figure is closed after it is shown.
    controls : dict
        Control name (``draw``'s keyword) -> ipywidgets value widget.
    title : str
        What the controls do, shown above them.
    """

    def __init__(self, draw: Callable[..., Figure], controls: dict[str, Any], title: str):
        self.draw, self.controls, self.title = draw, controls, title
        self.seconds = float("nan")  # the last redraw's duration
        self._handle = None
        for c in controls.values():
            c.observe(self._changed, names="value")

    def values(self) -> dict[str, Any]:
        return {name: c.value for name, c in self.controls.items()}

    def figure(self) -> Figure:
        return self.draw(**self.values())

    def png(self) -> bytes:
        t0 = time.perf_counter()
        fig = self.figure()
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=80)
        plt.close(fig)
        self.seconds = time.perf_counter() - t0
        return buf.getvalue()

    def set(self, **values: Any) -> None:
        """Move controls from code, as a slider would (the figure follows)."""
        for name, value in values.items():
            if name not in self.controls:
                raise KeyError(f"no control {name!r}; controls: {', '.join(self.controls)}")
            self.controls[name].value = value

    def _changed(self, change: Any) -> None:
        if self._handle is not None:
            from IPython.display import Image

            self._handle.update(Image(data=self.png(), format="png"))

    def _ipython_display_(self) -> None:
        import ipywidgets as widgets
        from IPython.display import Image, display

        self._handle = display(Image(data=self.png(), format="png"), display_id=True)
        box = widgets.VBox(
            [widgets.HTML(f"<b>{self.title}</b>"), *self.controls.values()],
            layout={"border": "1px solid #ddd", "padding": "4px 8px"},
        )
        bundle = box._repr_mimebundle_()
        bundle["text/plain"] = (
            f"[{self.title}: sliders {', '.join(self.controls)} — run this cell to use them]"
        )
        display(bundle, raw=True)


def _axes_labels(ax) -> None:
    ax.set_xlabel("x [m] (robot frame)")
    ax.set_ylabel("y [m]")


def _sqrt_scale(ax, top: float) -> None:
    """A square-root y axis from 0 to ``top`` metres: centimetre gaps stand apart near the
    bottom, and a threshold line still moves by a pixel or more at the top for a step of its
    slider."""
    ax.set_yscale("function", functions=(np.sqrt, np.square))
    ax.set_ylim(0.0, top)
    ticks = [t for t in (0.05, 0.1, 0.2, 0.5, 1.0, 2.0) if t < top]
    ax.set_yticks([0.0, *ticks], ["0", *(f"{t:g}" for t in ticks)])


def _gap_panel(
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
    _sqrt_scale(ax, top)
    ax.set_xlim(beams[0] - 2 if len(beams) else 0, beams[-1] + 2 if len(beams) else 1)
    ax.set_xlabel("beam (scan order)")
    ax.set_ylabel("gap to the next point [m]")
    ax.legend(loc="upper left", fontsize=7, framealpha=0.9)


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
        _axes_labels(ax)
        ax.set_title(
            f"scan {scan}, gap {cluster_gap:.2f} m: {len(sizes)} clusters, "
            f"{int((sizes >= min_points).sum())} with ≥ {min_points} points"
        )
        _gap_panel(gap_ax, pts, beams, labels, cluster_gap, top=2.2)
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


def _window_panel(ax, pts, p: ExtractionParams) -> None:
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


def _support_panel(ax, pts, beams, found, inlier_dist: float, top: float) -> None:
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


def extraction_explorer(log: Log, k: int):
    """Notebook 03: the lines of scan ``k`` under the extraction's thresholds, the support
    threshold first (the paper's "until the number to support a certain slope is lower than
    the threshold"). Left: the lines, each marked with its number and its support (scan
    points), on the clusters and the points densification adds (grey dots; they only vote);
    the title gives the count of lines and the thresholds.

    Right, each other threshold drawn where it acts: the gaps between neighbouring points with
    the cluster gap and the densify step (:func:`_gap_panel`); the pair directions of each
    cluster around its dominant one, with the Hough window (:func:`_window_panel`); and each
    point's distance to the nearest line, with the inlier distance (:func:`_support_panel`)."""
    from fhslam.extraction import densify

    d = ExtractionParams()

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
        _axes_labels(ax)
        ax.set_title(
            f"scan {scan}: {len(found)} lines with ≥ {min_points} points (in parentheses)\n"
            f"window ±{window_deg:g}°, inliers within {100 * inlier_dist:g} cm, "
            f"gap {cluster_gap:.2f} m, densify {densify_step:.2f} m",
            fontsize=10,
        )
        _gap_panel(gap_ax, pts, beams, labels, cluster_gap, top=1.6, densify_step=densify_step)
        gap_ax.set_title("clustering and densification", fontsize=10)
        _window_panel(window_ax, pts, p)
        window_ax.set_title("the Hough window on the slope histogram", fontsize=10)
        _support_panel(support_ax, pts, beams, found, inlier_dist, top=0.16)
        support_ax.set_title("the support of the lines", fontsize=10)
        return fig

    return Explorer(
        draw,
        {
            "min_points": slider(int(d.min_points), 2, 64, 1, "support threshold [points]"),
            "window_deg": slider(d.window_deg, 0.0, 20.0, 0.5, "Hough window ± [°]"),
            "inlier_dist": slider(
                d.inlier_dist, 0.005, 0.15, 0.005, "inlier distance [m]", readout_format=".3f"
            ),
            "cluster_gap": slider(d.cluster_gap, 0.05, 1.5, 0.05, "cluster gap [m]"),
            "densify_step": slider(d.densify_step, 0.0, 0.3, 0.01, "densify step [m]"),
            "scan": slider(int(k), 0, len(log) - 1, 1, "scan"),
        },
        "Fast Hough extraction: the thresholds",
    )


def similarity_explorer():
    """Notebook 04: the four similarity conditions of a reference line (Fig. 7's) and a new
    line that the sliders turn about its middle (the first slider: each 1° step changes the
    angle in the title), move across and slide along, under thresholds the sliders set; the
    robot stands at :data:`~fhslam.figures.scenes.SIMILARITY_POSE`, below the reference.

    Each threshold is drawn where it acts: (c)'s as a band either side of the reference, in
    which the new line's endpoints must lie, and (b)'s as a wedge through the new line's middle,
    the reference's direction turned by up to the threshold either way, in which the new line
    must lie."""
    from fhslam.figures.scenes import SIMILARITY_POSE, similarity_examples
    from fhslam.geometry import compose
    from fhslam.lines import transform_lines
    from fhslam.matching import MatchParams, similarity

    ref, _, _ = similarity_examples()[7]
    mid = 0.5 * (np.asarray(ref.sp) + np.asarray(ref.ep))

    def draw(turn_deg, offset, slide, max_angle_deg, max_distance) -> Figure:
        # the new line: the reference turned about its middle, moved across and along it
        about = (mid[0], mid[1], 0.0)
        moved = compose(
            compose(about, (slide, offset, np.radians(turn_deg))), (-mid[0], -mid[1], 0)
        )
        (new,) = transform_lines([ref], moved)
        params = MatchParams(max_angle_deg=max_angle_deg, max_distance=max_distance)
        s = similarity(ref, new, params, pose=SIMILARITY_POSE)
        fig, ax = plt.subplots(figsize=(8.5, 3.4), layout="constrained")
        # (c)'s band about the (horizontal) reference: the new line's endpoints must lie in
        # it, and the reference's endpoints as close to the new line
        ax.fill_between(
            [ref.sp[0], ref.ep[0]],
            mid[1] - max_distance,
            mid[1] + max_distance,
            color="0.9",
            zorder=1,
            label=f"(c) band ±{max_distance:.2f} m",
        )
        # (b)'s wedge: the directions within the threshold of the reference's (horizontal),
        # through the new line's middle; the new line lies in it when (b) holds
        centre = np.asarray(compose(moved, (mid[0], mid[1], 0.0))[:2])
        a = np.radians(max_angle_deg)
        up, down = np.array([np.cos(a), np.sin(a)]), np.array([np.cos(a), -np.sin(a)])
        reach = 12.0  # beyond the axes either way: the wedge is cut at their edges
        corners = [centre + reach * up, centre + reach * down, centre]
        corners += [centre - reach * up, centre - reach * down, centre]
        ax.fill(
            *np.array(corners).T,
            color="tab:blue",
            alpha=0.12,
            lw=0,
            zorder=1,
            label=f"(b) wedge ±{max_angle_deg:g}°",
        )
        plotting.plot_lines([ref], ax=ax, color="0.5", linewidth=5, label="reference")
        color = "tab:green" if s.similar else "tab:red"
        plotting.plot_lines([new], ax=ax, color=color, linewidth=2, label="new line")
        plotting.plot_robot(SIMILARITY_POSE, ax=ax, size=0.2, label="robot")
        ax.set(xlim=(-4.8, 4.8), ylim=(0.4, 3.6))
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8)
        ok = {True: "✓", False: "✗"}
        ax.set_title(
            f"(a) same side {ok[s.same_direction]}   "
            f"(b) angle {s.angle_deg:.1f}° {ok[s.angle_ok]}   "
            f"(c) distance {s.distance:.2f} m {ok[s.distance_ok]}   "
            f"(d) overlap {s.overlap:+.2f} m {ok[s.overlap_ok]}\n→ "
            + ("similar" if s.similar else "not similar"),
            fontsize=10,
        )
        return fig

    d = MatchParams()
    return Explorer(
        draw,
        {
            "turn_deg": slider(0.0, -30.0, 30.0, 1.0, "turn the new line [°]"),
            "offset": slider(0.0, -1.5, 1.0, 0.02, "move it across [m]"),
            "slide": slider(0.0, -3.5, 3.5, 0.1, "slide it along [m]"),
            "max_angle_deg": slider(d.max_angle_deg, 0.5, 30.0, 0.5, "threshold (b): angle [°]"),
            # 5 cm steps: the band's edges move by a few pixels (1 cm would be under one)
            "max_distance": slider(d.max_distance, 0.05, 1.0, 0.05, "threshold (c): distance [m]"),
        },
        "Similarity: move the new line and the thresholds",
    )


def calibration_explorer(log: Log, k: int):
    """Notebook 05: self-calibration of a pose that the sliders put wrong, on the lines of
    scan ``k`` placed with the true pose as the reference map.

    The sliders set the odometry's error in the robot's frame (forward, left, heading), the
    similarity thresholds (c) and (b) that decide which new lines are matched, and the
    Gauss-Newton rounds. Left: the new lines at the predicted pose, matched ones solid,
    unmatched dashed; middle: at the calibrated pose. The dashed triangle is the true pose.
    Right: what the rounds minimise, the rms distance of the matched lines' endpoints to their
    reference lines, after each round up to the slider's top, those applied solid and the
    others dotted: where it no longer falls, another round changes nothing."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Rectangle

    from fhslam.calibration import calibrate_pose
    from fhslam.geometry import compose, wrap_angle
    from fhslam.lines import transform_lines
    from fhslam.matching import MatchParams, match_lines, similarity_matrix

    truth = log.truth[k]
    points, _ = log.scan(k).points()
    observed = extract_lines(points)
    references = transform_lines(observed, truth)
    legend = [
        Line2D([], [], color="0.6", lw=5, label="reference lines"),
        Line2D([], [], color="tab:red", lw=2.5, label="new lines, matched"),
        Line2D([], [], color="tab:orange", lw=2.5, ls="--", label="new lines, not matched"),
        Line2D([], [], color="k", marker="^", ms=9, mfc=plotting.ROBOT_COLOR, ls="", label="pose"),
        Line2D([], [], color="k", marker="^", ms=9, mfc="none", ls="", label="true pose"),
    ]

    def segments(ax, lines, **kw) -> None:
        """All ``lines`` as one artist (a redraw well under a second): NaN between them."""
        if lines:
            xy = np.array([[q.sp, q.ep, (np.nan, np.nan)] for q in lines]).reshape(-1, 2)
            ax.plot(*xy.T, solid_capstyle="round", **kw)

    rounds = 6  # the iterations slider's top
    floor = 1e-9  # mm: below it, floating-point rounding

    def residual(pose, pairs) -> float:
        """The rms distance (m) of the matched lines' endpoints, placed at ``pose``, to their
        reference lines: what the Gauss-Newton rounds minimise."""
        placed = transform_lines([observed[i] for i, _ in pairs], pose)
        d = [
            references[j].rho - x * np.cos(references[j].theta) - y * np.sin(references[j].theta)
            for q, (_, j) in zip(placed, pairs, strict=True)
            for x, y in (q.sp, q.ep)
        ]
        return float(np.sqrt(np.mean(np.square(d))))

    def convergence(ax, predicted, pairs, iterations) -> None:
        each = np.arange(rounds + 1)
        if pairs:
            poses = [
                calibrate_pose(observed, references, pairs, predicted, iterations=n).pose
                for n in each
            ]
            mm = np.maximum([1000 * residual(p, pairs) for p in poses], floor)
            n, done = iterations, f"{iterations} round{'s' if iterations != 1 else ''} applied"
            ax.plot(each[n:], mm[n:], ":o", c="0.55", mfc="w", label="more rounds")
            ax.plot(each[: n + 1], mm[: n + 1], "-o", c="tab:red", label=done)
            ax.legend(loc="upper right", fontsize=8)
        else:
            ax.text(
                0.5,
                0.5,
                "no line matched:\nnothing to minimise",
                ha="center",
                va="center",
                transform=ax.transAxes,
            )
        ax.set_yscale("log")
        ax.set_ylim(floor / 10, 1e4)
        ax.axhspan(floor / 10, floor, color="0.92", zorder=0)
        ax.text(rounds, floor / 3, "rounding", ha="right", va="center", fontsize=8, color="0.4")
        ax.set_xticks(each)
        ax.set_xlim(-0.4, rounds + 0.4)
        ax.set_xlabel("Gauss-Newton round")
        ax.set_ylabel("rms endpoint distance [mm]")
        ax.set_title("matched endpoints to their lines", fontsize=10)

    angle_top, gate_top = 21.0, 1.6  # just above the sliders' tops

    def thresholds(ax, placed, params, predicted, match) -> None:
        """Thresholds (b) and (c) where they act: each new line at the predicted pose as a
        point, its angle to a reference line across, its endpoint distance (the largest of
        the four) up; the box of the two thresholds shaded. A line is matched inside the box:
        to the reference it is matched to, else the nearest one seen from the same side and
        overlapping it ((a) and (d), which the sliders do not set)."""
        m = similarity_matrix(placed, references, params, predicted)
        cost = np.where(
            m["same_direction"] & m["overlap_ok"], m["distance"] + 0.01 * m["angle_deg"], np.inf
        )
        ax.add_patch(
            Rectangle(
                (0, 0),
                params.max_angle_deg,
                params.max_distance,
                facecolor="tab:blue",
                alpha=0.15,
                edgecolor="none",
                label="(b) and (c) hold",
            )
        )
        ax.plot(
            [0, params.max_angle_deg, params.max_angle_deg],
            [params.max_distance, params.max_distance, 0],
            color="tab:blue",
            lw=1.2,
        )
        for i in range(len(placed)):
            j = match[i] if match[i] >= 0 else int(cost[i].argmin())
            if not np.isfinite(cost[i, j]):
                continue  # no reference seen from the same side and overlapping
            xy = min(m["angle_deg"][i, j], angle_top), min(m["distance"][i, j], gate_top)
            ok = match[i] >= 0
            ax.plot(
                *xy,
                "o",
                ms=6,
                mfc="tab:red" if ok else "none",
                mec="tab:red" if ok else "tab:orange",
                mew=1.5,
                clip_on=False,
                zorder=4,
            )
        ax.set_xlim(0, angle_top)
        ax.set_ylim(0, gate_top)
        ax.set_xlabel("(b) angle to the reference line [°]")
        ax.set_ylabel("(c) endpoint distance [m]")
        ax.set_title("matched inside the thresholds' box", fontsize=10)

    def draw(dx_cm, dy_cm, dtheta_deg, gate, max_angle_deg, iterations) -> Figure:
        predicted = compose(truth, (dx_cm / 100, dy_cm / 100, np.radians(dtheta_deg)))
        params = MatchParams(max_distance=gate, max_angle_deg=max_angle_deg)
        at_predicted = transform_lines(observed, predicted)
        match = match_lines(at_predicted, references, params, predicted)
        pairs = [(i, int(j)) for i, j in enumerate(match) if j >= 0]
        cal = calibrate_pose(observed, references, pairs, predicted, iterations=iterations)
        fig = plt.figure(figsize=(13, 6))
        grid = fig.add_gridspec(2, 3, width_ratios=[1, 1, 0.8], hspace=0.5, wspace=0.28)
        axes = [fig.add_subplot(grid[:, 0]), fig.add_subplot(grid[:, 1])]
        axes += [fig.add_subplot(grid[1, 2]), fig.add_subplot(grid[0, 2])]
        convergence(axes[2], predicted, pairs, iterations)
        thresholds(axes[3], at_predicted, params, predicted, match)
        ends = [np.array([[r.sp, r.ep] for r in references]).reshape(-1, 2)]
        for ax, p, name in ((axes[0], predicted, "predicted"), (axes[1], cal.pose, "calibrated")):
            placed = transform_lines(observed, p)
            ends.append(np.array([[q.sp, q.ep] for q in placed]).reshape(-1, 2))
            segments(ax, references, color="0.6", lw=5)
            matched = [placed[i] for i, _ in pairs]
            unmatched = [q for i, q in enumerate(placed) if match[i] < 0]
            segments(ax, matched, color="tab:red", lw=2.5, marker="o", ms=4)
            segments(ax, unmatched, color="tab:orange", lw=2.5, ls="--", marker="o", ms=4)
            plotting.plot_robot(p, ax=ax)
            plotting.plot_robot(truth, ax=ax, facecolor="none", linestyle="--", zorder=7)
            err = 100 * np.hypot(*(np.asarray(p[:2]) - truth[:2]))
            dth = round(float(np.degrees(wrap_angle(p[2] - truth[2]))), 2) + 0.0  # no "-0.00"
            ax.set_title(f"{name}: {err:.1f} cm, {dth:+.2f}° off")
            ax.set_xlabel("x [m] (world)")
        lo, hi = np.vstack(ends).min(axis=0) - 0.5, np.vstack(ends).max(axis=0) + 0.5
        for ax in axes[:2]:  # the same window on both sides, to see what moved
            ax.set_aspect("equal", adjustable="box")
            ax.set_xlim(lo[0], hi[0])
            ax.set_ylim(lo[1], hi[1])
        axes[0].set_ylabel("y [m] (world)")
        fig.legend(handles=legend, loc="lower center", ncol=5, fontsize=9, frameon=False)
        fig.subplots_adjust(left=0.06, right=0.98, bottom=0.16, top=0.85)
        fixed = {
            (True, True): "the position in both directions",
            (False, True): "the position in one direction only (the other is kept)",
        }.get(cal.constrained, "no position")
        fig.suptitle(
            f"{len(pairs)} of {len(observed)} lines matched (gate (c) {gate:.2f} m, "
            f"(b) {max_angle_deg:g}°)\nthey fix the heading and {fixed}"
            if pairs
            else f"no line matched (gate (c) {gate:.2f} m, (b) {max_angle_deg:g}°)\n"
            "the predicted pose is kept"
        )
        return fig

    d = MatchParams()
    return Explorer(
        draw,
        {
            "dx_cm": slider(20.0, -50.0, 50.0, 1.0, "odometry error forward (robot x) [cm]"),
            "dy_cm": slider(-15.0, -50.0, 50.0, 1.0, "odometry error left (robot y) [cm]"),
            "dtheta_deg": slider(3.0, -10.0, 10.0, 0.5, "odometry error heading [°]"),
            "gate": slider(0.6, 0.05, 1.5, 0.05, "threshold (c): distance gate [m]"),
            "max_angle_deg": slider(d.max_angle_deg, 1.0, 20.0, 0.5, "threshold (b): angle [°]"),
            "iterations": slider(3, 0, rounds, 1, "Gauss-Newton iterations"),
        },
        "Self-calibration: put the pose wrong, see it corrected",
    )


def slam_noise_explorer(seed: int = 0, scans: int = 250):
    """Notebook 06: FH-SLAM on the first ``scans`` scans of the paper world under odometry
    drift and range noise that the sliders set (a new simulation each time, seeded)."""
    from dataclasses import replace

    from fhslam.metrics import ate
    from fhslam.pipeline import run_slam
    from fhslam.sim import LaserParams, OdometryNoise, paper_world, simulate

    world, base = paper_world(), OdometryNoise.drifting()

    def draw(drift, range_noise_cm, seed) -> Figure:
        odo = replace(
            base,
            **{
                f: drift * getattr(base, f)
                for f in (
                    "alpha1",
                    "alpha2",
                    "alpha3",
                    "alpha4",
                    "scale_error",
                    "heading_bias",
                    "turn_scale_error",
                )
            },
        )
        laser = LaserParams(range_noise_std=range_noise_cm / 100)
        log = simulate(world, seed=seed, laser=laser, odometry=odo, max_scans=scans)
        result = run_slam(log, "fht")
        fig, ax = plt.subplots(figsize=FIGSIZE)
        plotting.plot_walls(world.walls, ax=ax, color="0.75")
        ax.plot(*log.truth[:, :2].T, "k-", lw=2, label="truth")
        e_odo, e_slam = ate(log.odometry, log.truth).rmse, ate(result.poses, log.truth).rmse
        ax.plot(*log.odometry[:, :2].T, "tab:orange", label=f"odometry (ATE {e_odo:.2f} m)")
        ax.plot(*result.poses[:, :2].T, "tab:blue", label=f"FH-SLAM (ATE {100 * e_slam:.1f} cm)")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.legend(loc="best", fontsize=8)
        ax.set_title(f"first {len(log)} scans, drift ×{drift:g}, range noise {range_noise_cm:g} cm")
        return fig

    return Explorer(
        draw,
        {
            "drift": slider(1.0, 0.0, 4.0, 0.25, "odometry drift (× drifting)"),
            "range_noise_cm": slider(1.0, 0.0, 8.0, 0.5, "range noise σ [cm]"),
            "seed": slider(int(seed), 0, 20, 1, "seed"),
        },
        "SLAM under noise: odometry drift and range noise",
    )
