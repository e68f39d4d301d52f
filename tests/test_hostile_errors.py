"""Hostile input that the command once answered with a traceback, and the command's last
resort for its own bugs, each run through ``fhslam`` (``fhslam.cli.main`` in this process, or
``python -m fhslam.cli``).

The contract (the docstrings of :mod:`fhslam.cli` and :mod:`fhslam.errors`): bad input ends
with exit status 2 and exactly one line on stderr, ``fhslam: error: ...``, naming what is
wrong and where; a bug inside the package with exit status 1 and one line ``fhslam: internal
error: <type>: <message> (...)``, whose traceback ``--debug`` shows instead. Here:

- parameters out of their range (``slam --set``), refused when their dataclass is made;
- map and keyframe-graph files holding ``NaN``, ``Infinity`` or numbers beyond a float;
- ROS bags with damaged bytes or cut short;
- a package whose numba cache cannot be written beside it (installed by root, run by a user
  whose home is not writable);
- a bug: any other exception.
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import fhslam
from fhslam import _numba
from fhslam.cli import main
from fhslam.errors import InputError, ParameterError, Range
from fhslam.extraction import ExtractionParams
from fhslam.io import (
    GraphFormatError,
    lines_from_segments,
    read_graph,
    write_carmen,
    write_map,
    write_trajectory,
)
from fhslam.io.jsontext import MAX_INTEGER_DIGITS, parse_json
from fhslam.matching import MatchParams
from fhslam.sim import paper_world, simulate
from fhslam.slam import GraphSlamParams
from fhslam.slam.fht import SlamParams
from fhslam.slam.graph import (
    EdgeParams,
    GlobalSearchParams,
    KeyframeParams,
    LoopParams,
    OptimiserParams,
    TrackerParams,
)

PARAMS = (
    KeyframeParams,
    TrackerParams,
    EdgeParams,
    LoopParams,
    GlobalSearchParams,
    OptimiserParams,
    SlamParams,
    ExtractionParams,
    MatchParams,
)
"""The default (graph) method's dataclasses of parameters, nested ones included."""

INTERNAL = "(please report it; run again with --debug for the traceback)"


def one_line_error(err: str, *names: str) -> str:
    """``err`` is exactly one line ``fhslam: error: ...`` naming each of ``names``."""
    assert "Traceback" not in err, err
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("fhslam: error: "), err
    for name in names:
        assert name in lines[0], (name, lines[0])
    return lines[0]


def command(*args: str, **kw) -> subprocess.CompletedProcess:
    """``python -m fhslam.cli ARGS``, as a user runs the command."""
    return subprocess.run(
        [sys.executable, "-m", "fhslam.cli", *args],
        capture_output=True,
        text=True,
        timeout=300,
        **kw,
    )


@pytest.fixture(scope="module")
def small_log(tmp_path_factory) -> Path:
    """A CARMEN log of 12 scans of the paper world."""
    path = tmp_path_factory.mktemp("log") / "small.clf"
    write_carmen(simulate(paper_world(), seed=0, max_scans=12), path)
    return path


# --------------------------------------------------------------------------------------------
# Parameters: every number of the graph method's dataclasses has a range


def _default(f: dataclasses.Field):
    return f.default_factory() if f.default is dataclasses.MISSING else f.default


def _is_number(v) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool)


def _numbers(cls) -> set[str]:
    """The fields of ``cls`` whose default is a number or a tuple of numbers."""
    out = set()
    for f in dataclasses.fields(cls):
        v = _default(f)
        if _is_number(v) or (isinstance(v, tuple) and v and all(map(_is_number, v))):
            out.add(f.name)
    return out


def _below(r: Range):
    if r.open_low:
        return r.low
    return r.low - 1 if r.integer else r.low - 1e-9 * max(1.0, abs(r.low))


def _above(r: Range):
    return r.high + 1 if r.integer else r.high * (1 + 1e-9) + 1e-12


def _bad_values(r: Range, default) -> list:
    """Values of every kind that ``r`` refuses, for a field whose default is ``default``."""
    scalars = [float("nan"), float("inf"), -float("inf"), 1e308, -1e308, _below(r), _above(r)]
    scalars += ["1", b"1", True, np.bool_(False), [], object(), complex(1, 0)]
    if r.integer:
        scalars += [2.5, float(r.low + 1), np.float64(r.low + 1)]  # a float, even a whole one
    if not r.optional:
        scalars.append(None)
    if not r.items:
        return scalars
    d = list(default)
    tuples = [tuple([v, *d[1:]]) for v in scalars if v is not None] + [
        tuple([*d[:-1], float("nan")]),
        tuple(d[:1]),
        tuple(d + d[:1]),
        d[0],
        None,
        "ab",
    ]
    return tuples


