"""``fhslam benchmark --out notebooks/results/``: every measurement of notebook 09 and the
README's results table, remade by one call of :func:`run_benchmark`.

On each benchmark log (:data:`BENCHMARK_LOGS`) the default SLAM (``graph``), the paper's
procedure (``fht``) and odometry run one after the other in this process, each timed alone
and measured as ``fhslam evaluate TRAJ --relations NAME`` measures the trajectory file that
``fhslam slam --trajectory`` writes (:func:`measure_run`). Then, in parallel, the default runs
over :class:`Draws`: logs degraded by range noise or dropped scans or with their odometry
perturbed in the last bit (the runs of ``fhslam sweep --log``), a simulated world likewise
(``fhslam sweep --world``), and every method on a sparse copy of each log (one scan per metre
or half radian, :func:`fhslam.sim.sparsify`). The files written into ``out``:

- ``benchmark.csv``: one :class:`BenchmarkRow` per log and method, the published numbers
  (:data:`PUBLISHED`) as rows of the method ``cartographer``;
- ``table.md``: the README's results table of those rows (:func:`results_table`);
- ``robustness.csv``: one :class:`DrawRow` per run over draws, for box plots, and per sparse
  copy and method;
- per log and SLAM method its trajectory ``{log}_{method}.txt`` and map
  ``{log}_{method}_map.json``, for ``graph`` its keyframe graph ``{log}_graph_graph.json``:
  byte for byte what ``fhslam slam LOG --method M --trajectory ... --map ... --graph ...``
  writes (notebook 08 loads Intel's and MIT CSAIL's).

A call that runs some logs or methods keeps the other rows of an ``out`` that has them.
Bad input (an unknown log, an ``out`` that is a file, a damaged results file there) is
refused before any run; the files appear together once every run is done, or none does.
"""

from __future__ import annotations

import csv
import math
import os
import tempfile
import time
import warnings
from collections.abc import Iterable, Sequence
from dataclasses import astuple, dataclass, fields, replace
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from fhslam.datasets import DATASETS, find_dataset, load_log
from fhslam.errors import InputError, MissingInputError
from fhslam.io import Log, write_graph, write_map, write_trajectory
from fhslam.io.files import atomic_output, output_batch, output_folder, reading

BENCHMARK_LOGS = ("intel", "aces", "mit-csail", "fr079", "fr-clinic", "fr101", "mit-killian-full")
"""The logs :func:`run_benchmark` runs by default, in the table's order: the five logs of the
Freiburg SLAM benchmark with published results, then two scored against pseudo ground truth
(:data:`PSEUDO_TRUTH`)."""

PSEUDO_TRUTH = frozenset({"fr101", "mit-killian-full"})
"""Logs whose relations come from a corrected log, not the benchmark's checked reference
(:mod:`fhslam.datasets`): their errors have a floor of a few centimetres."""

METHODS = ("graph", "fht", "odometry")
"""The methods run on every log: the default, the paper's procedure, dead reckoning."""

LABELS = dict(zip(BENCHMARK_LOGS, ("Intel", "ACES", "MIT CSAIL", "Freiburg 079",
    "Freiburg hospital", "Freiburg 101", "MIT Killian Court"), strict=True))  # fmt: skip
"""How tables and figures name the logs."""


@dataclass(frozen=True)
class Published:
    """A published result on one log: the mean translational relation error (metres) and,
    where reported, the wall time of the run (seconds); ``source`` names the paper."""

    error_m: float
    seconds: float = math.nan
    source: str = "Hess et al. 2016"


PUBLISHED = {
    "intel": Published(0.0229, 179.0),
    "aces": Published(0.0375),
    "mit-csail": Published(0.0319),
    "fr079": Published(0.0452),
    "fr-clinic": Published(0.1071),
}
"""Cartographer's mean translational relation errors (W. Hess, D. Kohler, H. Rapp, D. Andor,
"Real-time loop closure in 2D LIDAR SLAM", ICRA 2016, Table II) and its wall time on Intel,
as reported: other machines, another implementation."""

PUBLISHED_METHOD = "cartographer"
"""The method name of :data:`PUBLISHED`'s rows in ``benchmark.csv``."""


DRAW_KINDS = (
    "range noise",
    "dropped",
    "last bit",
    "world",
    "world range noise",
    "world dropped",
    "world last bit",
    "frame",
)
"""What each stream of :meth:`Draws.seeds_of` draws seeds for (its index: the stream)."""


