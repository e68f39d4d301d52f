"""The SLAM explorer of notebook 06: FH-SLAM on the paper world under odometry drift and
range noise that the sliders set (:func:`slam_noise_explorer`).
"""

from __future__ import annotations

import matplotlib.pyplot as plt
from matplotlib.figure import Figure

from fhslam import plotting
from fhslam.figures.explorer_base import FIGSIZE, Explorer, slider


def slam_noise_explorer(seed: int = 0, scans: int = 250):
    """Notebook 06: FH-SLAM on the first ``scans`` scans of the paper world under odometry
    drift and range noise that the sliders set (a new simulation each time, seeded)."""
    from dataclasses import replace

    from fhslam.metrics import ate
    from fhslam.pipeline import run_slam
    from fhslam.sim import LaserParams, OdometryNoise, paper_world, simulate

    world, base = paper_world(), OdometryNoise.drifting()

    def draw(drift, range_noise_cm, seed) -> Figure:
        odo = replace(
            base,
            **{
                f: drift * getattr(base, f)
                for f in (
                    "alpha1",
                    "alpha2",
                    "alpha3",
                    "alpha4",
                    "scale_error",
                    "heading_bias",
                    "turn_scale_error",
                )
            },
        )
        laser = LaserParams(range_noise_std=range_noise_cm / 100)
        log = simulate(world, seed=seed, laser=laser, odometry=odo, max_scans=scans)
        result = run_slam(log, "fht")
        fig, ax = plt.subplots(figsize=FIGSIZE)
        plotting.plot_walls(world.walls, ax=ax, color="0.75")
        ax.plot(*log.truth[:, :2].T, "k-", lw=2, label="truth")
        e_odo, e_slam = ate(log.odometry, log.truth).rmse, ate(result.poses, log.truth).rmse
        ax.plot(*log.odometry[:, :2].T, "tab:orange", label=f"odometry (ATE {e_odo:.2f} m)")
        ax.plot(*result.poses[:, :2].T, "tab:blue", label=f"FH-SLAM (ATE {100 * e_slam:.1f} cm)")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.legend(loc="best", fontsize=8)
        ax.set_title(f"first {len(log)} scans, drift ×{drift:g}, range noise {range_noise_cm:g} cm")
        return fig

    return Explorer(
        draw,
        {
            "drift": slider(1.0, 0.0, 4.0, 0.25, "odometry drift (× drifting)"),
            "range_noise_cm": slider(1.0, 0.0, 8.0, 0.5, "range noise σ [cm]"),
            "seed": slider(int(seed), 0, 20, 1, "seed"),
        },
        "SLAM under noise: odometry drift and range noise",
    )
