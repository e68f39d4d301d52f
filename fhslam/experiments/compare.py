"""Monte-Carlo comparison of SLAM methods: the claims the paper makes without measuring them.

:func:`slam_sweep` runs every method on the same simulated logs (seeds × odometry-noise
levels; optionally degraded as real logs are, and each also with its odometry perturbed in
the last bit: the robustness checks) through :mod:`joblib`, so the same code runs on
the local cores or, through joblib's backends, on a Dask or Ray cluster; every run is
seeded, and the rows come back in a fixed order whatever the backend.
"""

from __future__ import annotations

import csv
import os
import signal
import threading
import time
import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import astuple, dataclass, fields, is_dataclass, replace
from pathlib import Path

import numpy as np
from joblib import Parallel, delayed
from numpy.typing import ArrayLike
from tqdm.auto import tqdm

from fhslam.errors import InputError, InputWarning
from fhslam.io.files import atomic_output
from fhslam.metrics import ate, map_error
from fhslam.pipeline import METHODS, run_slam
from fhslam.sim import (
    OdometryNoise,
    degrade,
    load_world,
    perturb_odometry,
    simulate,
    transform_world,
)
from fhslam.sim.degrade import check_degradation


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
    """One method on one simulated log.

    Five fields say how the log was changed before the run (all zero: not at all):
    :func:`fhslam.sim.degrade`'s ``range_noise``, ``drop_fraction`` and ``clutter_fraction``
    drawn with ``degrade_seed``, then :func:`fhslam.sim.perturb_odometry` with seed
    ``last_bit`` (0: the odometry as simulated); the last, ``settings``, which of the
    ``graph`` method's parameters differed from their defaults (:func:`settings_text`).
    """

    method: str
    level: str
    seed: int
    ate_rmse: float
    odometry_ate_rmse: float
    map_error: float
    ms_per_step: float
    n_map_lines: int
    range_noise: float = 0.0
    drop_fraction: float = 0.0
    clutter_fraction: float = 0.0
    degrade_seed: int = 0
    last_bit: int = 0
    settings: str = ""


def settings_text(params: object | None, prefix: str = "") -> str:
    """The fields of a parameter dataclass that differ from its defaults, as ``fhslam slam
    --set`` names them: ``"tracker.window=0.3 loops.target_keyframes=4"`` (a nested parameter
    dataclass, such as :class:`~fhslam.slam.GraphSlamParams`'s ``tracker``, field by field);
    empty for ``None`` or the defaults."""
    if params is None:
        return ""
    default = type(params)()
    out = []
    for f in fields(params):
        value, base = getattr(params, f.name), getattr(default, f.name)
        if value == base:
            continue
        if is_dataclass(value) and type(value) is type(base):
            out.append(settings_text(value, f"{prefix}{f.name}."))
        else:
            out.append(f"{prefix}{f.name}={value!r}")
    return " ".join(out)


def _thread_lock_for_tqdm() -> None:
    """Give tqdm a plain thread lock in a worker process that has none yet: its default
    lock is a multiprocessing one, a named semaphore that a worker killed after Ctrl-C never
    releases (Python then warns of "leaked semaphore objects" at exit)."""
    import threading

    from tqdm import tqdm as std_tqdm

    if not hasattr(std_tqdm, "_lock"):
        std_tqdm.set_lock(threading.RLock())


