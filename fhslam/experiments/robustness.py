"""How far a SLAM result on a real log moves when the log is degraded (``fhslam sweep --log``).

The robustness bound: 1 mm of Gaussian noise on every range, or 10 % of the scans dropped,
may change no log's relation error by more than 25 % or 1 cm, whichever is larger
(:func:`beyond`). One degraded run says little where a result turns on luck (the Freiburg
hospital's return is found or missed); :func:`log_sweep` runs the log as read and degraded
with seeds ``0 .. N-1`` (:func:`fhslam.sim.degrade`), and optionally with its odometry
perturbed in the last bit (:func:`fhslam.sim.perturb_odometry`), in parallel, each run
measured against the log's benchmark relations (:func:`fhslam.metrics.relations_error`).
"""

from __future__ import annotations

import csv
import os
import time
from collections.abc import Sequence
from dataclasses import astuple, dataclass, fields

import numpy as np
from joblib import Parallel, delayed
from tqdm.auto import tqdm

from fhslam import metrics
from fhslam.datasets import DATASETS, find_dataset, load_log
from fhslam.errors import InputError
from fhslam.experiments.compare import (
    _thread_lock_for_tqdm,
    _workers_deaf_to_ctrl_c,
    check_runs,
    settings_text,
)
from fhslam.io import Log, read_relations
from fhslam.io.files import atomic_output
from fhslam.pipeline import METHODS, run_slam
from fhslam.sim import degrade, perturb_odometry
from fhslam.sim.degrade import check_degradation

__all__ = ["LOG_FIELDS", "LogRun", "beyond", "format_log_sweep", "log_sweep", "save_log_sweep"]

RELATIVE_BOUND = 0.25
"""The robustness bound: a degraded run may change the relation error by this share of the
run's on the log as read, or by :data:`ABSOLUTE_BOUND`, whichever is larger."""
ABSOLUTE_BOUND = 0.01
"""See :data:`RELATIVE_BOUND`, metres."""


@dataclass(frozen=True)
class LogRun:
    """One SLAM run on a real log, measured against the log's relations.

    ``degrade_seed`` is -1 for a run on the log as read (no noise, no drops, no clutter);
    ``last_bit`` 0 for the odometry as read, else the seed of
    :func:`fhslam.sim.perturb_odometry`. The run with both is the *reference*.
    """

    log: str
    method: str
    range_noise: float
    drop_fraction: float
    clutter_fraction: float
    degrade_seed: int
    last_bit: int
    trans_error: float
    """Mean translational relation error, metres."""
    rot_error_deg: float
    """Mean rotational relation error, degrees."""
    n_relations: int
    """Relations used (both timestamps found among the run's scans)."""
    seconds: float
    settings: str = ""
    """The ``graph`` method's parameters that differ from their defaults, as ``--set``
    names them (``"tracker.window=0.3 loops.target_keyframes=4"``: :func:`~fhslam.experiments.
    compare.settings_text`; empty: the defaults, or another method)."""

    @property
    def reference(self) -> bool:
        """Whether this is the run on the log as read."""
        return self.degrade_seed < 0 and self.last_bit == 0


LOG_FIELDS = tuple(f.name for f in fields(LogRun))
"""The columns of ``fhslam sweep --log --out``'s CSV file, in order."""


def beyond(run: LogRun, reference: LogRun) -> bool:
    """Whether ``run``'s relation error differs from ``reference``'s by more than the
    robustness bound allows: 25 % of the reference's, or 1 cm, whichever is larger."""
    bound = max(RELATIVE_BOUND * reference.trans_error, ABSOLUTE_BOUND)
    return bool(abs(run.trans_error - reference.trans_error) > bound)


def _one(
    log: Log,
    name: str,
    relations: tuple[np.ndarray, np.ndarray, np.ndarray],
    method: str,
    params: object | None,
    degradation: dict[str, float],
    seed: int,
    last_bit: int,
) -> LogRun:
    """One run of :func:`log_sweep` (in a worker process)."""
    _thread_lock_for_tqdm()
    changed = {k: (v if seed >= 0 else 0.0) for k, v in degradation.items()}
    if seed >= 0:
        log = degrade(log, seed=seed, **changed)
    if last_bit:
        log = perturb_odometry(log, last_bit)
    t0 = time.perf_counter()
    result = run_slam(log, method, params if method == "graph" else None)
    seconds = time.perf_counter() - t0
    e = metrics.relations_error(result.timestamps, result.poses, *relations)
    return LogRun(
        name, method, changed["range_noise"], changed["drop_fraction"],
        changed["clutter_fraction"], seed, last_bit, e.trans_mean, e.rot_mean_deg, e.n_used,
        seconds, settings_text(params) if method == "graph" else "",
    )  # fmt: skip


