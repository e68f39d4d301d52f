"""``fhslam bench``: speed and accuracy of every line extractor on the same simulated scans,
and where a SLAM method's time goes on a real log.

Time is the median over ``repeats`` calls per scan, then the median over scans, measured in
one run with the extractors interleaved scan by scan (so machine load hits all alike). The
reference is the bare ``cv2.HoughLinesPointSet`` call with a 1 cm × 1° accumulator on the
same points — the classical Hough transform the paper claims to beat; the table gives each
extractor's time as a ratio to it. Accuracy is scored with :mod:`fhslam.metrics` against the
true walls. Scans come from held-out random worlds the extraction was not tuned on.

:func:`run_log_bench` (``fhslam bench --log LOG``) runs a SLAM method over a log and splits its
wall time into stages (extraction, tracking, loop closure, ...), measured by wrapping methods
of the back-end *instance* with a :class:`StageTimer` (the SLAM modules are not changed); the
per-scan times are again given as ratios to the same reference call, measured on the log's own
scans before and after the run, so they compare across machines.
"""

from __future__ import annotations

import functools
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import cv2
import numpy as np
from numpy.typing import NDArray
from tqdm.auto import tqdm

from fhslam.baselines import (
    hough_numpy_accumulator,
    hough_opencv_pointset,
    hough_opencv_probabilistic,
    hough_opencv_raster,
    split_and_merge,
)
from fhslam.extraction import extract_lines
from fhslam.io import Log
from fhslam.lines import Line
from fhslam.metrics import detection_scores
from fhslam.scan import scan_to_points
from fhslam.sim import load_world, simulate, true_lines

HELD_OUT_WORLDS = ("random:101", "random:102", "random:103", "random:104")
"""Worlds for evaluation; the extraction parameters were tuned on the paper world only."""

REFERENCE = "cv2.HoughLinesPointSet call"


def extractors() -> dict[str, Callable[[NDArray[np.float64]], list[Line]]]:
    """Every extractor, by display name; each maps points (N, 2) to a list of Line."""
    return {
        "fast Hough (fhslam)": extract_lines,
        "OpenCV HoughLinesPointSet": hough_opencv_pointset,
        "OpenCV HoughLines (raster)": hough_opencv_raster,
        "OpenCV HoughLinesP (raster)": hough_opencv_probabilistic,
        "NumPy full accumulator": hough_numpy_accumulator,
        "split-and-merge": split_and_merge,
    }


def cv2_pointset_call(points: NDArray[np.float64], max_range: float = 8.0) -> NDArray:
    """The bare classical Hough call: 1 cm × 1° accumulator over rho in ±max_range, 0-180°."""
    pts = points.astype(np.float32).reshape(-1, 1, 2)
    return cv2.HoughLinesPointSet(pts, 64, 6, -max_range, max_range, 0.01, 0.0, np.pi, np.pi / 180)


@dataclass(frozen=True)
class BenchRow:
    name: str
    ms_per_scan: float
    ratio_to_reference: float
    true_pos_rate: float
    false_pos_rate: float
    rms_drho_cm: float
    rms_dtheta_deg: float


def _median_time(f: Callable[[], object], repeats: int) -> float:
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts))