def one_run(
    world: str,
    level: str,
    seed: int,
    methods: Sequence[str],
    range_noise: float = 0.0,
    drop_fraction: float = 0.0,
    clutter_fraction: float = 0.0,
    degrade_seed: int = 0,
    last_bit: int = 0,
    params: object | None = None,
    frame: ArrayLike | None = None,
) -> list[RunResult]:
    """Simulate ``world`` with noise ``level`` and ``seed``; run every method on that log
    (the ``graph`` method with ``params``, default its defaults). With ``frame`` (a rigid
    motion ``(x, y, theta)``) the world is moved by it first (:func:`fhslam.sim.transform_world`:
    the same scans, the truth and odometry moved).

    The log is first degraded (:func:`fhslam.sim.degrade` with ``range_noise``,
    ``drop_fraction``, ``clutter_fraction`` and ``degrade_seed``) if any of those is not
    zero, then its odometry perturbed in the last bit (:func:`fhslam.sim.perturb_odometry`
    with seed ``last_bit``) if ``last_bit`` is not 0. The ATE is taken over the scans kept.
    """
    _thread_lock_for_tqdm()
    with warnings.catch_warnings():  # a world file's warnings: given once, before the sweep
        warnings.simplefilter("ignore", InputWarning)
        w = load_world(world)
    if frame is not None:
        w = transform_world(w, frame)
    log = simulate(w, seed=seed, odometry=noise_levels()[level])
    changed = {
        "range_noise": range_noise,
        "drop_fraction": drop_fraction,
        "clutter_fraction": clutter_fraction,
    }
    if any(changed.values()):
        log = degrade(log, seed=degrade_seed, **changed)
    if last_bit:
        log = perturb_odometry(log, last_bit)
    odo = ate(log.odometry, log.truth).rmse
    out = []
    for m in methods:
        t0 = time.perf_counter()
        r = run_slam(log, m, params if m == "graph" else None)
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
                **changed,
                degrade_seed=degrade_seed,
                last_bit=last_bit,
                settings=settings_text(params) if m == "graph" else "",
            )
        )
    return out


def check_runs(methods: Sequence[str], params: object | None, last_bit_draws: int) -> None:
    """What every sweep checks before its first run (:func:`slam_sweep`,
    :func:`fhslam.experiments.robustness.log_sweep`): known methods, ``params`` only with
    the graph method, ``last_bit_draws`` a whole number >= 0; ``ValueError`` otherwise."""
    unknown = set(methods) - set(METHODS)
    if unknown:
        raise ValueError(f"unknown SLAM methods {sorted(unknown)}; choose from {list(METHODS)}")
    if params is not None and "graph" not in methods:
        raise ValueError("params apply to the graph method only, which is not among the methods")
    if isinstance(last_bit_draws, bool) or not (
        isinstance(last_bit_draws, int | np.integer) and last_bit_draws >= 0
    ):
        raise ValueError(f"last_bit_draws must be a whole number >= 0, got {last_bit_draws!r}")


def slam_sweep(
    world: str = "paper",
    seeds: Sequence[int] = range(20),
    levels: Sequence[str] = ("low", "medium", "high"),
    methods: Sequence[str] = tuple(METHODS),
    n_jobs: int = -1,
    progress: bool = True,
    range_noise: float = 0.0,
    drop_fraction: float = 0.0,
    clutter_fraction: float = 0.0,
    degrade_seed: int = 0,
    last_bit_draws: int = 0,
    params: object | None = None,
) -> list[RunResult]:
    """Every method on ``len(seeds) × len(levels)`` simulated logs, in parallel via joblib.

    Parameters
    ----------
    range_noise, drop_fraction, clutter_fraction, degrade_seed
        Every log is degraded so (:func:`fhslam.sim.degrade`; all zero: not at all).
    last_bit_draws : int
        Each log is also run with its odometry perturbed in the last bit
        (:func:`fhslam.sim.perturb_odometry`, seeds ``1 .. last_bit_draws``): what the same
        code does on other CPUs. A result that changes much under it is not robust.
    params : GraphSlamParams, optional
        The ``graph`` method's parameters (default: its defaults).
    n_jobs : int
        joblib's worker count (-1: all cores). Use ``joblib.parallel_config(backend=...)``
        around the call to run on another backend (e.g. ``"dask"`` or ``"ray"``).

    Returns
    -------
    list of RunResult
        Ordered by level, seed, odometry draw (``last_bit``), method.

    Raises
    ------
    ValueError
        If a method is unknown, ``last_bit_draws`` is not a whole number >= 0 or the
        degradation is not one :func:`fhslam.sim.degrade` takes; before any run starts.
    """
    check_runs(methods, params, last_bit_draws)
    drop_fraction, clutter_fraction, degrade_seed, range_noise = check_degradation(
        drop_fraction, clutter_fraction, degrade_seed, range_noise
    )
    changed = {
        "range_noise": range_noise,
        "drop_fraction": drop_fraction,
        "clutter_fraction": clutter_fraction,
        "degrade_seed": degrade_seed,
    }
    jobs = [(lv, s, b) for lv in levels for s in seeds for b in range(last_bit_draws + 1)]
    par = Parallel(n_jobs=n_jobs, return_as="generator")
    with _workers_deaf_to_ctrl_c():  # the call starts the worker processes
        results = par(
            delayed(one_run)(world, lv, s, tuple(methods), **changed, last_bit=b, params=params)
            for lv, s, b in jobs
        )
    rows: list[RunResult] = []
    for batch in tqdm(
        results, total=len(jobs), desc="SLAM sweep", unit="log", disable=not progress
    ):
        rows.extend(batch)
    return rows


