"""Simulate a robot driving a world's route: true poses, laser scans and drifting odometry.

Stands in for the paper's SRIsim simulator (Pioneer II with a SICK LMS200, "Simulation
result"). The output is an ordinary :class:`~fhslam.io.log.Log`; the ground truth rides along
in ``Log.truth`` and is never written into the CARMEN log itself.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from tqdm.auto import tqdm

from fhslam.errors import InputError
from fhslam.geometry import wrap_angle
from fhslam.io.log import Log
from fhslam.sim.laser import LaserParams, add_range_noise, beam_angles, cast_rays
from fhslam.sim.odometry import OdometryNoise, odometry_from_truth
from fhslam.sim.world import World


@dataclass(frozen=True)
class MotionParams:
    """How the simulated robot drives and how often it scans.

    The controller steers toward the next waypoint: turn rate ``turn_gain * heading_error``
    (limited to ``max_turn_rate``), forward speed ``speed`` at zero heading error falling
    linearly to 0 at ``drive_angle_deg``, so sharp corners are turned on the spot and the
    path stays close to the route polyline.

    Attributes
    ----------
    speed : float
        Cruising speed, m/s.
    max_turn_rate : float
        Largest turn rate, rad/s.
    turn_gain : float
        Proportional gain from heading error (rad) to turn rate (rad/s), 1/s.
    drive_angle_deg : float
        Heading error, degrees, at and beyond which the robot only turns.
    scan_period : float
        Time between scans, s (0.2 s: a 5 Hz laser).
    waypoint_tolerance : float
        A waypoint counts as reached within this distance, metres.
    substeps : int
        Integration steps of the unicycle model per scan period.
    """

    speed: float = 0.4
    max_turn_rate: float = 0.6
    turn_gain: float = 2.0
    drive_angle_deg: float = 30.0
    scan_period: float = 0.2
    waypoint_tolerance: float = 0.1
    substeps: int = 10

    def __post_init__(self) -> None:
        for name in ("speed", "max_turn_rate", "turn_gain", "drive_angle_deg", "scan_period"):
            if not getattr(self, name) > 0:
                raise ValueError(f"MotionParams.{name} must be positive, got {getattr(self, name)}")
        if not self.waypoint_tolerance > 0:
            raise ValueError(
                f"MotionParams.waypoint_tolerance must be positive, got {self.waypoint_tolerance}"
            )
        if int(self.substeps) != self.substeps or self.substeps < 1:
            raise ValueError(f"MotionParams.substeps must be an integer >= 1, got {self.substeps}")


MAX_SCANS = 500_000
"""The most scans :func:`simulate` makes of a world's route (without ``max_scans``): 28 hours
of driving, 40 km at the default speed. Measured for 125,000 scans: 38 s, 1 GB of memory and a
161 MB log; the limit's run would take some 4 GB and 2.5 minutes. The largest built-in run, a
hundred laps of the paper world, is 92,000 scans."""


def expected_scans(world: World, motion: MotionParams | None = None, laps: int = 1) -> int:
    """About how many scans driving ``world``'s route ``laps`` times takes, without driving it:
    the path's length at ``motion.speed`` plus each corner's turn at ``max_turn_rate``, in
    scan periods (within a few per cent of :func:`follow_route`'s count on the built-in
    worlds; the turns make it an estimate)."""
    m = DEFAULT_MOTION if motion is None else motion
    route = lap_route(world.route, laps)
    pts = np.vstack([world.start[:2], route])
    steps = np.diff(pts, axis=0)
    lengths = np.hypot(steps[:, 0], steps[:, 1])
    steps = steps[lengths > 0]
    headings = np.concatenate([[world.start[2]], np.arctan2(steps[:, 1], steps[:, 0])])
    turns = float(np.abs(wrap_angle(np.diff(headings))).sum())
    seconds = float(lengths.sum()) / m.speed + turns / m.max_turn_rate
    return int(np.ceil(seconds / m.scan_period)) + 1


def check_scan_limit(
    world: World, laps: int = 1, motion: MotionParams | None = None, source: str | None = None
) -> int:
    """:func:`expected_scans`, after checking it is within :data:`MAX_SCANS`.

    Raises
    ------
    InputError
        Naming the world (``source``, e.g. its file, or its name), the route's length and
        the limit, if the route would take more scans than :data:`MAX_SCANS`.
    """
    n = expected_scans(world, motion, laps)
    if n > MAX_SCANS:
        m = DEFAULT_MOTION if motion is None else motion
        label = repr(world.name) if source is None else f"{source} ({world.name!r})"
        times = f" driven {laps} times" if laps > 1 else ""
        raise InputError(
            f"world {label}: its route of {world.route_length:,.0f} m{times} is about {n:,} "
            f"scans at {m.speed:g} m/s and {1 / m.scan_period:g} scans per second; the limit "
            f"is {MAX_SCANS:,} scans (nothing was simulated)"
        )
    return n


def is_closed_route(route: NDArray[np.float64], tolerance: float = 1e-6) -> bool:
    """Whether a route ``(K, 2)`` is a closed loop: its last waypoint is its first.

    ``tolerance`` (metres) absorbs rounding, e.g. of a route read back from JSON.
    """
    return bool(len(route) >= 3 and np.hypot(*(route[-1] - route[0])) <= tolerance)


def lap_route(route: NDArray[np.float64], laps: int) -> NDArray[np.float64]:
    """The waypoints of ``laps`` consecutive laps of a closed ``route`` (K, 2).

    Returns
    -------
    ndarray, shape (laps * (K - 1) + 1, 2)
        ``route`` followed ``laps - 1`` more times by ``route[1:]``; ``route`` itself (a copy)
        for ``laps == 1``.

    Raises
    ------
    ValueError
        If ``laps`` is not an integer >= 1, or ``laps > 1`` for an open route (one whose
        last waypoint is not its first: driving it again would teleport the robot back).
    """
    route = np.asarray(route, dtype=float)
    if isinstance(laps, bool) or int(laps) != laps or laps < 1:
        raise ValueError(f"laps must be an integer >= 1, got {laps!r}")
    laps = int(laps)
    if laps > 1 and not is_closed_route(route):
        raise ValueError(
            f"laps={laps} needs a closed route (last waypoint equal to the first); this route "
            f"runs from {route[0].tolist()} to {route[-1].tolist()}"
        )
    return np.vstack([route, *([route[1:]] * (laps - 1))])


def follow_route(
    world: World,
    motion: MotionParams | None = None,
    max_scans: int | None = None,
    laps: int = 1,
    progress: bool = False,
) -> NDArray[np.float64]:
    """True poses at the scan times while driving ``world.route`` from ``world.start``.

    Deterministic (no noise): a unicycle integrated with the midpoint rule, steered by the
    controller described in :class:`MotionParams`. The run ends at the first scan after the
    last waypoint (of the last lap) is reached, or after ``max_scans`` scans.

    Parameters
    ----------
    world : World
    motion : MotionParams, optional
    max_scans : int, optional
        Stop after this many scans.
    laps : int
        How many times to drive a closed route (see :func:`lap_route`); open routes allow
        only 1.
    progress : bool
        Show a progress bar (tqdm, on stderr) over the estimated scans
        (:func:`expected_scans`).

    Returns
    -------
    ndarray, shape (T, 3)
        Pose ``(x, y, theta)`` at scan times ``0, period, 2 period, ...``.
    """
    m = MotionParams() if motion is None else motion
    route = lap_route(world.route, laps)
    pose = world.start.astype(float).copy()
    tol = m.waypoint_tolerance
    target = 1 if np.hypot(*(route[0] - pose[:2])) <= tol else 0
    dt = m.scan_period / m.substeps
    drive_angle = np.radians(m.drive_angle_deg)
    # A generous bound on the scans needed: driving time plus half a turn per waypoint, x3.
    length = float(np.hypot(*np.diff(np.vstack([pose[:2], route]), axis=0).T).sum())
    expected = length / m.speed + len(route) * np.pi / m.max_turn_rate
    limit = int(3 * expected / m.scan_period) + 100 if max_scans is None else int(max_scans)
    poses = [pose.copy()]
    done = False
    with tqdm(
        total=min(expected_scans(world, m, laps), limit),
        initial=1,
        desc=f"simulate {world.name}: driving",
        unit="scan",
        disable=not progress,
    ) as bar:
        while not done and len(poses) < limit:
            for _ in range(m.substeps):
                d = route[target] - pose[:2]
                while np.hypot(*d) <= tol:  # reached: aim at the next waypoint
                    if target == len(route) - 1:
                        done = True
                        break
                    target += 1
                    d = route[target] - pose[:2]
                if done:
                    break
                err = wrap_angle(np.arctan2(d[1], d[0]) - pose[2])
                w = float(np.clip(m.turn_gain * err, -m.max_turn_rate, m.max_turn_rate))
                v = m.speed * max(0.0, 1.0 - abs(err) / drive_angle)
                mid = pose[2] + 0.5 * w * dt
                pose = np.array(
                    [
                        pose[0] + v * dt * np.cos(mid),
                        pose[1] + v * dt * np.sin(mid),
                        pose[2] + w * dt,
                    ]
                )
                pose[2] = wrap_angle(pose[2])
            poses.append(pose.copy())
            bar.update()
        bar.total = bar.n  # the estimate, corrected
    if not done and max_scans is None:
        raise RuntimeError(
            f"the robot did not reach the end of route {world.name!r} within {limit} scans; "
            "check the route and MotionParams"
        )
    return np.array(poses)


# The defaults of simulate() (frozen, so safe to share).
DEFAULT_LASER = LaserParams()
DEFAULT_ODOMETRY = OdometryNoise()
DEFAULT_MOTION = MotionParams()


def simulate(
    world: World,
    seed: int = 0,
    laser: LaserParams = DEFAULT_LASER,
    odometry: OdometryNoise = DEFAULT_ODOMETRY,
    motion: MotionParams = DEFAULT_MOTION,
    max_scans: int | None = None,
    laps: int = 1,
    progress: bool = False,
) -> Log:
    """Drive ``world``'s route and record noisy scans and drifting odometry.

    Parameters
    ----------
    world : World
    seed : int
        Seeds the laser and odometry noise (two independent streams, so changing the laser
        does not change the odometry errors). The path itself is deterministic.
    laser : LaserParams
    odometry : OdometryNoise
    motion : MotionParams
    max_scans : int, optional
        Stop after this many scans (default: at the end of the route). The path and the
        ranges are the first ``max_scans`` of the whole route's, but the odometry's random
        errors are drawn for the run as a whole, so they are not: a run cut short is another
        draw of the odometry, not a prefix of the full run's (the ``campus``'s first 8,000
        scans: up to 1 m apart; ``tests/test_sim.py``).
    laps : int
        Drive a closed route (last waypoint equal to the first, as in every
        :func:`~fhslam.sim.random_world`) this many times in a row, for longer runs with
        more drift and more loop closures. ``Log.world`` keeps the one-lap route.
    progress : bool
        Show progress bars (tqdm, on stderr) for driving the route and casting the beams.

    Returns
    -------
    Log
        ``timestamps[k] = round(k * scan_period, 6)``, noisy ``ranges`` (T, B), ``angles``
        (B,), ``odometry`` (T, 3), and the simulation's ``truth`` (T, 3), ``hits`` (T, B)
        and ``world``.

    Raises
    ------
    ValueError
        For ``max_scans < 1``, ``laps < 1``, or ``laps > 1`` on an open route (such as the
        paper world's, which ends at the far end of the corridor).
    InputError
        Without ``max_scans``, for a route longer than :data:`MAX_SCANS` scans
        (:func:`check_scan_limit`), before any work.
    """
    if max_scans is not None and (int(max_scans) != max_scans or max_scans < 1):
        raise ValueError(f"max_scans must be a positive integer or None, got {max_scans!r}")
    if max_scans is None:
        lap_route(world.route, laps)  # a bad laps is a ValueError first
        check_scan_limit(world, laps, motion)
    truth = follow_route(world, motion, max_scans, laps, progress=progress)
    laser_rng, odom_rng = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(2))
    angles = beam_angles(laser)
    clean = np.empty((len(truth), len(angles)))
    hits = np.empty((len(truth), len(angles)), dtype=np.intp)
    desc = f"simulate {world.name}: laser"
    for k, pose in enumerate(tqdm(truth, desc=desc, unit="scan", disable=not progress)):
        clean[k], hits[k] = cast_rays(world.walls, pose, angles, laser.max_range)
    return Log(
        name=world.name,
        timestamps=np.array([round(k * motion.scan_period, 6) for k in range(len(truth))]),
        ranges=add_range_noise(clean, hits, laser, laser_rng),
        angles=angles,
        odometry=odometry_from_truth(truth, odometry, odom_rng),
        max_range=laser.max_range,
        truth=truth,
        hits=hits,
        world=world,
    )
