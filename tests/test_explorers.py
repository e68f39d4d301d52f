"""The notebooks' explorers: each draws a labelled figure, follows its sliders — every one of
them changes what the figure draws in one step, not only a number in a title —, and shows a
static image plus a plain-text line when saved (no ``interactive(children=...`` text)."""

import matplotlib

matplotlib.use("Agg")

import io

import IPython.display
import matplotlib.pyplot as plt
import pytest

from fhslam.figures import figure_scan, paper_log
from fhslam.figures.explorers import (
    Explorer,
    calibration_explorer,
    clustering_explorer,
    extraction_explorer,
    similarity_explorer,
    slam_noise_explorer,
    slider,
)


@pytest.fixture(scope="module")
def log():
    return paper_log(0)


#: Each explorer as its notebook makes it (notebooks 02-06; SEED = 0, k = figure_scan or 200).
EXPLORERS = {
    "clustering": lambda log: clustering_explorer(log, figure_scan(log)),
    "extraction": lambda log: extraction_explorer(log, figure_scan(log)),
    "similarity": lambda log: similarity_explorer(),
    "calibration": lambda log: calibration_explorer(log, 200),
    "slam_noise": lambda log: slam_noise_explorer(0),
}


def drawing(explorer) -> bytes:
    """The figure as a PNG with every text blanked: the figure's and each axes' titles, the
    legends' entries, the notes in the axes and on the figure. What is left is what is drawn:
    a slider that only changes a number in a title or a legend leaves it as it was."""
    fig = explorer.figure()
    texts = [*fig.texts, *(t for lg in fig.legends for t in lg.get_texts())]
    if fig._suptitle is not None:
        texts.append(fig._suptitle)
    for ax in fig.axes:
        texts += [ax.title, ax._left_title, ax._right_title, *ax.texts]
        if ax.get_legend() is not None:
            texts += ax.get_legend().get_texts()
    for text in texts:
        text.set_text("")
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=80)  # as Explorer.png shows it
    plt.close(fig)
    return buf.getvalue()


@pytest.mark.parametrize("name", EXPLORERS)
def test_every_slider_changes_the_drawing_in_one_step(name, log):
    """From the defaults, one step of any slider (up, or down from the top) draws another
    figure, its texts left out: no slider a student moves in vain there, nor one that only
    changes a number in a title."""
    e = EXPLORERS[name](log)
    start = drawing(e)
    same = []
    for control, widget in e.controls.items():
        value = widget.value
        moved = value + widget.step if value + widget.step <= widget.max else value - widget.step
        e.set(**{control: moved})
        if drawing(e) == start:
            same.append(f"{control} {value:g} -> {moved:g}")
        e.set(**{control: value})
    assert not same, f"{name}: one step draws the same figure, texts aside, for {same}"
    assert drawing(e) == start  # the same values draw the same figure: the changes are real


def test_a_change_in_the_texts_alone_is_not_a_change_of_the_drawing():
    """The comparison above is blind to numbers in titles, legends and notes, and sees a
    threshold line move by one step."""

    def draw(value, line):
        fig, (ax, other) = plt.subplots(1, 2)
        fig.suptitle(f"value {value}")
        ax.set_title(f"value {value}")
        ax.plot([0, 1], [line, line], label=f"value {value}")
        ax.legend()
        ax.text(0.5, 0.5, f"value {value}")
        other.set_title(f"value {value}", loc="left")
        ax.set_ylim(0, 2)
        return fig

    controls = {"value": slider(1, 0, 9, 1, "value"), "line": slider(1.0, 0.0, 2.0, 0.02, "y")}
    e = Explorer(draw, controls, "a title and a line")
    start, png = drawing(e), e.png()
    e.set(value=2)
    assert e.png() != png and drawing(e) == start  # only the texts changed
    e.set(value=1, line=1.02)
    assert drawing(e) != start  # the line moved


def title(explorer) -> str:
    fig = explorer.figure()
    text = fig._suptitle.get_text() if fig._suptitle else ""
    plt.close(fig)
    return text + " | " + " | ".join(ax.get_title() for ax in fig.axes)


def labelled(explorer) -> bool:
    fig = explorer.figure()
    plt.close(fig)
    return all(ax.get_xlabel() for ax in fig.axes) and bool(fig.axes[0].get_ylabel())


def axes(explorer, i):
    fig = explorer.figure()
    plt.close(fig)
    return fig.axes[i]


