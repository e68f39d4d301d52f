"""The pose graph: exact recovery, the Jacobians, the Cauchy kernel, bad input."""

from __future__ import annotations

import numpy as np
import pytest

from fhslam.geometry import compose, relative, wrap_angle
from fhslam.posegraph import PoseGraph, _errors_and_jacobians, edge_errors, optimize


def _ring(n=12, radius=3.0):
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.column_stack([radius * np.cos(a), radius * np.sin(a), wrap_angle(a + np.pi / 2)])


def test_consistent_edges_recover_the_poses_exactly():
    truth = _ring()
    i = np.r_[np.arange(11), 0, 3]
    j = np.r_[np.arange(1, 12), 11, 9]
    z = relative(truth[i], truth[j])
    rng = np.random.default_rng(0)
    start = truth + rng.normal(scale=[0.3, 0.3, 0.1], size=truth.shape)
    start[0] = truth[0]  # the gauge
    x = optimize(start, i, j, z, np.ones((len(i), 3)), iterations=20, tol=1e-12)
    np.testing.assert_allclose(x, truth, atol=1e-9)
    np.testing.assert_allclose(edge_errors(x, i, j, z), 0.0, atol=1e-9)


def test_jacobians_match_finite_differences():
    rng = np.random.default_rng(1)
    x = rng.normal(size=(2, 3))
    z = rng.normal(size=(1, 3))
    i, j = np.array([0]), np.array([1])
    _, ji, jj = _errors_and_jacobians(x, i, j, z)
    h = 1e-7
    for node, jac in ((0, ji[0]), (1, jj[0])):
        for k in range(3):
            xp, xm = x.copy(), x.copy()
            xp[node, k] += h
            xm[node, k] -= h
            num = (edge_errors(xp, i, j, z)[0] - edge_errors(xm, i, j, z)[0]) / (2 * h)
            np.testing.assert_allclose(jac[:, k], num, atol=1e-6)


def test_a_wrong_loop_closure_is_down_weighted_by_the_kernel():
    """A square driven once: odometry edges exact, one true loop edge and one 1.5 m wrong.
    Plain least squares bends the square by decimetres; the Cauchy kernel keeps it within
    2 cm."""
    truth = np.array([[0, 0, 0], [2, 0, np.pi / 2], [2, 2, np.pi], [0, 2, -np.pi / 2],
                      [0, 0.1, 0]], dtype=float)  # fmt: skip
    i = np.array([0, 1, 2, 3, 0, 1])
    j = np.array([1, 2, 3, 4, 4, 3])
    z = relative(truth[i], truth[j])
    z[5] = compose(z[5], [1.5, 0.0, 0.0])  # the wrong one
    info = np.tile([100.0, 100.0, 1000.0], (6, 1))
    plain = optimize(truth, i, j, z, info)
    robust = optimize(truth, i, j, z, info, robust=np.array([0, 0, 0, 0, 1.0, 1.0]))
    assert np.abs(plain[:, :2] - truth[:, :2]).max() > 0.2
    assert np.abs(robust[:, :2] - truth[:, :2]).max() < 0.02


def test_pose_graph_class_and_bad_input():
    g = PoseGraph()
    a = g.add_node([0, 0, 0])
    b = g.add_node([1.2, 0.1, 0.05])
    e = g.add_edge(a, b, [1.0, 0.0, 0.0], [1e4, 1e4, 1e4])
    g.optimize()
    np.testing.assert_allclose(g.poses[1], [1.0, 0.0, 0.0], atol=1e-9)
    g.set_measurement(e, [2.0, 0.0, 0.0])
    g.optimize()
    np.testing.assert_allclose(g.poses[1], [2.0, 0.0, 0.0], atol=1e-9)
    assert g.edges[3] == ["odometry"]
    g.set_information(e, np.diag([1e4, 1e4, 1e2]))
    np.testing.assert_array_equal(g.information(e), np.diag([1e4, 1e4, 1e2]))
    for bad in ([1.0, 2.0, 3.0], np.full((3, 3), np.nan)):
        with pytest.raises(ValueError, match="finite 3 x 3"):
            g.set_information(e, bad)
    with pytest.raises(ValueError, match="two different nodes"):
        g.add_edge(0, 0, [0, 0, 0], [1, 1, 1])
    with pytest.raises(ValueError, match="two different nodes"):
        g.add_edge(0, 5, [0, 0, 0], [1, 1, 1])
    with pytest.raises(ValueError, match="same length"):
        optimize(np.zeros((2, 3)), [0], [1, 0], np.zeros((1, 3)), np.ones((1, 3)))
    with pytest.raises(ValueError, match="index the 2 poses"):
        optimize(np.zeros((2, 3)), [0], [2], np.zeros((1, 3)), np.ones((1, 3)))
    # a graph without edges is returned unchanged
    np.testing.assert_array_equal(optimize(np.ones((3, 3)), [], [], [], []), np.ones((3, 3)))


def test_full_information_matrices_agree_with_diagonals_and_rotate_with_the_edge():
    truth = _ring()
    i, j = np.r_[np.arange(11), 0], np.r_[np.arange(1, 12), 11]
    z = relative(truth[i], truth[j])
    rng = np.random.default_rng(2)
    z_noisy = z + rng.normal(scale=[0.02, 0.02, 0.01], size=z.shape)
    diag = rng.uniform(10, 1000, size=(len(i), 3))
    a = optimize(truth, i, j, z_noisy, diag, tol=1e-12)
    b = optimize(truth, i, j, z_noisy, diag[:, :, None] * np.eye(3), tol=1e-12)
    np.testing.assert_allclose(a, b, atol=1e-12)
    with pytest.raises(ValueError, match=r"shape \(E, 3\) or \(E, 3, 3\)"):
        optimize(truth, i, j, z, np.ones((len(i), 2, 2)))


def test_an_edge_without_information_along_an_axis_leaves_it_to_the_others():
    """A corridor's edge: nothing known along x. Its wrong x (1 m) must not move node 1, which
    a weak second edge places; its y, known well, wins over the weak edge's."""
    g = PoseGraph()
    for _ in range(2):
        g.add_node([0.0, 0.0, 0.0])
    corridor = np.diag([0.0, 1e6, 1e6])  # the error's x: along the corridor
    g.add_edge(0, 1, [1.0, 0.0, 0.0], corridor)
    g.add_edge(0, 1, [2.0, 0.3, 0.0], [1.0, 1.0, 1.0])
    g.optimize(iterations=10, tol=1e-12)
    np.testing.assert_allclose(g.poses[1], [2.0, 0.3e-6, 0.0], atol=1e-6)


def test_switched_off_edges_take_no_part_and_chi2_measures_the_rest():
    g = PoseGraph()
    for _ in range(2):
        g.add_node([0.0, 0.0, 0.0])
    good = g.add_edge(0, 1, [1.0, 0.0, 0.0], [100.0, 100.0, 100.0])
    bad = g.add_edge(0, 1, [1.0, 2.0, 0.0], [100.0, 100.0, 100.0], kind="loop")
    g.optimize(iterations=10, tol=1e-12)
    np.testing.assert_allclose(g.poses[1], [1.0, 1.0, 0.0], atol=1e-9)  # the average
    np.testing.assert_allclose(g.chi2([good, bad]), [100.0, 100.0], rtol=1e-9)
    g.set_active(bad, False)
    assert g.is_active(good) and not g.is_active(bad)
    g.optimize(iterations=10, tol=1e-12)
    np.testing.assert_allclose(g.poses[1], [1.0, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(g.chi2([good, bad]), [0.0, 400.0], atol=1e-9)
