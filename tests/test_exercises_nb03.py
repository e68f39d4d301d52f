"""Notebook 03's exercise checks: right answers accepted, wrong ones rejected in one line."""

import math

import numpy as np
import pytest

from fhslam.exercises.nb03 import (
    ALL_PAIRS,
    check_line_count,
    check_pair_angles,
    check_window_reading,
    pair_angle_cases,
)
from fhslam.extraction import (
    ExtractionParams,
    cluster_scan,
    densify,
    dominant_angle,
    slope_histogram,
)
from fhslam.figures import figure_scan, paper_log


@pytest.fixture(scope="module")
def scan():
    """The notebook's scan, its largest cluster (S3) and that cluster densified."""
    log = paper_log(0)
    points, _ = log.scan(figure_scan(log)).points()
    labels = cluster_scan(points, ExtractionParams().cluster_gap)
    cluster = points[labels == np.argmax(np.bincount(labels))]
    dense, _, _ = densify(cluster, np.zeros(len(cluster), int), ExtractionParams().densify_step)
    one = np.zeros(len(dense), int)
    phi, _ = dominant_angle(slope_histogram(dense, one))
    return points, cluster, dense, phi


def pairs(p):
    i, j = np.triu_indices(len(p), k=1)
    return p[j] - p[i]


def right_angles(p):
    d = pairs(p)
    return np.arctan2(d[:, 1], d[:, 0]) % np.pi


def todo(*args):
    raise NotImplementedError


def one_line(feedback):
    return "\n" not in str(feedback)


def test_the_reference_directions_are_what_slope_histogram_counts(scan):
    _, cluster, _, _ = scan
    for what, pts in [*pair_angle_cases(), ("cluster", cluster)]:
        a = right_angles(pts)
        x = a * 180 / np.pi
        mine = np.bincount(np.minimum(x.astype(int), 179), minlength=180)
        hist = slope_histogram(pts, np.zeros(len(pts), int), ALL_PAIRS)[0]
        assert hist.sum() == len(a), what
        # a direction on a bin edge (0°, 45°, 90°; π from arctan2 in the last bin) may be
        # counted either side of it: apart from those, the same histogram
        edge = int(np.sum(np.abs(x - np.round(x)) < 1e-6))
        assert np.abs(mine - hist).sum() <= 2 * edge, what
    assert edge < 5  # on the cluster, almost every pair is clear of the edges


def test_pair_angles_accepts_equivalent_representations(scan):
    _, cluster, _, _ = scan
    ok = check_pair_angles(right_angles, cluster)
    assert ok and "7 cases" in ok.message and "90.5°" in ok.message and one_line(ok)
    assert check_pair_angles(right_angles)  # without the notebook's cluster: 6 cases

    def kernel_fold(p):  # π, not 0, for a pair scanned right to left
        d = pairs(p)
        a = np.arctan2(d[:, 1], d[:, 0])
        return np.where(a < 0, a + np.pi, a)

    def loops(p):  # plain Python, a list
        out = []
        for i in range(len(p)):
            for j in range(i + 1, len(p)):
                a = math.atan2(p[j][1] - p[i][1], p[j][0] - p[i][0])
                out.append(a + math.pi if a < 0 else a)
        return out

    def atan_folded(p):  # atan of dy / dx, folded: the right direction modulo π
        d = pairs(p)
        with np.errstate(divide="ignore"):
            return np.arctan(d[:, 1] / d[:, 0]) % np.pi

    for fn in (kernel_fold, loops, atan_folded):
        assert check_pair_angles(fn, cluster), fn.__name__
    assert check_pair_angles(lambda p: right_angles(p)[::-1], cluster)  # any pair order
    assert check_pair_angles(lambda p: right_angles(p)[:, None], cluster)  # a column


def test_pair_angles_rejects_the_usual_mistakes_naming_the_case(scan):
    _, cluster, _, _ = scan

    def unfolded(p):
        d = pairs(p)
        return np.arctan2(d[:, 1], d[:, 0])

    def atan(p):
        d = pairs(p)
        with np.errstate(divide="ignore"):
            return np.arctan(d[:, 1] / d[:, 0])

    def slope(p):
        d = pairs(p)
        return d[:, 1] / np.where(d[:, 0] == 0, 1e-300, d[:, 0])

    no = check_pair_angles(unfolded, cluster)
    assert no.status == "wrong" and "going down to the left" in no.message
    assert "-153.4°" in no.message and "add π" in no.message and one_line(no)
    no = check_pair_angles(atan, cluster)
    assert "vertical wall" in no.message and "-90.0° is not in [0, π)" in no.message
    no = check_pair_angles(lambda p: np.degrees(right_angles(p)), cluster)
    assert "2 m right and 1 m up" in no.message and "degrees" in no.message
    no = check_pair_angles(lambda p: right_angles(p) + np.pi / 2, cluster)
    assert "normals" in no.message
    no = check_pair_angles(slope, cluster)
    assert no.status == "wrong" and "slopes dy / dx" in no.message
    swapped = check_pair_angles(lambda p: np.arctan2(*pairs(p).T) % np.pi, cluster)  # (dx, dy)
    assert "expected the directions 26.6°" in swapped.message and "got 63.4°" in swapped.message


