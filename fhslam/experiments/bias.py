"""One refinement at a time: where the tracker's point-to-line refinement places a scan,
against a map of the scans before it at their *true* poses, measured from the truth along
the robot's heading.

Along the ``ring``'s corridors the SLAM comes out 0.20-0.24 % too large: each keyframe is
placed a little ahead. This takes the tracker's part apart from the rest (no odometry
prior, no correlative search, no graph): a world simulated with perfect odometry, every
``every``-th scan refined from its true pose against the ``map_scans`` scans before it,
each smoothed, filled in and given normals as a keyframe's cloud is
(:class:`fhslam.slam.GraphFastHoughSLAM`), thinned on one ``cloud_voxel`` grid::

    from fhslam.experiments.bias import refinement_bias
    b = refinement_bias("ring")                    # +0.83 mm a refinement (se 0.25)
    b = refinement_bias("ring", corner_deg=20.0)   # -0.26 mm (se 0.34)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from fhslam.geometry import transform_points
from fhslam.scanmatch import PointMap, refine, voxel_index
from fhslam.sim import load_world, simulate
from fhslam.sim.odometry import OdometryNoise
from fhslam.slam.graph import GraphSlamParams, scan_cloud
from fhslam.slam.tracker import TrackerParams

__all__ = ["RefinementBias", "refinement_bias"]


@dataclass(frozen=True)
class RefinementBias:
    """What :func:`refinement_bias` measured, one entry per refinement."""

    seed: NDArray[np.int64]
    scan: NDArray[np.int64]
    along: NDArray[np.float64]
    """The refined position's error along the true heading, metres (positive: ahead)."""
    heading: NDArray[np.float64]
    """The refined heading's error, radians."""

    def mean(self) -> float:
        """The mean error along the heading, metres."""
        return float(self.along.mean())

    def standard_error(self) -> float:
        """The standard error of :meth:`mean`, metres."""
        return float(self.along.std(ddof=1) / np.sqrt(len(self.along)))


def _cloud(points, pose, params):
    """A scan's cloud as a keyframe's (:func:`~fhslam.slam.graph.scan_cloud`), at ``pose``."""
    dense, normals = scan_cloud(points, params)
    c, s = np.cos(pose[2]), np.sin(pose[2])
    return transform_points(pose, dense), normals @ [[c, s], [-s, c]]


def refinement_bias(
    world: str = "ring",
    seeds: tuple[int, ...] = (0, 1, 2),
    n_scans: int = 400,
    first: int = 30,
    every: int = 3,
    map_scans: int = 6,
    corner_deg: float = 0.0,
) -> RefinementBias:
    """Refine scans ``first, first + every, ... < n_scans`` of ``world`` (simulated with
    each seed, the default laser, perfect odometry) from their true poses against the
    ``map_scans`` scans before each (see the module docs); ``corner_deg`` as in
    :class:`~fhslam.slam.GraphSlamParams` (0: off). The refinement is the tracker's
    (:class:`~fhslam.slam.tracker.TrackerParams`' ``refine_distance`` and
    ``refine_iterations``) without its odometry prior."""
    if not (1 <= map_scans <= first < n_scans and every >= 1 and len(seeds)):
        raise ValueError(
            f"need 1 <= map_scans <= first < n_scans, every >= 1 and a seed, got map_scans="
            f"{map_scans}, first={first}, n_scans={n_scans}, every={every}, seeds={seeds}"
        )
    tracker, params = TrackerParams(), GraphSlamParams(corner_deg=corner_deg)
    rows = []
    for seed in seeds:
        log = simulate(
            load_world(world),
            seed=seed,
            odometry=OdometryNoise(0, 0, 0, 0, 0, 0, 0),
            max_scans=n_scans,
        )
        if len(log) <= first:
            raise ValueError(f"the {world!r} run has {len(log)} scans: none to refine from {first}")
        scans = [log.scan(i).points()[0] for i in range(len(log))]
        truth = log.truth
        for k in range(first, len(log), every):
            parts = [_cloud(scans[m], truth[m], params) for m in range(k - map_scans, k)]
            cloud = np.vstack([p for p, _ in parts])
            normals = np.vstack([n for _, n in parts])
            keep = voxel_index(cloud, params.cloud_voxel)
            target = PointMap.build(cloud[keep], normals[keep])
            ref = refine(
                target,
                scans[k],
                truth[k],
                tracker.refine_distance,
                tracker.refine_iterations,
            )
            e = ref.pose - truth[k]
            th = truth[k, 2]
            along = e[0] * np.cos(th) + e[1] * np.sin(th)
            rows.append((seed, k, along, np.angle(np.exp(1j * e[2]))))
    seed_, scan_, along_, heading_ = (np.array(c) for c in zip(*rows, strict=True))
    return RefinementBias(seed_.astype(np.int64), scan_.astype(np.int64), along_, heading_)
