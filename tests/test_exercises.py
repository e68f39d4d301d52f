"""The exercise checks accept right answers and reject wrong ones with a useful message."""

import numpy as np
import pytest

from fhslam.exercises import (
    check_ate,
    check_clustering,
    check_heading_correction,
    check_observation,
)


def test_clustering_check():
    assert "correct" in check_clustering(
        lambda p, g: np.concatenate([[0], np.cumsum(np.hypot(*np.diff(p, axis=0).T) > g)])
    )
    with pytest.raises(AssertionError, match="expected"):
        check_clustering(lambda p, g: np.zeros(len(p), int))  # never splits
    with pytest.raises(AssertionError, match="None"):
        check_clustering(lambda p, g: None)


def test_observation_check():
    def right(rho, theta, pose):
        s = rho - pose[0] * np.cos(theta) - pose[1] * np.sin(theta)
        return int(np.sign(s)), abs(s)

    assert "correct" in check_observation(right)
    with pytest.raises(AssertionError, match="expected dir"):
        check_observation(
            lambda rho, theta, pose: (-right(rho, theta, pose)[0], right(rho, theta, pose)[1])
        )


def test_heading_check():
    def right(obs, ref, w):
        d = np.pi - np.mod(np.pi - (ref - obs), 2 * np.pi)
        return float(np.sum(w * d) / w.sum())

    assert "correct" in check_heading_correction(right)
    with pytest.raises(AssertionError, match="wrap"):
        check_heading_correction(lambda obs, ref, w: float(np.sum(w * (ref - obs)) / w.sum()))


def test_ate_check():
    assert "correct" in check_ate(
        lambda e, t: float(np.sqrt(np.mean(np.sum((e[:, :2] - t[:, :2]) ** 2, 1))))
    )
    with pytest.raises(AssertionError, match="rmse"):
        check_ate(lambda e, t: float(np.mean(np.abs(e[:, :2] - t[:, :2]))))