def test_pair_angles_rejects_wrong_pairs(scan):
    _, cluster, _, _ = scan
    neighbours = check_pair_angles(lambda p: np.arctan2(*np.diff(p, axis=0).T[::-1]) % np.pi)
    assert "corner" in neighbours.message and "only neighbours" in neighbours.message

    def table(p):
        d = p[None] - p[:, None]
        return np.arctan2(d[..., 1], d[..., 0]) % np.pi

    assert "N × N" in check_pair_angles(table).message
    twice = check_pair_angles(lambda p: np.concatenate([right_angles(p), right_angles(p)]))
    assert "(j, i) are the same line" in twice.message
    assert "you returned 1 angles" in check_pair_angles(lambda p: right_angles(p)[:1]).message

    def with_nan(p):
        a = right_angles(p)
        a[-1] = np.nan
        return a

    assert "NaN" in check_pair_angles(with_nan).message
    assert "returned None" in check_pair_angles(lambda p: None).message
    assert check_pair_angles(lambda *args, **kwargs: None, cluster).status == "wrong"
    assert "(numbers)" in check_pair_angles(lambda p: "angles").message
    crash = check_pair_angles(lambda p: p[100], cluster)
    assert crash.status == "wrong" and "IndexError" in str(crash) and one_line(crash)

    def off_on_the_cluster(p):  # right on the small cases, one direction off on the cluster
        a = right_angles(p)
        if len(p) > 20:
            a[0] = (a[0] + 0.01) % np.pi
        return a

    off = check_pair_angles(off_on_the_cluster, cluster)
    assert "the notebook's cluster (79 points)" in off.message and "1 of 3081" in off.message


def test_pair_angles_template_is_not_attempted(scan):
    assert check_pair_angles(todo, scan[1]).status == "not attempted"
    assert "my_pair_angles" in str(check_pair_angles(todo))
    assert check_pair_angles(...).status == "not attempted"


def test_window_reading_quotes_the_clusters_accumulators(scan):
    _, _, dense, phi = scan
    ok = check_window_reading("a", dense, phi)
    assert ok and check_window_reading(" (A) ", dense, phi)
    assert "best cell, θ = 0.0° with 101 votes" in ok.message
    assert "θ = 180.0°, 101 votes" in ok.message and "13 of its 360 rows" in ok.message
    b = check_window_reading("b", dense, phi)
    assert b.status == "wrong" and "37 votes at θ = 89.5°" in b.message and one_line(b)
    assert "13 of its 360 rows" in check_window_reading("c", dense, phi).message
    assert "l5" in check_window_reading("d", dense, phi).message
    assert check_window_reading("a")  # without the cluster: the explanation alone
    assert "Here" not in check_window_reading("a").message
    assert "one of" in check_window_reading("e").message
    assert check_window_reading(3, dense, phi).status == "wrong"
    assert check_window_reading(...).status == "not attempted"


def test_line_count_is_computed_by_the_extraction(scan):
    points = scan[0]
    ok = check_line_count(4, points)
    assert ok and "(60, 61, 18, 15)" in ok.message and "9, 6, 11 points are gone" in ok.message
    assert check_line_count(4.0, points) and check_line_count("4", points)
    assert check_line_count(2, points, min_points=24)  # another threshold, another answer
    assert check_line_count(4, points, min_points=24).status == "wrong"
    default = check_line_count(7, points)
    assert default.status == "wrong" and "default min_points = 6" in default.message
    for wrong in (3, 5, -12345.0):
        feedback = check_line_count(wrong, points)
        assert feedback.status == "wrong" and "n ≥ 12" in feedback.message and one_line(feedback)
    assert "whole number" in check_line_count(4.5, points).message
    assert "whole number" in check_line_count(float("nan"), points).message
    assert check_line_count("four", points).status == "wrong"
    assert check_line_count(..., points).status == "not attempted"
