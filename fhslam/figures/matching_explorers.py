"""The matching explorers of notebooks 04 and 05: the four similarity conditions of two lines
under thresholds the sliders set (:func:`similarity_explorer`), and the self-calibration of a
pose that the sliders put wrong (:func:`calibration_explorer`), with their drawing helpers.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from fhslam import plotting
from fhslam.extraction import extract_lines
from fhslam.figures.explorer_base import Explorer, slider
from fhslam.io.log import Log

ROUNDS = 6
"""The top of the calibration explorer's iterations slider: the rounds its right panel shows."""

FLOOR = 1e-9
"""Millimetres: an rms endpoint distance below it is floating-point rounding."""

ANGLE_TOP, GATE_TOP = 21.0, 1.6
"""The thresholds panel's axes: just above the tops of the (b) and (c) sliders."""


def _threshold_regions(ax, ref, mid, moved, max_angle_deg: float, max_distance: float) -> None:
    """Thresholds (c) and (b) where they act on the new line, the reference ``ref`` moved by
    ``moved`` about its middle ``mid``: (c)'s band about the reference and (b)'s wedge through
    the new line's middle."""
    from fhslam.geometry import compose

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


def _similarity_title(s) -> str:
    """The four conditions of the similarity ``s``, each ✓ or ✗, and the verdict."""
    ok = {True: "✓", False: "✗"}
    return (
        f"(a) same side {ok[s.same_direction]}   "
        f"(b) angle {s.angle_deg:.1f}° {ok[s.angle_ok]}   "
        f"(c) distance {s.distance:.2f} m {ok[s.distance_ok]}   "
        f"(d) overlap {s.overlap:+.2f} m {ok[s.overlap_ok]}\n→ "
        + ("similar" if s.similar else "not similar")
    )


def _similarity_controls() -> dict:
    """The sliders of :func:`similarity_explorer`: the new line's move, then the thresholds."""
    from fhslam.matching import MatchParams

    d = MatchParams()
    return {
        "turn_deg": slider(0.0, -30.0, 30.0, 1.0, "turn the new line [°]"),
        "offset": slider(0.0, -1.5, 1.0, 0.02, "move it across [m]"),
        "slide": slider(0.0, -3.5, 3.5, 0.1, "slide it along [m]"),
        "max_angle_deg": slider(d.max_angle_deg, 0.5, 30.0, 0.5, "threshold (b): angle [°]"),
        # 5 cm steps: the band's edges move by a few pixels (1 cm would be under one)
        "max_distance": slider(d.max_distance, 0.05, 1.0, 0.05, "threshold (c): distance [m]"),
    }


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
        _threshold_regions(ax, ref, mid, moved, max_angle_deg, max_distance)
        plotting.plot_lines([ref], ax=ax, color="0.5", linewidth=5, label="reference")
        color = "tab:green" if s.similar else "tab:red"
        plotting.plot_lines([new], ax=ax, color=color, linewidth=2, label="new line")
        plotting.plot_robot(SIMILARITY_POSE, ax=ax, size=0.2, label="robot")
        ax.set(xlim=(-4.8, 4.8), ylim=(0.4, 3.6))
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8)
        ax.set_title(_similarity_title(s), fontsize=10)
        return fig

    return Explorer(
        draw, _similarity_controls(), "Similarity: move the new line and the thresholds"
    )


def _calibration_legend() -> list:
    """The figure legend's entries of :func:`calibration_explorer`."""
    from matplotlib.lines import Line2D

    return [
        Line2D([], [], color="0.6", lw=5, label="reference lines"),
        Line2D([], [], color="tab:red", lw=2.5, label="new lines, matched"),
        Line2D([], [], color="tab:orange", lw=2.5, ls="--", label="new lines, not matched"),
        Line2D([], [], color="k", marker="^", ms=9, mfc=plotting.ROBOT_COLOR, ls="", label="pose"),
        Line2D([], [], color="k", marker="^", ms=9, mfc="none", ls="", label="true pose"),
    ]


def _segments(ax, lines, **kw) -> None:
    """All ``lines`` as one artist (a redraw well under a second): NaN between them."""
    if lines:
        xy = np.array([[q.sp, q.ep, (np.nan, np.nan)] for q in lines]).reshape(-1, 2)
        ax.plot(*xy.T, solid_capstyle="round", **kw)


def _residual(observed, references, pose, pairs) -> float:
    """The rms distance (m) of the matched lines' endpoints, placed at ``pose``, to their
    reference lines: what the Gauss-Newton rounds minimise."""
    from fhslam.lines import transform_lines

    placed = transform_lines([observed[i] for i, _ in pairs], pose)
    d = [
        references[j].rho - x * np.cos(references[j].theta) - y * np.sin(references[j].theta)
        for q, (_, j) in zip(placed, pairs, strict=True)
        for x, y in (q.sp, q.ep)
    ]
    return float(np.sqrt(np.mean(np.square(d))))


def _convergence_panel(ax, observed, references, predicted, pairs, iterations) -> None:
    """What the rounds minimise (:func:`_residual`) after each round up to :data:`ROUNDS`,
    those applied solid and the others dotted; a note where nothing was matched."""
    from fhslam.calibration import calibrate_pose

    each = np.arange(ROUNDS + 1)
    if pairs:
        poses = [
            calibrate_pose(observed, references, pairs, predicted, iterations=n).pose for n in each
        ]
        mm = np.maximum([1000 * _residual(observed, references, p, pairs) for p in poses], FLOOR)
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
    ax.set_ylim(FLOOR / 10, 1e4)
    ax.axhspan(FLOOR / 10, FLOOR, color="0.92", zorder=0)
    ax.text(ROUNDS, FLOOR / 3, "rounding", ha="right", va="center", fontsize=8, color="0.4")
    ax.set_xticks(each)
    ax.set_xlim(-0.4, ROUNDS + 0.4)
    ax.set_xlabel("Gauss-Newton round")
    ax.set_ylabel("rms endpoint distance [mm]")
    ax.set_title("matched endpoints to their lines", fontsize=10)


