"""``fhslam benchmark``: the results notebook 09 loads and the README's results table are what
:func:`fhslam.experiments.benchmark.run_benchmark` makes; its table, files and errors.

The committed files in ``notebooks/results/`` (``benchmark.csv``, ``table.md``,
``robustness.csv``, every log's trajectory, map and keyframe graph) were made, from the
repository root, by::

    fhslam benchmark --out notebooks/results/

``tried.csv`` is kept by hand, from the project's history.
"""

from __future__ import annotations

import csv
import math
import re
import shutil
import subprocess
from dataclasses import replace
from pathlib import Path

import pytest

from fhslam.errors import InputError
from fhslam.experiments.benchmark import (
    BENCHMARK_LOGS,
    PUBLISHED,
    QUICK_DRAWS,
    BenchmarkRow,
    Draws,
    load_benchmark,
    load_draws,
    results_table,
    run_benchmark,
)
from fhslam.experiments.draw_runs import frame_text

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "notebooks" / "results"
COMMAND = "fhslam benchmark --out notebooks/results/"


def readme_results_table() -> str:
    """The table of the README's "Results" section, as text."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("\n## Results\n", 1)[1].split("\n## ", 1)[0]
    return "".join(line + "\n" for line in section.splitlines() if line.startswith("|"))


# ------------------------------------------------------------------ the committed results


def test_the_readme_shows_the_table_the_benchmark_rendered():
    """The README's numbers are remade by the command: its results table is ``table.md``,
    and ``table.md`` is the table of the committed ``benchmark.csv``."""
    rows = load_benchmark(RESULTS / "benchmark.csv")
    table = (RESULTS / "table.md").read_text(encoding="utf-8")
    assert results_table(rows) == table
    assert readme_results_table() == table
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert COMMAND in readme and "09_benchmarks" in readme


def test_the_committed_benchmark_has_every_log_and_method():
    rows = load_benchmark(RESULTS / "benchmark.csv")
    pairs = {(r.log, r.method) for r in rows}
    for log in BENCHMARK_LOGS:
        assert {(log, m) for m in ("graph", "fht", "odometry")} <= pairs, log
        assert ((log, "cartographer") in pairs) == (log in PUBLISHED), log
    for r in rows:
        if r.source == "fhslam":
            assert r.relations_used == r.relations_total > 0, r
            assert r.seconds > 0 and r.real_time_factor == pytest.approx(r.duration_s / r.seconds)
        else:
            assert r.error_m == PUBLISHED[r.log].error_m
    for log in BENCHMARK_LOGS:  # the files of every SLAM run, for the maps
        for name in (f"{log}_graph.txt", f"{log}_graph_map.json", f"{log}_graph_graph.json"):
            assert (RESULTS / name).is_file(), name
        for name in (f"{log}_fht.txt", f"{log}_fht_map.json"):
            assert (RESULTS / name).is_file(), name


def test_the_committed_draws_are_the_default_matrix_from_the_runs_as_read():
    """Every benchmark log over draws: its run as read (the benchmark's graph run) and eight
    draws of each kind, each with a seed of its own; every world log in four frames and once
    with each degradation."""
    rows = {(r.log, r.method): r for r in load_benchmark(RESULTS / "benchmark.csv")}
    draws = load_draws(RESULTS / "robustness.csv")
    assert {r.name for r in draws if r.kind == "log"} == set(BENCHMARK_LOGS)
    for name in BENCHMARK_LOGS:
        sel = [r for r in draws if r.kind == "log" and r.name == name]
        (as_read,) = [r for r in sel if r.variant == "as read"]
        assert as_read.error_m == rows[(name, "graph")].error_m
        for variant in ("1 mm range noise", "10 % dropped", "as read, last bit"):
            seeds = [r.degrade_seed if r.degrade_seed >= 0 else r.last_bit
                     for r in sel if r.variant == variant]  # fmt: skip
            assert len(seeds) == len(set(seeds)) == 8 and min(seeds) > 0, (name, variant)
    world = [r for r in draws if r.kind == "world"]
    seeds = {r.seed for r in world}
    assert len(seeds) == 8 and {r.name for r in world} == {"paper"}
    for seed in seeds:
        variants = [r.variant for r in world if r.seed == seed]
        assert len(variants) == 7 and sum(", moved (" in v for v in variants) == 3, variants
    assert all(math.isfinite(r.error_m) and r.error_m > 0 for r in draws)


def test_a_world_moved_gives_the_same_error_in_every_committed_draw():
    """Four frames of each of eight fresh world logs: a rigid motion of the world frame
    changes the ATE by rounding only (under a micrometre)."""
    world = [r for r in load_draws(RESULTS / "robustness.csv") if r.kind == "world"]
    given = {r.seed: r.error_m for r in world if r.variant == "as simulated"}
    moved = [r for r in world if ", moved (" in r.variant]
    assert len(moved) == 24
    for r in moved:
        assert r.error_m == pytest.approx(given[r.seed], abs=1e-6), r


STOP_OR_ISSUE = re.compile(r"\b(stop|issue)s? [0-9]+", re.IGNORECASE)


def test_the_committed_sparse_copies_are_what_test_real_logs_measures():
    """Every benchmark log's sparse copy run by each method, and the default's errors the
    ones tests/test_real_logs.py's SPARSE states were measured, to 1 mm."""
    from test_real_logs import SPARSE

    draws = [r for r in load_draws(RESULTS / "robustness.csv") if r.kind == "sparse"]
    assert {(r.name, r.method) for r in draws} == {
        (n, m) for n in BENCHMARK_LOGS for m in ("graph", "fht", "odometry")
    }
    by = {(r.name, r.method): r.error_m for r in draws}
    for name, (graph, fht, odometry) in SPARSE.items():
        assert by[(name, "graph")] == pytest.approx(graph, abs=0.001), name
        assert by[(name, "odometry")] == pytest.approx(odometry, rel=1e-3), name
        assert by[(name, "fht")] == pytest.approx(fht, rel=0.25), name


def test_the_tried_table_names_a_commit_per_idea():
    with open(RESULTS / "tried.csv", encoding="utf-8", newline="") as f:
        reader = csv.reader(f)
        assert next(reader) == ["idea", "decided_by", "commit"]
        tried = list(reader)
    assert 1 <= len(tried) <= 30
    for idea, number, commit in tried:
        assert idea and re.search(r"\d", number), idea
        assert re.fullmatch(r"[0-9a-f]{7,40}", commit), commit
        assert not STOP_OR_ISSUE.search(idea + " " + number), idea
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("no git history to look the commits up in")
    for _, _, commit in tried:
        r = subprocess.run(
            ["git", "cat-file", "-e", f"{commit}^{{commit}}"], cwd=ROOT, capture_output=True
        )
        assert r.returncode == 0, f"{commit}: not a commit of this repository"


# ------------------------------------------------------------------------------ the table


def row(log: str, method: str, error: float, rtf: float = math.nan) -> BenchmarkRow:
    nan = math.nan
    return BenchmarkRow(
        log, method, error, nan, nan, 10, 10, 100, 50.0, 50.0 / rtf, nan, rtf,
        "pseudo ground truth" if log == "fr101" else "benchmark", "fhslam",
    )  # fmt: skip


def test_the_table_rounds_as_the_readme_and_bolds_the_smallest_error():
    rows = [
        row("intel", "graph", 0.014049, 92.4),
        row("intel", "fht", 2.7812),
        row("intel", "odometry", 7.3849),
        replace(row("intel", "cartographer", 0.0229), source="Hess et al. 2016"),
        row("fr-clinic", "graph", 0.12704, 88.0),
        row("fr-clinic", "odometry", 0.6149),
        replace(row("fr-clinic", "cartographer", 0.1071), source="Hess et al. 2016"),
        row("fr101", "graph", 0.0543, 14.2),
    ]
    lines = results_table(rows).splitlines()
    assert lines[0].startswith("| log | default (`graph`) | paper (`fht`) | odometry |")
    assert lines[2] == "| Intel | **0.0140 m** | 2.78 m | 7.38 m | 0.0229 m | 92× |"
    assert lines[3] == "| Freiburg hospital | 0.127 m | – | 0.61 m | **0.1071 m** | 88× |"
    assert lines[4] == "| Freiburg 101 (pseudo ground truth) | **0.0543 m** | – | – | – | 14× |"
    assert len(lines) == 5


def test_a_damaged_results_file_is_an_error_naming_file_and_line(tmp_path):
    good = RESULTS / "benchmark.csv"
    text = good.read_text(encoding="utf-8").splitlines()
    bad = tmp_path / "benchmark.csv"
    fields = text[1].split(",")
    bad.write_text("\n".join([text[0], ",".join([*fields[:2], "x", *fields[3:]])]) + "\n")
    with pytest.raises(InputError, match=r"benchmark.csv:2: not a number"):
        load_benchmark(bad)
    bad.write_text("\n".join([text[0], text[1] + ",1"]) + "\n")
    with pytest.raises(InputError, match=r"benchmark.csv:2: 16 fields, expected 15"):
        load_benchmark(bad)
    bad.write_text("log,method\n")
    with pytest.raises(InputError, match=r"benchmark.csv:1: not a benchmark file"):
        load_benchmark(bad)
    with pytest.raises(InputError, match=r"robustness.csv: no such robustness file; write it wi"):
        load_draws(tmp_path / "robustness.csv")


# ----------------------------------------------------------------------------- bad input


def test_an_unknown_log_is_refused_before_any_run(tmp_path):
    with pytest.raises(InputError, match=r"logs: unknown benchmark log 'nope'; choose from intel"):
        run_benchmark(tmp_path / "out", logs=["intel", "nope"], progress=False)
    with pytest.raises(InputError, match=r"unknown benchmark log 'mit-killian'"):  # relations only
        run_benchmark(tmp_path / "out", logs=["mit-killian"], progress=False)
    with pytest.raises(InputError, match=r"draws.logs: unknown benchmark log 'intel2'"):
        run_benchmark(tmp_path / "out", draws=Draws(logs=("intel2",)), progress=False)
    with pytest.raises(InputError, match=r"draws.sparse_logs: unknown benchmark log 'x'"):
        run_benchmark(tmp_path / "out", draws=Draws(sparse_logs=("x",)), progress=False)
    with pytest.raises(InputError, match="not the string 'intel'"):
        run_benchmark(tmp_path / "out", logs="intel", progress=False)
    with pytest.raises(ValueError, match="unknown SLAM methods"):
        run_benchmark(tmp_path / "out", methods=("graph", "magic"), progress=False)
    assert not (tmp_path / "out").exists()


def test_the_command_refuses_an_unknown_log_in_one_line(tmp_path, capsys):
    from fhslam.cli import main

    assert main(["benchmark", "--out", str(tmp_path / "o"), "--logs", "nope", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("fhslam: error: ") and "unknown benchmark log 'nope'" in err
    assert err.count("\n") == 1 and not (tmp_path / "o").exists()


def test_an_out_that_is_a_file_is_refused_before_any_run(tmp_path):
    out = tmp_path / "results"
    out.write_text("not a folder")
    with pytest.raises(InputError, match=r"results: is a file, not a folder"):
        run_benchmark(out, quick=True, progress=False)
    assert out.read_text() == "not a folder"


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"seeds": -1}, r"Draws.seeds must be a whole number >= 0, got -1"),
        ({"last_bit_draws": 1.5}, r"Draws.last_bit_draws must be a whole number"),
        ({"drop_fraction": 1.5}, "drop_fraction"),
        ({"world_level": "extreme"}, r"Draws.world_level must be one of"),
        ({"frames": -1}, r"Draws.frames must be a whole number >= 0, got -1"),
        ({"frames": 0}, r"Draws.frames must be at least 1 \(the world as given\)"),
        ({"seed": -3}, r"Draws.seed must be a whole number >= 0 or None, got -3"),
        ({"seed": 2.5}, r"Draws.seed must be a whole number >= 0 or None, got 2.5"),
        ({"seed": True}, r"Draws.seed must be a whole number >= 0 or None, got True"),
    ],
)
def test_bad_draws_are_refused_when_made(change, message):
    with pytest.raises(ValueError, match=message):
        Draws(**change)