@contextmanager
def _workers_deaf_to_ctrl_c() -> Iterator[None]:
    """Block SIGINT in this thread while worker processes are started, so that they inherit
    the block and only this process answers Ctrl-C.

    A terminal sends Ctrl-C to its whole foreground process group, workers included, and a
    worker hit between two tasks prints a traceback of its own. Here the process that
    started the workers gets the Ctrl-C (a blocked signal stays pending and arrives as
    KeyboardInterrupt when the block ends) and joblib ends the workers. Threads started in
    the block (joblib's, loky's) inherit it too; Python runs signal handlers in the main
    thread whichever thread the signal is delivered to.

    The resource trackers are started first: Python's own (3.11-3.13) ends its start by
    unblocking SIGINT instead of restoring the mask it found.
    """
    if not hasattr(signal, "pthread_sigmask") or threading.current_thread() is not (
        threading.main_thread()
    ):
        yield
        return
    from multiprocessing import resource_tracker

    from joblib.externals.loky.backend import resource_tracker as loky_resource_tracker

    resource_tracker.ensure_running()
    loky_resource_tracker.ensure_running()
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


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


LAST_BIT_MOVE = 0.001
"""How far (metres of ATE) a log's runs may differ over last-bit draws before
:func:`last_bit_spread` counts the log as moved."""


@dataclass(frozen=True)
class LastBitSpread:
    """How much the last bit of the odometry moves one (level, method)'s ATE in a sweep
    (a result that changes under floating-point noise is not robust)."""

    largest: float
    """The largest difference (m) between two runs of one log that differ only in the
    odometry's last bit."""
    seed: int
    """The seed of the log with the largest difference."""
    moved: int
    """How many logs' runs differ by more than :data:`LAST_BIT_MOVE`."""
    logs: int
    """How many logs were drawn more than once."""


def last_bit_spread(rows: Sequence[RunResult]) -> dict[tuple[str, str], LastBitSpread]:
    """Per (level, method), how far the ATE of one log moves over its last-bit draws
    (``last_bit_draws``): the runs of one log share the level, method, seed and
    degradation and differ only in ``last_bit``. Levels and methods whose logs were run
    once each are left out."""
    groups: dict[tuple, list[float]] = {}
    for r in rows:
        log = (r.level, r.method, r.seed, r.range_noise, r.drop_fraction,
               r.clutter_fraction, r.degrade_seed, r.settings)  # fmt: skip
        groups.setdefault(log, []).append(r.ate_rmse)
    out: dict[tuple[str, str], LastBitSpread] = {}
    for key in sorted({k[:2] for k, v in groups.items() if len(v) > 1}):
        spread = [(max(v) - min(v), k[2]) for k, v in groups.items() if k[:2] == key and len(v) > 1]
        largest, seed = max(spread, key=lambda x: (x[0], -x[1]))
        moved = sum(d > LAST_BIT_MOVE for d, _ in spread)
        out[key] = LastBitSpread(float(largest), int(seed), moved, len(spread))
    return out


LABELS = {
    "fht": "FH-SLAM (paper)",
    "graph": "FH-SLAM graph",
    "classical": "FH-SLAM + classical Hough",
    "ekf": "EKF line SLAM",
    "odometry": "odometry",
}
"""How tables and figures name the methods."""

FIELDS = tuple(f.name for f in fields(RunResult))
"""The columns of a sweep file, in order: one :class:`RunResult` per row."""


