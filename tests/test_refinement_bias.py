"""The tracker's refinement along the ``ring``'s corridors, one refinement at a time
(:mod:`fhslam.experiments.bias`): the cut corners push it forward."""

from __future__ import annotations

import numpy as np
import pytest

from fhslam.experiments.bias import refinement_bias


def test_the_fills_across_corners_push_each_refinement_forward():
    """Three seeds, 372 refinements from the true pose against the six scans before each:
    +0.83 mm ahead on average (standard error 0.25) with every filled point's normal,
    -0.26 mm (0.34) without the normals of those filled across corners (``corner_deg``).
    The heading has no such bias (+1.7 and +0.3 millidegrees, standard errors 2). The
    median error is 2.5 mm either way; without those normals a few refinements lose what
    held them along the corridor (the largest error 7.3 cm, 2.5 cm with them; the 99th
    percentiles 1.65 and 1.54 cm)."""
    plain = refinement_bias("ring")
    cornered = refinement_bias("ring", corner_deg=20.0)
    assert len(plain.along) == len(cornered.along) == 3 * 124
    np.testing.assert_array_equal(plain.scan, cornered.scan)
    assert plain.mean() >= 0.5e-3 and plain.mean() >= 2 * plain.standard_error()
    assert abs(cornered.mean()) <= 0.5e-3
    for b in (plain, cornered):
        assert abs(np.degrees(b.heading.mean())) <= 0.01
        assert np.median(np.abs(b.along)) <= 0.004
        assert np.percentile(np.abs(b.along), 99) <= 0.025
    assert np.abs(plain.along).max() <= 0.035


def test_refinement_bias_bad_input():
    with pytest.raises(ValueError, match="map_scans <= first < n_scans"):
        refinement_bias("ring", n_scans=20, first=30)
    with pytest.raises(ValueError, match="map_scans <= first"):
        refinement_bias("ring", first=3, map_scans=6)
    with pytest.raises(ValueError, match="and a seed"):
        refinement_bias("ring", seeds=())
    with pytest.raises(ValueError, match="corner_deg must be in"):
        refinement_bias("ring", seeds=(0,), n_scans=40, corner_deg=-1.0)