CASES = [(cls, name) for cls in PARAMS for name in cls.RANGES]


@pytest.mark.parametrize("cls", PARAMS, ids=lambda c: c.__name__)
def test_the_defaults_are_valid_and_every_number_has_a_range(cls):
    params = cls()  # each checks its ranges when made
    assert set(cls.RANGES) == _numbers(cls), "a number without a range, or a range too many"
    for name, allowed in cls.RANGES.items():
        allowed.check(cls.__name__, name, getattr(params, name))


@pytest.mark.parametrize(("cls", "name"), CASES, ids=[f"{c.__name__}.{n}" for c, n in CASES])
def test_a_value_out_of_range_is_refused_naming_the_field(cls, name):
    r = cls.RANGES[name]
    default = getattr(cls(), name)
    for value in _bad_values(r, default):
        with pytest.raises(ParameterError) as e:
            cls(**{name: value})
        message = str(e.value)
        assert message.startswith(f"{cls.__name__}.{name} must be {r.describe()}, got "), message
        assert (e.value.owner, e.value.name) == (cls.__name__, name)
        assert isinstance(e.value, ValueError) and not isinstance(e.value, InputError)


@pytest.mark.parametrize(("cls", "name"), CASES, ids=[f"{c.__name__}.{n}" for c, n in CASES])
def test_the_ends_of_a_range_are_taken(cls, name):
    r = cls.RANGES[name]
    ends = [r.high] if r.open_low else [r.low, r.high]
    for end in ends:
        value = int(end) if r.integer else float(end)
        value = (value,) * r.items if r.items else value
        assert getattr(cls(**{name: value}), name) == value


def test_the_graph_method_refuses_parameters_of_another_class():
    from fhslam.slam import GraphFastHoughSLAM

    with pytest.raises(TypeError, match=r"^GraphFastHoughSLAM: lines must be a SlamParams, got M"):
        GraphFastHoughSLAM(lines=MatchParams())
    with pytest.raises(TypeError, match=r"params must be a GraphSlamParams, got SlamParams$"):
        GraphFastHoughSLAM(SlamParams())


def test_nested_parameters_must_be_of_their_class():
    for make, message in (
        (lambda: GraphSlamParams(tracker={"window": 0.3}), "GraphSlamParams.tracker must be"),
        (lambda: SlamParams(matching=3), "SlamParams.matching must be a MatchParams"),
        (lambda: SlamParams(extractor=5), "SlamParams.extractor must be callable"),
        (lambda: ExtractionParams(densify_step=1e-9), "densify_step must be 0 (off) or"),
    ):
        with pytest.raises(ParameterError, match=message.replace("(", r"\(").replace(")", r"\)")):
            make()


@pytest.mark.parametrize(
    ("setting", "names"),
    [
        ("tracker.window=-1", ["TrackerParams.window", ">= 0 and at most 10 m", "got -1.0"]),
        ("tracker.window=1e308", ["TrackerParams.window", "got 1e+308"]),
        ("tracker.resolution=1e-9", ["TrackerParams.resolution", ">= 0.01"]),
        ("tracker.refine_iterations=1000", ["TrackerParams.refine_iterations", "at most 100"]),
        ("tracker.prior_sigma=1", ["is not a number or switch"]),
        ("loops.growth=0", ["LoopParams.growth", "> 0"]),
        ("search.keyframes=0", ["GlobalSearchParams.keyframes", ">= 1"]),
        ("search.max_window=1e300", ["GlobalSearchParams.max_window"]),
        ("loops.min_score=1.5", ["LoopParams.min_score must be in [0, 1]"]),
        ("optimiser.tol=nan", ["optimiser.tol takes a finite number"]),
        ("keyframes.submap=2.5", ["keyframes.submap takes an integer"]),
        ("loop_min_score=0.5", ["'loop_min_score' is not a number or switch"]),
    ],
)
def test_slam_set_out_of_range_is_one_line_naming_the_option(
    setting, names, small_log, tmp_path, capsys
):
    out = tmp_path / "t.txt"
    code = main(["slam", str(small_log), "--trajectory", str(out), "--quiet", "--set", setting])
    assert code == 2
    one_line_error(capsys.readouterr().err, "--set", setting.partition("=")[0], *names)
    assert not out.exists()


def test_slam_set_names_the_option_of_the_bad_one_among_several(small_log, tmp_path, capsys):
    argv = ["slam", str(small_log), "--trajectory", str(tmp_path / "t.txt"), "--quiet"]
    argv += [
        "--set",
        "tracker.window=0.3",
        "--set",
        "tracker.resolution=0",
        "--set",
        "loops.radius=3",
    ]
    assert main(argv) == 2
    one_line_error(
        capsys.readouterr().err, "--set 'tracker.resolution=0': TrackerParams.resolution"
    )


def test_sweep_set_out_of_range_is_one_line(capsys, monkeypatch):
    from fhslam.experiments import compare

    monkeypatch.setattr(compare, "slam_sweep", lambda **kw: pytest.fail("the sweep ran"))
    assert main(["sweep", "--seeds", "1", "--quiet", "--set", "tracker.window=1e308"]) == 2
    one_line_error(capsys.readouterr().err, "--set 'tracker.window=1e308'", "TrackerParams")


# --------------------------------------------------------------------------------------------
# Map and keyframe-graph files: JSON as the standard has it


@pytest.fixture(scope="module")
def evaluate_files(tmp_path_factory) -> tuple[Path, list[str]]:
    """A folder with a trajectory and its truth (10 poses along the paper world's first
    corridor), and a good map's text lines (one line object per text line, from line 2)."""
    d = tmp_path_factory.mktemp("evaluate")
    t = np.arange(10.0)
    poses = np.column_stack([0.5 + 0.5 * t, np.full(10, 1.0), np.zeros(10)])
    write_trajectory(d / "est.txt", t, poses)
    write_trajectory(d / "truth.txt", t, poses)
    write_map(d / "good.json", lines_from_segments([[0, 0, 6, 0], [6, 0, 6, 4], [6, 4, 0, 4]], 5))
    return d, (d / "good.json").read_text().splitlines()


def _evaluate_map(d: Path, text: str, capsys) -> tuple[int, str]:
    (d / "m.json").write_text(text)
    argv = ["evaluate", str(d / "est.txt"), "--truth", str(d / "truth.txt")]
    code = main([*argv, "--world", "paper", "--map", str(d / "m.json")])
    out, err = capsys.readouterr()
    assert code != 2 or out == ""
    return code, err


def test_the_good_map_evaluates(evaluate_files, capsys):
    d, lines = evaluate_files
    assert _evaluate_map(d, "\n".join(lines), capsys) == (0, "")


N_MUST = "m.json: lines[1]: 'n' must be a whole number from 0 to 9223372036854775807, got"


@pytest.mark.parametrize(
    ("old", "new", "says"),
    [
        ('"n": 5', '"n": NaN', f"{N_MUST} NaN (line 3)"),
        ('"n": 5', '"n": Infinity', f"{N_MUST} Infinity (line 3)"),
        ('"n": 5', '"n": -Infinity', f"{N_MUST} -Infinity (line 3)"),
        ('"n": 5', '"n": 1e400', f"{N_MUST} 1e400 (line 3)"),
        ('"n": 5', '"n": 1E+999', f"{N_MUST} 1E+999 (line 3)"),
        ('"n": 5', '"n": 1e19', f"{N_MUST} 1e+19"),
        ('"n": 5', '"n": 2.5', f"{N_MUST} 2.5"),
        ('"n": 5', '"n": ' + "9" * 200, "m.json:3: an integer of 200 digits (at most 100)"),
        ('"sp": [6.0', '"sp": [NaN', "m.json: lines[1]: 'sp' coordinate is not finite: NaN (li"),
        ('"rho": ', '"rho": 1e400, "x": ', "m.json: lines[1]: 'rho' is not finite: 1e400 (line 3)"),
        ('"sp": [6.0', '"sp": [1e300', "m.json: lines[1]: 'sp' coordinate 1e+300 m is beyond"),
    ],
)
def test_a_map_with_numbers_json_has_not_is_one_line_naming_the_line(
    old, new, says, evaluate_files, capsys
):
    d, lines = evaluate_files
    assert old in lines[2]
    bad = [*lines[:2], lines[2].replace(old, new, 1), *lines[3:]]
    code, err = _evaluate_map(d, "\n".join(bad), capsys)
    assert code == 2
    one_line_error(err, says)


