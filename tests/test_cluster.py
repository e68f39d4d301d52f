"""The parallel runs on a Dask cluster (``--scheduler``): the same runs as on this machine, and
a scheduler that is not there or not an address refused in one line before any run."""

from __future__ import annotations

import sys
from dataclasses import astuple

import numpy as np
import pytest

from fhslam.cli import main
from fhslam.errors import InputError
from fhslam.experiments.cluster import dask_cluster
from fhslam.experiments.compare import slam_sweep

distributed = pytest.importorskip("distributed")

SWEEP = {"world": "corridor", "seeds": [0, 1], "levels": ("low",), "methods": ("fht", "odometry")}


@pytest.fixture(scope="module")
def cluster():
    """A Dask cluster of two single-threaded workers in this process (no dashboard)."""
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None
    ) as c:
        yield c


def _numbers(runs):
    """The runs' fields but their timing (``ms_per_step``), which no two runs share."""
    return [astuple(r)[:6] + astuple(r)[7:] for r in runs]


def test_a_sweep_on_a_dask_cluster_gives_the_runs_of_this_machine(cluster):
    here = slam_sweep(**SWEEP, n_jobs=1, progress=False)
    with dask_cluster(cluster.scheduler_address) as client:
        there = slam_sweep(**SWEEP, progress=False)
        assert len(client.scheduler_info()["workers"]) == 2
    assert len(there) == 4
    np.testing.assert_equal(_numbers(there), _numbers(here))  # NaN: the odometry's map error
    assert {(r.seed, r.method) for r in there} == {(s, m) for s in (0, 1) for m in SWEEP["methods"]}


def test_the_sweep_command_runs_on_a_dask_cluster(cluster, tmp_path, capsys):
    """``fhslam sweep --scheduler``: the file of the runs holds what a run here writes."""
    argv = ["sweep", "--world", "corridor", "--seeds", "2", "--levels", "low", "--methods",
            "fht", "odometry", "--quiet"]  # fmt: skip
    assert main([*argv, "--out", str(tmp_path / "here.csv")]) == 0
    out = tmp_path / "there.csv"
    assert main([*argv, "--out", str(out), "--scheduler", cluster.scheduler_address]) == 0
    assert "4 runs: 2 seeds x 1 levels x 2 methods" in capsys.readouterr().out
    here, there = (np.genfromtxt(p, delimiter=",", names=True, dtype=None, encoding="utf-8")
                   for p in (tmp_path / "here.csv", out))  # fmt: skip
    assert len(there) == 4
    for name in ("method", "seed", "ate_rmse", "odometry_ate_rmse", "map_error"):
        np.testing.assert_equal(there[name], here[name])


@pytest.mark.parametrize(
    ("address", "message"),
    [
        ("nonsense", "--scheduler 'nonsense': not a scheduler's address (missing port number"),
        ("foo://bar:1", "--scheduler 'foo://bar:1': not a scheduler's address (unknown address"),
    ],
)
def test_a_bad_scheduler_address_is_one_line_exit_2(address, message, capsys):
    argv = ["sweep", "--seeds", "1", "--levels", "low", "--methods", "odometry", "--quiet"]
    assert main([*argv, "--scheduler", address]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"fhslam: error: {message}") and len(err.splitlines()) == 1


def test_a_scheduler_that_does_not_answer_is_refused_in_time():
    refused = pytest.raises(InputError, match=r"no Dask scheduler answers there within 0\.5 s")
    with refused, dask_cluster("tcp://127.0.0.1:9", timeout=0.5):
        pytest.fail("connected to nothing")


def test_without_dask_distributed_the_error_says_what_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import fails as if not installed
    refused = pytest.raises(InputError, match=r"needs dask\.distributed: pip install 'fhslam\[")
    with refused, dask_cluster("tcp://127.0.0.1:8786"):
        pytest.fail("no dask.distributed, yet connected")