def test_clustering_explorer_follows_the_gap(log):
    e = clustering_explorer(log, figure_scan(log))
    assert "5 clusters" in title(e) and labelled(e)

    def gap_panel():  # the threshold line's height and the splits (black crosses)
        ax = axes(e, 1)
        (threshold,) = ax.get_lines()
        return threshold.get_ydata()[0], len(ax.collections[-1].get_offsets())

    assert gap_panel() == (0.3, 4)  # 4 gaps above 0.3 m: 5 clusters
    e.set(cluster_gap=0.32)  # one step: the line moves, no split does
    assert gap_panel() == (0.32, 4)
    e.set(cluster_gap=0.04)
    assert "5 clusters" not in title(e) and gap_panel()[1] > 4
    e.set(cluster_gap=2.0)
    assert "3 clusters" in title(e) and gap_panel() == (2.0, 2)  # notebook 02's table at 2 m


def test_extraction_explorer_follows_its_thresholds(log):
    e = extraction_explorer(log, figure_scan(log))

    def lines() -> int:
        return int(title(e).split(": ")[1].split()[0])

    assert next(iter(e.controls)) == "min_points" and labelled(e)
    assert lines() == 7 and "≥ 6 points" in title(e)  # notebook 03's table of lines
    e.set(min_points=7)  # one step of the first slider: l3 (6 points) goes
    assert lines() == 6 and "≥ 7 points" in title(e)
    e.set(min_points=12)  # exercise 3.3
    assert lines() == 4
    e.set(min_points=64)  # above every wall's support
    assert lines() == 0
    e.set(min_points=6, window_deg=0.0)  # the dominant slope alone still finds every line
    assert lines() == 7 and "window ±0°" in title(e)
    e.set(window_deg=3.0, inlier_dist=0.02)  # 2 noise sigmas: walls split into pieces
    assert lines() == 9
    e.set(inlier_dist=0.04, scan=300)
    assert "scan 300:" in title(e)


def test_extraction_explorer_draws_each_threshold_where_it_acts(log):
    e = extraction_explorer(log, figure_scan(log))
    gap_ax, window_ax, support_ax = (axes(e, i) for i in (1, 2, 3))
    gap, densify = (line.get_ydata()[0] for line in gap_ax.get_lines())
    assert (gap, densify) == (0.3, 0.05)
    (voted,) = window_ax.get_lines()  # the directions the Hough vote tries: every 0.5°
    assert list(voted.get_xdata()) == [0.5 * k for k in range(-6, 7)]
    (band,) = support_ax.get_lines()
    grey, red = (len(c.get_offsets()) for c in support_ax.collections)
    assert band.get_ydata()[0] == 0.04 and (red, grey) == (180, 1)  # the support of 7 lines
    e.set(window_deg=3.5, inlier_dist=0.045, cluster_gap=0.35, densify_step=0.06)
    gap_ax, window_ax, support_ax = (axes(e, i) for i in (1, 2, 3))
    assert [line.get_ydata()[0] for line in gap_ax.get_lines()] == [0.35, 0.06]
    assert max(window_ax.get_lines()[0].get_xdata()) == 3.5
    assert support_ax.get_lines()[0].get_ydata()[0] == 0.045


def test_similarity_explorer_shows_each_condition_failing():
    e = similarity_explorer()
    assert title(e).endswith("→ similar") and labelled(e)
    assert "(b) angle 0.0° ✓" in title(e) and "(d) overlap +2.20 m ✓" in title(e)
    before = e.png()
    e.set(turn_deg=1.0)  # one step of the first slider (the browser test's key press)
    assert "(b) angle 1.0° ✓" in title(e) and e.png() != before
    assert e.seconds < 1.0
    e.set(turn_deg=12.0)
    assert "(b) angle 12.0° ✗" in title(e) and title(e).endswith("→ not similar")
    e.set(max_angle_deg=15.0, max_distance=0.5)  # both thresholds past it: similar again
    assert title(e).endswith("→ similar")
    e.set(turn_deg=0.0, max_angle_deg=5.0, max_distance=0.15, offset=0.5)
    assert "(c) distance 0.50 m ✗" in title(e) and "(b) angle 0.0° ✓" in title(e)
    e.set(max_distance=0.6)  # the threshold moved past the offset: similar again
    assert title(e).endswith("→ similar")
    e.set(max_distance=0.15, offset=0.0, slide=3.5)
    assert "(d) overlap -1.30 m ✗" in title(e) and "(c) distance 0.00 m ✓" in title(e)
    e.set(slide=0.0, offset=-1.3)  # the robot (y = 1 m) between the two lines
    assert "(a) same side ✗" in title(e) and "(d) overlap +2.20 m ✓" in title(e)


