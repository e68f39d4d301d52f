"""Pictures of a trajectory's errors, as ``fhslam evaluate --plot`` draws them: each benchmark
relation's error over the run (:func:`relation_errors_figure`), and each pose's error against
the truth (:func:`pose_errors_figure`); and of many runs' errors, as ``fhslam sweep --log
--plot`` draws them (:func:`sweep_errors_figure`).

A mean hides where a run went wrong: on the Freiburg hospital log the few relations across the
unclosed return to the start are tens of metres off and the thousands under a minute a tenth
of a metre. Drawn over the run's time and coloured by how far apart in time a relation's two
poses are, the two kinds part at a glance.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import LogNorm
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from fhslam import metrics, plotting

__all__ = ["pose_errors_figure", "relation_errors_figure", "sweep_errors_figure"]


def _error_axis(ax, when, err, unit: str, level: float, label: str, **scatter):
    """Scatter ``err`` over ``when`` with a dashed line at ``level`` (its mean or rmse,
    ``label``); a log scale when every error is positive."""
    sc = ax.scatter(when, err, s=6, linewidths=0, **scatter)
    ax.axhline(level, color="k", ls="--", lw=0.8, label=label)
    if np.all(err > 0):
        ax.set_yscale("log")
    ax.set_ylabel(unit)
    ax.legend(loc="upper left", fontsize=9)
    return sc


def relation_errors_figure(
    timestamps: ArrayLike,
    poses: ArrayLike,
    t1: ArrayLike,
    t2: ArrayLike,
    rel: ArrayLike,
    max_diff: float = 0.001,
    title: str = "",
) -> Figure:
    """Each relation's translational and rotational error (:func:`fhslam.metrics.relations_errors`;
    the arguments are its) over the time of its first pose since the trajectory's start, coloured
    by the time between its two poses.

    Raises
    ------
    ValueError
        When no relation's two timestamps are in the trajectory.
    """
    trans, rot, used = metrics.relations_errors(timestamps, poses, t1, t2, rel, max_diff)
    if not used.any():
        raise ValueError(f"none of the {len(used)} relations has both poses in the trajectory")
    when = np.asarray(t1, dtype=float)[used] - np.min(timestamps)
    gap = np.abs(np.asarray(t2, dtype=float) - np.asarray(t1, dtype=float))[used]
    deg = np.degrees(rot)
    norm = LogNorm(max(gap.min(), 1e-3), max(gap.max(), 2 * max(gap.min(), 1e-3)))
    fig, (a, b) = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True)
    style = {"c": np.maximum(gap, norm.vmin), "cmap": "viridis", "norm": norm}
    m, md = float(trans.mean()), float(deg.mean())
    sc = _error_axis(a, when, trans, "translational error (m)", m, f"mean {m:.4f} m", **style)
    _error_axis(b, when, deg, "rotational error (deg)", md, f"mean {md:.3f}°", **style)
    b.set_xlabel("time of the relation's first pose since the trajectory's start (s)")
    fig.colorbar(sc, ax=[a, b], label="time between the two poses (s)")
    a.set_title(
        f"{title + ': ' if title else ''}{used.sum()} of {len(used)} relations, "
        f"translational {m:.4f} m, rotational {md:.3f}° (means)"
    )
    return fig


def pose_errors_figure(
    t_est: ArrayLike,
    est: ArrayLike,
    t_ref: ArrayLike,
    ref: ArrayLike,
    max_diff: float = 0.01,
    align: bool = False,
    title: str = "",
) -> Figure:
    """The estimate against the truth: both trajectories, and each pose's position error
    (:func:`fhslam.metrics.ate_errors`, poses paired by :func:`fhslam.metrics.associate`
    within ``max_diff`` seconds; ``align``: after the SE(2) alignment) over time.

    Raises
    ------
    ValueError
        When no pose of the estimate matches one of the truth.
    """
    i, j = metrics.associate(t_est, t_ref, max_diff)
    if len(i) == 0:
        raise ValueError(f"no pose of the estimate is within {max_diff:g} s of one of the truth")
    e, r = np.asarray(est, dtype=float)[i], np.asarray(ref, dtype=float)[j]
    err = metrics.ate_errors(e, r, align=align)
    when = np.asarray(t_ref, dtype=float)[j] - np.min(t_ref)
    rmse = float(np.sqrt(np.mean(err**2)))
    fig, (a, b) = plt.subplots(1, 2, figsize=(13, 5), gridspec_kw={"width_ratios": [1, 1.3]})
    plotting.plot_trajectory(r, ax=a, color="k", ls="--", label="truth")
    plotting.plot_trajectory(e, ax=a, color="tab:blue", linewidth=1.0, label="estimate")
    a.set_xlabel("x (m)")
    a.set_ylabel("y (m)")
    a.legend(loc="best", fontsize=9)
    _error_axis(b, when, err, "position error (m)", rmse, f"rmse {rmse:.4f} m", color="tab:blue")
    b.set_xlabel("time since the truth's first pose (s)")
    fig.suptitle(
        f"{title + ': ' if title else ''}ATE{' aligned' if align else ''} rmse {rmse:.4f} m "
        f"over {len(i)} poses"
    )
    return fig


def sweep_errors_figure(
    runs, relative: float = 0.25, absolute: float = 0.01, title: str = ""
) -> Figure:
    """Each run of a sweep over one log (``fhslam sweep --log``: objects with the fields and
    the ``reference`` property of :class:`fhslam.experiments.robustness.LogRun`) as a point:
    its mean translational relation error over its degradation seed (the runs on the log as
    read at "as read", last-bit draws beside their seed), one panel per method, with the run
    on the log as read as a line and the robustness bound about it (``relative`` of its error or
    ``absolute`` metres, whichever is larger) as a band; the runs beyond it red and labelled.

    Raises
    ------
    ValueError
        When there are no runs, or a method has no run on the log as read.
    """
    runs = list(runs)
    if not runs:
        raise ValueError("no runs to draw")
    methods = list(dict.fromkeys(r.method for r in runs))
    fig, axes = plt.subplots(
        1, len(methods), figsize=(max(6.5, 4.5 * len(methods)), 4.2), squeeze=False
    )
    draws = max(r.last_bit for r in runs) + 1
    for ax, method in zip(axes[0], methods, strict=True):
        mine = [r for r in runs if r.method == method]
        refs = [r for r in mine if r.reference]
        if not refs:
            raise ValueError(f"{method}: no run on the log as read among the runs")
        ref = refs[0].trans_error
        bound = max(relative * ref, absolute)
        others = [r for r in mine if r is not refs[0]]
        x = np.array([r.degrade_seed + 0.5 * r.last_bit / draws for r in others])
        e = np.array([r.trans_error for r in others])
        out = np.abs(e - ref) > bound
        ax.axhspan(max(ref - bound, ref / 10), ref + bound, color="0.9", lw=0)
        ax.axhline(ref, color="k", lw=1, label=f"as read {ref:.4f} m (band: ± {bound:.3g} m)")
        ax.scatter([-1], [ref], s=18, color="k")
        ax.scatter(x[~out], e[~out], s=18, color="tab:blue", label="within the robustness bound")
        ax.scatter(x[out], e[out], s=24, color="tab:red", label="beyond it")
        for xi, ei in zip(x[out], e[out], strict=True):
            ax.annotate(f"{ei:.3g} m", (xi, ei), textcoords="offset points", xytext=(4, 3),
                        fontsize=8, color="tab:red")  # fmt: skip
        ax.set_yscale("log")
        seeds = sorted({r.degrade_seed for r in others} | {-1})
        ax.set_xticks(seeds, ["as read" if s < 0 else str(s) for s in seeds], fontsize=8)
        ax.set_xlabel("degradation seed")
        ax.set_ylabel("translational relation error (m)")
        ax.set_title(f"{method}: {len(others)} runs, {int(out.sum())} beyond the bound")
        ax.legend(loc="best", fontsize=8)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig
