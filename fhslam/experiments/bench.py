"""``fhslam bench``: speed and accuracy of every line extractor on the same simulated scans.

Time is the median over ``repeats`` calls per scan, then the median over scans, measured in
one run with the extractors interleaved scan by scan (so machine load hits all alike). The
reference is the bare ``cv2.HoughLinesPointSet`` call with a 1 cm × 1° accumulator on the
same points — the classical Hough transform the paper claims to beat; the table gives each
extractor's time as a ratio to it. Accuracy is scored with :mod:`fhslam.metrics` against the
true walls. Scans come from held-out random worlds the extraction was not tuned on.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

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
    ``repeats`` runs, one process)."""
    from fhslam.pipeline import run_slam

    log = simulate(load_world(world), seed=seed)
    rows = []
    for method in ("fht", "graph", "classical", "ekf"):
        run_slam(log, method)  # warm-up (JIT, caches)
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
