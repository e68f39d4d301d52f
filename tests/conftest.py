"""Shared fixtures: small worlds built in the test, and the location of the real logs."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

ROOM = np.array([[0, 0, 6, 0], [6, 0, 6, 4], [6, 4, 0, 4], [0, 4, 0, 0]], dtype=float)
"""A 6 m x 4 m rectangular room, walls [x1, y1, x2, y2]."""


def cast(walls: np.ndarray, pose, n_beams: int = 181, noise: float = 0.01, seed: int = 0):
    """Ranges of a 180° laser at ``pose`` in a world of wall segments (inf: no wall hit),
    with Gaussian range noise; and the bearings."""
    from fhslam.sim import cast_rays

    a = np.radians(np.linspace(-90, 90, n_beams))
    r, _ = cast_rays(walls, pose, a, max_range=np.inf)
    return r + np.random.default_rng(seed).normal(0, noise, n_beams), a


def room_points(pose=(2.0, 1.5, 0.3), noise=0.01, seed=0):
    """Laser-frame points of a scan in ROOM."""
    r, a = cast(ROOM, pose, noise=noise, seed=seed)
    return np.column_stack([r * np.cos(a), r * np.sin(a)])


def data_dir() -> Path | None:
    """The shared real-data folder ($FHSLAM_DATA, else ../shared/data beside the repo)."""
    env = os.environ.get("FHSLAM_DATA")
    candidates = [Path(env)] if env else []
    candidates.append(Path(__file__).resolve().parents[2] / "shared" / "data")
    return next((c for c in candidates if c.is_dir()), None)


@pytest.fixture
def real_data() -> Path:
    d = data_dir()
    if d is None:
        pytest.skip("no real laser logs: set FHSLAM_DATA or place them in ../shared/data")
    return d


@pytest.fixture(scope="session")
def paper_log_perfect():
    """The paper world driven with perfect odometry (seed 0)."""
    from fhslam.sim import OdometryNoise, paper_world, simulate

    return simulate(paper_world(), seed=0, odometry=OdometryNoise.none())


@pytest.fixture(scope="session")
def paper_log_small():
    from fhslam.sim import paper_world, simulate

    return simulate(paper_world(), seed=0, max_scans=20)