def test_the_draws_seeds_come_from_one_seed_fresh_unless_given():
    a, b = Draws().seeded(), Draws().seeded()
    assert Draws().seed is None and a.seed != b.seed  # drawn anew (equal: one in 2**32)
    d = Draws(seed=7)
    assert d.seeded() is d
    eight = d.seeds_of("range noise", 8)
    assert len(set(eight)) == 8 and all(1 <= s < 2**31 for s in eight)
    assert d.seeds_of("range noise", 3) == eight[:3]  # the first do not depend on how many
    assert Draws(seed=7, seeds=2).seeds_of("range noise", 8) == eight  # nor on the counts
    assert d.seeds_of("dropped", 8) != eight and Draws(seed=8).seeds_of("range noise", 8) != eight
    with pytest.raises(ValueError, match=r"Draws.seed is None: call Draws.seeded\(\) first"):
        Draws().seeds_of("last bit", 1)
    with pytest.raises(ValueError, match=r"unknown kind of draw 'noise'; one of \['range noise'"):
        d.seeds_of("noise", 1)
    moves = d.motions()
    assert len(set(moves)) == 4 and moves[0] == (0.0, 0.0, 0.0)
    assert all(abs(x) <= 10 and abs(y) <= 10 and abs(t) <= math.pi for x, y, t in moves)
    assert Draws(seed=7, frames=2).motions() == moves[:2]
    assert frame_text((1.234, -5.0, math.pi / 2)) == "moved (1.23, -5.00) m, 90.0°"