def _thresholds_box(ax, params) -> None:
    """The box where thresholds (b) and (c) hold, shaded and outlined."""
    from matplotlib.patches import Rectangle

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


def _thresholds_panel(ax, references, placed, params, predicted, match) -> None:
    """Thresholds (b) and (c) where they act: each new line at the predicted pose as a
    point, its angle to a reference line across, its endpoint distance (the largest of
    the four) up; the box of the two thresholds shaded. A line is matched inside the box:
    to the reference it is matched to, else the nearest one seen from the same side and
    overlapping it ((a) and (d), which the sliders do not set)."""
    from fhslam.matching import similarity_matrix

    m = similarity_matrix(placed, references, params, predicted)
    cost = np.where(
        m["same_direction"] & m["overlap_ok"], m["distance"] + 0.01 * m["angle_deg"], np.inf
    )
    _thresholds_box(ax, params)
    for i in range(len(placed)):
        j = match[i] if match[i] >= 0 else int(cost[i].argmin())
        if not np.isfinite(cost[i, j]):
            continue  # no reference seen from the same side and overlapping
        xy = min(m["angle_deg"][i, j], ANGLE_TOP), min(m["distance"][i, j], GATE_TOP)
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
    ax.set_xlim(0, ANGLE_TOP)
    ax.set_ylim(0, GATE_TOP)
    ax.set_xlabel("(b) angle to the reference line [°]")
    ax.set_ylabel("(c) endpoint distance [m]")
    ax.set_title("matched inside the thresholds' box", fontsize=10)


def _pose_panels(axes, observed, references, truth, poses, pairs, match) -> None:
    """The new lines placed at each of ``poses`` (``{name: pose}``, one panel each) on the
    reference lines, matched ones solid and unmatched dashed, the pose and the true one
    (dashed); the same window on every panel, to see what moved."""
    from fhslam.geometry import wrap_angle
    from fhslam.lines import transform_lines

    ends = [np.array([[r.sp, r.ep] for r in references]).reshape(-1, 2)]
    for ax, (name, p) in zip(axes, poses.items(), strict=True):
        placed = transform_lines(observed, p)
        ends.append(np.array([[q.sp, q.ep] for q in placed]).reshape(-1, 2))
        _segments(ax, references, color="0.6", lw=5)
        matched = [placed[i] for i, _ in pairs]
        unmatched = [q for i, q in enumerate(placed) if match[i] < 0]
        _segments(ax, matched, color="tab:red", lw=2.5, marker="o", ms=4)
        _segments(ax, unmatched, color="tab:orange", lw=2.5, ls="--", marker="o", ms=4)
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


def _calibration_title(cal, n_pairs: int, n_lines: int, gate: float, max_angle_deg) -> str:
    """The figure's title: how many lines matched and what they fix of the pose."""
    fixed = {
        (True, True): "the position in both directions",
        (False, True): "the position in one direction only (the other is kept)",
    }.get(cal.constrained, "no position")
    return (
        f"{n_pairs} of {n_lines} lines matched (gate (c) {gate:.2f} m, "
        f"(b) {max_angle_deg:g}°)\nthey fix the heading and {fixed}"
        if n_pairs
        else f"no line matched (gate (c) {gate:.2f} m, (b) {max_angle_deg:g}°)\n"
        "the predicted pose is kept"
    )


def _calibration_controls() -> dict:
    """The sliders of :func:`calibration_explorer`: the odometry's error, the thresholds,
    the rounds."""
    from fhslam.matching import MatchParams

    d = MatchParams()
    return {
        "dx_cm": slider(20.0, -50.0, 50.0, 1.0, "odometry error forward (robot x) [cm]"),
        "dy_cm": slider(-15.0, -50.0, 50.0, 1.0, "odometry error left (robot y) [cm]"),
        "dtheta_deg": slider(3.0, -10.0, 10.0, 0.5, "odometry error heading [°]"),
        "gate": slider(0.6, 0.05, 1.5, 0.05, "threshold (c): distance gate [m]"),
        "max_angle_deg": slider(d.max_angle_deg, 1.0, 20.0, 0.5, "threshold (b): angle [°]"),
        "iterations": slider(3, 0, ROUNDS, 1, "Gauss-Newton iterations"),
    }


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
    from fhslam.calibration import calibrate_pose
    from fhslam.geometry import compose
    from fhslam.lines import transform_lines
    from fhslam.matching import MatchParams, match_lines

    truth = log.truth[k]
    points, _ = log.scan(k).points()
    observed = extract_lines(points)
    references = transform_lines(observed, truth)
    legend = _calibration_legend()

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
        _convergence_panel(axes[2], observed, references, predicted, pairs, iterations)
        _thresholds_panel(axes[3], references, at_predicted, params, predicted, match)
        poses = {"predicted": predicted, "calibrated": cal.pose}
        _pose_panels(axes[:2], observed, references, truth, poses, pairs, match)
        axes[0].set_ylabel("y [m] (world)")
        fig.legend(handles=legend, loc="lower center", ncol=5, fontsize=9, frameon=False)
        fig.subplots_adjust(left=0.06, right=0.98, bottom=0.16, top=0.85)
        fig.suptitle(_calibration_title(cal, len(pairs), len(observed), gate, max_angle_deg))
        return fig

    return Explorer(
        draw, _calibration_controls(), "Self-calibration: put the pose wrong, see it corrected"
    )