def format_summary(rows: Sequence[RunResult]) -> str:
    """The medians of a sweep per level and method, as a table (what ``fhslam sweep`` prints)."""
    s = summary(rows)
    levels = [lv for lv in ("low", "medium", "high") if any(k[0] == lv for k in s)]
    levels += sorted({k[0] for k in s} - set(levels))
    methods = [m for m in LABELS if any(k[1] == m for k in s)]
    seeds = len({r.seed for r in rows})
    head = f"{len(rows)} runs: {seeds} seeds x {len(levels)} levels x {len(methods)} methods"
    draws = len({r.last_bit for r in rows})
    if draws > 1:
        head += f" x {draws} odometry draws (last bit)"
    changed = sorted(
        {(r.range_noise, r.drop_fraction, r.clutter_fraction, r.degrade_seed) for r in rows}
    )
    for noise, drop, clutter, dseed in changed:
        done = [f"{1000 * noise:g} mm range noise"] if noise else []
        done += [f"{100 * drop:g} % of the scans dropped"] if drop else []
        done += [f"{100 * clutter:g} % clutter"] if clutter else []
        if done:
            head += f"; logs with {', '.join(done)} (seed {dseed})"
    lines = [
        head,
        f"{'level':7} {'method':26} {'ATE median':>11} {'ATE max':>9} {'map err med':>12} "
        f"{'ms/step':>8}",
    ]
    for lv in levels:
        for m in methods:
            if (lv, m) not in s:
                continue
            v = s[(lv, m)]
            me = v["map_error_median"]
            me_s = "" if np.isnan(me) else f"{100 * me:9.1f} cm"
            lines.append(
                f"{lv:7} {LABELS[m]:26} {v['ate_median']:9.3f} m {v['ate_max']:7.3f} m "
                f"{me_s:>12} {v['ms_per_step_median']:8.2f}"
            )
    spread = last_bit_spread(rows)
    for lv, m in [(lv, m) for lv in levels for m in methods if (lv, m) in spread]:
        b = spread[(lv, m)]
        lines.append(
            f"last bit, {lv} {LABELS[m]}: one log's ATE moves by up to {100 * b.largest:.2f} cm "
            f"(seed {b.seed}); {b.moved} of {b.logs} logs by more than "
            f"{1000 * LAST_BIT_MOVE:g} mm"
        )
    return "\n".join(lines)


def save_sweep(rows: Sequence[RunResult], path: str | os.PathLike[str]) -> None:
    """Write a sweep as CSV, one :class:`RunResult` per row (columns :data:`FIELDS`), so that
    a notebook can show the full sweep without running it (``fhslam sweep --out``)."""
    with atomic_output(path) as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(FIELDS)
        for r in rows:
            w.writerow([repr(v) if isinstance(v, float) else v for v in astuple(r)])


def load_sweep(path: str | os.PathLike[str]) -> list[RunResult]:
    """Read a sweep written by :func:`save_sweep`.

    Raises
    ------
    InputError
        If the file is missing or not a sweep file: a wrong header, a row with another number
        of fields, an unknown method or level, a number that is not one; naming file and line.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(
            f"{p}: no such sweep file; write it with: fhslam sweep --out {p}"
        ) from None
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(f"{p}: cannot read ({e})") from None
    reader = csv.reader(text.splitlines())
    header = next(reader, None)
    # files written before the sweep could degrade its logs have the first eight columns,
    # before it recorded the graph method's settings the first thirteen
    names = tuple(header or ())
    if names not in (FIELDS, FIELDS[:13], FIELDS[:8]):
        raise InputError(f"{p}:1: not a sweep file (expected the header {','.join(FIELDS)})")
    types = [f.type for f in fields(RunResult)]
    rows = []
    for line, values in enumerate(reader, start=2):
        if not values:
            continue
        if len(values) != len(names):
            raise InputError(f"{p}:{line}: {len(values)} fields, expected {len(names)}")
        try:
            kw = {
                name: (int(v) if t in ("int", int) else float(v) if t in ("float", float) else v)
                for name, t, v in zip(names, types, values, strict=False)
            }
        except ValueError as e:
            raise InputError(f"{p}:{line}: not a number ({e})") from None
        if kw["method"] not in METHODS:
            raise InputError(f"{p}:{line}: unknown method {kw['method']!r}")
        if kw["level"] not in noise_levels():
            raise InputError(f"{p}:{line}: unknown noise level {kw['level']!r}")
        r = RunResult(**kw)
        try:
            check_degradation(r.drop_fraction, r.clutter_fraction, r.degrade_seed, r.range_noise)
            if r.last_bit < 0:
                raise ValueError(f"last_bit must be >= 0, got {r.last_bit}")
        except ValueError as e:
            raise InputError(
                f"{p}:{line}: not a degradation fhslam.sim.degrade makes ({e})"
            ) from None
        rows.append(r)
    if not rows:
        raise InputError(f"{p}: no runs in this sweep file")
    return rows
