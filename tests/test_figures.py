"""The paper's sketches of Loop 2 (Figs. 6-12): the examples behind them and that they draw."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.figure import Figure

from fhslam import figures
from fhslam.matching import MatchParams, merge, similarity

# (a) same direction, (b) angle, (c) distance, (d) overlap -- as the paper's text says:
# "Fig. 8 satisfies condition (d) and does not satisfy condition (c), Fig. 9 does not satisfy
# condition (b) and (d), Fig. 10 does not satisfy condition (b) and (c)".
CAPTION_CONDITIONS = {
    7: (True, True, True, True),
    8: (True, True, False, True),
    9: (True, False, True, False),
    10: (True, False, False, True),
}


@pytest.mark.parametrize("k", sorted(CAPTION_CONDITIONS))
def test_similarity_examples_match_the_captions(k):
    ref, new, pose = figures.similarity_examples()[k]
    sim = similarity(ref, new, MatchParams(), pose=pose)
    got = (sim.same_direction, sim.angle_ok, sim.distance_ok, sim.overlap_ok)
    assert got == CAPTION_CONDITIONS[k]
    assert sim.similar == (k == 7)
    # the conditions are symmetric, so the verdict does not depend on which line is "new"
    rev = similarity(new, ref, MatchParams(), pose=pose)
    assert (rev.same_direction, rev.angle_ok, rev.distance_ok, rev.overlap_ok) == got


def test_similarity_examples_share_one_pose_and_margins_are_clear():
    ex = figures.similarity_examples()
    assert sorted(ex) == [7, 8, 9, 10]
    assert all(pose == figures.SIMILARITY_POSE for _, _, pose in ex.values())
    p = MatchParams()
    for ref, new, pose in ex.values():
        s = similarity(ref, new, p, pose=pose)
        # no example sits on a threshold, so small numeric changes cannot flip a condition
        assert abs(s.angle_deg - p.max_angle_deg) > 1.0
        assert abs(s.distance - p.max_distance) > 0.01
        assert abs(s.overlap - p.min_overlap) > 0.1
        assert ref.observed_from(pose).dir == new.observed_from(pose).dir == 1


def test_line_attributes_example_is_seen_from_the_origin_side():
    line, pose = figures.line_attributes_example()
    x, y, _ = pose
    s = line.rho - x * np.cos(line.theta) - y * np.sin(line.theta)  # paper: dir = sign(s)
    assert line.dir == np.sign(s) == 1
    assert line.d == pytest.approx(abs(s))
    assert line.n == 9
    assert line.rho == pytest.approx(2.5, abs=0.03)
    assert np.degrees(line.theta) == pytest.approx(60.0, abs=1.0)
    assert line.length == pytest.approx(np.linalg.norm(line.ep - line.sp))


def test_merged_line_spans_from_c_to_f():
    ef, ab = figures.merging_example()
    merged = merge(ef, ab)
    assert similarity(ef, ab, pose=(2.5, 0.0, np.pi / 2)).similar
    # C is A projected onto EF's line (y = 1); F is EF's end point.
    C, F = np.array([-0.5, 1.0]), np.array([4.0, 1.0])
    np.testing.assert_allclose(ef.sp, [1.0, 1.0], atol=1e-9)
    np.testing.assert_allclose(ef.ep, F, atol=1e-9)
    u = ef.ep - ef.sp
    u /= np.linalg.norm(u)
    assert merged.sp @ u == pytest.approx(C @ u, abs=2e-3)  # extended to C ...
    assert merged.ep @ u == pytest.approx(F @ u, abs=2e-3)  # ... and still reaching F
    assert merged.length == pytest.approx(4.5, abs=2e-3)  # |CF|
    # the refit keeps the merged line within a few centimetres of EF's line
    assert abs(merged.sp[1] - C[1]) < 0.05 and abs(merged.ep[1] - F[1]) < 0.05
    assert merged.n == ef.n + ab.n


@pytest.mark.parametrize(
    ("make", "number"),
    [
        (figures.fig06_line_attributes, "Fig. 6"),
        (figures.fig07_to_10_similarity, "Figs. 7–10"),
        (figures.fig11_merging, "Fig. 11"),
        (figures.fig12_pioneer, "Fig. 12"),
    ],
)
def test_new_figures_draw_and_close(make, number):
    fig = make()
    try:
        assert isinstance(fig, Figure)
        assert fig.axes
        titles = [fig.get_suptitle()]
        titles += [ax.get_title() for ax in fig.axes]
        assert any(t.startswith(number + "  ") for t in titles)
        fig.canvas.draw()
    finally:
        plt.close(fig)
    assert not plt.fignum_exists(fig.number)


def test_similarity_figure_prints_each_verdict():
    fig = figures.fig07_to_10_similarity()
    try:
        assert len(fig.axes) == 4
        texts = [t.get_text() for ax in fig.axes for t in ax.texts]
        assert texts.count("→ similar") == 1 and texts.count("→ not similar") == 3
    finally:
        plt.close(fig)


def test_figures_are_deterministic():
    a, b = figures.similarity_examples(), figures.similarity_examples()
    for k in a:
        for la, lb in zip(a[k][:2], b[k][:2], strict=True):
            np.testing.assert_array_equal(la.sp, lb.sp)
            np.testing.assert_array_equal(la.ep, lb.ep)
    (l1, p1), (l2, p2) = figures.line_attributes_example(), figures.line_attributes_example()
    assert p1 == p2 and l1.rho == l2.rho and l1.theta == l2.theta


def test_plot_lines_and_trajectory_take_matplotlib_aliases():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fhslam.lines import line_from_points
    from fhslam.plotting import plot_lines, plot_trajectory

    fig, ax = plt.subplots()
    line = line_from_points(np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]))
    plot_lines([line, line], ax=ax, lw=0.5, markers=False)
    assert len(ax.lines) == 2 and ax.lines[0].get_linewidth() == 0.5  # no endpoint markers
    plot_lines([line], ax=ax)
    assert len(ax.lines) == 4  # one segment + its endpoint markers
    plot_trajectory(np.zeros((3, 3)), ax=ax, lw=0.3)
    assert ax.lines[-1].get_linewidth() == 0.3
    plt.close(fig)


def test_a_slam_run_figure_shows_the_run_its_closures_and_not_the_odometrys_drift():
    """:func:`fhslam.figures.slam_run_figure` (``fhslam slam --plot``): the map, the run, the
    truth with its ATE in the title, each loop closure still in the graph as a segment between
    its two keyframes; the view holds the run and the true walls, not the odometry's metres of
    drift."""
    from dataclasses import replace

    from matplotlib.collections import LineCollection
    from matplotlib.colors import to_rgba

    from fhslam.pipeline import keyframe_graph, make_backend, run_backend
    from fhslam.sim import OdometryNoise, load_world, simulate

    log = simulate(load_world("random:105"), seed=0, odometry=OdometryNoise.drifting(), laps=2)
    backend = make_backend("graph")
    result = run_backend(backend, log)
    graph = keyframe_graph(backend, log)
    # drawn with an odometry that drifts 40 m along x (the SLAM ran on the log's own)
    drifted = log.odometry + np.linspace(0, 40, len(log))[:, None] * [1, 0, 0]
    fig = figures.slam_run_figure(replace(log, odometry=drifted), result, "graph", graph)
    ax = fig.axes[0]
    kept = graph.loops[graph.active]
    labels = ax.get_legend_handles_labels()[1]
    assert len(kept) > 5 and f"{len(kept)} loop closures" in labels
    assert {"odometry", "truth", "graph", f"map ({len(result.map)} reference lines)"} <= set(labels)
    green = [
        c
        for c in ax.collections
        if isinstance(c, LineCollection) and np.allclose(c.get_colors()[0], to_rgba("tab:green"))
    ]
    assert len(green) == 1
    np.testing.assert_allclose(np.array(green[0].get_segments()), graph.poses[kept][:, :, :2])
    ate = np.sqrt(np.mean(np.sum((result.poses[:, :2] - log.truth[:, :2]) ** 2, axis=1)))
    assert ax.get_title() == (
        f"random:105: graph, {len(log)} scans, ATE {ate:.3f} m, {len(graph)} keyframes"
    )
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    inside = lambda p: (x0 <= p[:, 0]) & (p[:, 0] <= x1) & (y0 <= p[:, 1]) & (p[:, 1] <= y1)  # noqa: E731
    assert inside(result.poses).all() and inside(np.reshape(log.world.walls, (-1, 2))).all()
    assert x1 - x0 < 25 and not inside(drifted).all()  # the world's 14 m, not the drift's 40
    plt.close(fig)


def test_the_error_figures_draw_each_error_where_it_happened():
    """:func:`fhslam.figures.relation_errors_figure` and :func:`pose_errors_figure`
    (``fhslam evaluate --plot``): each relation's errors at the time of its first pose,
    coloured by the time between its poses, a dashed line at the mean; each pose's error at
    its time, a dashed line at the rmse; no usable relation or pose is refused."""
    from fhslam import metrics
    from fhslam.geometry import relative

    t = 100.0 + np.arange(60)
    truth = np.column_stack([0.1 * np.arange(60), np.zeros(60), 0.01 * np.arange(60)])
    est = truth.copy()
    est[30:, 1] += 0.2  # a 20 cm jump half-way
    pairs = [(k, k + 5) for k in range(0, 55, 5)] + [(0, 40)]
    t1, t2 = t[[a for a, _ in pairs]], t[[b for _, b in pairs]]
    rel = np.array([relative(truth[a], truth[b]) for a, b in pairs])
    trans, rot, _ = metrics.relations_errors(t, est, t1, t2, rel)
    fig = figures.relation_errors_figure(t, est, t1, t2, rel, title="case")
    a, b = fig.axes[:2]
    for ax, err in ((a, trans), (b, np.degrees(rot))):
        (points,) = ax.collections
        np.testing.assert_allclose(points.get_offsets(), np.column_stack([t1 - 100, err]))
        np.testing.assert_allclose(points.get_array(), np.maximum(t2 - t1, 5))  # gaps 5 and 40 s
        (mean,) = ax.get_lines()
        assert mean.get_ydata()[0] == pytest.approx(np.mean(err))
    assert trans.max() == pytest.approx(0.2) and (trans > 0.1).sum() == 2  # 25-30 and 0-40
    assert a.get_title() == (
        f"case: 12 of 12 relations, translational {trans.mean():.4f} m, rotational "
        f"{np.degrees(rot).mean():.3f}° (means)"
    )
    plt.close(fig)

    fig = figures.pose_errors_figure(t, est, t, truth, title="case")
    left, right = fig.axes[:2]
    err = np.where(np.arange(60) >= 30, 0.2, 0.0)
    (points,) = right.collections
    np.testing.assert_allclose(points.get_offsets(), np.column_stack([t - 100, err]), atol=1e-12)
    rmse = np.sqrt(np.mean(err**2))
    assert right.get_lines()[0].get_ydata()[0] == pytest.approx(rmse)
    assert right.get_yscale() == "linear"  # errors of 0: no log scale
    assert fig._suptitle.get_text() == f"case: ATE rmse {rmse:.4f} m over 60 poses"
    assert len(left.get_lines()) == 2  # truth and estimate
    plt.close(fig)

    with pytest.raises(ValueError, match="none of the 12 relations"):
        figures.relation_errors_figure(t + 1000, est, t1, t2, rel)
    with pytest.raises(ValueError, match="no pose of the estimate"):
        figures.pose_errors_figure(t + 1000, est, t, truth)
