"""Shared fixtures: small worlds built in the test, and the location of the real logs."""

from __future__ import annotations

import os
import time
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


def blind_turn(log, degrees, before, blind, after):
    """``log`` (a route driven twice) cut ``after`` metres into its second lap, blind for
    ``blind`` scans (every range NaN) from ``before`` metres ahead of the first lap's end,
    while its odometry turns ``degrees`` too far (spread over the blind scans, kept after):
    the estimate comes back to the start turned and shifted by an amount no scan could
    correct on the way."""
    from dataclasses import replace

    from fhslam.geometry import compose, relative

    travelled = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(log.truth[:, :2], axis=0).T))])
    lap = travelled[-1] / 2
    a = int(np.searchsorted(travelled, lap - before))
    end = int(np.searchsorted(travelled, lap + after))
    odometry = log.odometry.copy()
    for k in range(a, len(odometry)):
        turn = np.radians(degrees) * min(1.0, (k - a) / blind)
        odometry[k] = compose(
            log.odometry[a], compose([0, 0, turn], relative(log.odometry[a], log.odometry[k]))
        )
    ranges = log.ranges.copy()
    ranges[a : a + blind] = np.nan
    return replace(
        log, timestamps=log.timestamps[:end], ranges=ranges[:end], odometry=odometry[:end],
        truth=log.truth[:end], hits=None if log.hits is None else log.hits[:end],
    )  # fmt: skip


# --------------------------------------------------------------------------------------------
# Tiers. Plain ``pytest`` runs the fast tier: unit, property, small CLI and file tests, a
# couple of minutes on 2 cores. ``--all-tiers`` adds the slow tier (whole logs, sweeps,
# goldens, notebooks run in a kernel, the browser); with ``--nbval-lax`` the notebooks too.
# ``-m`` selects by marker as usual (``-m slow``, ``-m browser``) and overrides the default.
# Every run spreads the files over the cores, a file to a worker (pytest-xdist, ``-n auto
# --dist loadfile`` in pyproject's addopts): a notebook's cells share one kernel, in order,
# and a module's whole-log runs cached for its tests are made once.

SLOW_MODULES = {
    "test_browser.py",  # JupyterLab in headless Chromium
    "test_gaps.py",  # the default SLAM on worlds with scans missing in a row
    "test_golden.py",  # whole-log trajectories and maps pinned to the bit
    "test_graphslam.py",  # the default SLAM on simulated worlds, whole runs
    "test_real_logs.py",  # every real log with the default SLAM, and its degradations
    "test_invariance.py",  # the default SLAM on worlds moved and turned
    "test_log_sweep.py",  # degraded copies of logs, in parallel
    "test_parameters.py",  # the default SLAM run once per parameter
    "test_sweep.py",  # seeds x noise levels x methods
    "test_unseen_worlds.py",  # random worlds driven three laps
}
"""Test modules of the slow tier, whole."""

