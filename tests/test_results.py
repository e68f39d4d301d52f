"""Keyframe-graph files (``fhslam slam --graph``) read back exactly and reject malformed
input in one line; the committed results notebook 08 loads are what the code gives now.

The files in ``notebooks/results/`` were made with (from the repository root)::

    fhslam slam intel --method fht --trajectory notebooks/results/intel_fht.txt \\
        --map notebooks/results/intel_fht_map.json --quiet
    fhslam slam intel --method graph --trajectory notebooks/results/intel_graph.txt \\
        --map notebooks/results/intel_graph_map.json \\
        --graph notebooks/results/intel_graph_graph.json --quiet

and the same for ``mit-csail``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fhslam.errors import InputError, MissingInputError
from fhslam.io import GraphFormatError, KeyframeGraph, read_graph, write_graph

RESULTS = Path(__file__).parents[1] / "notebooks" / "results"
LOGS = ("intel", "mit-csail")


def small_graph() -> KeyframeGraph:
    rng = np.random.default_rng(3)
    poses = np.cumsum(rng.normal(0, 0.3, (6, 3)), axis=0)
    poses[2, 2] = np.pi  # an angle at the wrap, and numbers with all their bits
    return KeyframeGraph(
        timestamps=1e9 + np.arange(6) * 0.7,
        poses=poses,
        loops=np.array([[0, 4], [1, 5], [0, 5]]),
        active=np.array([True, False, True]),
        scores=np.array([0.91, 0.6 + 1e-12, 1.0]),
    )


# ------------------------------------------------------------------------- graph files


def test_a_graph_file_reads_back_exactly(tmp_path):
    g = small_graph()
    write_graph(tmp_path / "g.json", g)
    back = read_graph(tmp_path / "g.json")
    for name in ("timestamps", "poses", "loops", "active", "scores"):
        np.testing.assert_array_equal(getattr(back, name), getattr(g, name), err_msg=name)
    assert back.active.dtype == bool and back.loops.dtype == np.intp
    assert len(back) == 6 and back.n_active == 2
    text = (tmp_path / "g.json").read_text()
    assert text.count("\n") == 2 + 6 + 3  # two opening lines, one keyframe or loop per line
    assert [f.name for f in tmp_path.iterdir()] == ["g.json"]  # no temporary file left


def test_a_graph_without_loop_closures_reads_back(tmp_path):
    g = KeyframeGraph(np.array([0.5]), np.array([[1.0, 2.0, 0.1]]), [], [], [])
    write_graph(tmp_path / "g.json", g)
    back = read_graph(tmp_path / "g.json")
    assert len(back) == 1 and back.loops.shape == (0, 2) and back.n_active == 0
    np.testing.assert_array_equal(back.poses, g.poses)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"poses": np.zeros((5, 3))}, r"poses must have shape \(6, 3\)"),
        ({"scores": np.ones(2)}, "same length, got 3, 3 and 2"),
        ({"loops": np.array([[0, 4], [5, 1], [0, 5]])}, r"loops\[1\] = \(5, 1\)"),
        ({"loops": np.array([[0, 4], [1, 6], [0, 5]])}, "< 6 keyframes"),
        ({"timestamps": np.r_[np.arange(5.0), np.nan]}, "finite"),
    ],
)
def test_a_bad_graph_is_refused_before_writing(change, message):
    g = small_graph()
    fields = {n: getattr(g, n) for n in ("timestamps", "poses", "loops", "active", "scores")}
    with pytest.raises(ValueError, match=message):
        KeyframeGraph(**{**fields, **change})


GOOD_LOOP = '{"old": 0, "new": 1, "active": true, "score": 0.9}'
TWO_FRAMES = "[0, 0, 0, 0], [1, 1, 0, 0]"


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ('{"keyframes": [\n[0, 0, 0, 0],\n', ":3: not valid JSON"),
        ('{"keyframes": []}', 'expected a JSON object {"keyframes"'),
        ('{"keyframes": {}, "loops": []}', "'keyframes' must be a list, got dict"),
        ('{"keyframes": [[0, 0, 0]], "loops": []}', r"keyframes\[0\]: expected \[timestamp"),
        ('{"keyframes": [[0, 0, "x", 0]], "loops": []}', r"keyframes\[0\]: y must be a number"),
        ('{"keyframes": [[0, 0, NaN, 0]], "loops": []}', r"keyframes\[0\]: y is not finite"),
        (f'{{"keyframes": [{TWO_FRAMES}], "loops": [[0, 1]]}}', r"loops\[0\]: expected an obj"),
        (
            f'{{"keyframes": [{TWO_FRAMES}], "loops": [{{"old": 0, "new": 1, "score": 1}}]}}',
            r"loops\[0\]: missing key 'active'",
        ),
        (
            f'{{"keyframes": [{TWO_FRAMES}], "loops": [{GOOD_LOOP.replace("1,", "2,")}]}}',
            r"loops\[0\]: 'new' must be a keyframe index 0 to 1, got 2",
        ),
        (
            f'{{"keyframes": [{TWO_FRAMES}], "loops": [{GOOD_LOOP.replace("0,", "1,", 1)}]}}',
            r"'old' \(1\) must be an older keyframe than 'new' \(1\)",
        ),
        (
            f'{{"keyframes": [{TWO_FRAMES}], "loops": [{GOOD_LOOP.replace("true", "1")}]}}',
            "'active' must be true or false, got 1",
        ),
        (
            f'{{"keyframes": [{TWO_FRAMES}], "loops": [{GOOD_LOOP.replace("0.9", "null")}]}}',
            "'score' must be a number, got None",
        ),
    ],
)
def test_a_malformed_graph_file_is_an_error_naming_file_and_entry(tmp_path, content, message):
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(GraphFormatError, match=message) as e:
        read_graph(path)
    assert str(e.value).startswith(str(path)) and "\n" not in str(e.value)


def test_a_missing_or_binary_graph_file(tmp_path):
    with pytest.raises(MissingInputError, match="no such keyframe-graph file"):
        read_graph(tmp_path / "nope.json")
    (tmp_path / "b.json").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(InputError, match="not a text file"):
        read_graph(tmp_path / "b.json")


# --------------------------------------------------------------- the committed results


@pytest.fixture(scope="module")
def real_logs():
    from conftest import data_dir

    if data_dir() is None:
        pytest.skip("no real laser logs: set FHSLAM_DATA or place them in ../shared/data")
    from fhslam.datasets import find_dataset, load_log
    from fhslam.io import read_relations

    return {
        name: (load_log(name), read_relations(find_dataset(name, "relations"))) for name in LOGS
    }


def load(name: str, method: str):
    from fhslam.io import read_map, read_trajectory

    t, poses = read_trajectory(RESULTS / f"{name}_{method}.txt")
    return t, poses, read_map(RESULTS / f"{name}_{method}_map.json")


@pytest.mark.parametrize("name", LOGS)
def test_the_committed_graph_files_are_one_run(name):
    """Trajectory, map and keyframe graph of one ``fhslam slam --graph`` run: every keyframe
    is a scan of the trajectory, at the trajectory's pose."""
    t, poses, lines = load(name, "graph")
    g = read_graph(RESULTS / f"{name}_graph_graph.json")
    assert len(lines) > 100 and len(g) > 500 and g.n_active > 20
    assert g.timestamps[0] == t[0] and np.all(np.diff(g.timestamps) > 0)
    k = np.searchsorted(t, g.timestamps)
    np.testing.assert_array_equal(t[k], g.timestamps)
    np.testing.assert_allclose(g.poses[:, :2], poses[k, :2], rtol=0, atol=1e-9)
    dtheta = np.angle(np.exp(1j * (g.poses[:, 2] - poses[k, 2])))
    np.testing.assert_allclose(dtheta, 0, atol=1e-9)


