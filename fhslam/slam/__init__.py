"""The SLAM back ends: every method the package runs, with one contract.

A back end (:class:`Backend`) is fed one scan at a time with the odometry pose at that scan
(``step(scan, odometry)``, ``scan=None`` for a dropped scan) and gives its map, and any
revised poses, at the end (``finish()``). :func:`fhslam.pipeline.run_slam` drives any of them
over a log.

- :class:`FastHoughSLAM` (:mod:`fhslam.slam.fht`): the paper's step-by-step procedure,
  Loops 1-3;
- :class:`GraphFastHoughSLAM` (:mod:`fhslam.slam.graph`): the paper's procedure as the front
  end of a pose graph with loop closures, for long real logs;
- :class:`EKFLineSLAM` (:mod:`fhslam.slam.ekf`): the EKF line-SLAM baseline (filterpy);
- :class:`OdometryOnly` (:mod:`fhslam.slam.odometry`): dead reckoning.
"""

from fhslam.slam.base import Backend, FinalEstimate, StepResult
from fhslam.slam.ekf import EKFLineSLAM, EKFParams
from fhslam.slam.fht import FastHoughSLAM, SlamParams
from fhslam.slam.graph import GraphFastHoughSLAM, GraphSlamParams, LoopClosure
from fhslam.slam.odometry import OdometryOnly

__all__ = [
    "Backend",
    "EKFLineSLAM",
    "EKFParams",
    "FastHoughSLAM",
    "FinalEstimate",
    "GraphFastHoughSLAM",
    "GraphSlamParams",
    "LoopClosure",
    "OdometryOnly",
    "SlamParams",
    "StepResult",
]
