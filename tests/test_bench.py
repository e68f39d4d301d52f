"""``fhslam bench``'s real-log section: the stage timer and the per-stage split of a run.

No test here asserts a duration: only how the times relate (stages non-negative, adding up to
the total), which holds on any machine under any load.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from fhslam.experiments.bench import (
    STAGES,
    LogBench,
    StageTimer,
    format_log_bench,
    instrumented_backend,
    log_head,
    run_log_bench,
)
from fhslam.pipeline import run_backend, run_slam
from fhslam.sim import paper_world, simulate


@pytest.fixture(scope="module")
def short_log():
    return simulate(paper_world(), seed=0, max_scans=60)


def test_stage_timer_subtracts_nested_stages():
    ticks = itertools.count()  # a fake clock: one second per reading
    timer = StageTimer(clock=lambda: float(next(ticks)))
    inner = timer.wrap(lambda: None, "inner")

    def outer_fn():
        inner()
        inner()

    outer = timer.wrap(outer_fn, "outer")
    outer()
    # outer reads the clock at 0 and 5, the inner calls at 1-2 and 3-4
    assert timer.calls == {"inner": 2, "outer": 1}
    assert timer.seconds == {"inner": 2.0, "outer": 3.0}  # 5 - 0 less the nested 2 seconds


def test_stage_timer_patches_one_instance_only():
    class Thing:
        def f(self, x):
            return 2 * x

    a, b = Thing(), Thing()
    timer = StageTimer()
    timer.patch(a, "f", "doubling")
    assert a.f(3) == 6 and b.f(4) == 8
    assert timer.calls == {"doubling": 1}
    assert "f" not in vars(b) and Thing.f is not a.f


def test_stage_timer_nests_per_thread_and_keeps_other_threads_apart():
    import threading

    timer = StageTimer()
    inner = timer.wrap(lambda: threading.Event().wait(0.05), "inner")
    outer = timer.wrap(lambda: inner(), "outer")
    t = threading.Thread(target=inner)
    t.start()
    outer()  # while the other thread's inner call runs: it is not nested in this one
    t.join()
    assert timer.calls == {"inner": 2, "outer": 1}
    assert timer.off_main == {"inner": pytest.approx(timer.seconds["inner"] / 2, rel=0.5)} | {
        "outer": 0.0
    }
    assert 0 <= timer.seconds["outer"] < 0.05  # its own inner call only was subtracted


def test_stage_timer_counts_a_call_that_raises():
    timer = StageTimer()
    f = timer.wrap(lambda: 1 / 0, "broken")
    with pytest.raises(ZeroDivisionError):
        f()
    assert timer.calls["broken"] == 1 and timer.seconds["broken"] >= 0
    assert not timer._open  # the stack of open calls is balanced again


@pytest.mark.parametrize("method", ["graph", "fht"])
def test_timed_backend_gives_the_same_result(short_log, method):
    timed = run_backend(instrumented_backend(method, StageTimer()), short_log)
    plain = run_slam(short_log, method)
    np.testing.assert_array_equal(timed.poses, plain.poses)
    assert len(timed.map) == len(plain.map)


@pytest.mark.parametrize("method", ["graph", "fht", "classical", "ekf", "odometry"])
def test_log_bench_stages_add_up_to_the_total(short_log, method):
    b = run_log_bench(short_log, method, progress=False)
    assert isinstance(b, LogBench)
    assert list(b.stages) == [*STAGES.get(method, ()), "other"]
    assert all(s >= 0 for s in b.stages.values())
    # the main thread's stages add up to at most the wall time; the back end's overlap them
    assert sum(b.stages.values()) - sum(b.parallel.values()) <= b.seconds + 1e-9
    assert all(0 < b.parallel[k] <= b.stages[k] for k in b.parallel)
    assert set(b.parallel) <= ({"loop closure", "optimisation"} if method == "graph" else set())
    assert b.n_scans == len(short_log) == 60
    assert b.steps_per_second == pytest.approx(b.n_scans / b.seconds)
    span = short_log.timestamps[-1] - short_log.timestamps[0]
    assert b.real_time_factor == pytest.approx(span / b.seconds)
    assert b.reference_seconds > 0
    assert b.ratio_to_reference() == pytest.approx(b.seconds / b.n_scans / b.reference_seconds)
    if method in STAGES:
        assert b.calls["extraction"] > 0 and b.calls["map"] >= 1
    if method == "graph":
        assert b.calls["tracking"] == len(short_log) - 1  # every scan but the first
        assert "loop closure" in b.parallel  # on the back end's thread
    table = format_log_bench(b)
    assert "60 scans" in table and "total" in table
    assert ("ran on the back end's thread" in table) == (method == "graph")


def test_log_bench_medians_over_repeats(short_log):
    b = run_log_bench(log_head(short_log, 25), "fht", repeats=3, progress=False)
    assert b.repeats == 3 and b.n_scans == 25
    assert all(s >= 0 for s in b.stages.values())
    assert "medians of 3 runs" in format_log_bench(b)


def test_log_head_cuts_every_per_scan_array(short_log):
    head = log_head(short_log, 10)
    assert len(head) == 10
    assert head.truth.shape == (10, 3) and head.hits.shape == (10, short_log.n_beams)
    np.testing.assert_array_equal(head.ranges, short_log.ranges[:10])
    assert len(log_head(short_log, 1000)) == len(short_log)
    with pytest.raises(ValueError, match="n must be >= 1"):
        log_head(short_log, 0)