@pytest.mark.parametrize("name", LOGS)
def test_the_committed_graph_run_is_the_one_test_real_logs_measures(name, real_logs):
    """The mean translational relations error of the committed run is the one
    tests/test_real_logs.py's REAL_LOGS states was measured with the default method, to 1 mm
    (last-bit noise in the odometry moved mit-csail's by 0.4 mm): when a change of the method
    moves that number, the files are made again."""
    from test_real_logs import REAL_LOGS

    from fhslam.metrics import relations_error

    log, rel = real_logs[name]
    t, poses, _ = load(name, "graph")
    np.testing.assert_array_equal(t, log.timestamps)
    e = relations_error(t, poses, *rel)
    assert e.n_used == e.n_total
    assert e.trans_mean == pytest.approx(REAL_LOGS[name][1], abs=0.001)


@pytest.mark.parametrize("name", LOGS)
def test_the_committed_fht_run_starts_as_a_run_now(name, real_logs):
    """The paper's procedure never revises a pose: its first 400 poses are those of a run
    over the first 400 scans (a second or so), to 1e-6 (bit for bit on this machine)."""
    from fhslam.experiments.bench import log_head
    from fhslam.pipeline import run_slam

    log, _ = real_logs[name]
    t, poses, lines = load(name, "fht")
    np.testing.assert_array_equal(t, log.timestamps)
    assert len(lines) > 500
    now = run_slam(log_head(log, 400), "fht")
    np.testing.assert_allclose(poses[:400], now.poses, rtol=0, atol=1e-6)