def log_sweep(
    log: str | os.PathLike[str],
    relations: str | os.PathLike[str] | None = None,
    seeds: Sequence[int] = range(20),
    range_noise: float = 0.0,
    drop_fraction: float = 0.0,
    clutter_fraction: float = 0.0,
    last_bit_draws: int = 0,
    methods: Sequence[str] = ("graph",),
    params: object | None = None,
    n_jobs: int = -1,
    progress: bool = True,
) -> list[LogRun]:
    """Each method on a real log as read, then on the log degraded with each seed (and with
    its odometry perturbed in the last bit with seeds ``1 .. last_bit_draws``), in parallel.

    Parameters
    ----------
    log : str or path-like
        A laser log file or a dataset name (:func:`fhslam.datasets.load_log`).
    relations : str or path-like, optional
        Its benchmark relations: a ``.relations`` file or a dataset name; by default the
        dataset's own when ``log`` is a dataset name.
    seeds : sequence of int
        Seeds of :func:`fhslam.sim.degrade` (with ``range_noise``, ``drop_fraction``,
        ``clutter_fraction``); unused when all three are zero.
    last_bit_draws : int
        Each (degraded) log is also run with its odometry multiplied by (1 + 1e-15 ε),
        ε drawn with seeds ``1 .. last_bit_draws``.
    params : GraphSlamParams, optional
        The ``graph`` method's parameters (default: its defaults).
    n_jobs : int
        joblib's worker count (-1: all cores).

    Returns
    -------
    list of LogRun
        Per method, the reference run first, then by seed and odometry draw.

    Raises
    ------
    InputError
        Before any run: for a log or relations file that cannot be read, a log given by
        path without ``relations``, nothing to vary (no degradation and no last-bit draws),
        no seeds for a degradation, or a degradation :func:`fhslam.sim.degrade` refuses.
    ValueError
        For an unknown method, or ``params`` without the ``graph`` method.
    """
    if not methods:
        raise ValueError(f"no SLAM method given; choose from {list(METHODS)}")
    check_runs(methods, params, last_bit_draws)
    drop_fraction, clutter_fraction, _, range_noise = check_degradation(
        drop_fraction, clutter_fraction, 0, range_noise
    )
    degradation = {
        "range_noise": range_noise,
        "drop_fraction": drop_fraction,
        "clutter_fraction": clutter_fraction,
    }
    degraded = any(degradation.values())
    seeds = [int(s) for s in seeds]
    if any(s < 0 for s in seeds):
        raise InputError(f"seeds must be >= 0, got {seeds}")
    if degraded and not seeds:
        raise InputError("no seeds for the degradation: give at least one")
    if not degraded and not last_bit_draws:
        raise InputError(
            "nothing to vary: give a range noise, a share of scans to drop, clutter or "
            "last-bit draws"
        )
    name = os.fspath(log)
    if relations is None:
        if name not in DATASETS:
            raise InputError(
                f"{name}: which relations? Give its .relations file (--relations FILE) or a "
                "dataset name"
            )
        relations = name
    rel = read_relations(find_dataset(relations, "relations"))
    data = load_log(log)  # a bad log is an error before any worker starts
    variants = [(s, b) for s in (seeds if degraded else [-1]) for b in range(last_bit_draws + 1)]
    variants = [(-1, 0)] + [v for v in variants if v != (-1, 0)]
    jobs = [(m, s, b) for m in methods for s, b in variants]
    par = Parallel(n_jobs=n_jobs, return_as="generator")
    with _workers_deaf_to_ctrl_c():
        results = par(
            delayed(_one)(data, name, rel, m, params, degradation, s, b) for m, s, b in jobs
        )
    desc = f"SLAM on {os.path.basename(name) or name}"
    return list(tqdm(results, total=len(jobs), desc=desc, unit="run", disable=not progress))


def degradation_text(run: LogRun) -> str:
    """How ``run``'s log was changed, in words."""
    done = [f"{1000 * run.range_noise:g} mm of range noise"] if run.range_noise else []
    done += [f"{100 * run.drop_fraction:g} % of the scans dropped"] if run.drop_fraction else []
    done += [f"{100 * run.clutter_fraction:g} % clutter"] if run.clutter_fraction else []
    return ", ".join(done) or "as read"


def format_log_sweep(rows: Sequence[LogRun]) -> str:
    """Per method: the reference run, then the degraded runs' median and largest error and
    those beyond the robustness bound (:func:`beyond`), by seed (what ``fhslam sweep --log``
    prints)."""
    lines = []
    for method in dict.fromkeys(r.method for r in rows):
        sel = [r for r in rows if r.method == method]
        ref = next(r for r in sel if r.reference)
        others = [r for r in sel if not r.reference]
        label = f"{method} ({ref.settings})" if ref.settings else method
        lines.append(
            f"{ref.log}, {label}: as read {ref.trans_error:.4f} m, {ref.rot_error_deg:.2f} deg "
            f"({ref.n_relations} relations, {ref.seconds:.1f} s)"
        )
        if not others:
            continue
        e = np.array([r.trans_error for r in others])
        out = [r for r in others if beyond(r, ref)]
        seeds = sorted({r.degrade_seed for r in others})
        draws = sorted({r.last_bit for r in others})
        what = degradation_text(others[0])
        if seeds != [-1]:
            what += f", seeds {seeds[0]}-{seeds[-1]}" if len(seeds) > 1 else f", seed {seeds[0]}"
        if draws != [0]:
            what += f", last-bit draws {draws[0]}-{draws[-1]}"
        lines.append(
            f"  {what}: {len(others)} runs, median {np.median(e):.4f} m, max {e.max():.4f} m; "
            f"{len(out)} beyond {100 * RELATIVE_BOUND:g} % or {100 * ABSOLUTE_BOUND:g} cm of "
            "the run as read"
        )
        for r in out:
            tag = [f"seed {r.degrade_seed}"] if r.degrade_seed >= 0 else []
            tag += [f"last bit {r.last_bit}"] if r.last_bit else []
            lines.append(f"    {', '.join(tag)}: {r.trans_error:.4f} m")
    return "\n".join(lines)


def save_log_sweep(rows: Sequence[LogRun], path: str | os.PathLike[str]) -> None:
    """Write the runs as CSV, one :class:`LogRun` per row (columns :data:`LOG_FIELDS`)."""
    with atomic_output(path) as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(LOG_FIELDS)
        for r in rows:
            w.writerow([repr(v) if isinstance(v, float) else v for v in astuple(r)])