def fresh_seed() -> int:
    """A seed for :class:`Draws` nobody picked: drawn from the operating system's entropy."""
    return int(np.random.SeedSequence().generate_state(1, np.uint32)[0])


@dataclass(frozen=True)
class Draws:
    """The runs over draws of :func:`run_benchmark`, all of the default SLAM; their seeds
    come from ``seed`` (:meth:`seeds_of`).

    On each log of ``logs``: ``seeds`` copies with ``range_noise`` metres of Gaussian noise on
    every range, ``seeds`` copies with a ``drop_fraction`` share of the scans dropped
    (:func:`fhslam.sim.degrade`), and ``last_bit_draws`` runs of the log as read with its
    odometry perturbed in the last bit (:func:`fhslam.sim.perturb_odometry`: what another CPU
    may do). On each world of ``worlds``: ``world_seeds`` simulated logs at the odometry noise
    ``world_level``, each run in ``frames`` frames (as given, then moved by a random rigid
    motion: the method must not care where the world frame lies), and once each with the
    range noise, with the dropped scans and (``last_bit_draws`` > 0) with a last-bit
    perturbation. On each log of ``sparse_logs``: every method of :data:`METHODS` on its
    sparse copy (:func:`fhslam.experiments.draw_runs.sparse_error`).

    The default matrix is hundreds of whole-log runs (an hour or more on 2 cores): ``fhslam
    benchmark --jobs`` or ``--scheduler`` spreads them.

    ``seed`` None (the default) draws a fresh one (:func:`fresh_seed`) when the runs start:
    results are judged by draws nobody picked. The seed of every run is in its
    :class:`DrawRow`, so any one run can be repeated alone, and ``Draws(seed=S)`` repeats
    them all.
    """

    logs: tuple[str, ...] = BENCHMARK_LOGS
    seeds: int = 8
    range_noise: float = 0.001
    drop_fraction: float = 0.1
    last_bit_draws: int = 8
    worlds: tuple[str, ...] = ("paper",)
    world_seeds: int = 8
    world_level: str = "medium"
    frames: int = 4
    sparse_logs: tuple[str, ...] = BENCHMARK_LOGS
    seed: int | None = None

    def __post_init__(self) -> None:
        from fhslam.experiments.compare import noise_levels
        from fhslam.sim.degrade import check_degradation

        for name in ("seeds", "last_bit_draws", "world_seeds", "frames"):
            n = getattr(self, name)
            if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 0:
                raise ValueError(f"Draws.{name} must be a whole number >= 0, got {n!r}")
        if self.frames < 1 and self.world_seeds and self.worlds:
            raise ValueError("Draws.frames must be at least 1 (the world as given)")
        if self.seed is not None and (
            isinstance(self.seed, bool)
            or not isinstance(self.seed, int | np.integer)
            or self.seed < 0
        ):
            raise ValueError(f"Draws.seed must be a whole number >= 0 or None, got {self.seed!r}")
        check_degradation(self.drop_fraction, 0.0, 0, self.range_noise)
        if self.world_level not in noise_levels():
            raise ValueError(
                f"Draws.world_level must be one of {list(noise_levels())}, got {self.world_level!r}"
            )
        object.__setattr__(self, "logs", tuple(self.logs))
        object.__setattr__(self, "worlds", tuple(self.worlds))
        object.__setattr__(self, "sparse_logs", tuple(self.sparse_logs))

    def seeded(self) -> Draws:
        """These draws with a seed: their own, or a fresh one."""
        return self if self.seed is not None else replace(self, seed=fresh_seed())

    def seeds_of(self, kind: str, n: int) -> list[int]:
        """``n`` seeds (1 .. 2³¹ - 1; 0 means "none" to a last-bit draw) of the stream
        ``kind`` (one of :data:`DRAW_KINDS`), drawn from :attr:`seed` (which must be set:
        :meth:`seeded`). The streams are independent, and the first ``n`` of a stream do not
        depend on ``n``."""
        if self.seed is None:
            raise ValueError("Draws.seed is None: call Draws.seeded() first")
        if kind not in DRAW_KINDS:
            raise ValueError(f"unknown kind of draw {kind!r}; one of {list(DRAW_KINDS)}")
        state = np.random.SeedSequence([int(self.seed), DRAW_KINDS.index(kind)])
        return [int(v) % (2**31 - 1) + 1 for v in state.generate_state(n, np.uint32)]

    def motions(self) -> list[tuple[float, float, float]]:
        """The frames' rigid motions ``(x, y, theta)``: none first, then ``frames - 1``
        drawn from :attr:`seed` (x and y uniform in ± 10 m, theta in ± 180°)."""
        rng = np.random.default_rng(self.seeds_of("frame", 1)[0])
        moves = [(0.0, 0.0, 0.0)]
        for _ in range(self.frames - 1):
            x, y = rng.uniform(-10.0, 10.0, 2)
            moves.append((float(x), float(y), float(rng.uniform(-np.pi, np.pi))))
        return moves