def run_bench(
    worlds: Sequence[str] = HELD_OUT_WORLDS,
    scans_per_world: int = 25,
    repeats: int = 9,
    seed: int = 0,
    progress: bool = True,
) -> list[BenchRow]:
    """Time and score every extractor on the same scans; the first row is the reference call."""
    fns = extractors()
    cases = []
    for name in worlds:
        log = simulate(load_world(name), seed=seed)
        for k in np.linspace(0, len(log) - 1, scans_per_world).astype(int):
            pts, beams = scan_to_points(log.ranges[k], log.angles, max_range=log.max_range)
            truth, rob = true_lines(log.hits[k], log.world.walls, log.truth[k])
            cases.append((pts, beams, truth, rob))
    for f in fns.values():  # warm-up: JIT compilation and caches are not what we measure
        f(cases[0][0])
    times: dict[str, list[float]] = {REFERENCE: [], **{n: [] for n in fns}}
    found: dict[str, list] = {n: [] for n in fns}
    for pts, beams, truth, rob in tqdm(cases, desc="bench", unit="scan", disable=not progress):
        times[REFERENCE].append(_median_time(lambda p=pts: cv2_pointset_call(p), repeats))
        for n, f in fns.items():
            times[n].append(_median_time(lambda p=pts, f=f: f(p), repeats))
            found[n].append((f(pts), beams, truth, rob))
    ref = float(np.median(times[REFERENCE]))
    rows = [BenchRow(REFERENCE, 1e3 * ref, 1.0, *([float("nan")] * 4))]
    for n in fns:
        s = detection_scores(found[n])
        t = float(np.median(times[n]))
        rows.append(
            BenchRow(
                n,
                1e3 * t,
                t / ref,
                s.true_pos_rate,
                s.false_pos_rate,
                100 * s.rms_drho,
                s.rms_dtheta_deg,
            )
        )
    return rows


@dataclass(frozen=True)
class SlamBenchRow:
    method: str
    steps_per_second: float
    seconds: float
    n_steps: int


def run_slam_bench(world: str = "paper", seed: int = 0, repeats: int = 3) -> list[SlamBenchRow]:
    """SLAM steps per second of FH-SLAM, FH-SLAM on a pose graph, FH-SLAM with the classical
    Hough extractor and the EKF baseline on one simulated run (median wall time over
    ``repeats`` runs, one process, after a warm-up run over its first scans)."""
    from fhslam.pipeline import run_slam

    log = simulate(load_world(world), seed=seed)
    rows = []
    for method in ("fht", "graph", "classical", "ekf"):
        run_slam(log_head(log, 20), method)  # warm-up (JIT, caches)
        t = _median_time(lambda m=method: run_slam(log, m), repeats)
        rows.append(SlamBenchRow(method, len(log) / t, t, len(log)))
    return rows


def format_slam_table(rows: Sequence[SlamBenchRow]) -> str:
    head = f"{'SLAM method':<14} {'steps/s':>10} {'s per run':>10} {'steps':>7}"
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r.method:<14} {r.steps_per_second:10.0f} {r.seconds:10.3f} {r.n_steps:7d}")
    return "\n".join(lines)


def format_table(rows: Sequence[BenchRow]) -> str:
    """The bench result as a plain-text table."""
    head = (
        f"{'extractor':<28} {'ms/scan':>8} {'time/ref':>9} {'TruePos':>8} {'FalsePos':>9} "
        f"{'rms dρ cm':>10} {'rms dθ °':>9}"
    )
    lines = [head, "-" * len(head)]
    for r in rows:
        acc = (
            ""
            if np.isnan(r.true_pos_rate)
            else f"{r.true_pos_rate:8.3f} {r.false_pos_rate:9.3f} {r.rms_drho_cm:10.2f} "
            f"{r.rms_dtheta_deg:9.2f}"
        )
        lines.append(f"{r.name:<28} {r.ms_per_scan:8.3f} {r.ratio_to_reference:9.2f} {acc}")
    return "\n".join(lines)


# ----------------------------------------------------------------------------- a real log


