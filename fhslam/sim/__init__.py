"""Simulation: polygonal worlds, a ray-casting laser, drifting odometry, `simulate()`,
`degrade()` (dropped scans, clutter returns, range noise), `perturb_odometry()` (the last
bit) and `sparsify()` (one scan per metre or half radian) for any log, and the ground truth
the metrics score against (true lines of a scan, wall points the laser hit)."""

from fhslam.sim.degrade import degrade, perturb_odometry, sparsify
from fhslam.sim.laser import LaserParams, add_range_noise, beam_angles, cast_rays
from fhslam.sim.odometry import OdometryNoise, odometry_from_truth
from fhslam.sim.simulate import MotionParams, follow_route, is_closed_route, lap_route, simulate
from fhslam.sim.truth import (
    TrueLine,
    beam_wall_points,
    observed_wall_points,
    true_lines,
    visible_wall_points,
)
from fhslam.sim.world import (
    World,
    WorldFormatError,
    campus_world,
    corridor_world,
    hall_world,
    load_world,
    offices_world,
    paper_world,
    random_world,
    ring_world,
    route_clearance,
    transform_world,
)

__all__ = [
    "LaserParams",
    "MotionParams",
    "OdometryNoise",
    "TrueLine",
    "World",
    "WorldFormatError",
    "add_range_noise",
    "beam_angles",
    "beam_wall_points",
    "campus_world",
    "cast_rays",
    "corridor_world",
    "degrade",
    "follow_route",
    "hall_world",
    "is_closed_route",
    "lap_route",
    "load_world",
    "observed_wall_points",
    "odometry_from_truth",
    "offices_world",
    "paper_world",
    "perturb_odometry",
    "random_world",
    "ring_world",
    "route_clearance",
    "simulate",
    "sparsify",
    "transform_world",
    "true_lines",
    "visible_wall_points",
]
