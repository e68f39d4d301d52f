"""fhslam: the fast-Hough-transform line SLAM of the paper, as a teaching and research workbook.

The names below are the public API; each is loaded on first use (PEP 562), so
``import fhslam`` is cheap and does not compile the numba kernels of Loop 1 until a line is
extracted. Everything else lives in its module (``fhslam.metrics``, ``fhslam.io``, ...).

>>> import fhslam
>>> log = fhslam.simulate(fhslam.load_world("paper"), seed=0)        # doctest: +SKIP
>>> result = fhslam.run_slam(log, "fht")                           # doctest: +SKIP
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

_API: dict[str, str] = {
    # errors
    "InputError": "fhslam.errors",
    # geometry and data types
    "Line": "fhslam.lines",
    "Scan": "fhslam.scan",
    "scan_to_points": "fhslam.scan",
    # Loop 1: lines from a scan
    "ExtractionParams": "fhslam.extraction",
    "extract_lines": "fhslam.extraction",
    # Loop 2: matching and merging
    "MatchParams": "fhslam.matching",
    "similarity": "fhslam.matching",
    "match_lines": "fhslam.matching",
    "merge": "fhslam.matching",
    # Loop 3: calibration and the map
    "calibrate_pose": "fhslam.calibration",
    "ReferenceMap": "fhslam.reference_map",
    # SLAM back ends and the pipeline
    "SlamParams": "fhslam.slam",
    "FastHoughSLAM": "fhslam.slam",
    "GraphSlamParams": "fhslam.slam",
    "GraphFastHoughSLAM": "fhslam.slam",
    "EKFParams": "fhslam.slam",
    "EKFLineSLAM": "fhslam.slam",
    "METHODS": "fhslam.pipeline",
    "SlamResult": "fhslam.pipeline",
    "run_slam": "fhslam.pipeline",
    "run_backend": "fhslam.pipeline",
    # data
    "Log": "fhslam.io",
    "load_log": "fhslam.datasets",
    "load_world": "fhslam.sim",
    "simulate": "fhslam.sim",
    "degrade": "fhslam.sim",
    "perturb_odometry": "fhslam.sim",
}

__all__ = sorted(_API)


def __getattr__(name: str) -> Any:
    module = _API.get(name)
    if module is None:
        raise AttributeError(f"module 'fhslam' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later lookups skip __getattr__
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_API])


if TYPE_CHECKING:  # for type checkers and IDEs: the same names, eagerly
    from fhslam.calibration import calibrate_pose
    from fhslam.datasets import load_log
    from fhslam.errors import InputError
    from fhslam.extraction import ExtractionParams, extract_lines
    from fhslam.io import Log
    from fhslam.lines import Line
    from fhslam.matching import MatchParams, match_lines, merge, similarity
    from fhslam.pipeline import METHODS, SlamResult, run_backend, run_slam
    from fhslam.reference_map import ReferenceMap
    from fhslam.scan import Scan, scan_to_points
    from fhslam.sim import degrade, load_world, perturb_odometry, simulate
    from fhslam.slam import (
        EKFLineSLAM,
        EKFParams,
        FastHoughSLAM,
        GraphFastHoughSLAM,
        GraphSlamParams,
        SlamParams,
    )