def test_a_map_nested_too_deeply_is_one_line(evaluate_files, capsys):
    d, _ = evaluate_files
    code, err = _evaluate_map(d, '{"lines": ' + "[" * 100_000 + "]" * 100_000 + "}", capsys)
    assert code == 2
    one_line_error(err, "m.json: not readable JSON (lists or objects nested too deeply)")


def test_parse_json_names_the_line_of_each_word_not_of_a_string_holding_it():
    text = '{"note": "NaN, Infinity, 1e400",\n "a": [1, -Infinity],\n "b": [3, NaN, 2e999]}'
    data = parse_json(text, "f.json", InputError)
    assert data["note"] == "NaN, Infinity, 1e400"
    assert [repr(v) for v in (*data["a"], *data["b"])] == [
        "1",
        "-Infinity (line 2)",
        "3",
        "NaN (line 3)",
        "2e999 (line 3)",
    ]
    assert data["a"][1] == -np.inf and np.isnan(data["b"][1]) and data["b"][2] == np.inf
    assert parse_json('{"b": 1e300, "c": -0}', "f.json", InputError) == {"b": 1e300, "c": 0}
    assert parse_json("[" + "9" * MAX_INTEGER_DIGITS + "]", "f.json", InputError)
    with pytest.raises(InputError, match=r"^f\.json:2: an integer of 101 digits"):
        parse_json("[1,\n -" + "9" * 101 + "]", "f.json", InputError)


@pytest.mark.parametrize(
    ("row", "says"),
    [
        ("[1.0, NaN, 0, 0]", "keyframes[1]: x is not finite: NaN (line 3)"),
        ("[1.0, 0, Infinity, 0]", "keyframes[1]: y is not finite: Infinity (line 3)"),
        ("[1.0, 0, 0, 1e400]", "keyframes[1]: theta is not finite: 1e400 (line 3)"),
    ],
)
def test_a_keyframe_graph_with_numbers_json_has_not_names_the_field_and_line(row, says, tmp_path):
    path = tmp_path / "g.json"
    path.write_text('{"keyframes": [\n  [0.0, 0, 0, 0],\n  ' + row + '],\n "loops": []}\n')
    with pytest.raises(GraphFormatError) as e:
        read_graph(path)
    assert str(e.value) == f"{path}: {says}"


# --------------------------------------------------------------------------------------------
# ROS bags: damaged bytes, cut short


