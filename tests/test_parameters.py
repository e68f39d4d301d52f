"""Every parameter of the default SLAM is alive: moved within its range, it changes a run.

The run: the ``offices`` floor driven twice, blind for 60 scans shortly before the end of the
first lap while the odometry turns 20 degrees too far (``conftest.blind_turn``), so that the
local loop closures, their confirmation and the global search (which closes the lap) act.
A clean simulation never makes the tracker's searches reach beyond a degree, nor a loop
closure's heading: the parameters of those (:data:`ON_A_REAL_LOG`) are moved on MIT CSAIL,
whose odometry glitches. Each of the default method's parameters is moved, one at a time, to
another value in its range; the run's poses must change. A parameter that changes nothing is
dead code, or needs a scenario of its own.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest
from conftest import blind_turn

from fhslam.pipeline import run_slam
from fhslam.sim import load_world, simulate
from fhslam.slam import GraphSlamParams
from fhslam.slam.graph import LoopParams, count_parameters

BASE = GraphSlamParams(loops=LoopParams(max_radius=3.0))
"""The local search's reach cut to 10 m of travel, so that the global search closes the lap."""

MOVED = {
    "keyframes.distance": 0.7,
    "keyframes.angle_deg": 10.0,
    "keyframes.max_range": 6.0,
    "keyframes.voxel": 0.04,
    "keyframes.submap": 3,
    "tracker.resolution": 0.04,
    "tracker.window": 0.02,
    "tracker.window_deg": 0.5,
    "tracker.recovery_window": 0.02,
    "tracker.recovery_window_deg": 1.0,
    "tracker.min_score": 0.9,
    "tracker.sure_score": 0.7,
    "tracker.refine_iterations": 3,
    "edges.sigma": 0.05,
    "edges.points": 10.0,
    "edges.odometry_sigma": (0.05, 1.0),
    "loops.candidates": 1,
    "loops.min_gap": 30,
    "loops.radius": 1.5,
    "loops.growth": 0.1,
    "loops.max_radius": 5.0,
    "loops.target_keyframes": 3,
    "loops.window": 0.2,
    "loops.window_deg": 0.5,
    "loops.min_score": 0.7,
    "loops.max_chi2": 0.01,
    "loops.confirm_distance": 0.001,
    "loops.consistency": 0.001,
    "search.every": 0,
    "search.after": 30.0,
    "search.keyframes": 5,
    "search.min_score": 0.95,
    "search.window_deg": 10.0,
    "search.max_window": 0.5,
    "optimiser.iterations": 2,
    "optimiser.tol": 1e-2,
}
"""Each parameter's other value (the default's group, one field moved): far enough that a
clean simulated run notices (moved a little, a search window or score threshold that the
run's matches clear anyway changes no bit)."""


ELSEWHERE = {
    "search.confirm_score": "test_graphslam.py::test_a_held_global_match_is_confirmed_at_the_"
    "lower_score",
}
"""Parameters that neither run exercises (no confirmation of a global hypothesis scores
between 0.5 and 0.55 on the floor or on MIT CSAIL), shown alive by the test named, on canned
matches."""

ON_A_REAL_LOG = {
    "tracker.window_deg",
    "tracker.recovery_window",
    "tracker.recovery_window_deg",
    "loops.growth",
    "loops.window_deg",
    "loops.consistency",
}
"""The parameters moved on MIT CSAIL instead of the simulated floor."""


@functools.cache
def _log(real: bool):
    if real:
        from conftest import data_dir

        from fhslam.datasets import load_log

        if data_dir() is None:
            pytest.skip("no real laser logs: set FHSLAM_DATA or place them in ../shared/data")
        return load_log("mit-csail")
    return blind_turn(simulate(load_world("offices"), seed=0, laps=2), 20, 8, 60, 30)


@functools.cache
def _poses(setting: str | None, real: bool) -> np.ndarray:
    params = BASE if not real else GraphSlamParams()
    if setting is not None:
        group, name = setting.split(".")
        moved = dataclasses.replace(getattr(params, group), **{name: MOVED[setting]})
        params = dataclasses.replace(params, **{group: moved})
    return run_slam(_log(real), params=params).poses


def test_every_parameter_is_moved_once():
    names = {
        f"{g.name}.{f.name}"
        for g in dataclasses.fields(GraphSlamParams)
        for f in dataclasses.fields(
            g.type if isinstance(g.type, type) else type(getattr(BASE, g.name))
        )
    }
    assert set(MOVED) | set(ELSEWHERE) == names and not set(MOVED) & set(ELSEWHERE)
    assert len(names) == count_parameters(BASE)


@pytest.mark.parametrize("setting", sorted(MOVED))
def test_a_moved_parameter_changes_the_run(setting):
    real = setting in ON_A_REAL_LOG
    base, moved = _poses(None, real), _poses(setting, real)
    assert base.shape == moved.shape
    assert not np.array_equal(base, moved), f"{setting}={MOVED[setting]!r} changed nothing"
