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
    default = title(e)
    assert "lines" in default and labelled(e)
    e.set(min_points=40)  # a support threshold above every wall's points: fewer lines
    n = int(title(e).split(": ")[1].split()[0])
    assert n < int(default.split(": ")[1].split()[0])


def test_similarity_explorer_shows_each_condition_failing():
    e = similarity_explorer()
    assert title(e).endswith(": similar") and labelled(e)
    e.set(turn_deg=12.0)
    assert "(b) angle ✗" in title(e) and "not similar" in title(e)
    e.set(turn_deg=0.0, offset=0.5)
    assert "(c) distance ✗" in title(e)
    e.set(max_distance=0.6)  # the threshold moved past the offset: similar again
    assert title(e).endswith(": similar")
    e.set(max_distance=0.15, offset=0.0, slide=3.5)
    assert "(d) overlap ✗" in title(e)


def test_calibration_explorer_recovers_the_pose(log):
    e = calibration_explorer(log, 200)
    t = title(e)
    assert "predicted: 25.0 cm, +3.00° off" in t and "calibrated: 0.0 cm, +0.00° off" in t
    e.set(iterations=0)
    assert "calibrated: 25.0 cm" in title(e)  # no iteration: nothing corrected
    assert labelled(e)


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