def _damaged(source: Path, where: str) -> bytes:
    data = bytearray(source.read_bytes())
    n = len(data)
    if where == "cut at 50 %":
        return bytes(data[: n // 2])
    size = 4096 if "kB" in where else 2000
    start = {  # 2,000 bytes centred on the place, or the first or last 4,096
        "25 %": n // 4 - 1000,
        "50 %": n // 2 - 1000,
        "75 %": 3 * n // 4 - 1000,
        "first 4 kB": 0,
        "last 4 kB": n - 4096,
    }[where]
    for i in range(start, start + size):
        data[i] ^= 0xFF
    return bytes(data)


@pytest.mark.parametrize(
    ("where", "names"),
    [
        ("25 %", ["scan 1822 of topic '/scan': damaged data in chunk 5 of 17 (bytes 340485-"]),
        ("50 %", ["not a readable ROS bag", "its records break at byte 688663"]),
        ("75 %", ["scan 5478 of topic '/scan': damaged data in chunk 13 of 17", "bytes"]),
        ("first 4 kB", []),  # the magic gone: not a bag, read as a CARMEN log and refused
        ("last 4 kB", ["not a readable ROS bag", "its records break at byte"]),
        ("cut at 50 %", ["its records break at byte 688663", "runs past the end of the file"]),
    ],
)
def test_a_damaged_aces_bag_is_one_line_naming_where(where, names, real_data, tmp_path, capsys):
    source = real_data / "aces.orig.bag"
    if not source.exists():
        pytest.skip("no aces.orig.bag in the shared data")
    bag = tmp_path / "x.bag"
    bag.write_bytes(_damaged(source, where))
    assert main(["info", str(bag)]) == 2
    one_line_error(capsys.readouterr().err, "x.bag", *names)
    if where == "25 %":  # slam reads the bag the same way, and writes nothing
        out = tmp_path / "t.txt"
        assert main(["slam", str(bag), "--trajectory", str(out), "--quiet"]) == 2
        one_line_error(capsys.readouterr().err, "x.bag", *names)
        assert not out.exists()


def test_bytes_damaged_across_a_small_bag_end_cleanly(tmp_path, capsys):
    """A small uncompressed bag, with 1 or 4 bytes flipped at every 71st byte: its records'
    headers, its messages' fields and lengths: each run ends in a result (perhaps with
    warnings) or in one line naming the bag; never in a traceback or an internal error."""
    from test_rosbag import write_bag

    whole = write_bag(tmp_path / "g.bag", scans=6).read_bytes()
    bag, out = tmp_path / "d.bag", tmp_path / "t.txt"
    errors = []
    for at in range(13, len(whole), 71):
        for n in (1, 4):
            data = bytearray(whole)
            for i in range(at, min(at + n, len(data))):
                data[i] ^= 0xFF
            bag.write_bytes(bytes(data))
            code = main(["slam", str(bag), "--trajectory", str(out), "--method", "odometry"])
            err = capsys.readouterr().err
            where = f"{n} bytes at {at}: {err}"
            assert code in (0, 2) and "internal error" not in err and "Traceback" not in err, where
            if code == 2:
                errors.append(one_line_error(err, "d.bag"))
            else:
                assert all(ln.startswith("fhslam: warning: ") for ln in err.splitlines()), where
    damaged = [e for e in errors if "damaged data in chunk 1 of 1 (bytes " in e]
    assert len(damaged) >= 10 and any("scan" in e for e in damaged), errors
    assert any("its records break at byte" in e for e in errors), errors


# --------------------------------------------------------------------------------------------
# numba's cache where the package's folders cannot be written

BLOCKED = """
import os, sys, tempfile
blocked = [os.path.realpath(b) for b in sys.argv[1].split(os.pathsep) if b]
real = tempfile.TemporaryFile
def refuse(*args, dir=None, **kw):  # numba's and fhslam._numba's test of a cache folder
    if dir is not None:
        d = os.path.realpath(dir)
        if any(d == b or d.startswith(b + os.sep) for b in blocked):
            raise PermissionError(13, "Permission denied", str(dir))
    return real(*args, dir=dir, **kw)
tempfile.TemporaryFile = refuse
from fhslam.cli import main
sys.exit(main(sys.argv[2:]))
"""
"""``python -c BLOCKED FOLDERS ARGS...``: the command, in a process where no file can be
created in the folders ``FOLDERS`` (joined by ``os.pathsep``), as for a user who may not
write there: the package's own folder and the user's home, as installed by root."""


def _blocked_run(tmp_path: Path, blocked: list[Path], *args: str, **env: str):
    environ = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    environ.update(env)
    folders = os.pathsep.join(str(b) for b in blocked)
    return subprocess.run(
        [sys.executable, "-c", BLOCKED, folders, *args],
        capture_output=True,
        text=True,
        timeout=600,
        cwd=tmp_path,
        env=environ,
    )


@pytest.fixture
def user_folders(tmp_path) -> dict[str, Path]:
    out = {name: tmp_path / name for name in ("home", "xdg", "tmp")}
    for p in out.values():
        p.mkdir()
    return out


def test_a_package_and_home_that_cannot_be_written_cache_in_a_private_temp_folder(
    tmp_path, user_folders
):
    """Without a writable ``__pycache__`` beside the package and a writable home (nor
    ``XDG_CACHE_HOME``) numba finds no cache folder, and every command failed with "cannot
    cache function ...: no locator available". The kernels are cached in the user's own
    folder in the temporary folder instead, without a word."""
    package = Path(fhslam.__file__).parent
    home, xdg, tmp = user_folders["home"], user_folders["xdg"], user_folders["tmp"]
    env = {"HOME": str(home), "XDG_CACHE_HOME": str(xdg), "TMPDIR": str(tmp)}
    argv = ["simulate", "paper", "--log", "p.clf", "--truth", "p.txt"]
    r = _blocked_run(tmp_path, [package, home, xdg], *argv, **env)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    cache = tmp / f"fhslam-numba-{os.getuid()}"
    assert stat.S_IMODE(cache.stat().st_mode) == 0o700
    assert list(cache.rglob("geometry._transform-*.nbi")), sorted(cache.rglob("*"))
    # given an unwritable NUMBA_CACHE_DIR, the same
    shutil.rmtree(cache)
    r = _blocked_run(tmp_path, [package, home, xdg], *argv, NUMBA_CACHE_DIR="/proc/x", **env)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    assert list(cache.rglob("geometry._transform-*.nbi"))


def test_a_writable_cache_folder_of_the_user_is_taken_first(tmp_path, user_folders):
    package = Path(fhslam.__file__).parent
    home, xdg, tmp = user_folders["home"], user_folders["xdg"], user_folders["tmp"]
    env = {"HOME": str(home), "XDG_CACHE_HOME": str(xdg), "TMPDIR": str(tmp)}
    r = _blocked_run(tmp_path, [package], "simulate", "paper", "--log", "p", "--truth", "t", **env)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    assert list((xdg / "fhslam" / "numba").rglob("geometry._transform-*.nbi"))
    assert list(tmp.iterdir()) == []


def test_no_writable_cache_folder_at_all_compiles_without_one_saying_so_once(
    tmp_path, user_folders
):
    package = Path(fhslam.__file__).parent
    home, xdg, tmp = user_folders["home"], user_folders["xdg"], user_folders["tmp"]
    env = {"HOME": str(home), "XDG_CACHE_HOME": str(xdg), "TMPDIR": str(tmp)}
    argv = ["simulate", "paper", "--log", "p.clf", "--truth", "p.txt"]
    r = _blocked_run(tmp_path, [package, home, xdg, tmp], *argv, **env)
    assert r.returncode == 0, r.stderr
    lines = r.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("fhslam: warning: no writable folder for")
    assert "set NUMBA_CACHE_DIR" in lines[0] and str(tmp / "fhslam-numba-") in lines[0]
    assert (tmp_path / "p.clf").stat().st_size > 0


@pytest.mark.skipif(not hasattr(os, "getuid"), reason="POSIX users")
def test_cache_folder_choice(tmp_path, monkeypatch):
    """:func:`fhslam._numba.cache_folder` in the cases numba cannot cache by itself. A folder
    under ``/proc`` cannot be made even by root."""
    unwritable = (Path("/proc/fhslam-no-such-folder"),)
    if _numba._writable(unwritable[0]):
        pytest.skip("no /proc: no folder that root cannot write")
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    fine = (tmp_path / "pkg",)
    env = {"HOME": "/proc/h", "XDG_CACHE_HOME": str(tmp_path / "xdg")}
    assert _numba.cache_folder(env, fine) == (None, True)  # beside the sources
    assert _numba.cache_folder({**env, "NUMBA_CACHE_DIR": str(tmp_path / "n")}, unwritable) == (
        None,
        True,
    )
    assert _numba.cache_folder(env, unwritable) == (tmp_path / "xdg" / "fhslam" / "numba", True)
    home = {"HOME": str(tmp_path / "home")}
    assert _numba.cache_folder(home, unwritable) == (
        tmp_path / "home" / ".cache" / "fhslam" / "numba",
        True,
    )
    nowhere = {"HOME": "/proc/h", "XDG_CACHE_HOME": "/proc/x", "NUMBA_CACHE_DIR": "/proc/n"}
    private = tmp_path / "tmp" / f"fhslam-numba-{os.getuid()}"
    assert _numba.cache_folder(nowhere, unwritable) == (private, True)
    assert stat.S_IMODE(private.stat().st_mode) == 0o700
    private.chmod(0o777)  # another user could put compiled code there: not taken
    assert _numba.cache_folder(nowhere, unwritable) == (None, False)
    private.rmdir()
    private.symlink_to(tmp_path / "home")  # nor through a link
    assert _numba.cache_folder(nowhere, unwritable) == (None, False)


def test_no_module_imports_numba_but_the_shim():
    """numba reads ``NUMBA_CACHE_DIR`` when it is first imported: only :mod:`fhslam._numba`,
    which settles it first, may import numba."""
    package = Path(fhslam.__file__).parent
    found = [
        str(p.relative_to(package))
        for p in package.rglob("*.py")
        if p.name != "_numba.py"
        and any(
            ln.lstrip().startswith(("import numba", "from numba"))
            for ln in p.read_text(encoding="utf-8").splitlines()
        )
    ]
    assert found == []


def test_a_user_who_cannot_write_the_package_runs_it(tmp_path):
    """The case itself, where it can be made: root runs the command as ``nobody`` (whose
    home, ``/nonexistent``, does not exist), with this interpreter and this package."""
    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        pytest.skip("needs root, to run the command as another user")
    try:
        probe = subprocess.run(
            [sys.executable, "-c", "import fhslam.cli"], user=65534, capture_output=True
        )
    except (OSError, subprocess.SubprocessError):
        probe = None
    if probe is None or probe.returncode != 0:
        pytest.skip("the user nobody cannot run this interpreter or read this package")
    work = tmp_path / "work"
    work.mkdir()
    tmp_path.chmod(0o755)
    work.chmod(0o777)
    env = {"PATH": os.environ.get("PATH", ""), "HOME": "/nonexistent", "TMPDIR": str(work)}
    r = subprocess.run(
        [sys.executable, "-m", "fhslam.cli", "simulate", "paper", "--log", "p", "--truth", "t"],
        user=65534,
        cwd=work,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert r.returncode == 0 and r.stderr == "", r.stderr


# --------------------------------------------------------------------------------------------
# A bug: one line, exit status 1; --debug shows the traceback


@pytest.fixture
def broken_info(monkeypatch):
    import fhslam.cli.info

    def broken(args):
        raise RuntimeError("a bug\n  on two lines")

    monkeypatch.setattr(fhslam.cli.info, "run", broken)


def test_a_bug_is_one_line_and_exit_status_1(broken_info, small_log, capsys):
    assert main(["info", str(small_log)]) == 1
    out, err = capsys.readouterr()
    assert err == f"fhslam: internal error: RuntimeError: a bug on two lines {INTERNAL}\n"
    assert out == ""


@pytest.mark.parametrize("where", ["before", "after"])
def test_debug_before_or_after_the_command_shows_the_traceback(
    where, broken_info, small_log, capsys
):
    argv = ["--debug", "info", str(small_log)] if where == "before" else ["info", "--debug"]
    if where == "after":
        argv.append(str(small_log))
    with pytest.raises(RuntimeError, match="a bug"):
        main(argv)
    assert capsys.readouterr().err == ""


def test_debug_does_not_change_bad_input(small_log, tmp_path, capsys):
    assert main(["--debug", "info", str(tmp_path / "none.clf")]) == 2
    one_line_error(capsys.readouterr().err, "none.clf")
    assert main(["info", str(small_log), "--debug"]) == 0


def test_the_command_shows_a_bug_as_one_line_and_its_traceback_with_debug(small_log):
    script = (
        "import sys, fhslam.cli\n"
        "def broken(args):\n"
        "    raise KeyError('lost')\n"
        "fhslam.cli.info.run = broken\n"
        "sys.exit(fhslam.cli.main(sys.argv[1:]))\n"
    )
    r = subprocess.run(
        [sys.executable, "-c", script, "info", str(small_log)], capture_output=True, text=True
    )
    assert r.returncode == 1 and r.stdout == ""
    assert r.stderr == f"fhslam: internal error: KeyError: 'lost' {INTERNAL}\n"
    r = subprocess.run(
        [sys.executable, "-c", script, "--debug", "info", str(small_log)],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 1 and "Traceback (most recent call last)" in r.stderr
    assert r.stderr.rstrip().endswith("KeyError: 'lost'") and "internal error" not in r.stderr


def test_ctrl_c_and_exits_keep_their_ways(monkeypatch, small_log, capsys):
    import fhslam.cli.info

    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(fhslam.cli.info, "run", interrupted)
    assert main(["info", str(small_log)]) == 130
    assert capsys.readouterr().err.startswith("fhslam: interrupted")

    def leaves(args):
        sys.exit(3)

    monkeypatch.setattr(fhslam.cli.info, "run", leaves)
    with pytest.raises(SystemExit) as e:
        main(["info", str(small_log)])
    assert e.value.code == 3


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX pipes")
def test_a_closed_standard_output_ends_quietly(small_log):
    """``fhslam info LOG | head -1``: the reader goes away before the command has written;
    no message, and exit status 141 (as a shell reports SIGPIPE)."""
    p = subprocess.Popen(
        [sys.executable, "-m", "fhslam.cli", "info", str(small_log)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    p.stdout.close()
    err = p.stderr.read().decode()
    assert p.wait(timeout=300) == 141 and err == ""
