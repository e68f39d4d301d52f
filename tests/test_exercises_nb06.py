"""Notebook 06's exercise checks: right answers accepted, wrong ones rejected in one line."""

import numpy as np

from fhslam.exercises.nb06 import check_ate, check_drift_ratio, check_random_worlds_reading


def right_ate(estimate, truth):
    d = estimate[:, :2] - truth[:, :2]
    return float(np.sqrt(np.mean(np.sum(d**2, axis=1))))


def todo(*args):
    raise NotImplementedError


def one_line(feedback):
    return "\n" not in str(feedback)


# a run like the notebook's: odometry about 1.7 m off, FH-SLAM about 5 cm
TRUTH = np.column_stack([np.linspace(0, 20, 50), np.zeros(50), np.zeros(50)])
SLAM = TRUTH + np.array([0.03, 0.04, 0.01])
ODOMETRY = TRUTH + np.array([1.0, 1.4, 0.2])


def test_drift_ratio_is_decided_from_the_run():
    assert check_drift_ratio("c", SLAM, ODOMETRY, TRUTH)  # 1.72 m / 0.05 m = 34 times
    assert "34 times" in check_drift_ratio(" (C) ", SLAM, ODOMETRY, TRUTH).message
    low = check_drift_ratio("a", SLAM, ODOMETRY, TRUTH)
    assert low.status == "wrong" and "Loop 3" in low.message
    high = check_drift_ratio("d", SLAM, ODOMETRY, TRUTH)
    assert high.status == "wrong" and "1 cm" in high.message and one_line(high)
    near = check_drift_ratio("b", SLAM, ODOMETRY, TRUTH)
    assert near.status == "wrong"
    for wrong in (low, high, near):  # a prediction: the numbers are not given away
        assert "34" not in wrong.message and "1.72" not in wrong.message, wrong
        assert " m / " not in wrong.message and "0.05 m" not in wrong.message, wrong
    # another run, another right answer: 10 times is "b", a perfect SLAM is "d"
    assert check_drift_ratio("b", TRUTH * 1.1, TRUTH * 2.0, TRUTH)
    assert check_drift_ratio("d", TRUTH, ODOMETRY, TRUTH)
    assert check_drift_ratio(34, SLAM, ODOMETRY, TRUTH).status == "wrong"  # a letter, not a number
    assert check_drift_ratio(..., SLAM, ODOMETRY, TRUTH).status == "not attempted"


def test_ate_accepts_the_rmse_of_positions_and_gives_the_runs():
    assert check_ate(right_ate)
    assert check_ate(lambda e, t: np.sqrt(np.mean(np.hypot(*(e - t)[:, :2].T) ** 2)))  # numpy float
    ok = check_ate(right_ate, TRUTH, {"FH-SLAM": SLAM, "odometry": ODOMETRY})
    assert ok and "FH-SLAM 0.050 m, odometry 1.720 m" in ok.message and "7 cases" in ok.message


def test_ate_rejects_the_usual_mistakes_naming_the_case():
    def d(e, t):
        return e[:, :2] - t[:, :2]

    no_root = check_ate(lambda e, t: np.mean(np.sum(d(e, t) ** 2, axis=1)))
    assert (
        no_root.status == "wrong"
        and "3 m east" in no_root.message
        and "square root" in no_root.message
    )
    cm = check_ate(lambda e, t: 100 * right_ate(e, t))
    assert cm.status == "wrong" and "centimetres" in cm.message
    mean = check_ate(lambda e, t: np.mean(np.hypot(*d(e, t).T)))
    assert "different sizes" in mean.message and "mean distance" in mean.message
    total = check_ate(lambda e, t: np.sum(np.hypot(*d(e, t).T)))
    assert "sum of the distances" in total.message
    theta = check_ate(lambda e, t: np.sqrt(np.mean(np.sum((e - t) ** 2, axis=1))))
    assert "heading only" in theta.message and "x and y only" in theta.message
    sign = check_ate(lambda e, t: right_ate(e, -t))  # estimate + truth
    assert sign.status == "wrong" and "sqrt(mean" in sign.message and one_line(sign)
    per_pose = check_ate(lambda e, t: np.hypot(*d(e, t).T))
    assert "one number" in per_pose.message and "(200,)" in per_pose.message
    sample_std = check_ate(lambda e, t: np.sqrt(np.sum(d(e, t) ** 2) / (len(e) - 1)))
    assert sample_std.status == "wrong" and "3 m east" in sample_std.message
    assert "returned None" in check_ate(lambda e, t: None).message
    crash = check_ate(lambda e, t: e[:, 5])
    assert crash.status == "wrong" and "IndexError" in str(crash) and one_line(crash)


def test_ate_template_is_not_attempted():
    assert check_ate(todo).status == "not attempted" and "my_ate" in str(check_ate(todo))
    assert check_ate(todo, TRUTH, {"odometry": ODOMETRY}).status == "not attempted"


def test_random_worlds_reading():
    assert check_random_worlds_reading("d") and check_random_worlds_reading("(D)")
    assert "corridor" in check_random_worlds_reading("d").message
    for wrong in ("a", "b", "c"):
        feedback = check_random_worlds_reading(wrong)
        assert feedback.status == "wrong" and one_line(feedback)
    assert "loop closure" in check_random_worlds_reading("a").message
    assert "one of" in check_random_worlds_reading("e").message
    assert check_random_worlds_reading(...).status == "not attempted"
