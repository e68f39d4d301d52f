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


def test_simulate_accepts_a_world_file(tmp_path):
    world = tmp_path / "box.json"
    world.write_text(
        json.dumps(
            {
                "name": "box",
                "walls": [[0, 0, 6, 0], [6, 0, 6, 4], [6, 4, 0, 4], [0, 4, 0, 0]],
                "route": [[1, 1], [5, 1], [5, 3]],
            }
        )
    )
    out = tmp_path / "box.clf"
    assert main(["simulate", str(world), "--log", str(out), "--truth", str(tmp_path / "t")]) == 0
    assert len(read_carmen(out)) > 10


def test_info_summarises_a_log(tmp_path, capsys):
    out = tmp_path / "paper.clf"
    main(["simulate", "paper", "--log", str(out), "--truth", str(tmp_path / "t.txt")])
    capsys.readouterr()
    assert main(["info", str(out)]) == 0
    text = capsys.readouterr().out
    assert "916 scans of 181 beams" in text
    median_lines = float(text.rsplit(":", 1)[1])
    assert 3 <= median_lines <= 15  # an office seen over 180°: several walls per scan


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


def test_reproduce_writes_figures_1_to_5(tmp_path):
    r = run("reproduce", "--out", str(tmp_path))
    assert r.returncode == 0, r.stderr
    names = sorted(p.name for p in tmp_path.glob("*.png"))
    assert names == [
        "fig01_hough_principle.png",
        "fig02_environment.png",
        "fig03_extended_points.png",
        "fig04_clusters.png",
        "fig05_lines.png",
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
