"""The runs over draws of :func:`fhslam.experiments.benchmark.run_benchmark`, in parallel
(joblib): a log degraded or with its odometry perturbed in the last bit
(:func:`log_draws`), a simulated world likewise (:func:`world_draws`), and every method on
a sparse copy of a log (:func:`sparse_draws`)."""

from __future__ import annotations

import numpy as np
from tqdm.auto import tqdm

from fhslam.datasets import find_dataset
from fhslam.experiments.benchmark import METHODS, DrawRow, Draws
from fhslam.io import Log, read_relations

__all__ = [
    "SPARSE_VARIANT",
    "frame_text",
    "log_draws",
    "sparse_draws",
    "sparse_error",
    "world_draws",
]


def _draw_row(kind, name, run, level, seed, error, moved="") -> DrawRow:
    """A :class:`DrawRow` of ``run`` (a :class:`~fhslam.experiments.robustness.LogRun` or a
    :class:`~fhslam.experiments.compare.RunResult`: degraded with its ``degrade_seed``, or
    not at all; ``moved``: the frame it ran in, in words, if not the world's own)."""
    done = [f"{1000 * run.range_noise:g} mm range noise"] if run.range_noise else []
    done += [f"{100 * run.drop_fraction:g} % dropped"] if run.drop_fraction else []
    variant = ", ".join(done) or ("as read" if kind == "log" else "as simulated")
    variant += f", {moved}" if moved else ""
    return DrawRow(
        kind=kind,
        name=name,
        method=run.method,
        variant=f"{variant}, last bit" if run.last_bit else variant,
        level=level,
        seed=seed,
        range_noise=run.range_noise,
        drop_fraction=run.drop_fraction,
        degrade_seed=run.degrade_seed if done else -1,
        last_bit=run.last_bit,
        error_m=error,
    )


def frame_text(motion) -> str:
    """A frame's rigid motion in words, as a world :class:`DrawRow`'s ``variant`` names it:
    ``"moved (3.14, -2.72) m, 57.3°"``."""
    x, y, theta = motion
    return f"moved ({x:.2f}, {y:.2f}) m, {np.degrees(theta):.1f}°"


def log_draws(
    draws: Draws, logs: dict[str, Log], as_read: dict[str, float], n_jobs: int, progress: bool
) -> list[DrawRow]:
    """The log draws of ``draws`` (seeded: :meth:`Draws.seeded`) in parallel (the runs of
    ``fhslam sweep --log``); the run as read only for a log whose ``graph`` run is not in
    ``as_read`` (log -> error)."""
    from joblib import Parallel, delayed

    from fhslam.experiments.compare import _workers_deaf_to_ctrl_c
    from fhslam.experiments.robustness import _one

    none = {"range_noise": 0.0, "drop_fraction": 0.0, "clutter_fraction": 0.0}
    noise = {**none, "range_noise": draws.range_noise}
    drop = {**none, "drop_fraction": draws.drop_fraction}
    noise_seeds = draws.seeds_of("range noise", draws.seeds) if draws.range_noise else []
    drop_seeds = draws.seeds_of("dropped", draws.seeds) if draws.drop_fraction else []
    jobs = []
    for name in draws.logs:
        if name not in as_read:
            jobs.append((name, none, -1, 0))
        jobs += [(name, noise, s, 0) for s in noise_seeds]
        jobs += [(name, drop, s, 0) for s in drop_seeds]
        jobs += [(name, none, -1, b) for b in draws.seeds_of("last bit", draws.last_bit_draws)]
    rows: dict[str, list[DrawRow]] = {
        name: [DrawRow("log", name, "graph", "as read", "", -1, 0.0, 0.0, -1, 0, as_read[name])]
        if name in as_read
        else []
        for name in draws.logs
    }
    if jobs:
        relations = {n: read_relations(find_dataset(n, "relations")) for n in draws.logs}
        par = Parallel(n_jobs=n_jobs, return_as="generator")
        with _workers_deaf_to_ctrl_c():
            runs = par(
                delayed(_one)(logs[n], n, relations[n], "graph", None, deg, s, b)
                for n, deg, s, b in jobs
            )
            bar = tqdm(runs, total=len(jobs), desc="log draws", unit="run", disable=not progress)
            for r in bar:  # in the order of the jobs
                rows[r.log].append(_draw_row("log", r.log, r, "", -1, r.trans_error))
    return [r for name in draws.logs for r in rows[name]]


