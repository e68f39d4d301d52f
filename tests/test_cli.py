"""The fhslam command: outputs, round trips, and one-line errors with exit status 2."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from fhslam.cli import main
from fhslam.io import read_carmen, read_trajectory
from fhslam.sim import paper_world, simulate
from fhslam.slam.graph import KeyframeParams, LoopParams, TrackerParams


def run(*args: str) -> subprocess.CompletedProcess:
    """The installed console entry point, as a user calls it."""
    return subprocess.run(
        [sys.executable, "-m", "fhslam.cli", *args], capture_output=True, text=True, timeout=300
    )


def test_simulate_writes_a_log_that_reads_back_exactly(tmp_path):
    log_path, truth_path = tmp_path / "paper.clf", tmp_path / "truth.txt"
    assert (
        main(
            ["simulate", "paper", "--seed", "3", "--log", str(log_path), "--truth", str(truth_path)]
        )
        == 0
    )
    expected = simulate(paper_world(), seed=3)
    log = read_carmen(log_path)
    assert len(log) == len(expected) == 916
    np.testing.assert_array_equal(log.ranges, expected.ranges)
    np.testing.assert_array_equal(log.odometry, expected.odometry)
    t, poses = read_trajectory(truth_path)
    np.testing.assert_array_equal(t, expected.timestamps)
    np.testing.assert_array_equal(poses, expected.truth)
    # The log carries odometry, never truth: they differ once the odometry has drifted.
    assert np.abs(log.odometry[-1, :2] - poses[-1, :2]).max() > 0.1


BOX = {
    "name": "box",
    "walls": [[0, 0, 6, 0], [6, 0, 6, 4], [6, 4, 0, 4], [0, 4, 0, 0]],
    "route": [[1, 1], [5, 1], [5, 3]],
}
"""A 6 x 4 m room and a route through it (a world file's keys)."""


def test_simulate_accepts_a_world_file(tmp_path):
    world = tmp_path / "box.json"
    world.write_text(json.dumps(BOX))
    out = tmp_path / "box.clf"
    assert main(["simulate", str(world), "--log", str(out), "--truth", str(tmp_path / "t")]) == 0
    assert len(read_carmen(out)) > 10


def test_slam_odometry_of_a_log_counting_turns_stays_in_minus_pi_pi(tmp_path):
    """A CARMEN log whose headings are theta + 2 pi (a logger counting the turns): the
    trajectories written are in (-pi, pi], the same as the plain log's."""
    from test_carmen import _count_turns

    plain = tmp_path / "p.clf"
    assert main(["simulate", "paper", "--seed", "0", "--log", str(plain), "--truth",
                 str(tmp_path / "truth.txt"), "--quiet"]) == 0  # fmt: skip
    turned = tmp_path / "rot.clf"
    turned.write_text(_count_turns(plain.read_text(), 1))
    for log, out in ((plain, "o0.txt"), (turned, "o.txt")):
        args = ["slam", str(log), "--method", "odometry", "--trajectory", str(tmp_path / out)]
        assert main([*args, "--quiet"]) == 0
    _, poses = read_trajectory(tmp_path / "o.txt")
    _, want = read_trajectory(tmp_path / "o0.txt")
    assert np.all((poses[:, 2] > -np.pi) & (poses[:, 2] <= np.pi))
    assert poses[0, 2] == 0.0
    np.testing.assert_allclose(poses, want, rtol=0, atol=1e-12)


def test_simulate_wraps_the_start_heading_of_a_world_file(tmp_path):
    world = tmp_path / "box.json"
    world.write_text(json.dumps({**BOX, "start": [1, 1, 7.0]}))
    log, truth = tmp_path / "box.clf", tmp_path / "t.txt"
    assert main(["simulate", str(world), "--log", str(log), "--truth", str(truth), "--quiet"]) == 0
    _, poses = read_trajectory(truth)
    assert poses[0, 2] == pytest.approx(7.0 - 2 * np.pi, abs=1e-12)
    assert np.all((poses[:, 2] > -np.pi) & (poses[:, 2] <= np.pi))
    odometry = read_carmen(log).odometry[:, 2]
    assert np.all((odometry > -np.pi) & (odometry <= np.pi))


def test_info_summarises_a_log(tmp_path, capsys):
    out = tmp_path / "paper.clf"
    main(["simulate", "paper", "--log", str(out), "--truth", str(tmp_path / "t.txt")])
    capsys.readouterr()
    assert main(["info", str(out)]) == 0
    text = capsys.readouterr().out
    assert "916 scans of 181 beams" in text
    # write_carmen states the (zero) mount of a simulated log in PARAM lines
    assert "laser offset x 0 m, y 0 m, theta 0 deg (from the log's PARAM lines)" in text
    median_lines = float(text.rsplit(":", 1)[1])
    assert 3 <= median_lines <= 15  # an office seen over 180°: several walls per scan


def test_info_reports_the_laser_offset_and_its_source(tmp_path, capsys):
    from dataclasses import replace

    from fhslam.io import write_carmen

    log = simulate(paper_world(), seed=0, max_scans=5)
    mounted = tmp_path / "mounted.clf"
    write_carmen(replace(log, laser_offset=np.array([0.25, -0.1, np.radians(30)])), mounted)
    assert main(["info", str(mounted)]) == 0
    text = capsys.readouterr().out
    assert "laser offset x 0.25 m, y -0.1 m, theta 30 deg (from the log's PARAM lines)" in text

    # No PARAM lines; laser poses 4 cm ahead of the odometry on every line.
    rows = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.5), (1.5, 0.5, 1.0)]
    lines = []
    for k, (x, y, th) in enumerate(rows):
        lx, ly = x + 0.04 * np.cos(th), y + 0.04 * np.sin(th)
        ranges = " ".join(["2.0"] * 181)
        lines.append(f"FLASER 181 {ranges} {lx:f} {ly:f} {th:f} {x:f} {y:f} {th:f} {k}.0 h {k}.0")
    posed = tmp_path / "posed.clf"
    posed.write_text("\n".join(lines) + "\n")
    assert main(["info", str(posed)]) == 0
    text = capsys.readouterr().out
    assert "laser offset x 0.04 m, y 0 m, theta 0 deg (from the laser poses" in text

    # Laser poses that are not odometry + a constant: no mount.
    lines[1] = lines[1].replace(f"{1.0 + 0.04 * np.cos(0.5):f}", "1.300000", 1)
    posed.write_text("\n".join(lines) + "\n")
    assert main(["info", str(posed)]) == 0
    text = capsys.readouterr().out
    assert "laser offset x 0 m, y 0 m, theta 0 deg (none stated in the log" in text