def test_calibration_explorer_recovers_the_pose(log):
    e = calibration_explorer(log, 200)
    t = title(e)
    assert "predicted: 25.0 cm, +3.00° off" in t and "calibrated: 0.0 cm, +0.00° off" in t
    assert "8 of 8 lines matched" in t and "in both directions" in t
    e.set(dx_cm=21.0)  # the first slider, one step (as the browser test): the figure changes
    assert "predicted: 25.8 cm" in title(e)
    e.set(dx_cm=20.0, iterations=0)
    assert "calibrated: 25.0 cm" in title(e)  # no iteration: nothing corrected
    for n in (0, 3, 4):  # the right panel: the rounds applied solid, the others dotted
        e.set(iterations=n)
        fig = e.figure()
        plt.close(fig)
        applied, more = sorted(fig.axes[2].get_lines(), key=lambda line: line.get_linestyle())
        assert list(applied.get_xdata()) == list(range(n + 1)), n
        assert list(more.get_xdata()) == list(range(n, 7)), n
        residual = applied.get_ydata()
        assert residual[0] > 100 and (n < 3 or residual[3] <= 1e-9)  # mm: converged at 3
    e.set(iterations=3)
    assert labelled(e)

    def box():  # the thresholds' box, and the lines inside it (filled) and outside (hollow)
        ax = axes(e, 3)
        (rect,) = ax.patches
        filled = [m.get_markerfacecolor() != "none" for m in ax.get_lines()[1:]]
        return rect.get_width(), rect.get_height(), sum(filled), len(filled) - sum(filled)

    assert box() == (5.0, 0.6, 8, 0)
    e.set(dtheta_deg=6.0)  # past (b): every line out of the box, 6° across
    assert box() == (5.0, 0.6, 0, 8)
    e.set(max_angle_deg=6.5, gate=0.65)  # the box grows over them
    assert box() == (6.5, 0.65, 8, 0)
    e.set(dtheta_deg=3.0, max_angle_deg=5.0, gate=0.6)
    # 20 cm forward at the package's 15 cm gate: only lines (nearly) along the motion match, and
    # the position along them is kept (notebook 05's corridor)
    e.set(dy_cm=0.0, dtheta_deg=0.0, gate=0.15, iterations=3)
    t = title(e)
    assert "3 of 8 lines matched" in t and "one direction only" in t
    assert "calibrated: 20.0 cm" in t
    e.set(dtheta_deg=8.0)  # beyond threshold (b), 5°: nothing matched, nothing corrected
    assert "no line matched" in title(e) and "calibrated: 20.0 cm, +8.00° off" in title(e)
    e.set(max_angle_deg=10.0, gate=1.5)
    assert "calibrated: 0.0 cm, +0.00° off" in title(e)


def test_slam_noise_explorer_shows_odometry_and_slam_errors():
    e = slam_noise_explorer(scans=120)
    t = title(e)
    assert "drift ×1" in t and labelled(e)
    e.set(drift=0.0, range_noise_cm=0.0)
    assert "drift ×0, range noise 0 cm" in title(e)
    fig = e.figure()
    plt.close(fig)
    legend = [x.get_text() for x in fig.axes[0].get_legend().get_texts()]
    assert any(x.startswith("odometry (ATE 0.00 m)") for x in legend), legend


def test_unknown_control_is_named():
    with pytest.raises(KeyError, match="no control 'gap'; controls: turn_deg"):
        similarity_explorer().set(gap=1)


def test_display_is_an_image_updated_in_place_and_sliders_with_a_text_line(log, monkeypatch):
    shown = []

    class Handle:
        def update(self, obj):
            shown.append(("update", obj))

    def display(obj, raw=False, display_id=None):
        shown.append(("display", obj))
        return Handle() if display_id else None

    monkeypatch.setattr(IPython.display, "display", display)
    e = clustering_explorer(log, figure_scan(log))
    e._ipython_display_()
    (k1, image), (k2, bundle) = shown
    assert (k1, k2) == ("display", "display")
    assert isinstance(image, IPython.display.Image) and image.data[:4] == b"\x89PNG"
    assert (
        bundle["text/plain"].startswith("[Clustering") and "run this cell" in bundle["text/plain"]
    )
    assert "application/vnd.jupyter.widget-view+json" in bundle
    e.set(cluster_gap=1.0)
    assert shown[-1][0] == "update" and shown[-1][1].data != image.data
    assert 0 < e.seconds < 30
