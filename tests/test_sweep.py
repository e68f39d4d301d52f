"""``fhslam sweep`` and its file: the Monte-Carlo comparison notebook 07 loads from a file."""

from pathlib import Path

import numpy as np
import pytest

from fhslam.cli import main
from fhslam.errors import InputError
from fhslam.experiments.compare import (
    FIELDS,
    format_summary,
    load_sweep,
    one_run,
    save_sweep,
)

COMMITTED = Path(__file__).parents[1] / "notebooks" / "results" / "sweep_paper.csv"


@pytest.fixture(scope="module")
def runs():
    every = one_run("paper", "low", 0, ("fht", "graph", "classical", "ekf", "odometry"))
    return every + one_run("paper", "medium", 0, ("graph",))


#: How far a run now may be from the committed file's, in ATE (m): the line methods'
#: results hold to far below a millimetre on any machine. The graph method's does not on the
#: paper world: along its long corridor only the odometry and faint cues place the robot, and
#: a discrete choice that flips with the last bit (scan 33 of seed 0) grows to centimetres
#: there. Seed 0 with the odometry multiplied by (1 + 1e-15 ε), 8 draws each (README,
#: "robustness"): low 0.040-0.066 m, medium 0.051-0.080 m; the committed medium row (0.043 m,
#: another machine) and this machine's unperturbed run (0.080 m) lie at the two ends. So a
#: graph row is only checked to lie within that spread of a run now: 0.045 m.
ATE_TOLERANCE = {"graph": 0.045}


def test_a_sweep_file_reads_back_exactly(runs, tmp_path):
    save_sweep(runs, tmp_path / "s.csv")
    back = load_sweep(tmp_path / "s.csv")
    for a, b in zip(runs, back, strict=True):
        for name in FIELDS:
            x, y = getattr(a, name), getattr(b, name)
            assert x == y or (np.isnan(x) and np.isnan(y)), name  # odometry: no map, NaN
    table = format_summary(back)
    assert table.splitlines()[0] == "6 runs: 1 seeds x 2 levels x 5 methods"
    assert "FH-SLAM (paper)" in table and "odometry" in table


def test_the_committed_sweep_is_what_this_code_computes(runs):
    """The file notebook 07 shows came from ``fhslam sweep --seeds 20``: its runs of seed 0
    at the low level, every method, and the graph method's at the medium level agree with a
    run now (ATE to 0.5 mm, the graph method's to 4.5 cm: see ``ATE_TOLERANCE``; times are the
    machine's)."""
    committed = load_sweep(COMMITTED)
    assert len(committed) == 20 * 3 * 5
    assert {(r.seed, r.level) for r in committed} == {
        (s, lv) for s in range(20) for lv in ("low", "medium", "high")
    }
    for r in runs:
        c = next(x for x in committed if (x.method, x.level, x.seed) == (r.method, r.level, 0))
        assert c.ate_rmse == pytest.approx(r.ate_rmse, abs=ATE_TOLERANCE.get(r.method, 5e-4)), (
            r.method
        )
        assert c.odometry_ate_rmse == pytest.approx(r.odometry_ate_rmse, abs=1e-9)
        assert c.n_map_lines == pytest.approx(r.n_map_lines, abs=2)


@pytest.mark.parametrize(
    "content, message",
    [
        ("", ":1: not a sweep file"),
        ("a,b,c\n1,2,3\n", ":1: not a sweep file"),
        (",".join(FIELDS) + "\n", "no runs"),
        (",".join(FIELDS) + "\nfht,low,0,0.1\n", ":2: 4 fields, expected 8"),
        (",".join(FIELDS) + "\nfht,low,zero,0.1,0.2,0.3,1.0,5\n", ":2: not a number"),
        (",".join(FIELDS) + "\nslow,low,0,0.1,0.2,0.3,1.0,5\n", ":2: unknown method 'slow'"),
        (",".join(FIELDS) + "\nfht,huge,0,0.1,0.2,0.3,1.0,5\n", ":2: unknown noise level"),
    ],
)
def test_a_bad_sweep_file_is_an_error_naming_file_and_line(tmp_path, content, message):
    path = tmp_path / "bad.csv"
    path.write_text(content)
    with pytest.raises(InputError, match=message):
        load_sweep(path)


def test_a_missing_sweep_file_says_how_to_make_it(tmp_path):
    with pytest.raises(InputError, match="fhslam sweep --out"):
        load_sweep(tmp_path / "none.csv")


def test_sweep_command_writes_the_file_and_prints_the_table(tmp_path, capsys):
    out = tmp_path / "s.csv"
    args = ["sweep", "--seeds", "1", "--levels", "low", "--methods", "odometry"]
    assert main([*args, "--jobs", "1", "--out", str(out), "--quiet"]) == 0
    printed = capsys.readouterr().out
    assert printed.startswith("1 runs: 1 seeds x 1 levels x 1 methods")
    (r,) = load_sweep(out)
    assert (r.method, r.level, r.seed, r.n_map_lines) == ("odometry", "low", 0, 0)


@pytest.mark.parametrize(
    "args, message",
    [
        (["--seeds", "0"], "--seeds must be between 1 and 1000"),
        (["--jobs", "0"], "--jobs must not be 0"),
        (["--world", "nowhere"], "unknown world 'nowhere'"),
        (["--out", "/no/such/folder/s.csv"], "no such folder"),
    ],
)
def test_sweep_command_refuses_bad_options_before_running(args, message, tmp_path, capsys):
    assert main(["sweep", *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith("fhslam: error:") and message in err and err.count("\n") == 1
    assert main(["sweep", "--out", str(tmp_path)]) == 2
    assert "is a directory" in capsys.readouterr().err