@pytest.mark.parametrize(
    ("content", "lineno"),
    [
        ("FLASER 3 1.0 2.0 3.0 0 0 0 0 0 0 1.0 host 1.0\nFLASER 3 1.0 2.0\n", 2),
        ("# header\nFLASER 3 1.0 x 3.0 0 0 0 0 0 0 1.0 host 1.0\n", 2),
        ("FLASER 4 1.0 2.0 3.0 0 0 0 0 0 0 1.0 host 1.0\n", 1),
    ],
    ids=["truncated", "non-numeric", "wrong-count"],
)
def test_malformed_log_line_is_one_line_error_naming_file_and_line(tmp_path, content, lineno):
    bad = tmp_path / "bad.clf"
    bad.write_text(content)
    r = run("info", str(bad))
    assert r.returncode == 2
    assert r.stdout == ""
    assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr
    assert f"bad.clf:{lineno}:" in r.stderr


def test_missing_file_and_unknown_world_exit_2(tmp_path):
    r = run("info", str(tmp_path / "nope.clf"))
    assert r.returncode == 2 and "nope.clf" in r.stderr and "Traceback" not in r.stderr
    r = run("simulate", "atlantis", "--log", str(tmp_path / "a"), "--truth", str(tmp_path / "b"))
    assert r.returncode == 2 and "atlantis" in r.stderr and "paper" in r.stderr
    assert not (tmp_path / "a").exists()


def test_bad_world_json_names_the_file(tmp_path):
    bad = tmp_path / "w.json"
    bad.write_text('{"name": "w", "walls": [[0, 0, 1]], "route": [[0, 0], [1, 1]]}')
    r = run("simulate", str(bad), "--log", str(tmp_path / "a"), "--truth", str(tmp_path / "b"))
    assert r.returncode == 2 and "w.json" in r.stderr


def test_reproduce_writes_figures_1_to_14(tmp_path):
    r = run("reproduce", "--out", str(tmp_path))
    assert r.returncode == 0, r.stderr
    names = sorted(p.name for p in tmp_path.glob("*.png"))
    assert names == [
        "fig01_hough_principle.png",
        "fig02_environment.png",
        "fig03_extended_points.png",
        "fig04_clusters.png",
        "fig05_lines.png",
        "fig06_line_attributes.png",
        "fig07_10_similarity.png",
        "fig11_merging.png",
        "fig12_pioneer.png",
        "fig13_environment_map.png",
        "fig14_slam_result.png",
    ]
    assert all((tmp_path / n).stat().st_size > 20_000 for n in names)  # real pictures


def test_bench_table_has_every_extractor(capsys):
    assert main(["bench", "--scans", "2", "--repeats", "1", "--quiet"]) == 0
    out = capsys.readouterr().out
    for name in (
        "cv2.HoughLinesPointSet call",
        "fast Hough (fhslam)",
        "split-and-merge",
        "NumPy full accumulator",
        "OpenCV HoughLinesP (raster)",
    ):
        assert name in out
    slam_rows = [
        ln.split()
        for ln in out.splitlines()
        if ln.split()[:1] in (["fht"], ["graph"], ["classical"], ["ekf"])
    ]
    assert [r[0] for r in slam_rows] == ["fht", "graph", "classical", "ekf"]
    assert all(float(r[1]) > 0 for r in slam_rows)  # steps per second


@pytest.fixture(scope="module")
def short_clf(tmp_path_factory):
    """60 scans of the paper world as a CARMEN log."""
    from fhslam.io import write_carmen

    path = tmp_path_factory.mktemp("bench") / "short.clf"
    write_carmen(simulate(paper_world(), seed=0, max_scans=60), path)
    return path


