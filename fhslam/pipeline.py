"""The one SLAM pipeline: a log in, a trajectory and a map out, for every method.

Every SLAM method is a back end (:class:`fhslam.slam.Backend`: ``step(scan, odometry)`` and
``finish()``). :func:`run_slam` picks one by name from :data:`METHODS` with its parameters;
:func:`run_backend` drives any back end over a :class:`fhslam.io.Log`. What every run needs
lives here once:

- the **laser's mount**: a log whose laser sits off the robot's origin (``Log.laser_offset``)
  is run on the laser's poses ``odometry ⊕ offset`` and reported as robot poses;
- **dropped scans** (every range NaN) reach the back end as ``None``;
- the **progress bar**.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray
from tqdm.auto import tqdm

from fhslam.baselines import hough_opencv_pointset
from fhslam.geometry import compose, inverse
from fhslam.io import KeyframeGraph, Log
from fhslam.lines import Line
from fhslam.slam import (
    Backend,
    EKFLineSLAM,
    EKFParams,
    FastHoughSLAM,
    GraphFastHoughSLAM,
    GraphSlamParams,
    OdometryOnly,
    SlamParams,
    StepResult,
)

__all__ = [
    "METHODS",
    "Method",
    "SlamResult",
    "keyframe_graph",
    "make_backend",
    "run_backend",
    "run_slam",
]


@dataclass
class SlamResult:
    """A whole run: one pose per scan (robot frame), the map, and what each step did."""

    timestamps: NDArray[np.float64]
    poses: NDArray[np.float64]
    map: list[Line]
    steps: list[StepResult] = field(repr=False)


@dataclass(frozen=True)
class Method:
    """A SLAM method by name: its parameter type and how to build its back end."""

    name: str
    params_type: type | None
    build: Callable[[object | None], Backend]
    summary: str


def _classical(params: SlamParams | None) -> FastHoughSLAM:
    return FastHoughSLAM(replace(params or SlamParams(), extractor=hough_opencv_pointset))


METHODS: dict[str, Method] = {
    m.name: m
    for m in (
        Method(
            "fht",
            SlamParams,
            FastHoughSLAM,
            "FH-SLAM, the paper's step-by-step procedure (fast Hough lines, four-condition "
            "matching, pose calibration, merging)",
        ),
        Method(
            "graph",
            GraphSlamParams,
            GraphFastHoughSLAM,
            "the default: pose-graph SLAM with scan-to-map tracking, information-weighted "
            "edges, verified loop closures and a map of fast Hough lines",
        ),
        Method(
            "classical",
            SlamParams,
            _classical,
            "FH-SLAM with OpenCV's classical Hough transform as Loop 1 (baseline)",
        ),
        Method("ekf", EKFParams, EKFLineSLAM, "EKF line SLAM on filterpy (baseline)"),
        Method("odometry", None, lambda _params: OdometryOnly(), "dead reckoning (baseline)"),
    )
}
"""The SLAM methods :func:`run_slam` knows, by name."""


def make_backend(method: str, params: object | None = None) -> Backend:
    """A fresh back end for ``method`` (a key of :data:`METHODS`) with ``params``.

    Raises
    ------
    ValueError
        For an unknown method.
    TypeError
        For parameters of another type than the method's (e.g. :class:`SlamParams` for
        ``"ekf"``), instead of silently ignoring them.
    """
    spec = METHODS.get(method)
    if spec is None:
        raise ValueError(f"unknown SLAM method {method!r}; choose one of {', '.join(METHODS)}")
    if params is not None and (
        spec.params_type is None or not isinstance(params, spec.params_type)
    ):
        want = "no parameters" if spec.params_type is None else spec.params_type.__name__
        raise TypeError(f"SLAM method {method!r} takes {want}, got {type(params).__name__}")
    return spec.build(params)


def run_backend(backend: Backend, log: Log, progress: bool = False, desc: str = "") -> SlamResult:
    """Drive a back end over a whole log (see the module docs).

    Parameters
    ----------
    backend : Backend
        A fresh back end (e.g. ``FastHoughSLAM()``); it keeps its state, for inspection.
    log : Log
    progress : bool
        Show a progress bar (tqdm).
    desc : str
        The progress bar's label.

    Returns
    -------
    SlamResult
        Robot poses, one per scan, with the log's timestamps.
    """
    offset = log.laser_offset
    mounted = offset is not None and bool(np.any(offset != 0))
    odometry = compose(log.odometry, offset) if mounted else log.odometry
    steps = []
    for k in tqdm(range(len(log)), desc=desc or log.name, unit="scan", disable=not progress):
        scan = log.scan(k)
        dropped = bool(np.isnan(scan.ranges).all())
        steps.append(backend.step(None if dropped else scan, odometry[k]))
    final = backend.finish()
    if final.poses is not None:
        poses = np.asarray(final.poses, dtype=float).reshape(-1, 3)
        steps = [replace(s, pose=q) for s, q in zip(steps, poses, strict=True)]
    else:
        poses = np.array([s.pose for s in steps], dtype=float).reshape(-1, 3)
    if mounted:
        poses = compose(poses, inverse(offset))
    return SlamResult(np.asarray(log.timestamps, dtype=float), poses, final.map, steps)


def run_slam(
    log: Log, method: str = "graph", params: object | None = None, progress: bool = False
) -> SlamResult:
    """Run a SLAM method (a key of :data:`METHODS`) over a log: by default the package's
    SLAM (``"graph"``), with the same defaults for every log.

    Every method starts at the first odometry pose, which a simulated log sets to the true
    start ("suppose the initial localization of mobile robot is correct").

    Parameters
    ----------
    log : Log
    method : str
        ``"graph"`` (default: pose-graph SLAM with scan-to-map tracking, verified loop
        closures and a fast Hough line map), ``"fht"`` (the paper's procedure), or the
        baselines ``"classical"``, ``"ekf"``, ``"odometry"``.
    params : optional
        The method's parameters: :class:`SlamParams` (``fht``, ``classical``),
        :class:`GraphSlamParams` (``graph``), :class:`EKFParams` (``ekf``), none
        (``odometry``); any other type raises :class:`TypeError`.
    progress : bool
        Show a progress bar.
    """
    backend = make_backend(method, params)
    return run_backend(backend, log, progress, desc=f"{method} {log.name}".strip())


def keyframe_graph(backend: GraphFastHoughSLAM, log: Log) -> KeyframeGraph:
    """The keyframes and loop closures of a graph back end that :func:`run_backend` drove
    over ``log``: each keyframe's timestamp and optimised robot pose in the world frame (the
    pose the trajectory gives the scan that started it), each accepted loop closure and
    whether it is still active (what ``fhslam slam --graph`` writes)."""
    steps = backend.keyframe_steps
    if len(steps) != len(backend.graph) or (len(steps) and steps[-1] >= len(log)):
        raise ValueError("the back end was not run over this log (keyframes do not match)")
    poses = compose(backend.origin, backend.graph.poses).reshape(-1, 3) if len(steps) else []
    offset = log.laser_offset
    if len(steps) and offset is not None and np.any(offset != 0):  # it ran on laser poses
        poses = compose(poses, inverse(offset)).reshape(-1, 3)
    loops = backend.loops
    return KeyframeGraph(
        timestamps=np.asarray(log.timestamps, dtype=float)[steps],
        poses=np.asarray(poses, dtype=float).reshape(-1, 3),
        loops=np.array([(lc.old, lc.new) for lc in loops], dtype=np.intp).reshape(-1, 2),
        active=np.array([backend.graph.is_active(lc.edge) for lc in loops], dtype=bool),
        scores=np.array([lc.score for lc in loops], dtype=float),
    )