DRAWS = Draws()
"""The draws of a default :func:`run_benchmark`."""

QUICK_LOGS = ("mit-csail",)
"""The logs of ``run_benchmark(..., quick=True)``: the shortest benchmark log (7 minutes of
log, seconds to run)."""

QUICK_DRAWS = Draws(logs=(), seeds=0, last_bit_draws=1, world_seeds=1, frames=2, sparse_logs=())
"""The draws of ``run_benchmark(..., quick=True)``: one paper-world log in two frames, with
range noise, with dropped scans and with a last-bit perturbation (seconds)."""


# ------------------------------------------------------------------------------ rows


@dataclass(frozen=True)
class BenchmarkRow:
    """One method on one log (a row of ``benchmark.csv``); NaN or -1 where not known (a
    published row has its error, and for Intel its wall time, only)."""

    log: str
    method: str
    error_m: float
    """Mean translational relation error, metres (``fhslam evaluate --relations``)."""
    error_std_m: float = math.nan
    """Its standard deviation over the relations, metres."""
    rot_error_deg: float = math.nan
    """Mean rotational relation error, degrees."""
    relations_used: int = -1
    relations_total: int = -1
    n_scans: int = -1
    duration_s: float = math.nan
    """The log's time span, seconds."""
    seconds: float = math.nan
    """The run time: wall time of the run alone (every step and the end, not reading the
    log), seconds; longer where other jobs keep the machine busy (``cpu_load``)."""
    cpu_seconds: float = math.nan
    """The processor time of the same run (all threads of the process), seconds: hardly
    moved by other jobs; above ``seconds`` where the default's back end ran on a second core
    beside its front end, below it on a busy machine."""
    real_time_factor: float = math.nan
    """``duration_s / seconds``: how many times faster than the robot recorded the log the
    run is done."""
    reference: str = "benchmark"
    """``"benchmark"``: the benchmark's relations; ``"pseudo ground truth"``
    (:data:`PSEUDO_TRUTH`)."""
    source: str = "fhslam"
    """``"fhslam"`` for a run here, else the publication (:data:`PUBLISHED`)."""
    cpu_load: float = math.nan
    """The machine's load average over the minute before the run (``os.getloadavg``): a
    busy machine makes ``seconds`` longer."""


BENCHMARK_FIELDS = tuple(f.name for f in fields(BenchmarkRow))
"""The columns of ``benchmark.csv``, in order."""


@dataclass(frozen=True)
class DrawRow:
    """One run of the default SLAM over draws (a row of ``robustness.csv``).

    ``kind`` is ``"log"`` (``error_m``: the mean translational relation error), ``"world"``
    (``error_m``: the ATE RMSE against the simulated truth, at odometry noise ``level``,
    simulated with ``seed``) or ``"sparse"`` (a log's sparse copy, any ``method``:
    . ``degrade_seed`` is -1 for a log as read or a world
    as simulated; ``last_bit`` 0 for the odometry as read. ``variant`` says it in words.
    """

    kind: str
    name: str
    method: str
    variant: str
    level: str
    seed: int
    range_noise: float
    drop_fraction: float
    degrade_seed: int
    last_bit: int
    error_m: float


DRAW_FIELDS = tuple(f.name for f in fields(DrawRow))
"""The columns of ``robustness.csv``, in order."""


# ------------------------------------------------------------------------------ files


def _write_rows(path: Path, header: Sequence[str], rows: Iterable[object]) -> None:
    with atomic_output(path) as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        for r in rows:
            w.writerow(["" if isinstance(v, float) and math.isnan(v) else
                        repr(v) if isinstance(v, float) else v for v in astuple(r)])  # fmt: skip