def test_bench_on_a_log_prints_the_stage_table(short_clf, capsys):
    assert main(["bench", "--log", str(short_clf), "--scans", "20", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "short (graph): 20 scans" in out and "scans/s" in out and "real time" in out
    rows = {ln.split()[0]: ln.split() for ln in out.splitlines() if ln.split()}
    for stage in ("extraction", "tracking", "optimisation", "map", "other", "total"):
        assert stage in rows
    assert "local map" in out and "loop closure" in out
    assert rows["total"][2] == "100.0%"
    assert float(rows["total"][1]) >= float(rows["tracking"][1]) >= 0  # ms/scan


def test_bench_on_a_log_with_another_method(short_clf, capsys):
    argv = ["bench", "--log", str(short_clf), "--method", "fht", "--scans", "10", "--quiet"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "short (fht): 10 scans" in out and "association" in out


def test_bench_profile_prints_where_the_time_goes(short_clf):
    r = run("bench", "--log", str(short_clf), "--scans", "20", "--quiet", "--profile")
    assert r.returncode == 0, r.stderr
    assert "20 scans" in r.stdout and "cumulative" not in r.stdout
    assert "Ordered by: cumulative time" in r.stderr and "run_log_bench" in r.stderr


@pytest.mark.parametrize("scans", ["0", "-5"])
def test_bench_bad_scans_is_one_line_exit_2(short_clf, scans):
    for argv in (["bench", "--log", str(short_clf), "--scans", scans], ["bench", "--scans", scans]):
        r = run(*argv)
        assert r.returncode == 2 and r.stdout == ""
        assert r.stderr == f"fhslam: error: --scans must be a positive number, got {scans}\n"


def test_bench_unknown_log_is_the_slam_error(tmp_path):
    bench = run("bench", "--log", "atlantis", "--quiet")
    slam = run("slam", "atlantis", "--trajectory", str(tmp_path / "t.txt"), "--quiet")
    assert bench.returncode == slam.returncode == 2
    assert bench.stderr == slam.stderr and bench.stderr.count("\n") == 1
    assert "atlantis" in bench.stderr and "Traceback" not in bench.stderr


def test_bench_log_options_need_log():
    r = run("bench", "--method", "fht")
    assert r.returncode == 2 and r.stderr == "fhslam: error: --method: only with --log\n"


# ----------------------------------------------------------------------------- evaluate


@pytest.fixture(scope="module")
def truth_file(tmp_path_factory):
    """The ground truth of the paper world (seed 0), written as a truth file."""
    from fhslam.io import write_trajectory

    log = simulate(paper_world(), seed=0)
    path = tmp_path_factory.mktemp("evaluate") / "truth.txt"
    write_trajectory(path, log.timestamps, log.truth, header="truth: timestamp x y theta")
    return path


def test_evaluate_truth_against_itself_is_zero(truth_file, capsys):
    assert main(["evaluate", str(truth_file), "--truth", str(truth_file), "--json"]) == 0
    out = capsys.readouterr().out
    assert out.count("\n") == 1  # one JSON object
    result = json.loads(out)
    assert result["ate_rmse"] == 0.0 and result["rpe_trans_mean"] < 1e-12
    assert result["n_poses"] == 916
    for key in ("ate_mean", "ate_median", "ate_std", "ate_min", "ate_max", "rpe_trans_rmse"):
        assert key in result
    assert "rpe_rot_mean_deg" in result and "map_error" not in result


def test_evaluate_shifted_copy_gives_half_a_metre(truth_file, tmp_path, capsys):
    from fhslam.io import write_trajectory

    t, poses = read_trajectory(truth_file)
    shifted = tmp_path / "shifted.txt"
    write_trajectory(shifted, t + 0.004, poses + np.array([0.3, 0.4, 0.0]))  # jittered stamps
    assert main(["evaluate", str(shifted), "--truth", str(truth_file), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["ate_rmse"] == pytest.approx(0.5, abs=1e-12)
    assert result["ate_max"] == pytest.approx(0.5, abs=1e-12)
    assert result["rpe_trans_max"] < 1e-12
    assert result["n_poses"] == 916
    # The same with --align is 0, and the readable table says so.
    assert main(["evaluate", str(shifted), "--truth", str(truth_file), "--align"]) == 0
    text = capsys.readouterr().out
    assert "ATE aligned (m)" in text and "RPE rot (deg)" in text and "916 poses" in text


def test_evaluate_malformed_trajectory_line(truth_file, tmp_path):
    bad = tmp_path / "traj.txt"
    bad.write_text("# t x y theta\n0.0 0 0 0\n0.2 0 0\n")
    r = run("evaluate", str(bad), "--truth", str(truth_file), "--json")
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr
    assert "traj.txt:3:" in r.stderr


def test_evaluate_needs_two_matched_poses(truth_file, tmp_path):
    late = tmp_path / "late.txt"
    late.write_text("1000.0 0 0 0\n1000.2 0 0 0\n")
    r = run("evaluate", str(late), "--truth", str(truth_file))
    assert r.returncode == 2 and r.stderr.count("\n") == 1
    assert "late.txt" in r.stderr and "truth.txt" in r.stderr and "only 0 poses" in r.stderr


def test_evaluate_map_of_the_true_walls(truth_file, tmp_path, capsys):
    from fhslam.io import lines_from_segments, write_map

    map_path = tmp_path / "walls.json"
    write_map(map_path, lines_from_segments(paper_world().walls))
    argv = ["evaluate", str(truth_file), "--truth", str(truth_file)]
    assert main([*argv, "--world", "paper", "--map", str(map_path), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["map_error"] < 1e-9
    assert result["map_coverage"] > 0.99
    assert result["n_map_lines"] == len(paper_world().walls)
    # Half the walls: the coverage drops, the error stays 0.
    write_map(map_path, lines_from_segments(paper_world().walls[::2]))
    assert main([*argv, "--world", "paper", "--map", str(map_path), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["map_error"] < 1e-9 and 0.1 < result["map_coverage"] < 0.9
    # --world without --map, and a malformed map: one-line errors.
    r = run(*argv, "--world", "paper")
    assert r.returncode == 2 and "--map" in r.stderr and r.stderr.count("\n") == 1
    map_path.write_text('{"lines": [{"sp": [0, 0]}]}')
    r = run(*argv, "--world", "paper", "--map", str(map_path))
    assert r.returncode == 2 and "walls.json: lines[0]" in r.stderr
    assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr


def _simulate_drifting(tmp_path, world):
    """``fhslam simulate WORLD`` with drifting odometry, 3 laps: the log and truth paths."""
    log, truth = tmp_path / "sim.clf", tmp_path / "truth.txt"
    argv = ["simulate", world, "--odometry", "drifting", "--laps", "3"]
    assert main([*argv, "--log", str(log), "--truth", str(truth)]) == 0
    return log, truth


def test_slam_then_evaluate_beats_odometry(tmp_path):
    """The default method (no --method) against dead reckoning, through the commands."""
    log, truth = _simulate_drifting(tmp_path, "random:105")
    slam, odo, mp = tmp_path / "slam.txt", tmp_path / "odo.txt", tmp_path / "map.json"
    r = run("slam", str(log), "--trajectory", str(slam), "--map", str(mp), "--quiet")
    assert r.returncode == 0, r.stderr
    assert main(["slam", str(log), "--method", "odometry", "--trajectory", str(odo)]) == 0
    t_slam, _ = read_trajectory(slam)
    t_log = read_carmen(log).timestamps
    np.testing.assert_array_equal(t_slam, t_log)  # one line per scan, the scan's own stamp
    scores = {}
    for name, traj in [("slam", slam), ("odo", odo)]:
        r = run(
            "evaluate",
            str(traj),
            "--truth",
            str(truth),
            "--world",
            "random:105",
            "--map",
            str(mp),
            "--json",
        )
        assert r.returncode == 0, r.stderr
        scores[name] = json.loads(r.stdout)
    assert scores["odo"]["ate_rmse"] > 1.0  # drifting odometry
    assert scores["slam"]["ate_rmse"] < 0.2 * scores["odo"]["ate_rmse"]
    assert scores["slam"]["map_error"] < 0.05 and scores["slam"]["map_coverage"] > 0.8


def test_slam_graph_writes_the_keyframes_and_loop_closures(tmp_path, capsys):
    """``--graph`` (graph method): every keyframe is a scan of the trajectory, at its pose;
    the closures of three laps are there; the trajectory is the one without ``--graph``."""
    from fhslam.io import read_graph

    log, _ = _simulate_drifting(tmp_path, "random:105")
    capsys.readouterr()
    traj, graph = tmp_path / "t.txt", tmp_path / "g.json"
    argv = ["slam", str(log), "--trajectory", str(traj), "--graph", str(graph), "--quiet"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    t, poses = read_trajectory(traj)
    g = read_graph(graph)
    assert out == (
        f"wrote {len(t)} poses to {traj} and {len(g)} keyframes and {len(g.active)} loop "
        f"closures ({g.n_active} active) to {graph}\n"
    )
    assert 50 < len(g) < len(t) and g.n_active > 10  # three laps: closures on laps 2 and 3
    assert g.timestamps[0] == t[0] and np.all(np.diff(g.timestamps) > 0)
    k = np.searchsorted(t, g.timestamps)
    np.testing.assert_array_equal(t[k], g.timestamps)
    np.testing.assert_allclose(g.poses, poses[k], rtol=0, atol=1e-9)
    assert np.all(g.loops[:, 0] < g.loops[:, 1]) and np.all(g.scores > 0)
    assert main(["slam", str(log), "--trajectory", str(tmp_path / "u.txt"), "--quiet"]) == 0
    np.testing.assert_array_equal(read_trajectory(tmp_path / "u.txt")[1], poses)


def test_slam_plot_writes_a_picture_of_the_run(tmp_path, capsys):
    """``--plot PNG``: a picture of the run, written with the other outputs (what it shows:
    ``tests/test_figures.py``); the trajectory is the one without ``--plot``."""
    import matplotlib.image

    log, _ = _simulate_drifting(tmp_path, "random:105")
    capsys.readouterr()
    for method in ("graph", "fht"):
        traj, png = tmp_path / f"{method}.txt", tmp_path / f"{method}.png"
        argv = ["slam", str(log), "--method", method, "--trajectory", str(traj), "--plot",
                str(png), "--quiet"]  # fmt: skip
        assert main(argv) == 0
        n = len(read_trajectory(traj)[0])
        assert capsys.readouterr().out == (
            f"wrote {n} poses to {traj} and a picture of the run to {png}\n"
        )
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        image = matplotlib.image.imread(png)
        assert image.ndim == 3 and image.shape[0] > 400 and image.shape[1] > 400
        assert image[..., :3].std() > 0.05  # not a blank page
        plain = tmp_path / f"{method}_plain.txt"
        assert (
            main(["slam", str(log), "--method", method, "--trajectory", str(plain), "--quiet"]) == 0
        )
        np.testing.assert_array_equal(read_trajectory(plain)[1], read_trajectory(traj)[1])
        capsys.readouterr()


def test_slam_plot_into_a_missing_folder_writes_nothing(short_clf, tmp_path):
    traj, png = tmp_path / "t.txt", tmp_path / "no" / "such" / "run.png"
    r = run("slam", str(short_clf), "--trajectory", str(traj), "--plot", str(png))
    assert r.returncode == 2 and r.stdout == "" and "--plot" in r.stderr and str(png) in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1  # one line, no traceback
    assert list(tmp_path.iterdir()) == []  # not even the trajectory


@pytest.mark.parametrize("method", ["fht", "odometry"])
def test_slam_graph_is_refused_for_a_method_without_one(short_clf, tmp_path, method):
    traj, graph = tmp_path / "t.txt", tmp_path / "g.json"
    r = run("slam", str(short_clf), "--method", method, "--trajectory", str(traj), "--graph",
            str(graph))  # fmt: skip
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr == (
        f"fhslam: error: --graph: only with --method graph; the {method} method keeps no "
        "keyframe graph (nothing was written)\n"
    )
    assert list(tmp_path.iterdir()) == []
    r = run("slam", str(short_clf), "--trajectory", str(traj), "--graph", str(traj))
    assert r.returncode == 2 and "--graph" in r.stderr and "also given as --trajectory" in r.stderr
    assert list(tmp_path.iterdir()) == []


def test_slam_bad_log_leaves_no_output(tmp_path):
    bad = tmp_path / "bad.clf"
    bad.write_text("FLASER 3 1.0 2.0 3.0 0 0 0 0 0 0 1.0 host 1.0\nFLASER 3 1.0 nan?\n")
    out = tmp_path / "t.txt"
    r = run("slam", str(bad), "--trajectory", str(out))
    assert r.returncode == 2 and "bad.clf:2:" in r.stderr and "Traceback" not in r.stderr
    assert not out.exists()


def test_slam_unknown_method_is_a_usage_error(tmp_path):
    r = run("slam", "x.clf", "--method", "ekf9", "--trajectory", str(tmp_path / "t"))
    assert r.returncode == 2 and "invalid choice" in r.stderr


@pytest.mark.parametrize("method", ["ekf", "classical", "fht"])
def test_slam_methods_through_the_command_line(tmp_path, method):
    log, truth = _simulate_drifting(tmp_path, "random:107")
    traj, mp = tmp_path / "t.txt", tmp_path / "m.json"
    r = run(
        "slam", str(log), "--method", method, "--trajectory", str(traj), "--map", str(mp), "--quiet"
    )
    assert r.returncode == 0, r.stderr
    r = run("evaluate", str(traj), "--truth", str(truth), "--json")
    odo = run("slam", str(log), "--method", "odometry", "--trajectory", str(tmp_path / "o"))
    assert odo.returncode == 0
    o = json.loads(run("evaluate", str(tmp_path / "o"), "--truth", str(truth), "--json").stdout)
    assert json.loads(r.stdout)["ate_rmse"] <= 0.5 * o["ate_rmse"]


def test_slam_reads_a_bag_and_a_bag_without_odometry_exits_2(tmp_path):
    from test_rosbag import write_bag

    good = write_bag(tmp_path / "g.bag", scans=5)
    r = run("slam", str(good), "--trajectory", str(tmp_path / "t.txt"), "--quiet")
    assert r.returncode == 0, r.stderr
    t, _ = read_trajectory(tmp_path / "t.txt")
    np.testing.assert_allclose(t, [10, 11, 12, 13, 14])
    bad = write_bag(tmp_path / "n.bag", odom=False)
    r = run("slam", str(bad), "--trajectory", str(tmp_path / "u.txt"))
    assert r.returncode == 2 and "n.bag: the bag has no odometry" in r.stderr
    assert r.stderr.count("\n") == 1 and not (tmp_path / "u.txt").exists()


def test_slam_on_a_dataset_name_then_relations(tmp_path, real_data, monkeypatch):
    monkeypatch.setenv("FHSLAM_DATA", str(real_data))
    traj = tmp_path / "odo.txt"
    r = run("slam", "mit-csail", "--method", "odometry", "--trajectory", str(traj))
    assert r.returncode == 0, r.stderr
    r = run("evaluate", str(traj), "--relations", str(real_data / "mit-csail.relations"), "--json")
    out = json.loads(r.stdout)
    assert out["relations_used"] == out["relations_total"] == 1172
    assert 1.0 < out["relations_trans_mean"] < 3.0  # raw odometry: 1.68 m
    # the relations by dataset name give the same numbers
    by_name = run("evaluate", str(traj), "--relations", "mit-csail", "--json")
    assert json.loads(by_name.stdout) == out
    # another dataset's relations share no timestamps: one line, exit 2
    r = run("evaluate", str(traj), "--relations", "aces")
    assert r.returncode == 2 and "no relation can be used" in r.stderr
    assert r.stderr.count("\n") == 1


def _relations_case(folder):
    """A trajectory 1 % too long on a straight line and true relations 5 and 40 poses apart."""
    from fhslam.geometry import relative
    from fhslam.io import write_trajectory

    t = 100.0 + np.arange(60)
    truth = np.column_stack([0.1 * np.arange(60), np.zeros(60), np.zeros(60)])
    est = truth * [1.01, 1, 1]
    write_trajectory(folder / "est.txt", t, est)
    pairs = [(k, k + 5) for k in range(0, 55, 5)] + [(0, 40), (10, 50)]
    lines = [
        f"{t[a]} {t[b]} {r[0]} {r[1]} 0 0 0 {r[2]}"
        for a, b in pairs
        for r in [relative(truth[a], truth[b])]
    ]
    (folder / "case.relations").write_text("\n".join(lines) + "\n")
    return folder / "est.txt", folder / "case.relations"


def test_evaluate_plot_draws_the_errors(tmp_path, capsys):
    """``evaluate --plot PNG``: with ``--relations`` each relation's error over the run, with
    ``--truth`` the trajectory and each pose's error; the report (text or ``--json``) is as
    without it. What the figures show: ``tests/test_figures.py``."""
    import matplotlib.image

    from fhslam.io import write_trajectory

    traj, relations = _relations_case(tmp_path)
    assert main(["evaluate", str(traj), "--relations", str(relations), "--json"]) == 0
    plain = capsys.readouterr().out
    png = tmp_path / "rel.png"
    argv = ["evaluate", str(traj), "--relations", str(relations), "--plot", str(png)]
    assert main([*argv, "--json"]) == 0
    assert capsys.readouterr().out == plain  # one JSON object, nothing else
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "13 of 13 relations used" in out and out.endswith(
        f"wrote a picture of the errors to {png}\n"
    )
    t, est = read_trajectory(traj)
    write_trajectory(tmp_path / "truth.txt", t, est * [1 / 1.01, 1, 1])
    png2 = tmp_path / "ate.png"
    assert (
        main(["evaluate", str(traj), "--truth", str(tmp_path / "truth.txt"), "--plot", str(png2)])
        == 0
    )
    assert capsys.readouterr().out.endswith(f"wrote a picture of the errors to {png2}\n")
    for p in (png, png2):
        image = matplotlib.image.imread(p)
        assert image.ndim == 3 and image.shape[1] > 600 and image[..., :3].std() > 0.05


def test_evaluate_plot_over_an_input_writes_nothing(tmp_path):
    traj, relations = _relations_case(tmp_path)
    before = sorted(tmp_path.iterdir())
    r = run("evaluate", str(traj), "--relations", str(relations), "--plot", str(relations))
    assert r.returncode == 2 and r.stdout == "" and r.stderr.count("\n") == 1
    assert f"--plot {relations}: is the reference" in r.stderr
    assert sorted(tmp_path.iterdir()) == before
    r = run(
        "evaluate",
        str(traj),
        "--relations",
        str(relations),
        "--plot",
        str(tmp_path / "no" / "x.png"),
    )
    assert r.returncode == 2 and r.stdout == "" and r.stderr.count("\n") == 1
    assert sorted(tmp_path.iterdir()) == before


def test_info_reads_a_bag_and_reports_the_max_range(tmp_path, capsys):
    """``fhslam info`` reads whatever ``fhslam slam`` reads, here a ROS bag."""
    from test_rosbag import write_bag

    bag = write_bag(tmp_path / "g.bag", scans=5)
    assert main(["info", str(bag)]) == 0
    text = capsys.readouterr().out
    assert "5 scans of 181 beams" in text and "max range" in text
    assert main(["info", str(bag), "--max-range", "3.5"]) == 0
    assert "max range 3.5 m (--max-range)" in capsys.readouterr().out


def test_info_on_a_dataset_name_reports_the_no_return_reading(real_data, monkeypatch, capsys):
    monkeypatch.setenv("FHSLAM_DATA", str(real_data))
    assert main(["info", "mit-csail"]) == 0
    text = capsys.readouterr().out
    assert "no-return reading: 81.91 m" in text  # the SICK's 80 m mode code in this log
    # no PARAM lines; every laser pose is a copy of the odometry
    assert "laser offset x 0 m, y 0 m, theta 0 deg (from the laser poses" in text


@pytest.mark.parametrize("value", ["0", "-1", "inf", "nan", "far"])
def test_max_range_must_be_a_positive_number(tmp_path, value):
    r = run("info", "paper.clf", "--max-range", value)
    assert r.returncode == 2 and "--max-range" in r.stderr and "Traceback" not in r.stderr


def test_slam_max_range_drops_far_readings(tmp_path):
    """``--max-range`` overrides the log's: readings beyond it give no points, so a short
    range leaves fewer lines to match and the trajectory changes."""
    log_path = tmp_path / "p.clf"
    main(["simulate", "paper", "--log", str(log_path), "--truth", str(tmp_path / "t.txt")])
    for name, extra in (("full", []), ("short", ["--max-range", "1.0"])):
        out = tmp_path / f"{name}.txt"
        args = ["slam", str(log_path), "--trajectory", str(out), "--quiet", *extra]
        assert main(args) == 0
    _, full = read_trajectory(tmp_path / "full.txt")
    _, short = read_trajectory(tmp_path / "short.txt")
    assert not np.allclose(full, short, atol=1e-3)


def test_a_bug_is_not_reported_as_bad_input(monkeypatch, capsys):
    """Only an InputError is bad input (exit status 2): any other exception is a bug in the
    package, one line ``fhslam: internal error: ...`` and exit status 1, and ``--debug``
    shows its traceback instead."""
    import fhslam.cli.simulate

    def broken(args):
        raise ValueError("an internal inconsistency")

    monkeypatch.setattr(fhslam.cli.simulate, "run", broken)
    assert main(["simulate", "paper", "--log", "x.clf", "--truth", "t.txt"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("fhslam: internal error: ValueError: an internal inconsistency (")
    assert err.count("\n") == 1 and "--debug" in err
    with pytest.raises(ValueError, match="internal inconsistency"):
        main(["--debug", "simulate", "paper", "--log", "x.clf", "--truth", "t.txt"])


def test_an_output_that_cannot_be_written_is_one_line_and_leaves_nothing(tmp_path):
    r = run(
        "simulate", "paper", "--log", str(tmp_path / "no" / "dir" / "p.clf"), "--truth", "t.txt"
    )
    assert r.returncode == 2 and r.stderr.count("\n") == 1
    assert "p.clf: cannot write" in r.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("which", ["world", "log", "outputs"])
def test_an_output_never_overwrites_an_input(tmp_path, which):
    # `simulate W.json --log W.json` would overwrite the world, `slam X.clf --trajectory
    # X.clf` the log: refused before anything is read or written
    world = tmp_path / "box.json"
    world.write_text(
        json.dumps({"name": "box", "walls": [[0, 0, 6, 0], [6, 0, 6, 4], [6, 4, 0, 4],
                    [0, 4, 0, 0]], "route": [[1, 1], [5, 1], [5, 3]]})
    )  # fmt: skip
    log = tmp_path / "box.clf"
    assert main(["simulate", str(world), "--log", str(log), "--truth", str(tmp_path / "t")]) == 0
    before = {p: p.read_bytes() for p in (world, log)}
    if which == "world":
        r = run("simulate", str(world), "--log", str(world), "--truth", str(tmp_path / "t2"))
        assert "--log" in r.stderr and "is the input world file" in r.stderr
    elif which == "log":
        r = run("slam", str(log), "--trajectory", str(tmp_path / ".." / tmp_path.name / "box.clf"))
        assert "--trajectory" in r.stderr and "is the input log" in r.stderr
    else:
        r = run("slam", str(log), "--trajectory", str(tmp_path / "o"), "--map", str(tmp_path / "o"))
        assert "--map" in r.stderr and "also given as --trajectory" in r.stderr
    assert r.returncode == 2 and "Traceback" not in r.stderr and len(r.stderr.splitlines()) == 1
    assert {p: p.read_bytes() for p in (world, log)} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["box.clf", "box.json", "t"]


def test_an_implausible_log_warns_in_one_line_and_goes_on(tmp_path):
    path = tmp_path / "t.clf"
    ranges = "2.5 2.6 2.7 2.8 2.9"
    path.write_text(
        "".join(f"FLASER 5 {ranges} 0 0 0 0 0 0 {t} host {t}\n" for t in (0.0, 0.4, 0.2))
    )
    r = run("info", str(path))
    assert r.returncode == 0 and "Traceback" not in r.stderr
    assert r.stderr.splitlines() == [
        f"fhslam: warning: {path}:3: time goes backwards from the scan on line 2 (0.4 -> 0.2); "
        "read as it is"
    ]


@pytest.mark.parametrize(
    ("options", "message"),
    [
        # each a one-line error, not a traceback from deep inside the simulator or NumPy
        (["--seed", "-1"], "--seed must be a non-negative integer, got -1"),
        (["--laps", "0"], "--laps must be between 1 and 100, got 0"),
        (["--laps", "100000"], "--laps must be between 1 and 100, got 100000"),
        (["--laps", "2"], "--laps 2: world 'paper' has an open route"),
    ],
)
def test_simulate_bad_options_are_one_line_exit_2(tmp_path, options, message):
    r = run("simulate", "paper", *options, "--log", str(tmp_path / "x.clf"), "--truth",
            str(tmp_path / "x.txt"))  # fmt: skip
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert len(r.stderr.splitlines()) == 1 and r.stderr.startswith("fhslam: error: ")
    assert message in r.stderr
    assert list(tmp_path.iterdir()) == []


def usage_error(argv: list[str], capsys) -> str:
    """stderr of a command that argparse refuses (exit status 2), in this process."""
    with pytest.raises(SystemExit) as e:
        main(argv)
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return err


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        # each a one-line error, not a ValueError traceback from metrics/trajectory.py or
        # (inf) accepted without a word
        ("--delta", "0", "argument --delta: must be a whole number >= 1, got 0"),
        ("--delta", "-3", "argument --delta: must be a whole number >= 1, got -3"),
        ("--delta", "2.5", "argument --delta: not a whole number: '2.5'"),
        ("--max-diff", "-1", "argument --max-diff: must be a finite number of seconds >= 0"),
        ("--max-diff", "nan", "argument --max-diff: must be a finite number of seconds >= 0"),
        ("--max-diff", "inf", "argument --max-diff: must be a finite number of seconds >= 0"),
        ("--max-diff", "soon", "argument --max-diff: not a number: 'soon'"),
    ],
)
def test_evaluate_bad_delta_and_max_diff_are_usage_errors(truth_file, capsys, option, value,
                                                          message):  # fmt: skip
    err = usage_error(["evaluate", str(truth_file), "--truth", str(truth_file), option, value],
                      capsys)  # fmt: skip
    assert err.splitlines()[-1] == f"fhslam evaluate: error: {message}" or message in err


def test_evaluate_delta_beyond_the_matched_poses_is_one_line(truth_file, capsys):
    argv = ["evaluate", str(truth_file), "--truth", str(truth_file)]
    for delta in ("100000", "916"):
        assert main([*argv, "--delta", delta]) == 2
        assert capsys.readouterr().err == (
            f"fhslam: error: --delta {delta}: the RPE pairs poses {delta} frames apart, but "
            f"only 916 poses of {truth_file} match {truth_file}; give a --delta from 1 to 915\n"
        )
    assert main([*argv, "--delta", "915", "--max-diff", "0"]) == 0
    assert "RPE over 1 pairs 915 frame(s) apart" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        # a one-line error, not `ValueError: Maximum allowed size exceeded` from np.linspace
        (["--scans", "99999999999999999999"], "--scans must be between 1 and 1000 scans per"),
        (["--scans", "1001"], "--scans must be between 1 and 1000 scans per held-out world"),
        (["--repeats", "1001"], "--repeats must be between 1 and 1000, got 1001"),
    ],
)
def test_bench_huge_counts_are_one_line_exit_2(argv, message, capsys):
    assert main(["bench", *argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("fhslam: error: ") and message in err and err.count("\n") == 1


def test_bench_on_a_log_takes_more_scans_than_it_has(short_clf, capsys):
    # with --log, --scans only cuts the log: a count beyond it is all of it
    assert main(["bench", "--log", str(short_clf), "--scans", "99999999999999999999",
                 "--method", "odometry", "--quiet"]) == 0  # fmt: skip
    assert "short (odometry): 60 scans" in capsys.readouterr().out


def test_slam_writes_its_outputs_all_or_none(short_clf, tmp_path, monkeypatch, capsys):
    """A failure writing a later output (the map) leaves no earlier one (the trajectory)
    behind: the outputs are renamed into place together, or not at all."""
    import fhslam.io
    from fhslam.errors import InputError

    traj, old = tmp_path / "t.txt", "an old trajectory\n"
    traj.write_text(old)

    def fail(path, lines):
        raise InputError(f"{path}: cannot write (disk full)")

    monkeypatch.setattr(fhslam.io, "write_map", fail)
    argv = ["slam", str(short_clf), "--method", "odometry", "--trajectory", str(traj)]
    assert main([*argv, "--map", str(tmp_path / "m.json"), "--quiet"]) == 2
    assert "m.json: cannot write (disk full)" in capsys.readouterr().err
    assert traj.read_text() == old  # the old file stands, the new one never appeared
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.txt"]


def test_simulate_writes_its_outputs_all_or_none(tmp_path, monkeypatch, capsys):
    import fhslam.io
    from fhslam.errors import InputError

    def fail(path, *args, **kwargs):
        raise InputError(f"{path}: cannot write (disk full)")

    monkeypatch.setattr(fhslam.io, "write_trajectory", fail)
    argv = ["simulate", "hall", "--log", str(tmp_path / "h.clf"), "--truth", str(tmp_path / "t")]
    assert main(argv) == 2
    assert capsys.readouterr().err == f"fhslam: error: {tmp_path / 't'}: cannot write (disk full)\n"
    assert list(tmp_path.iterdir()) == []  # the log, complete by then, was not renamed either


def _corridor(tmp_path, length: float):
    """A straight corridor ``length`` metres long (4 m wide), its route along it."""
    path = tmp_path / "long.json"
    walls = [[0, 0, length, 0], [length, 0, length, 4], [length, 4, 0, 4], [0, 4, 0, 0]]
    path.write_text(json.dumps({"name": "long", "walls": walls,
                                "route": [[1, 2], [length - 1, 2]]}))  # fmt: skip
    return path


def test_simulate_refuses_a_route_beyond_the_scan_limit_before_any_work(tmp_path):
    """A world 100 km long (1.25 million scans) is refused at once, not run for minutes
    without a word."""
    import time

    world = _corridor(tmp_path, 1e5)
    t0 = time.perf_counter()
    r = run("simulate", str(world), "--log", str(tmp_path / "o.clf"), "--truth",
            str(tmp_path / "o.txt"))  # fmt: skip
    assert r.returncode == 2 and time.perf_counter() - t0 < 30
    assert r.stderr == (
        f"fhslam: error: world {world} ('long'): its route of 99,998 m is about 1,249,976 scans "
        "at 0.4 m/s and 5 scans per second; the limit is 500,000 scans (nothing was simulated)\n"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["long.json"]


def test_simulate_shows_progress_on_a_long_route_unless_quiet(tmp_path):
    world = _corridor(tmp_path, 500.0)  # about 6,200 scans: 1-2 s
    args = [str(world), "--log", str(tmp_path / "o.clf"), "--truth", str(tmp_path / "o.txt")]
    r = run("simulate", *args)
    assert r.returncode == 0 and "Traceback" not in r.stderr
    assert r.stdout.startswith("wrote 6225 scans to ")
    bars = r.stderr.replace("\r", "\n")
    assert "simulate long: driving: 100%" in bars and "6225/6225" in bars
    assert "simulate long: laser: 100%" in bars
    r = run("simulate", *args, "--quiet")
    assert r.returncode == 0 and r.stderr == ""
    r = run("simulate", "paper", "--log", str(tmp_path / "p.clf"), "--truth", str(tmp_path / "t"))
    assert r.returncode == 0 and r.stderr == ""  # 916 scans: no bar


def test_the_help_names_every_built_in_world():
    from fhslam.cli import WORLDS_HELP
    from fhslam.sim.world import BUILTIN_WORLDS

    assert ", ".join(f"'{w}'" for w in BUILTIN_WORLDS) == WORLDS_HELP


def test_slam_robustness_options_run_the_degraded_log(short_clf, tmp_path, capsys):
    """``--range-noise``, ``--drop-scans``, ``--clutter`` and ``--last-bit`` (the
    robustness checks) run exactly ``fhslam.sim.degrade`` then ``perturb_odometry`` on the
    log, say so, and record it in the trajectory's header."""
    from fhslam.pipeline import run_slam
    from fhslam.sim import degrade, perturb_odometry

    out = tmp_path / "t.txt"
    opts = ["--range-noise", "0.001", "--drop-scans", "0.1", "--clutter", "0.02"]
    opts += ["--degrade-seed", "3", "--last-bit", "1"]
    assert main(["slam", str(short_clf), "--trajectory", str(out), "--quiet", *opts]) == 0
    said = capsys.readouterr().out
    what = "1 mm of range noise, 6 of 60 scans dropped, 2 % clutter (seed 3), "
    what += "odometry x (1 + 1e-15 e), seed 1"
    assert f"{short_clf}: {what}" in said and "wrote 54 poses" in said
    assert what in out.read_text().splitlines()[0]
    log = degrade(read_carmen(short_clf), 0.1, 0.02, seed=3, range_noise=0.001)
    expected = run_slam(perturb_odometry(log, 1))
    t, poses = read_trajectory(out)
    np.testing.assert_array_equal(t, expected.timestamps)
    np.testing.assert_allclose(poses, expected.poses, atol=1e-9)  # the file's 9+ digits


def test_slam_set_runs_the_graph_method_with_those_parameters(short_clf, tmp_path):
    """``--set NAME=VALUE`` sets a number or switch of ``GraphSlamParams``: the run is the
    Python run with those parameters, and the trajectory's header records them."""
    from fhslam.pipeline import run_slam
    from fhslam.slam import GraphSlamParams

    out = tmp_path / "t.txt"
    sets = ["--set", "keyframes.voxel=0.05", "--set", "loops.target_keyframes = 3"]
    assert main(["slam", str(short_clf), "--trajectory", str(out), "--quiet", *sets]) == 0
    header = out.read_text().splitlines()[0]
    assert "--set keyframes.voxel=0.05 --set loops.target_keyframes = 3" in header
    log = read_carmen(short_clf)
    params = GraphSlamParams(
        keyframes=KeyframeParams(voxel=0.05), loops=LoopParams(target_keyframes=3)
    )
    expected = run_slam(log, params=params)
    t, poses = read_trajectory(out)
    np.testing.assert_array_equal(t, expected.timestamps)
    np.testing.assert_allclose(poses, expected.poses, atol=1e-9)  # the file's 9+ digits
    default = run_slam(log).poses
    assert np.abs(default - expected.poses).max() > 1e-6  # coarser clouds changed the run


def test_slam_set_reaches_the_trackers_parameters(short_clf, tmp_path):
    """``--set tracker.NAME=VALUE`` sets a number of the scan tracker's ``TrackerParams``
    (``GraphSlamParams.tracker``), beside the graph's own."""
    from fhslam.pipeline import run_slam
    from fhslam.slam import GraphSlamParams

    out = tmp_path / "t.txt"
    sets = ["--set", "tracker.window=0.3", "--set", "tracker.resolution=0.1", "--set",
            "loops.target_keyframes=4"]  # fmt: skip
    assert main(["slam", str(short_clf), "--trajectory", str(out), "--quiet", *sets]) == 0
    log = read_carmen(short_clf)
    tracker = TrackerParams(window=0.3, resolution=0.1)
    params = GraphSlamParams(tracker=tracker, loops=LoopParams(target_keyframes=4))
    expected = run_slam(log, params=params)
    t, poses = read_trajectory(out)
    np.testing.assert_array_equal(t, expected.timestamps)
    np.testing.assert_allclose(poses, expected.poses, atol=1e-9)
    assert np.abs(run_slam(log).poses - expected.poses).max() > 1e-6


@pytest.mark.parametrize(
    ("setting", "message"),
    [
        (
            "foo=1",
            "'foo' is not a number or switch of GraphSlamParams or of its groups (",
        ),
        ("lines.extraction.cluster_gap=1", "'lines.extraction.cluster_gap' is not a number or"),
        ("tracker=1", "'tracker' is not a number or switch"),
        ("odometry_sigma=0.1", "'odometry_sigma' is not a number or switch"),
        ("loops.target_keyframes=1.5", "loops.target_keyframes takes an integer, got '1.5'"),
        ("loops.min_score=nan", "loops.min_score takes a finite number, got 'nan'"),
        ("loops.min_score=1.5", "'loops.min_score=1.5': LoopParams.min_score must be in"),
        ("loops.target_keyframes=-1", "target_keyframes must be >= 0 and at most 1000"),
        ("loops.target_keyframes", "expected NAME=VALUE"),
        ("loop_target_keyframes=3", "'loop_target_keyframes' is not a number or switch"),
        ("tracker.foo=1", "'tracker.foo' is not a number or switch"),
        ("tracker.prior_sigma=1", "'tracker.prior_sigma' is not a number or switch"),
        ("tracker.refine_iterations=2.5", "tracker.refine_iterations takes an integer"),
        ("tracker.resolution=0", "--set 'tracker.resolution=0': TrackerParams.resolution must"),
        ("=6", "expected NAME=VALUE"),
    ],
)
def test_slam_bad_set_is_named_and_writes_nothing(short_clf, tmp_path, setting, message):
    r = run("slam", str(short_clf), "--trajectory", str(tmp_path / "t.txt"), "--set", setting)
    assert r.returncode == 2 and r.stdout == "" and "Traceback" not in r.stderr
    assert r.stderr.startswith("fhslam: error: --set") and message in r.stderr
    assert list(tmp_path.iterdir()) == []


def test_set_reaches_every_group_of_the_parameters():
    """``--set GROUP.NAME=VALUE`` reaches a number or switch of any group of a method's
    parameters (``GraphSlamParams``, the paper's ``SlamParams``), at any depth, by
    ``dataclasses.replace`` on the defaults; an optional number also takes ``none``; the
    error names the groups and every settable name, and a value out of range names the
    ``--set`` that gave it."""
    from dataclasses import replace

    from fhslam.cli.common import method_params
    from fhslam.errors import InputError
    from fhslam.slam import GraphSlamParams, SlamParams

    params = method_params("graph", ["loops.min_score=0.6", "tracker.window = 0.3"])
    default = GraphSlamParams()
    assert params.loops.min_score == 0.6 and params.tracker.window == 0.3
    assert replace(params.tracker, window=default.tracker.window) == default.tracker
    assert replace(params.loops, min_score=default.loops.min_score) == default.loops
    assert params.keyframes == default.keyframes and params.search == default.search
    paper = method_params("fht", ["extraction.cluster_gap=0.3", "robust_scale=none",
                                  "extraction.drop_lone_points=off"])  # fmt: skip
    assert paper.extraction.cluster_gap == 0.3 and paper.robust_scale is None
    assert paper.extraction.drop_lone_points is not SlamParams().extraction.drop_lone_points
    assert paper.matching == SlamParams().matching
    with pytest.raises(InputError) as e:
        method_params("graph", ["foo=1"])
    for part in ("tracker.NAME: TrackerParams", "loops.NAME: LoopParams"):
        assert part in str(e.value)
    assert "loops.min_score, " in str(e.value).partition("; one of: ")[2]
    with pytest.raises(InputError, match=r"^--set 'extraction\.densify_step=1e-9': Extrac"):
        method_params("fht", ["matching.max_distance=0.3", "extraction.densify_step=1e-9"])
    with pytest.raises(InputError, match=r"robust_scale takes a finite number or none, got 'x'"):
        method_params("classical", ["robust_scale=x"])
    with pytest.raises(InputError, match="drop_lone_points takes true or false, got 'maybe'"):
        method_params("fht", ["extraction.drop_lone_points=maybe"])
    with pytest.raises(InputError, match=r"^--set: the odometry method takes no parameters$"):
        method_params("odometry", ["x=1"])


def test_slam_set_reaches_the_papers_method(short_clf, tmp_path):
    """``--method fht --set`` sets the paper's parameters: the run differs from the
    default's, and the trajectory's header records the setting."""
    out = [tmp_path / "a.txt", tmp_path / "b.txt"]
    for path, sets in zip(out, ([], ["--set", "extraction.cluster_gap=0.05"]), strict=True):
        r = run("slam", str(short_clf), "--method", "fht", "--trajectory", str(path), *sets)
        assert r.returncode == 0, r.stderr
    a, b = (np.loadtxt(p)[:, 1:] for p in out)
    assert a.shape == b.shape and np.abs(a - b).max() > 1e-6
    assert "--method fht --set extraction.cluster_gap=0.05 " in out[1].read_text()


def test_slam_set_is_refused_for_a_method_without_parameters(short_clf, tmp_path):
    r = run("slam", str(short_clf), "--method", "odometry", "--trajectory",
            str(tmp_path / "t.txt"), "--set", "loops.min_score=0.6")  # fmt: skip
    assert r.returncode == 2 and r.stderr == (
        "fhslam: error: --set: the odometry method takes no parameters\n"
    )
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("option", "value"),
    [
        ("--range-noise", "-0.001"),
        ("--range-noise", "inf"),
        ("--drop-scans", "1"),
        ("--drop-scans", "-0.1"),
        ("--clutter", "nan"),
        ("--degrade-seed", "x"),
        ("--degrade-seed", "-1"),
        ("--last-bit", "1.5"),
        ("--last-bit", "-2"),
    ],
)
def test_slam_bad_robustness_option_is_a_usage_error(short_clf, tmp_path, option, value):
    r = run("slam", str(short_clf), "--trajectory", str(tmp_path / "t.txt"), option, value)
    assert r.returncode == 2 and option in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "t.txt").exists()