class StageTimer:
    """Wall seconds and calls per stage, accumulated by wrapping callables.

    :meth:`wrap` returns a callable that times each call of ``fn`` into ``seconds[stage]``
    and counts it in ``calls[stage]``; :meth:`patch` puts such a wrapper on one object's
    attribute (an instance attribute: the class and its other instances are untouched).

    Nested stages are subtracted: a stage's time is *exclusive*. While a wrapped call runs
    inside another wrapped call (``_optimize`` inside ``_close_loops``), its time counts to
    its own stage only and is taken off the enclosing one; so no second counts twice and the
    stages of the main thread add up to at most its wall time. Calls on other threads nest
    per thread, and their seconds are also kept in :attr:`off_main`: they overlap the main
    thread's.

    Examples
    --------
    >>> timer = StageTimer()
    >>> f = timer.wrap(sorted, "sorting")
    >>> f([3, 1, 2]), timer.calls["sorting"]
    ([1, 2, 3], 1)
    """

    def __init__(self, clock: Callable[[], float] = time.perf_counter) -> None:
        self.clock = clock
        """Seconds from an arbitrary origin (a fake clock makes a test exact)."""
        self.seconds: dict[str, float] = {}
        self.calls: dict[str, int] = {}
        self.off_main: dict[str, float] = {}
        """Of :attr:`seconds`, those spent on threads other than the main thread."""
        self._lock = threading.Lock()
        self._local = threading.local()

    @property
    def _open(self) -> list[float]:
        """This thread's open wrapped calls: per call, the seconds of wrapped calls inside."""
        return self._local.__dict__.setdefault("open", [])

    def wrap(self, fn: Callable, stage: str) -> Callable:
        """``fn``, timed into ``stage`` (see the class docs)."""
        self.seconds.setdefault(stage, 0.0)
        self.calls.setdefault(stage, 0)
        self.off_main.setdefault(stage, 0.0)

        @functools.wraps(fn)
        def timed(*args, **kwargs):
            open_calls = self._open
            open_calls.append(0.0)
            t0 = self.clock()
            try:
                return fn(*args, **kwargs)
            finally:
                dt = self.clock() - t0
                inner = open_calls.pop()
                with self._lock:
                    self.seconds[stage] += dt - inner
                    self.calls[stage] += 1
                    if threading.current_thread() is not threading.main_thread():
                        self.off_main[stage] += dt - inner
                if open_calls:
                    open_calls[-1] += dt

        return timed

    def patch(self, obj: object, name: str, stage: str) -> None:
        """Replace ``obj.name`` (on ``obj`` itself) by its timed wrapper."""
        setattr(obj, name, self.wrap(getattr(obj, name), stage))


STAGES: dict[str, tuple[str, ...]] = {
    "graph": (
        "extraction",
        "tracking",
        "local map",
        "loop closure",
        "optimisation",
        "waiting",
        "map",
    ),
    "fht": ("extraction", "association", "map"),
    "classical": ("extraction", "association", "map"),
}
"""The stages measured per SLAM method (every method also has ``"other"``: the rest of the wall
time). ``graph`` (:class:`fhslam.slam.GraphFastHoughSLAM`): *extraction* the keyframes' Loop 1
(the ``lines.extractor`` parameter), *tracking* scan-to-map matching (``tracker.track``),
*local map* rebuilding the tracker's grids at each keyframe (``_update_local_map``), *loop
closure* the search and verification of closures (``_close_loops`` less the optimisation it
calls), *optimisation* the pose-graph solves (``_optimize``), both on the back end's own thread
while the front end goes on (until the last keyframe), *waiting* the front end waiting for the
back end (``sync``, and ``_in_turn`` when the back end is behind; without a background thread
it adds the keyframes to the graph), *map* the map of reference lines at the end
(``build_map``); *other* holds the keyframe clouds (densify, normals, voxel filter),
pose arithmetic and the driver. ``fht`` and ``classical`` (:class:`fhslam.slam.FastHoughSLAM`):
*extraction* Loop 1 (``extract``), *association* Loop 2 (``map.nearby`` and ``map.associate``),
*map* merging into the reference lines (``map.update``); *other* is mostly the pose calibration
(Loop 3). ``ekf`` and ``odometry``: the total only."""


def instrumented_backend(method: str, timer: StageTimer):
    """A fresh back end for ``method`` with its stages (:data:`STAGES`) timed by ``timer``."""
    from fhslam.pipeline import make_backend
    from fhslam.slam import GraphFastHoughSLAM, SlamParams

    if method == "graph":
        paper = SlamParams()
        loop1 = functools.partial(extract_lines, params=paper.extraction)
        lines = replace(paper, extractor=timer.wrap(loop1, "extraction"))
        backend = GraphFastHoughSLAM(lines=lines)
        timer.patch(backend.tracker, "track", "tracking")
        timer.patch(backend, "_update_local_map", "local map")
        timer.patch(backend, "_close_loops", "loop closure")
        timer.patch(backend, "_optimize", "optimisation")
        timer.patch(backend, "_in_turn", "waiting")
        timer.patch(backend, "sync", "waiting")
        timer.patch(backend, "build_map", "map")
    elif method in ("fht", "classical"):
        backend = make_backend(method)
        timer.patch(backend, "extract", "extraction")
        timer.patch(backend.map, "nearby", "association")
        timer.patch(backend.map, "associate", "association")
        timer.patch(backend.map, "update", "map")
    else:
        backend = make_backend(method)
    return backend


