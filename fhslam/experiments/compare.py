"""Monte-Carlo comparison of SLAM methods: the claims the paper makes without measuring them.

:func:`slam_sweep` runs every method on the same simulated logs (seeds × odometry-noise
levels) through :mod:`joblib`, so the same code runs on the local cores or, through joblib's
backends, on a Dask or Ray cluster; every run is seeded, and the rows come back in a fixed
order whatever the backend.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from joblib import Parallel, delayed
from tqdm.auto import tqdm

from fhslam.metrics import ate, map_error
from fhslam.pipeline import METHODS, run_slam
from fhslam.sim import OdometryNoise, load_world, simulate


def noise_levels() -> dict[str, OdometryNoise]:
    """The three odometry-noise levels of the comparison.

    ``low``: the simulator's default (about 1 m of drift on the paper route); ``medium``:
    :meth:`OdometryNoise.drifting` (2-6 m); ``high``: its systematic errors 1.5 times larger.
    """
    mid = OdometryNoise.drifting()
    high = replace(
        mid,
        scale_error=1.5 * mid.scale_error,
        heading_bias=1.5 * mid.heading_bias,
        turn_scale_error=1.5 * mid.turn_scale_error,
    )
    return {"low": OdometryNoise(), "medium": mid, "high": high}


@dataclass(frozen=True)
class RunResult:
    """One method on one simulated log."""

    method: str
    level: str
    seed: int
    ate_rmse: float
    odometry_ate_rmse: float
    map_error: float
    ms_per_step: float
    n_map_lines: int


def one_run(world: str, level: str, seed: int, methods: Sequence[str]) -> list[RunResult]:
    """Simulate ``world`` with noise ``level`` and ``seed``; run every method on that log."""
    log = simulate(load_world(world), seed=seed, odometry=noise_levels()[level])
    odo = ate(log.odometry, log.truth).rmse
    out = []
    for m in methods:
        t0 = time.perf_counter()
        r = run_slam(log, m)
        ms = 1e3 * (time.perf_counter() - t0) / len(log)
        out.append(
            RunResult(
                method=m,
                level=level,
                seed=seed,
                ate_rmse=ate(r.poses, log.truth).rmse,
                odometry_ate_rmse=odo,
                map_error=map_error(r.map, log.world.walls) if r.map else float("nan"),
                ms_per_step=ms,
                n_map_lines=len(r.map),
            )
        )
    return out


def slam_sweep(
    world: str = "paper",
    seeds: Sequence[int] = range(20),
    levels: Sequence[str] = ("low", "medium", "high"),
    methods: Sequence[str] = tuple(METHODS),
    n_jobs: int = -1,
    progress: bool = True,
) -> list[RunResult]:
    """Every method on ``len(seeds) × len(levels)`` simulated logs, in parallel via joblib.

    Parameters
    ----------
    n_jobs : int
        joblib's worker count (-1: all cores). Use ``joblib.parallel_config(backend=...)``
        around the call to run on another backend (e.g. ``"dask"`` or ``"ray"``).

    Returns
    -------
    list of RunResult
        Ordered by level, seed, method.
    """
    unknown = set(methods) - set(METHODS)
    if unknown:
        raise ValueError(f"unknown SLAM methods {sorted(unknown)}; choose from {list(METHODS)}")
    jobs = [(lv, s) for lv in levels for s in seeds]
    par = Parallel(n_jobs=n_jobs, return_as="generator")
    results = par(delayed(one_run)(world, lv, s, tuple(methods)) for lv, s in jobs)
    rows: list[RunResult] = []
    for batch in tqdm(
        results, total=len(jobs), desc="SLAM sweep", unit="log", disable=not progress
    ):
        rows.extend(batch)
    return rows


def summary(rows: Sequence[RunResult]) -> dict[tuple[str, str], dict[str, float]]:
    """Median ATE, map error and ms per step per (level, method)."""
    out = {}
    for key in sorted({(r.level, r.method) for r in rows}):
        sel = [r for r in rows if (r.level, r.method) == key]
        out[key] = {
            "ate_median": float(np.median([r.ate_rmse for r in sel])),
            "ate_max": float(np.max([r.ate_rmse for r in sel])),
            "map_error_median": float(np.nanmedian([r.map_error for r in sel]))
            if any(np.isfinite(r.map_error) for r in sel)
            else float("nan"),
            "ms_per_step_median": float(np.median([r.ms_per_step for r in sel])),
            "n": len(sel),
        }
    return out
