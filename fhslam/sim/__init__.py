"""Simulation: polygonal worlds, a ray-casting laser, drifting odometry, `simulate()`, and
`degrade()` (dropped scans, clutter returns)."""

from fhslam.sim.degrade import degrade
from fhslam.sim.laser import LaserParams, add_range_noise, beam_angles, cast_rays
from fhslam.sim.odometry import OdometryNoise, odometry_from_truth
from fhslam.sim.simulate import MotionParams, follow_route, is_closed_route, lap_route, simulate
from fhslam.sim.world import (
    World,
    WorldFormatError,
    load_world,
    paper_world,
    random_world,
    route_clearance,
)

__all__ = [
    "LaserParams",
    "MotionParams",
    "OdometryNoise",
    "World",
    "WorldFormatError",
    "add_range_noise",
    "beam_angles",
    "cast_rays",
    "degrade",
    "follow_route",
    "is_closed_route",
    "lap_route",
    "load_world",
    "odometry_from_truth",
    "paper_world",
    "random_world",
    "route_clearance",
    "simulate",
]
