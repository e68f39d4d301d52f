"""The notebooks' explorers: each draws a labelled figure, follows its sliders, and shows a
static image plus a plain-text line when saved (no ``interactive(children=...`` text)."""

import matplotlib

matplotlib.use("Agg")

import IPython.display
import matplotlib.pyplot as plt
import pytest

from fhslam.figures import figure_scan, paper_log
from fhslam.figures.explorers import (
    calibration_explorer,
    clustering_explorer,
    extraction_explorer,
    similarity_explorer,
    slam_noise_explorer,
)


@pytest.fixture(scope="module")
def log():
    return paper_log(0)


def title(explorer) -> str:
    fig = explorer.figure()
    text = fig._suptitle.get_text() if fig._suptitle else ""
    plt.close(fig)
    return text + " | " + " | ".join(ax.get_title() for ax in fig.axes)


def labelled(explorer) -> bool:
    fig = explorer.figure()
    plt.close(fig)
    return all(ax.get_xlabel() for ax in fig.axes) and bool(fig.axes[0].get_ylabel())


def test_clustering_explorer_follows_the_gap(log):
    e = clustering_explorer(log, figure_scan(log))
    assert "5 clusters" in title(e) and labelled(e)
    e.set(cluster_gap=0.04)
    assert "5 clusters" not in title(e)
    e.set(cluster_gap=2.0)
    assert "3 clusters" in title(e)  # as notebook 02's table: 3 clusters at 2 m


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
    assert labelled(e)
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
