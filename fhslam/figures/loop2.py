"""Figures 6-11: Loop 2, the line attributes, the four similarity conditions and merging,
drawn from the worked examples of :mod:`fhslam.figures.scenes`."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from fhslam import plotting
from fhslam.figures.scenes import (
    _fig06_points,
    line_attributes_example,
    merging_example,
    similarity_examples,
)
from fhslam.matching import MatchParams, Similarity, merge, similarity


def _fig06_axes(ax) -> None:
    """The x and y axes through the origin, as arrows."""
    ax.annotate("", (4.3, 0), (-0.6, 0), arrowprops={"arrowstyle": "-|>", "color": "0.5"})
    ax.annotate("", (0, 3.55), (0, -0.5), arrowprops={"arrowstyle": "-|>", "color": "0.5"})
    ax.text(4.3, -0.12, "x", ha="right", va="top", color="0.4")
    ax.text(-0.08, 3.55, "y", ha="right", va="top", color="0.4")


def _fig06_segment(ax, line, pts, P, u) -> None:
    """The infinite line through P (direction ``u``), the segment AB, its points and its
    length l."""
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


def _fig06_rho_theta(ax, line, P, nrm, u) -> None:
    """O, the foot P of the normal from O, rho and theta."""
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


def _fig06_robot(ax, line, pose, nrm, u) -> None:
    """The robot, its distance d to the line (to the foot of its normal) and dir."""
    x, y, _ = pose
    foot = np.array([x, y]) + line.d * nrm
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


def _fig06_attributes_text(line, pose) -> str:
    """The box of the line's attributes as observed from ``pose``, and how dir is worked out."""
    x, y, _ = pose
    s = line.rho - x * np.cos(line.theta) - y * np.sin(line.theta)
    return "\n".join(
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


def fig06_line_attributes() -> Figure:
    """Fig. 6: the attributes (ρ, θ, n, l, sp, ep, dir, d) of a feature line AB and a robot."""
    line, pose = line_attributes_example()
    pts = _fig06_points()
    nrm, u = line.normal, np.array([-line.normal[1], line.normal[0]])
    P = line.rho * nrm
    fig, ax = plt.subplots(figsize=(10, 7.5))
    _fig06_axes(ax)
    _fig06_segment(ax, line, pts, P, u)
    _fig06_rho_theta(ax, line, P, nrm, u)
    _fig06_robot(ax, line, pose, nrm, u)
    ax.text(
        0.985, 0.97, _fig06_attributes_text(line, pose), transform=ax.transAxes, ha="right",
        va="top", fontsize=10, multialignment="left",
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