def _read_rows(path: Path, cls: type, what: str) -> list:
    """The rows of a CSV file of ``cls`` (empty floats read as NaN); an InputError naming
    file and line for anything else."""
    if not path.exists():
        raise MissingInputError(
            f"{path}: no such {what} file; write it with: fhslam benchmark --out "
            f"{path.parent}{os.sep}",
            str(path),
        )
    with reading(path):
        text = path.read_text(encoding="utf-8")
    names = tuple(f.name for f in fields(cls))
    types = [f.type for f in fields(cls)]
    reader = csv.reader(text.splitlines())
    if tuple(next(reader, ())) != names:
        raise InputError(f"{path}:1: not a {what} file (expected the header {','.join(names)})")
    rows = []
    for line, values in enumerate(reader, start=2):
        if len(values) != len(names):
            raise InputError(f"{path}:{line}: {len(values)} fields, expected {len(names)}")
        try:
            kw = {
                n: int(v) if t in ("int", int) else
                (float(v) if v else math.nan) if t in ("float", float) else v
                for n, t, v in zip(names, types, values, strict=True)
            }  # fmt: skip
        except ValueError as e:
            raise InputError(f"{path}:{line}: not a number ({e})") from None
        rows.append(cls(**kw))
    return rows


def load_benchmark(path: str | os.PathLike[str]) -> list[BenchmarkRow]:
    """The rows of a ``benchmark.csv`` that :func:`run_benchmark` wrote.

    Raises
    ------
    InputError
        For a missing or unreadable file, or one that is not such a file (naming the line).
    """
    return _read_rows(Path(path), BenchmarkRow, "benchmark")


def load_draws(path: str | os.PathLike[str]) -> list[DrawRow]:
    """The rows of a ``robustness.csv`` that :func:`run_benchmark` wrote (raises as
    :func:`load_benchmark`)."""
    return _read_rows(Path(path), DrawRow, "robustness")


# ------------------------------------------------------------------------------ the table


def _sig3(x: float) -> str:
    """Three significant digits, trailing zeros kept: 0.0140, 0.127, 1.23."""
    return f"{x:#.3g}".rstrip(".")


def results_table(rows: Sequence[BenchmarkRow]) -> str:
    """The README's results table (Markdown) of ``rows``: per log (in the rows' order), the
    mean translational relation error of ``graph`` (three significant digits), ``fht`` and
    ``odometry`` (to the centimetre), Cartographer's as published, and how many times faster than
    real time ``graph`` ran; the smallest error of a row in bold, a dash where a number is
    missing. Logs scored against pseudo ground truth say so."""
    by = {(r.log, r.method): r for r in rows}
    logs = list(dict.fromkeys(r.log for r in rows))
    out = [
        "| log | default (`graph`) | paper (`fht`) | odometry | Cartographer (Hess et al. 2016) "
        "| run, × real time |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    columns = (
        ("graph", _sig3),
        ("fht", lambda x: f"{x:.2f}"),
        ("odometry", lambda x: f"{x:.2f}"),
        (PUBLISHED_METHOD, lambda x: f"{x:.4f}"),
    )
    for log in logs:
        errors = {m: by[(log, m)].error_m for m, _ in columns if (log, m) in by}
        errors = {m: e for m, e in errors.items() if not math.isnan(e)}
        best = min(errors.values(), default=math.nan)
        cells = []
        for m, fmt in columns:
            if m not in errors:
                cells.append("–")
                continue
            text = f"{fmt(errors[m])} m"
            cells.append(f"**{text}**" if errors[m] == best else text)
        run = by.get((log, "graph"))
        rtf = run.real_time_factor if run is not None else math.nan
        cells.append("–" if math.isnan(rtf) else f"{rtf:.0f}×")
        label = LABELS.get(log, log)
        if any(r.log == log and r.reference == "pseudo ground truth" for r in rows):
            label += " (pseudo ground truth)"
        out.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(out) + "\n"


# ------------------------------------------------------------------------------ runs


def _check_logs(logs: Sequence[str], what: str) -> tuple[str, ...]:
    """``logs`` without repeats, each the name of a dataset with a log and relations (an
    :class:`InputError` naming the first that is not)."""
    if isinstance(logs, str):
        raise InputError(f"{what}: give a sequence of log names, not the string {logs!r}")
    names = tuple(dict.fromkeys(logs))
    for name in names:
        ds = DATASETS.get(name) if isinstance(name, str) else None
        if ds is None or ds.log is None:
            known = ", ".join(n for n, d in DATASETS.items() if d.log is not None)
            raise InputError(f"{what}: unknown benchmark log {name!r}; choose from {known}")
    return names