SLOW_TESTS = {  # each over a second or so on 2 cores (pytest --durations)
    "test_benchmark.py::test_a_rerun_of_the_shortest_log_gives_the_committed_row",
    "test_benchmark.py::test_a_rerun_draws_the_world_again_and_keeps_the_log_draws",
    "test_cli.py::test_an_output_never_overwrites_an_input",
    "test_cli.py::test_bench_bad_scans_is_one_line_exit_2",
    "test_cli.py::test_bench_profile_prints_where_the_time_goes",
    "test_cli.py::test_bench_table_has_every_extractor",
    "test_cli.py::test_bench_unknown_log_is_the_slam_error",
    "test_cli.py::test_evaluate_map_of_the_true_walls",
    "test_cli.py::test_evaluate_plot_over_an_input_writes_nothing",
    "test_cli.py::test_reproduce_writes_figures_1_to_14",
    "test_cli.py::test_simulate_bad_options_are_one_line_exit_2",
    "test_cli.py::test_simulate_shows_progress_on_a_long_route_unless_quiet",
    "test_cli.py::test_slam_bad_robustness_option_is_a_usage_error",
    "test_cli.py::test_slam_bad_set_is_named_and_writes_nothing",
    "test_cli.py::test_slam_graph_is_refused_for_a_method_without_one",
    "test_cli.py::test_slam_graph_writes_the_keyframes_and_loop_closures",
    "test_cli.py::test_slam_max_range_drops_far_readings",
    "test_cli.py::test_slam_methods_through_the_command_line",
    "test_cli.py::test_slam_on_a_dataset_name_then_relations",
    "test_cli.py::test_slam_plot_writes_a_picture_of_the_run",
    "test_cli.py::test_slam_reads_a_bag_and_a_bag_without_odometry_exits_2",
    "test_cli.py::test_slam_then_evaluate_beats_odometry",
    "test_ekf.py::test_ekf_halves_the_odometry_error_on_held_out_worlds",
    "test_exercises.py::test_every_solution_passes_its_check",
    "test_explorers.py::test_every_slider_changes_the_drawing_in_one_step",
    "test_hostile.py::test_the_installed_command_on_a_sample_of_the_corpus",
    "test_hostile_commands.py::test_reproduce_interrupted_leaves_no_figure_and_no_folder",
    "test_hostile_commands.py::test_reproduce_that_fails_midway_leaves_no_figure_and_no_folder",
    "test_hostile_commands.py::test_run_notebooks_interrupted_names_the_notebook_left_as_it_was",
    "test_hostile_commands.py::test_slam_interrupted_prints_one_line_and_leaves_nothing",
    "test_hostile_commands.py::test_sweep_interrupted_prints_one_line_and_no_leaked_semaphores",
    "test_hostile_commands.py::test_sweep_warns_once_of_an_unknown_world_key",
    "test_hostile_errors.py::test_a_package_and_home_that_cannot_be_written_cache_in_a_private_temp_folder",
    "test_hostile_errors.py::test_a_writable_cache_folder_of_the_user_is_taken_first",
    "test_hostile_errors.py::test_bytes_damaged_across_a_small_bag_end_cleanly",
    "test_hostile_errors.py::test_no_writable_cache_folder_at_all_compiles_without_one_saying_so_once",
    "test_hostile_inputs.py::test_a_log_with_gigabytes_of_nul_bytes_is_read_in_bounded_memory",
    "test_house.py::test_readme_command_line_examples_run",
    "test_house.py::test_readme_python_example_runs",
    "test_kernels.py::test_graph_slam_gives_the_same_poses_with_and_without_the_loop_target_cache",
    "test_kernels.py::test_likelihood_grid_equals_opencv_construction",
    "test_no_return.py::test_a_log_without_no_return_beams_loses_no_reading",
    "test_no_return.py::test_simulated_logs_read_with_their_range",
    "test_no_return.py::test_slam_is_as_good_on_readings_rounded_to_1_cm",
    "test_no_return.py::test_the_code_is_found_whatever_the_rounding_stops_and_glitches",
    "test_no_return.py::test_the_real_logs_keep_their_range_and_code",
    "test_relations.py::test_evaluate_relations_errors_are_one_line",
    "test_results.py::test_the_committed_fht_run_starts_as_a_run_now",
    "test_results.py::test_the_committed_graph_run_is_the_one_test_real_logs_measures",
    "test_rosbag.py::test_fr079_loaded_as_a_dataset_gets_its_original_mount",
    "test_rosbag.py::test_intel_bag_matches_its_relations_and_published_odometry_error",
    "test_sim.py::test_drifting_preset_drift_over_seeds_as_documented",
    "test_slam.py::test_dropped_scans_and_clutter_at_most_double_the_ate",
    "test_slam.py::test_fh_slam_on_held_out_worlds_meets_its_limits",
    "test_slam.py::test_laser_mounted_off_the_robot_origin_reports_robot_poses",
    "test_slam.py::test_perfect_odometry_stays_on_the_truth",
    "test_special_outputs.py::test_a_non_ascii_name_under_the_c_locale_is_written",
    "test_special_outputs.py::test_simulate_writes_the_truth_to_standard_output",
    "test_tracker.py::test_an_odometry_glitch_is_absorbed",
    "test_tracker.py::test_a_sparse_copy_is_tracked",
    "test_workbook.py::test_a_rerun_that_changes_nothing_leaves_the_notebook_as_it_was",
}
"""Single tests of the slow tier (``module::name``, parameters included)."""

TIERS = ("fast", "slow", "browser", "notebooks")


def _tier(nodeid: str) -> str:
    """The tier of the test ``nodeid`` (``tests/test_x.py::name[params]``)."""
    path, _, name = nodeid.partition("::")
    module = Path(path).name
    if module.endswith(".ipynb"):
        return "notebooks"
    if module == "test_browser.py":
        return "browser"
    base = name.split("[")[0]
    return "slow" if module in SLOW_MODULES or f"{module}::{base}" in SLOW_TESTS else "fast"


def pytest_addoption(parser):
    parser.addoption(
        "--all-tiers",
        action="store_true",
        help="run every tier (fast, slow, browser; with --nbval-lax the notebooks), not only "
        "the fast one",
    )


class _TierClock:
    """Adds up each tier's test time (setup, call, teardown), for the summary's line, and
    the run's wall time (with ``-n``, pytest-xdist's workers run tests side by side, so
    the tiers' times add up to more than it). A plugin of its own, so that it also hears
    the notebooks' cells, which lie outside ``tests/`` and so outside this file's hooks."""

    def __init__(self) -> None:
        self.seconds = dict.fromkeys(TIERS, 0.0)
        self.counts = dict.fromkeys(TIERS, 0)
        self.start = time.perf_counter()

    def pytest_runtest_logreport(self, report) -> None:
        tier = _tier(report.nodeid)
        self.seconds[tier] += report.duration
        if report.when == "call":
            self.counts[tier] += 1

    def pytest_terminal_summary(self, terminalreporter) -> None:
        ran = [(t, self.counts[t], self.seconds[t]) for t in TIERS if self.counts[t]]
        if ran:
            wall = (time.perf_counter() - self.start) / 60
            terminalreporter.write_line(
                "tiers: "
                + ", ".join(f"{t} {n} tests in {s / 60:.1f} min" for t, n, s in ran)
                + f"; wall {wall:.1f} min"
            )


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: the slow tier (whole logs, sweeps, goldens)")
    config.addinivalue_line("markers", "browser: the browser tier (JupyterLab in Chromium)")
    config.addinivalue_line("markers", "notebooks: the notebooks under nbval")
    if not hasattr(config, "workerinput"):  # the controller (or a run without xdist)
        config.pluginmanager.register(_TierClock(), "fhslam-tier-clock")


def pytest_collection_modifyitems(config, items):
    for item in items:
        tier = _tier(item.nodeid)
        if tier != "fast":
            item.add_marker(getattr(pytest.mark, tier))
    if config.getoption("--all-tiers") or config.option.markexpr:
        return
    keep = [i for i in items if _tier(i.nodeid) in ("fast", "notebooks")]
    dropped = [i for i in items if _tier(i.nodeid) not in ("fast", "notebooks")]
    if dropped:
        config.hook.pytest_deselected(items=dropped)
        items[:] = keep
