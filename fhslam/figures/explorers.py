"""Interactive explorers for the notebooks: sliders for a threshold or a parameter, and one
figure that follows them.

An explorer shows its figure as an ordinary image output, updated in place when a slider
moves, so that the notebook as saved shows the last figure — useful before the kernel runs,
in a static viewer, on GitHub — and the sliders (ipywidgets) under it with a plain-text line
saying to run the cell, instead of ``interactive(children=(IntSlider(...``. Sliders act when
released (``continuous_update=False``); every redraw takes well under a second on a 2-core
machine (each explorer's work is one scan, one pair of lines or one short run).

Every explorer's first control changes its figure (the browser test moves it). Each
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


def clustering_explorer(log: Log, k: int, min_points: int = ExtractionParams().min_points):
    """Notebook 02: the clusters of scan ``k`` as the gap between neighbours changes."""

    def draw(cluster_gap: float, scan: int) -> Figure:
        pts, _ = log.scan(scan).points()
        labels = cluster_scan(pts, cluster_gap)
        sizes = np.bincount(labels) if len(labels) else np.zeros(0, int)
        fig, ax = plt.subplots(figsize=FIGSIZE)
        plotting.plot_clusters(pts, labels, ax=ax)
        ax.plot(0, 0, "k^", ms=9, label="robot")
        _axes_labels(ax)
        ax.set_title(
            f"scan {scan}, gap {cluster_gap:.2f} m: {len(sizes)} clusters, "
            f"{int((sizes >= min_points).sum())} with ≥ {min_points} points"
        )
        return fig

    return Explorer(
        draw,
        {
            "cluster_gap": slider(0.3, 0.02, 2.0, 0.02, "cluster gap [m]"),
            "scan": slider(int(k), 0, len(log) - 1, 1, "scan"),
        },
        "Clustering: a new cluster where neighbours are farther apart than the gap",
    )


def extraction_explorer(log: Log, k: int):
    """Notebook 03: the lines of scan ``k`` under the extraction's thresholds, the support
    threshold first (the paper's "until the number to support a certain slope is lower than
    the threshold"). Each line is marked with its number and its support (scan points); the
    title gives the count of lines and the thresholds."""
    d = ExtractionParams()

    def draw(min_points, window_deg, inlier_dist, cluster_gap, densify_step, scan) -> Figure:
        pts, _ = log.scan(scan).points()
        p = ExtractionParams(
            cluster_gap=cluster_gap,
            window_deg=window_deg,
            inlier_dist=inlier_dist,
            min_points=min_points,
            densify_step=densify_step,
        )
        found = extract_lines(pts, p)
        fig, ax = plt.subplots(figsize=FIGSIZE)
        plotting.plot_clusters(pts, cluster_scan(pts, cluster_gap), ax=ax)
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
    robot stands at :data:`~fhslam.figures.scenes.SIMILARITY_POSE`, below the reference."""
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
            "max_distance": slider(d.max_distance, 0.01, 1.0, 0.01, "threshold (c): distance [m]"),
        },
        "Similarity: move the new line and the thresholds",
    )


def calibration_explorer(log: Log, k: int):
    """Notebook 05: self-calibration of a pose that the sliders put wrong, on the lines of
    scan ``k`` placed with the true pose as the reference map.

    The sliders set the odometry's error in the robot's frame (forward, left, heading), the
    similarity thresholds (c) and (b) that decide which new lines are matched, and the
    Gauss-Newton rounds. Left: the new lines at the predicted pose, matched ones solid,
    unmatched dashed; right: at the calibrated pose. The dashed triangle is the true pose."""
    from matplotlib.lines import Line2D

    from fhslam.calibration import calibrate_pose
    from fhslam.geometry import compose, wrap_angle
    from fhslam.lines import transform_lines
    from fhslam.matching import MatchParams, match_lines

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

    def draw(dx_cm, dy_cm, dtheta_deg, gate, max_angle_deg, iterations) -> Figure:
        predicted = compose(truth, (dx_cm / 100, dy_cm / 100, np.radians(dtheta_deg)))
        params = MatchParams(max_distance=gate, max_angle_deg=max_angle_deg)
        match = match_lines(transform_lines(observed, predicted), references, params, predicted)
        pairs = [(i, int(j)) for i, j in enumerate(match) if j >= 0]
        cal = calibrate_pose(observed, references, pairs, predicted, iterations=iterations)
        fig, axes = plt.subplots(1, 2, figsize=(10, 5.2))
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
        for ax in axes:  # the same window on both sides, to see what moved
            ax.set_aspect("equal", adjustable="box")
            ax.set_xlim(lo[0], hi[0])
            ax.set_ylim(lo[1], hi[1])
        axes[0].set_ylabel("y [m] (world)")
        fig.legend(handles=legend, loc="lower center", ncol=5, fontsize=9, frameon=False)
        fig.subplots_adjust(left=0.07, right=0.98, bottom=0.2, top=0.8, wspace=0.2)
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
            "iterations": slider(3, 0, 6, 1, "Gauss-Newton iterations"),
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
