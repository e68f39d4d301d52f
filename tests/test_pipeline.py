"""The one SLAM pipeline: every method as a back end with the same contract."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from fhslam.geometry import compose, inverse
from fhslam.lines import line_from_points
from fhslam.pipeline import METHODS, make_backend, run_backend, run_slam
from fhslam.reference_map import ReferenceMap
from fhslam.slam import (
    Backend,
    EKFParams,
    FastHoughSLAM,
    FinalEstimate,
    GraphSlamParams,
    SlamParams,
    StepResult,
)


@pytest.mark.parametrize("method", list(METHODS))
def test_every_method_is_a_backend_and_keeps_the_result_contract(method, paper_log_small):
    backend = make_backend(method)
    assert isinstance(backend, Backend)
    r = run_slam(paper_log_small, method)
    n = len(paper_log_small)
    assert r.poses.shape == (n, 3) and len(r.steps) == n and np.isfinite(r.poses).all()
    np.testing.assert_array_equal(r.timestamps, paper_log_small.timestamps)
    np.testing.assert_array_equal(r.poses, [s.pose for s in r.steps])
    assert all(isinstance(s, StepResult) for s in r.steps)
    # every method starts at the first odometry pose
    np.testing.assert_allclose(r.poses[0], paper_log_small.odometry[0], atol=1e-12)


def test_odometry_method_returns_the_odometry(paper_log_small):
    r = run_slam(paper_log_small, "odometry")
    np.testing.assert_array_equal(r.poses, paper_log_small.odometry)
    assert r.map == []


@pytest.mark.parametrize(
    ("method", "params"),
    [
        ("ekf", SlamParams()),
        ("fht", EKFParams()),
        ("graph", SlamParams()),
        ("classical", GraphSlamParams()),
        ("odometry", SlamParams()),
    ],
)
def test_parameters_of_the_wrong_type_are_refused(method, params, paper_log_small):
    with pytest.raises(TypeError, match=f"SLAM method '{method}' takes"):
        run_slam(paper_log_small, method, params)


def test_parameters_reach_the_backend(paper_log_small):
    """A parameter change must change the result (it is not silently dropped)."""
    a = run_slam(paper_log_small, "ekf").poses
    b = run_slam(paper_log_small, "ekf", EKFParams(gate=1e-6)).poses  # associate nothing
    assert np.abs(a - b).max() > 1e-6


def test_unknown_method_lists_the_known_ones(paper_log_small):
    with pytest.raises(ValueError, match="choose one of fht, graph, classical, ekf, odometry"):
        run_slam(paper_log_small, "icp")


class _Recorder:
    """A minimal back end: remembers what the pipeline hands it."""

    def __init__(self):
        self.seen: list[tuple[bool, np.ndarray]] = []

    def step(self, scan, odometry):
        self.seen.append((scan is None, np.asarray(odometry, float)))
        return StepResult(np.asarray(odometry, float), 0, 0, 0, False)

    def finish(self):
        return FinalEstimate([])


def test_dropped_scans_reach_the_backend_as_none(paper_log_small):
    ranges = paper_log_small.ranges.copy()
    ranges[[3, 7]] = np.nan
    log = replace(paper_log_small, ranges=ranges)
    rec = _Recorder()
    run_backend(rec, log)
    assert [k for k, (dropped, _) in enumerate(rec.seen) if dropped] == [3, 7]


def test_the_pipeline_applies_the_laser_mount_once(paper_log_small):
    """Back ends see laser poses (odometry ⊕ offset); the result is in robot poses."""
    offset = np.array([0.2, -0.05, 0.1])
    log = replace(paper_log_small, laser_offset=offset)
    rec = _Recorder()
    r = run_backend(rec, log)
    np.testing.assert_allclose([o for _, o in rec.seen], compose(log.odometry, offset))
    np.testing.assert_allclose(r.poses, log.odometry, atol=1e-12)
    np.testing.assert_allclose(compose(r.poses, offset), compose(log.odometry, offset))
    assert np.abs(inverse(offset)).max() > 0  # a real offset was exercised


def test_final_poses_revise_every_step(paper_log_small):
    class Revising(_Recorder):
        def finish(self):
            return FinalEstimate([], np.zeros((len(self.seen), 3)))

    r = run_backend(Revising(), paper_log_small)
    assert not r.poses.any() and all(not s.pose.any() for s in r.steps)


def test_a_backend_driven_by_hand_equals_the_pipeline(paper_log_small):
    slam = FastHoughSLAM()
    poses = [slam.step(paper_log_small.scan(k), paper_log_small.odometry[k]).pose
             for k in range(len(paper_log_small))]  # fmt: skip
    np.testing.assert_array_equal(poses, run_slam(paper_log_small, "fht").poses)
    assert len(slam.references) == len(slam.finish().map) > 0


# -- the reference map: the one merge-or-add policy -------------------------------------


def _segment(p, q, n=30):
    t = np.linspace(0, 1, n)[:, None]
    return line_from_points(np.asarray(p) + t * (np.asarray(q) - np.asarray(p)))


def test_reference_map_adds_only_long_well_supported_lines():
    m = ReferenceMap(min_length=0.6, min_points=10)
    added = m.update(
        [_segment((0, 1), (2, 1)), _segment((0, 2), (0.3, 2)), _segment((3, 0), (3, 2), n=5)],
        [-1, -1, -1],
    )
    assert added == 1 and len(m) == 1
    assert m[0].length == pytest.approx(2.0)


def test_reference_map_merges_a_match_and_refuses_a_far_one():
    m = ReferenceMap(max_merge_residual=0.05)
    m.update([_segment((0, 1), (2, 1))], [-1])
    near = _segment((1.5, 1.01), (3.5, 1.01))
    assert m.associate([near], (1.0, 0.0, 0.0)).tolist() == [0]
    m.update([near], [0])
    assert len(m) == 1 and m[0].length == pytest.approx(3.5, abs=0.02)
    far = _segment((0, 1.2), (2, 1.2))  # matched by index, but 20 cm off: not merged
    before = m[0]
    m.update([far], [0])
    assert m[0] is before


def test_reference_map_nearby_uses_the_segments():
    m = ReferenceMap()
    m.update([_segment((0, 0), (2, 0)), _segment((10, 0), (12, 0))], [-1, -1])
    assert m.nearby((1.0, 0.5), reach=1.0).tolist() == [0]
    assert m.nearby((6.0, 0.0), reach=4.5).tolist() == [0, 1]
    assert m.nearby((6.0, 0.0), reach=1.0).tolist() == []


@pytest.mark.parametrize("method", list(METHODS))
def test_no_method_depends_on_the_blas_thread_count(method):
    """Every method gives the same bits with BLAS on 1 and on 2 threads (the
    EKF's dense covariance is the one place threaded BLAS changes them: it limits itself to
    one thread; fht, graph and classical use no BLAS large enough to be threaded: on MIT
    CSAIL and Intel, OPENBLAS_NUM_THREADS=1 and =2 gave identical trajectories and the BLAS
    worker threads no CPU time)."""
    from test_ekf import staggered_corridor
    from threadpoolctl import threadpool_limits

    from fhslam.sim import MotionParams, simulate

    log = simulate(staggered_corridor(), seed=0, motion=MotionParams(speed=1.0))
    poses = []
    for threads in (1, 2):
        with threadpool_limits(threads, "blas"):
            poses.append(run_slam(log, method).poses)
    np.testing.assert_array_equal(poses[0], poses[1])