def log_head(log: Log, n: int) -> Log:
    """The first ``n`` scans of ``log`` (all of them if it has fewer)."""
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n}")

    def cut(a):
        return None if a is None else a[:n]

    return replace(
        log,
        timestamps=log.timestamps[:n],
        ranges=log.ranges[:n],
        odometry=log.odometry[:n],
        truth=cut(log.truth),
        hits=cut(log.hits),
        angle_offsets=cut(log.angle_offsets),
    )


def _reference_samples(log: Log, n: int = 25) -> list[NDArray[np.float64]]:
    """The points of up to ``n`` scans spread over the log (dropped scans left out)."""
    samples = []
    for k in np.unique(np.linspace(0, len(log) - 1, n).astype(int)):
        pts = log.scan(int(k)).points()[0]
        if len(pts):
            samples.append(pts)
    return samples


def _reference_seconds(samples: Sequence[NDArray[np.float64]], calls: int = 5) -> float:
    """The reference call's time per scan: median over ``samples`` of the median of ``calls``."""
    if not samples:
        return float("nan")
    return float(
        np.median([_median_time(lambda p=p: cv2_pointset_call(p), calls) for p in samples])
    )


@dataclass(frozen=True)
class LogBench:
    """Where a SLAM method's time goes on one log (:func:`run_log_bench`).

    Attributes
    ----------
    log, method : str
    n_scans : int
    duration : float
        The log's time span from its timestamps, seconds.
    seconds : float
        Wall time of a run (``run_backend``: every step and ``finish``), seconds; the median
        over the repeats.
    stages : dict of str to float
        Exclusive wall seconds per stage (:data:`STAGES`, then ``"other"``: the rest of the
        run), each the median over the repeats (with one repeat, the main thread's add up to
        ``seconds``).
    parallel : dict of str to float
        Of ``stages``, the seconds spent on another thread (the graph's back end), which
        overlap the main thread's (median over the repeats).
    calls : dict of str to int
        Calls of each stage in one run.
    reference_seconds : float
        The reference call (:func:`cv2_pointset_call`) per scan on the log's scans: the mean
        of its time before and after the run (median over repeats).
    repeats : int
    """

    log: str
    method: str
    n_scans: int
    duration: float
    seconds: float
    stages: dict[str, float] = field(repr=False)
    calls: dict[str, int] = field(repr=False)
    reference_seconds: float
    repeats: int
    parallel: dict[str, float] = field(default_factory=dict, repr=False)

    @property
    def steps_per_second(self) -> float:
        """Scans per second of wall time."""
        return self.n_scans / self.seconds

    @property
    def real_time_factor(self) -> float:
        """The log's duration over the wall time (NaN for a log without a time span)."""
        return self.duration / self.seconds if self.duration > 0 else float("nan")

    def ms_per_scan(self, stage: str | None = None) -> float:
        """A stage's (``None``: the whole run's) milliseconds per scan."""
        s = self.seconds if stage is None else self.stages[stage]
        return 1e3 * s / self.n_scans

    def ratio_to_reference(self, stage: str | None = None) -> float:
        """A stage's (``None``: the run's) time per scan over the reference call's."""
        return (self.ms_per_scan(stage) / 1e3) / self.reference_seconds