def _warm_up(log: Log, method: str) -> None:
    """A short untimed run: JIT compilation and caches are not what is timed."""
    from fhslam.experiments.bench import log_head
    from fhslam.pipeline import make_backend, run_backend

    run_backend(make_backend(method), log_head(log, 20))


def measure_run(
    log: Log,
    name: str,
    method: str,
    folder: str | os.PathLike[str] | None = None,
    progress: bool = False,
) -> BenchmarkRow:
    """Run ``method`` over ``log`` (the dataset ``name``) once, timed alone, and measure it.

    The trajectory is written to ``{folder}/{name}_{method}.txt`` as ``fhslam slam
    --trajectory`` writes it and measured from that file by
    :func:`fhslam.evaluate.evaluate_relations` against the dataset's relations, as ``fhslam
    evaluate`` does; for ``graph`` and ``fht`` the map goes to ``{name}_{method}_map.json``
    and for ``graph`` the keyframe graph to ``{name}_graph_graph.json``. Without ``folder``,
    a temporary one is used and removed. ``progress`` shows a progress bar of the run.
    """
    from fhslam.evaluate import evaluate_relations
    from fhslam.pipeline import keyframe_graph, make_backend, run_backend

    if folder is None:
        with tempfile.TemporaryDirectory(prefix="fhslam-benchmark-") as tmp:
            return measure_run(log, name, method, tmp, progress)
    d = Path(folder)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else math.nan
    backend = make_backend(method)
    t0, c0 = time.perf_counter(), time.process_time()
    result = run_backend(backend, log, progress=progress, desc=f"{method} {name}")
    seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    trajectory = d / f"{name}_{method}.txt"
    header = f"fhslam slam --method {method} {name}: timestamp x y theta"  # as fhslam slam's
    write_trajectory(trajectory, result.timestamps, result.poses, header=header)
    if method != "odometry":
        write_map(d / f"{name}_{method}_map.json", result.map)
    if method == "graph":
        write_graph(d / f"{name}_graph_graph.json", keyframe_graph(backend, log))
    e = evaluate_relations(trajectory, name).error
    duration = float(log.timestamps[-1] - log.timestamps[0])
    reference = "pseudo ground truth" if name in PSEUDO_TRUTH else "benchmark"
    return BenchmarkRow(
        name, method, e.trans_mean, e.trans_std, e.rot_mean_deg, e.n_used, e.n_total, len(log),
        duration, seconds, cpu, duration / seconds, reference, "fhslam", load,
    )  # fmt: skip


def _published_rows(logs: Iterable[str]) -> list[BenchmarkRow]:
    return [
        BenchmarkRow(log, PUBLISHED_METHOD, p.error_m, seconds=p.seconds, source=p.source)
        for log in logs
        if (p := PUBLISHED.get(log)) is not None
    ]