def test_the_command_prints_the_draws_seed_and_takes_it_back(tmp_path, capsys):
    from fhslam.cli import main

    assert main(["benchmark", "--out", str(tmp_path / "o"), "--logs", "nope", "--quiet",
                 "--draw-seed", "5"]) == 2  # fmt: skip
    assert capsys.readouterr().out == "draws: seed 5 (to repeat them: --draw-seed 5)\n"
    assert main(["benchmark", "--out", str(tmp_path / "o"), "--logs", "nope", "--quiet"]) == 2
    seed = re.fullmatch(r"draws: seed (\d+) \(to repeat them: --draw-seed \1\)\n",
                        capsys.readouterr().out)  # fmt: skip
    assert seed is not None
    assert main(["benchmark", "--out", str(tmp_path / "o"), "--logs", "nope", "--no-draws"]) == 2
    assert capsys.readouterr().out == ""


# ---------------------------------------------------------------- a small subset, run again

# The same code on the same machine gives the same bits: the committed files came out of one
# run, and a second run on that machine matched them byte for byte. Another CPU, BLAS or NumPy
# build may round a sum differently in its last bit, and the default SLAM can turn such a bit
# into another decision (a loop closure taken or not): last-bit draws of the odometry moved
# MIT CSAIL's relation error by up to 0.4 mm (1.5 %). A rerun elsewhere is one more such
# draw, so it is held to 2 % of the committed error; a change of the method that matters
# moves it by more.
RELATIVE_TOLERANCE = 0.02


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    from conftest import data_dir

    if data_dir() is None:
        pytest.skip("no real laser logs: set FHSLAM_DATA or place them in ../shared/data")
    out = tmp_path_factory.mktemp("benchmark")
    for name in ("benchmark.csv", "robustness.csv"):  # rows of other runs are kept
        shutil.copy(RESULTS / name, out / name)
    rows = run_benchmark(out, quick=True, methods=("graph",), draws=QUICK, progress=False)
    return out, rows