def run_log_bench(
    log: Log, method: str = "graph", repeats: int = 1, progress: bool = True
) -> LogBench:
    """Run ``method`` over ``log`` ``repeats`` times and split the wall time into stages.

    Each run gets a fresh back end (:func:`fhslam.pipeline.make_backend`) whose stage methods
    are wrapped by a :class:`StageTimer` on the instance (:data:`STAGES`; nested stages are
    subtracted, so the main thread's stages plus ``"other"`` add up to the run's wall time;
    :attr:`LogBench.parallel` tells what ran on the back end's thread), driven by
    :func:`fhslam.pipeline.run_backend`. The reference call is timed on a sample of the log's
    scans right before and right after each run, so that machine load hits both alike. A
    short untimed run over the first scans warms up JIT-compiled code and caches first.
    Times are medians over the repeats; cProfile or another process slows both alike.
    """
    from fhslam.pipeline import make_backend, run_backend

    if len(log) == 0:
        raise ValueError("the log has no scans")
    if repeats < 1:
        raise ValueError(f"repeats must be >= 1, got {repeats}")
    samples = _reference_samples(log)
    run_backend(make_backend(method), log_head(log, 20))  # warm-up: JIT, caches
    _reference_seconds(samples[:1], 1)
    totals, refs, stage_runs, parallel_runs = [], [], [], []
    calls: dict[str, int] = {}
    for r in range(repeats):
        before = _reference_seconds(samples)
        timer = StageTimer()
        backend = instrumented_backend(method, timer)
        desc = f"bench {method} {log.name}" + (f" ({r + 1}/{repeats})" if repeats > 1 else "")
        t0 = time.perf_counter()
        run_backend(backend, log, progress=progress, desc=desc)
        total = time.perf_counter() - t0
        after = _reference_seconds(samples)
        stages = dict(timer.seconds)
        stages["other"] = total - sum(stages.values()) + sum(timer.off_main.values())
        totals.append(total)
        refs.append((before + after) / 2)
        stage_runs.append(stages)
        parallel_runs.append({k: v for k, v in timer.off_main.items() if v > 0})
        calls = dict(timer.calls)
    duration = float(log.timestamps[-1] - log.timestamps[0])
    return LogBench(
        log=log.name,
        method=method,
        n_scans=len(log),
        duration=duration,
        seconds=float(np.median(totals)),
        stages={k: float(np.median([s[k] for s in stage_runs])) for k in stage_runs[0]},
        calls=calls,
        reference_seconds=float(np.median(refs)),
        repeats=repeats,
        parallel={
            k: float(np.median([p.get(k, 0.0) for p in parallel_runs]))
            for k in dict.fromkeys(k for p in parallel_runs for k in p)
        },
    )


def format_log_bench(b: LogBench) -> str:
    """The real-log bench as a header line and a plain-text table of stages."""
    rt = "n/a" if np.isnan(b.real_time_factor) else f"{b.real_time_factor:.1f}"
    med = f", medians of {b.repeats} runs" if b.repeats > 1 else ""
    lines = [
        f"{b.log} ({b.method}): {b.n_scans} scans ({b.duration:.1f} s of log), wall "
        f"{b.seconds:.2f} s, {b.steps_per_second:.1f} scans/s, {rt} × real time{med}",
        f"reference: {REFERENCE} on the log's scans, {1e3 * b.reference_seconds:.3f} ms/scan "
        "(before and after the run)",
    ]
    head = f"{'stage':<14} {'ms/scan':>9} {'share':>7} {'time/ref':>9} {'calls':>7}"
    lines += [head, "-" * len(head)]
    if not b.calls:
        lines.append(f"(no stages measured for {b.method}: the total only)")
    for stage, s in b.stages.items() if b.calls else ():
        calls = f"{b.calls[stage]:7d}" if stage in b.calls else ""
        lines.append(
            f"{stage:<14} {b.ms_per_scan(stage):9.3f} {100 * s / b.seconds:6.1f}% "
            f"{b.ratio_to_reference(stage):9.2f} {calls}".rstrip()
        )
    lines.append("-" * len(head))
    lines.append(
        f"{'total':<14} {b.ms_per_scan():9.3f} {100.0:6.1f}% {b.ratio_to_reference():9.2f}"
    )
    if b.parallel:
        off = sum(b.parallel.values())
        lines.append(
            f"{off:.2f} s of {', '.join(b.parallel)} ran on the back end's thread, overlapping "
            f"the rest: the stages add up to {100 * (1 + off / b.seconds):.0f} % of the wall time"
        )
    return "\n".join(lines)