def world_draws(draws: Draws, n_jobs: int, progress: bool) -> list[DrawRow]:
    """The world draws of ``draws`` (seeded: :meth:`Draws.seeded`), in parallel: each
    simulated log in every frame of :meth:`Draws.motions`, and once each with range noise,
    with dropped scans and with a last-bit perturbation (as given)."""
    from joblib import Parallel, delayed

    from fhslam.experiments.compare import _workers_deaf_to_ctrl_c, one_run

    n = draws.world_seeds
    kws = [[{}] + [{"frame": m} for m in draws.motions()[1:]] for _ in range(n)]
    if draws.range_noise:
        for kw, s in zip(kws, draws.seeds_of("world range noise", n), strict=True):
            kw.append({"range_noise": draws.range_noise, "degrade_seed": s})
    if draws.drop_fraction:
        for kw, s in zip(kws, draws.seeds_of("world dropped", n), strict=True):
            kw.append({"drop_fraction": draws.drop_fraction, "degrade_seed": s})
    if draws.last_bit_draws:
        for kw, s in zip(kws, draws.seeds_of("world last bit", n), strict=True):
            kw.append({"last_bit": s})
    seeds = draws.seeds_of("world", n)
    jobs = [
        (world, seed, kw)
        for world in draws.worlds
        for seed, runs in zip(seeds, kws, strict=True)
        for kw in runs
    ]
    if not jobs:
        return []
    par = Parallel(n_jobs=n_jobs, return_as="generator")
    with _workers_deaf_to_ctrl_c():
        runs = par(
            delayed(one_run)(world, draws.world_level, seed, ("graph",), **kw)
            for world, seed, kw in jobs
        )
        bar = tqdm(runs, total=len(jobs), desc="world draws", unit="run", disable=not progress)
        rows = []
        for (world, _, kw), (r,) in zip(jobs, bar, strict=True):
            moved = frame_text(kw["frame"]) if "frame" in kw else ""
            rows.append(_draw_row("world", world, r, r.level, r.seed, r.ate_rmse, moved))
    return rows


SPARSE_VARIANT = "one scan per metre or half radian"
"""The ``variant`` of a sparse copy's :class:`DrawRow`."""


def sparse_error(log: Log, relations, method: str) -> float:
    """``method`` on the sparse copy of ``log`` (:func:`fhslam.sim.sparsify`, defaults), its
    trajectory extended to every scan of ``log`` by the odometry
    (:func:`fhslam.metrics.extend_by_odometry`) and measured against ``relations`` (``(t1,
    t2, rel)``): the mean translational relation error, metres."""
    from fhslam.sim import sparsify

    return _sparse_run(sparsify(log), log.timestamps, log.odometry, relations, method)


def _sparse_run(sparse: Log, timestamps, odometry, relations, method: str) -> float:
    """:func:`sparse_error` of a sparse copy made already: what a worker is sent (the full
    log's ``timestamps`` and ``odometry``, not its scans)."""
    from fhslam.experiments.compare import _thread_lock_for_tqdm
    from fhslam.metrics import extend_by_odometry, relations_error
    from fhslam.pipeline import run_slam

    _thread_lock_for_tqdm()
    r = run_slam(sparse, method)
    poses = extend_by_odometry(r.timestamps, r.poses, timestamps, odometry)
    return relations_error(timestamps, poses, *relations).trans_mean


def sparse_draws(draws: Draws, logs: dict[str, Log], n_jobs: int, progress: bool) -> list[DrawRow]:
    """Every method on the sparse copy of each of ``draws.sparse_logs``, in parallel (each
    log thinned once, here)."""
    from joblib import Parallel, delayed

    from fhslam.experiments.compare import _workers_deaf_to_ctrl_c
    from fhslam.sim import sparsify

    jobs = [(n, m) for n in draws.sparse_logs for m in METHODS]
    if not jobs:
        return []
    relations = {n: read_relations(find_dataset(n, "relations")) for n in draws.sparse_logs}
    sparse = {n: sparsify(logs[n]) for n in draws.sparse_logs}
    par = Parallel(n_jobs=n_jobs, return_as="generator")
    with _workers_deaf_to_ctrl_c():
        runs = par(
            delayed(_sparse_run)(sparse[n], logs[n].timestamps, logs[n].odometry, relations[n], m)
            for n, m in jobs
        )
        bar = tqdm(runs, total=len(jobs), desc="sparse copies", unit="run", disable=not progress)
        errors = list(bar)
    return [
        DrawRow("sparse", n, m, SPARSE_VARIANT, "", -1, 0.0, 0.0, -1, 0, e)
        for (n, m), e in zip(jobs, errors, strict=True)
    ]