QUICK = replace(QUICK_DRAWS, seed=11)
"""The quick draws of the tests, seeded (the command draws a fresh seed)."""


def test_a_rerun_of_the_shortest_log_gives_the_committed_row(quick_run):
    out, rows = quick_run
    committed = {(r.log, r.method): r for r in load_benchmark(RESULTS / "benchmark.csv")}
    new = {(r.log, r.method): r for r in rows}
    now, then = new[("mit-csail", "graph")], committed[("mit-csail", "graph")]
    assert now.error_m == pytest.approx(then.error_m, rel=RELATIVE_TOLERANCE)
    assert (now.relations_used, now.n_scans) == (then.relations_used, then.n_scans)
    assert now.duration_s == then.duration_s and now.seconds > 0
    # the other rows are kept as they were, and the table shows them all
    assert {k: v for k, v in new.items() if k != ("mit-csail", "graph")} == {
        k: v for k, v in committed.items() if k != ("mit-csail", "graph")
    }
    assert load_benchmark(out / "benchmark.csv") == rows
    assert (out / "table.md").read_text() == results_table(rows)
    names = sorted(p.name for p in out.iterdir())
    assert names == [
        "benchmark.csv",
        "mit-csail_graph.txt",
        "mit-csail_graph_graph.json",
        "mit-csail_graph_map.json",
        "robustness.csv",
        "table.md",
    ]
    head = (out / "mit-csail_graph.txt").read_text().splitlines()[0]
    assert head == "# fhslam slam --method graph mit-csail: timestamp x y theta"


def test_a_rerun_draws_the_world_again_and_keeps_the_log_draws(quick_run):
    out, _ = quick_run
    committed = load_draws(RESULTS / "robustness.csv")
    now = load_draws(out / "robustness.csv")
    assert [r for r in now if r.kind == "log"] == [r for r in committed if r.kind == "log"]
    world = [r for r in now if r.kind == "world"]
    # one fresh log of the paper world: as given, moved, with range noise, with dropped
    # scans, with a last-bit perturbation; each with its seed drawn from QUICK's
    assert [r.variant for r in world] == [
        "as simulated",
        f"as simulated, {frame_text(QUICK.motions()[1])}",
        "1 mm range noise",
        "10 % dropped",
        "as simulated, last bit",
    ]
    assert {r.seed for r in world} == set(QUICK.seeds_of("world", 1))
    noise, drop = QUICK.seeds_of("world range noise", 1), QUICK.seeds_of("world dropped", 1)
    assert [r.degrade_seed for r in world] == [-1, -1, *noise, *drop, -1]
    assert [r.last_bit for r in world] == [0, 0, 0, 0, *QUICK.seeds_of("world last bit", 1)]
    # a moved world frame changes nothing but rounding
    assert world[1].error_m == pytest.approx(world[0].error_m, abs=1e-6)
    assert all(0 < r.error_m < 0.2 for r in world)
