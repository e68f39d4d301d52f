"""Library calls that evaluate a result and return a report (after evo's ``main_ape``).

They read the files, call :mod:`fhslam.metrics` and return a report object; the ``fhslam``
command only parses its options, calls one of them and prints the report.

- :func:`evaluate_truth`: a trajectory (and map) against the ground truth: ATE, RPE, map
  error and coverage (``fhslam evaluate --truth``);
- :func:`evaluate_relations`: a trajectory against a SLAM-benchmark relations file,
  Kümmerle et al. (2009) (``fhslam evaluate --relations``);
- :func:`log_summary`: what a log holds (``fhslam info``);
- :func:`score_extractor`: a line extractor on a simulated log, scored against the true
  walls (Nguyen et al. 2005 line-detection scores, :mod:`fhslam.metrics.detection`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fhslam import metrics
from fhslam.datasets import find_dataset
from fhslam.errors import InputError
from fhslam.extraction import extract_lines
from fhslam.io import Log, no_return_reading, read_map, read_relations, read_trajectory
from fhslam.lines import Line
from fhslam.metrics import DetectionScores, ErrorStats, RelationsError, detection_scores
from fhslam.scan import scan_to_points
from fhslam.sim import load_world, true_lines, visible_wall_points

__all__ = [
    "LogSummary",
    "RelationsReport",
    "TruthReport",
    "evaluate_relations",
    "evaluate_truth",
    "log_summary",
    "score_extractor",
]

PathLike = str | os.PathLike[str]


@dataclass(frozen=True)
class TruthReport:
    """A trajectory (and optionally its map) against the ground truth."""

    stats: dict[str, ErrorStats]
    """``"ate"`` (m), ``"rpe_trans"`` (m) and ``"rpe_rot"`` (degrees)."""
    n_poses: int
    """Poses paired by timestamp."""
    n_est: int
    n_truth: int
    n_rpe_pairs: int
    delta: int
    """RPE frame distance."""
    aligned: bool
    """Whether the estimate was SE(2)-aligned before ATE."""
    map: dict[str, float | int | None] = field(default_factory=dict)
    """With a world and a map: ``map_error`` (m), ``map_coverage`` (0..1; ``None`` if
    undefined), ``n_map_lines``, ``n_observed_points``."""

    def as_dict(self) -> dict[str, Any]:
        """One flat dict: ``ate_rmse``, ..., ``rpe_rot_max_deg``, counts, map numbers."""
        out: dict[str, Any] = {}
        for name, st in self.stats.items():
            unit = "_deg" if name == "rpe_rot" else ""
            out.update({f"{name}_{k}{unit}": v for k, v in st.as_dict().items()})
        out.update(n_poses=self.n_poses, n_est=self.n_est, n_truth=self.n_truth)
        out["n_rpe_pairs"] = self.n_rpe_pairs
        out.update(self.map)
        return out


def evaluate_truth(
    trajectory: PathLike,
    truth: PathLike,
    world: str | PathLike | None = None,
    map_file: PathLike | None = None,
    max_diff: float = 0.01,
    delta: int = 1,
    align: bool = False,
) -> TruthReport:
    """Errors of a trajectory file against a ground-truth file, poses paired by timestamp.

    ATE is not aligned unless ``align`` (the SLAM starts at the true first pose). With
    ``world`` and ``map_file``, the map is compared with the world's walls: ``map_error`` is
    the mean distance of the map segments to the walls, ``map_coverage`` the share of the
    observed wall points within 5 cm of the map. Nothing is simulated for it: the observed
    points are the noise-free hits of the paper's laser (181 beams over 180 degrees, 8 m)
    cast into the world from every 5th true pose (:func:`fhslam.sim.visible_wall_points`).

    Raises
    ------
    InputError
        For unreadable files, fewer than 2 poses paired, or only one of world and map.
    """
    if (world is None) != (map_file is None):
        given, missing = ("world", "map") if map_file is None else ("map", "world")
        raise InputError(f"a {given} needs a {missing}: the map is compared with the walls")
    t_est, est = read_trajectory(trajectory)
    t_ref, ref = read_trajectory(truth)
    i_est, i_ref = metrics.associate(t_est, t_ref, max_diff=max_diff)
    if len(i_est) < 2:
        raise InputError(
            f"{trajectory} and {truth}: only {len(i_est)} poses have matching "
            f"timestamps (within {max_diff:g} s); at least 2 are needed"
        )
    e, r = est[i_est], ref[i_ref]
    stats = {
        "ate": metrics.ate(e, r, align=align),
        "rpe_trans": metrics.rpe(e, r, delta=delta),
        "rpe_rot": metrics.rpe_rot_deg(e, r, delta=delta),
    }
    map_numbers: dict[str, float | int | None] = {}
    if world is not None and map_file is not None:
        walls = load_world(world).walls
        lines = read_map(map_file)
        observed = visible_wall_points(walls, ref, every=5)
        error = metrics.map_error(lines, walls)
        map_numbers = {
            "map_error": None if math.isnan(error) else error,
            "map_coverage": metrics.map_coverage(lines, observed) if len(observed) else None,
            "n_map_lines": len(lines),
            "n_observed_points": len(observed),
        }
    return TruthReport(
        stats,
        len(i_est),
        len(t_est),
        len(t_ref),
        len(metrics.rpe_pairs(len(e), delta)),
        delta,
        align,
        map_numbers,
    )


@dataclass(frozen=True)
class RelationsReport:
    """A trajectory against a relations file (Kümmerle et al. 2009; Hess et al. 2016)."""

    error: RelationsError
    relations: Path
    """The relations file used (a dataset name is resolved to its file)."""
    max_diff: float

    def as_dict(self) -> dict[str, float | int]:
        """``relations_trans_mean``, ..., ``relations_used``, ``relations_total``."""
        out: dict[str, float | int] = {
            f"relations_{k}": v
            for k, v in self.error.as_dict().items()
            if k not in ("n_used", "n_total")
        }
        out.update(relations_used=self.error.n_used, relations_total=self.error.n_total)
        return out


def evaluate_relations(
    trajectory: PathLike, relations: str | PathLike, max_diff: float = 0.001
) -> RelationsReport:
    """The relations error of a trajectory file (:func:`fhslam.metrics.relations_error`).

    ``relations`` is a ``.relations`` file or a dataset name (``"intel"``: its relations
    file, :func:`fhslam.datasets.find_dataset`).

    Raises
    ------
    InputError
        For unreadable files, or when no relation's two timestamps match the trajectory's.
    """
    t_est, est = read_trajectory(trajectory)
    path = find_dataset(relations, kind="relations")
    t1, t2, rel = read_relations(path)
    try:
        err = metrics.relations_error(t_est, est, t1, t2, rel, max_diff=max_diff)
    except ValueError as e:  # no relation usable: the two files do not belong together
        raise InputError(f"{trajectory} and {path}: {e}") from None
    return RelationsReport(err, path, max_diff)


@dataclass(frozen=True)
class LogSummary:
    """What a log holds (``fhslam info``)."""

    n_scans: int
    n_beams: int
    duration: float
    """Time span, s."""
    odometry_path: float
    """Length of the odometry path, m."""
    max_range: float
    """The maximum range in use, m (readings at or beyond it are no returns)."""
    no_return: float | None
    """The no-return reading detected in the log (:func:`fhslam.io.no_return_reading`)."""
    n_sampled: int
    median_lines: float
    """Median number of fast Hough lines per scan over ``n_sampled`` scans."""


def log_summary(log: Log, n_sample: int = 200) -> LogSummary:
    """Summarise a log; Loop 1 runs on about ``n_sample`` evenly spread scans."""
    path = float(np.hypot(*np.diff(log.odometry[:, :2], axis=0).T).sum()) if len(log) else 0.0
    sample = range(0, len(log), max(1, len(log) // n_sample))
    n_lines = [len(extract_lines(log.scan(k).points()[0])) for k in sample]
    return LogSummary(
        n_scans=len(log),
        n_beams=log.n_beams,
        duration=float(log.timestamps[-1] - log.timestamps[0]) if len(log) else 0.0,
        odometry_path=path,
        max_range=float(log.max_range),
        no_return=no_return_reading(log.ranges, stated=log.stated_max_range),
        n_sampled=len(n_lines),
        median_lines=float(np.median(n_lines)) if n_lines else float("nan"),
    )


Extractor = Callable[[NDArray[np.float64]], list[Line]]


def score_extractor(
    extract: Extractor,
    log,
    scans: Iterable[int] | None = None,
    min_hits: int = 10,
    **match_kwargs: float,
) -> DetectionScores:
    """Run ``extract(points)`` on simulated scans and score it against the true walls.

    Parameters
    ----------
    extract : callable
        ``points (N, 2) in the laser frame -> list[Line]``.
    log : fhslam.io.Log
        A simulated log (it must carry ``truth``, ``hits`` and ``world``).
    scans : iterable of int, optional
        Scan indices to use (default: all).
    """
    if log.truth is None or log.hits is None or log.world is None:
        raise ValueError(
            f"log {log.name!r} has no ground truth (truth, hits, world): "
            "line-detection scores need a simulated log"
        )
    idx = range(len(log)) if scans is None else scans

    def per_scan():
        for k in idx:
            pts, beams = scan_to_points(log.ranges[k], log.angles, max_range=log.max_range)
            truth, rob = true_lines(log.hits[k], log.world.walls, log.truth[k], min_hits)
            yield extract(pts), beams, truth, rob

    return detection_scores(per_scan(), **match_kwargs)
