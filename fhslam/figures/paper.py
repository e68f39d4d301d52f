"""The paper's figures drawn: every figure written to files by :func:`reproduce`.

The data each figure shows comes from :mod:`fhslam.figures.scenes`; this module only draws.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import matplotlib.pyplot as plt
from matplotlib.figure import Figure

from fhslam.figures.loop1 import (
    fig01_hough_principle,
    fig02_environment,
    fig03_extended_points,
    fig04_clusters,
    fig05_lines,
)
from fhslam.figures.loop2 import fig06_line_attributes, fig07_to_10_similarity, fig11_merging
from fhslam.figures.scenes import (
    SEED,
    figure_scan,
    paper_log,
    slam_log,
)
from fhslam.figures.slam import fig12_pioneer, fig13_environment_map, fig14_slam_result
from fhslam.io.files import atomic_output, output_batch, output_folder
from fhslam.pipeline import run_slam


def reproduce(out_dir: str | Path = "figures", seed: int = SEED, what: str = "") -> list[Path]:
    """Write the reproduced figures as PNG files into ``out_dir``; return their paths.

    The folder is created if missing and checked writable before anything is computed; the
    figures appear all together once every one is drawn, or none (a failure or Ctrl-C leaves
    no figure, and no folder it created).

    Raises
    ------
    InputError
        If ``out_dir`` is a file, cannot be created or is not writable; ``what`` names it in
        the message (default: the path).
    """
    with output_folder(out_dir, what or str(out_dir)) as out, output_batch():
        log = paper_log(seed)
        drift_log = slam_log(seed)
        k = figure_scan(log)
        makers: dict[str, Callable[[], Figure]] = {
            "fig01_hough_principle": fig01_hough_principle,
            "fig02_environment": lambda: fig02_environment(log, k),
            "fig03_extended_points": lambda: fig03_extended_points(log, k),
            "fig04_clusters": lambda: fig04_clusters(log, k),
            "fig05_lines": lambda: fig05_lines(log, k),
            "fig06_line_attributes": fig06_line_attributes,
            "fig07_10_similarity": fig07_to_10_similarity,
            "fig11_merging": fig11_merging,
            "fig12_pioneer": fig12_pioneer,
            "fig13_environment_map": lambda: fig13_environment_map(log.world),
            "fig14_slam_result": lambda: fig14_slam_result(drift_log, run_slam(drift_log, "fht")),
        }
        paths = []
        for name, make in makers.items():
            fig = make()
            path = out / f"{name}.png"
            try:
                with atomic_output(path, "wb") as f:
                    fig.savefig(f, format="png", dpi=110, bbox_inches="tight",
                                metadata={"Software": None})  # fmt: skip
            finally:
                plt.close(fig)
            paths.append(path)
    return paths