def run_benchmark(
    out: str | os.PathLike[str],
    *,
    logs: Sequence[str] | None = None,
    methods: Sequence[str] = METHODS,
    draws: Draws | None = DRAWS,
    quick: bool = False,
    n_jobs: int = -1,
    progress: bool = True,
) -> list[BenchmarkRow]:
    """Run and measure every benchmark log, and write the results into the folder ``out``
    (see the module docs for the files).

    Parameters
    ----------
    out : path-like
        The results folder (``notebooks/results``), created if missing.
    logs : sequence of str, optional
        Dataset names (default :data:`BENCHMARK_LOGS`; with ``quick``, :data:`QUICK_LOGS`).
    methods : sequence of str
        SLAM methods (:data:`fhslam.pipeline.METHODS`) run on each log, one at a time.
    draws : Draws or None
        The runs over draws (default :data:`DRAWS`; with ``quick``, :data:`QUICK_DRAWS`),
        with fresh seeds unless ``draws.seed`` is given (the rows hold every run's seed);
        ``None``: none, and an existing ``robustness.csv`` is left as it is.
    quick : bool
        A small subset (minutes, against an hour or more on 2 cores): the logs and draws not given
        default to :data:`QUICK_LOGS` and :data:`QUICK_DRAWS`.
    n_jobs : int
        Worker processes for the draws (joblib; -1: one per core). The runs of ``methods``
        on ``logs`` are timed one at a time in this process.
    progress : bool
        Progress bars (tqdm).

    Returns
    -------
    list of BenchmarkRow
        The rows of ``benchmark.csv`` as written (the rows of runs not made kept from it).

    Raises
    ------
    InputError
        Before any run: a log that is not a dataset with a log and relations, or whose files
        are not found; ``out`` a file or not writable; a damaged results file in ``out``.
    ValueError
        For an unknown method, before any run.
    """
    from fhslam.experiments.compare import check_runs

    if logs is None:
        logs = QUICK_LOGS if quick else BENCHMARK_LOGS
    if quick and draws is DRAWS:
        draws = QUICK_DRAWS
    names = _check_logs(logs, "logs")
    if not names:
        raise InputError("logs: no benchmark log given")
    if not methods:
        raise ValueError("methods: no SLAM method given")
    check_runs(methods, None, 0)
    draw_logs = (
        _check_logs(draws.logs, "draws.logs") + _check_logs(draws.sparse_logs, "draws.sparse_logs")
        if draws is not None
        else ()
    )
    draws = None if draws is None else draws.seeded()
    with output_folder(out, str(out)) as folder:
        for name in dict.fromkeys(names + draw_logs):  # a DatasetNotFoundError if missing
            find_dataset(name, "log")
            find_dataset(name, "relations")
        csv_path, draws_path = folder / "benchmark.csv", folder / "robustness.csv"
        kept = load_benchmark(csv_path) if csv_path.exists() else []
        kept_draws = load_draws(draws_path) if draws_path.exists() else []
        with warnings.catch_warnings():  # a log's warnings once, not once per run and worker
            warnings.simplefilter("once")
            loaded = {}
            for name in tqdm(names, desc="reading logs", unit="log", disable=not progress):
                loaded[name] = load_log(name)
            for name in draw_logs:
                if name not in loaded:
                    loaded[name] = load_log(name)
        rows: list[BenchmarkRow] = []
        with tempfile.TemporaryDirectory(prefix="fhslam-benchmark-") as tmp:
            jobs = [(n, m) for n in names for m in methods]
            total = sum(len(loaded[n]) for n, _ in jobs)
            warm = set()
            with tqdm(total=total, desc="benchmark", unit="scan", disable=not progress) as bar:
                for name, method in jobs:
                    bar.set_postfix_str(f"{name} {method}")
                    if method not in warm:
                        _warm_up(loaded[name], method)
                        warm.add(method)
                    rows.append(measure_run(loaded[name], name, method, tmp))
                    bar.update(len(loaded[name]))
            found = []
            if draws is not None:
                from fhslam.experiments.draw_runs import log_draws, sparse_draws, world_draws

                as_read = {r.log: r.error_m for r in rows if r.method == "graph"}
                found = log_draws(draws, loaded, as_read, n_jobs, progress)
                found += world_draws(draws, n_jobs, progress)
                found += sparse_draws(draws, loaded, n_jobs, progress)
            # every file of the runs but the odometry's trajectory (made again in a moment)
            staged = [p for p in sorted(Path(tmp).iterdir()) if "_odometry" not in p.name]
            all_rows = _merged(kept, rows)
            with output_batch():
                for p in staged:
                    with atomic_output(folder / p.name, "wb") as f:
                        f.write(p.read_bytes())
                _write_rows(csv_path, BENCHMARK_FIELDS, all_rows)
                with atomic_output(folder / "table.md") as f:
                    f.write(results_table(all_rows))
                if draws is not None:
                    redone = {("log", n) for n in draws.logs} | {("world", w) for w in draws.worlds}
                    redone |= {("sparse", n) for n in draws.sparse_logs}
                    left = [r for r in kept_draws if (r.kind, r.name) not in redone]
                    _write_rows(draws_path, DRAW_FIELDS, left + found)
    return all_rows


def _merged(kept: Sequence[BenchmarkRow], new: Sequence[BenchmarkRow]) -> list[BenchmarkRow]:
    """The ``new`` rows, the ``kept`` rows of other (log, method) pairs and the published
    rows of every log among them, ordered by log (:data:`BENCHMARK_LOGS` first) and method
    (:data:`METHODS`, then Cartographer, then others)."""
    done = {(r.log, r.method) for r in new}
    rows = [r for r in kept if (r.log, r.method) not in done] + list(new)
    rows = [r for r in rows if r.method != PUBLISHED_METHOD]
    rows += _published_rows(dict.fromkeys(r.log for r in rows))
    log_order = {n: i for i, n in enumerate(BENCHMARK_LOGS)}
    method_order = {m: i for i, m in enumerate((*METHODS, PUBLISHED_METHOD))}
    return sorted(rows, key=lambda r: (log_order.get(r.log, 99), r.log,
                                       method_order.get(r.method, 99), r.method))  # fmt: skip
