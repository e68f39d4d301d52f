"""Notebook 02's exercise checks: right answers accepted, wrong ones rejected in one line."""

import numpy as np

from fhslam.exercises.nb02 import check_clustering, check_point_spacing, check_small_gap_reading


def right_cluster(points, gap):
    step = np.hypot(*np.diff(points, axis=0).T)
    return np.concatenate([[0], np.cumsum(step > gap)])


def todo(*args):
    raise NotImplementedError


def test_point_spacing_accepts_the_chord_and_rejects_a_wrong_unit():
    assert check_point_spacing(2 * 4.0 * np.tan(np.radians(0.5)))
    assert check_point_spacing(0.07)  # 4 m x 1 deg in radians, within the 5 mm tolerance
    assert check_point_spacing(...).status == "not attempted"
    wrong = check_point_spacing(7.0)  # centimetres, not metres
    assert wrong.status == "wrong" and "7" in str(wrong) and "\n" not in str(wrong)
    assert check_point_spacing("seven").status == "wrong"


def test_clustering_accepts_the_rule_with_any_label_values():
    assert check_clustering(right_cluster)
    assert check_clustering(lambda p, g: 10 + 2 * right_cluster(p, g))  # other label values


def test_clustering_rejects_wrong_rules_naming_the_case():
    never = check_clustering(lambda p, g: np.zeros(len(p), int))
    assert never.status == "wrong" and "a wall with a doorway" in never.message
    # ">=" instead of ">": breaks between points exactly gap apart
    at_least = check_clustering(
        lambda p, g: np.concatenate([[0], np.cumsum(np.hypot(*np.diff(p, axis=0).T) >= g)])
    )
    assert at_least.status == "wrong" and "exactly gap apart" in at_least.message
    assert "returned None" in check_clustering(lambda p, g: None).message
    assert "one per point" in check_clustering(lambda p, g: np.zeros(3)).message
    crash = check_clustering(lambda p, g: p[1000])
    assert crash.status == "wrong" and "IndexError" in str(crash) and "\n" not in str(crash)


def test_clustering_template_is_not_attempted():
    assert check_clustering(todo).status == "not attempted"
    assert "my_cluster" in str(check_clustering(todo))


def test_small_gap_reading():
    assert check_small_gap_reading("b") and check_small_gap_reading(" (B) ")
    for wrong in ("a", "c"):
        assert check_small_gap_reading(wrong).status == "wrong"
    assert check_small_gap_reading("d").status == "wrong"
    assert check_small_gap_reading(...).status == "not attempted"
