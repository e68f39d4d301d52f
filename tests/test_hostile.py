"""A corpus of malformed and implausible inputs, each run through the ``fhslam`` command.

Every case must end in one of two ways (the contract in fhslam/cli.py's module docstring):

- ``error``: exit status 2 and exactly one line on stderr, ``fhslam: error: ...``, that names
  the offending file (and its line where there is one); no output written, no temporary file
  left behind;
- ``warn``: a documented acceptance of readable but implausible input: exit status 0, its
  outputs written, and one line ``fhslam: warning: ...`` per finding naming the file.

In both, no input file changes by a byte, and nothing hangs: each case runs under a time
limit (SIGALRM, :data:`TIMEOUT` seconds). A traceback (any exception other than the command's
own bad-input error) fails the case with that traceback. The command runs in this process
(``fhslam.cli.main``), as the console script does, so that the corpus stays fast; a few cases
also run as a separate process (:func:`test_the_installed_command_on_a_sample_of_the_corpus`).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from fhslam.cli import main

TIMEOUT = 60
"""Seconds a case may take (the slowest takes about 3 s on a 2-core machine)."""

OUT = "out.txt"
"""The output every ``slam`` case asks for, in the case's own folder."""


# --------------------------------------------------------------------------------------------
# Inputs


def _base_clf(n_scans: int = 12) -> list[str]:
    """A small valid CARMEN log of the paper world, as lines (header comments dropped)."""
    import tempfile

    from fhslam.io import write_carmen
    from fhslam.sim import paper_world, simulate

    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "base.clf"
        write_carmen(simulate(paper_world(), seed=0, max_scans=n_scans), p)
        return [ln for ln in p.read_text().splitlines() if not ln.startswith("#")]


BASE = _base_clf()
SCAN_LINES = [i for i, ln in enumerate(BASE) if ln.startswith("FLASER")]
"""Indices (0-based) of BASE's laser lines; the file line is index + 1."""


def _base_robotlaser1(n_scans: int = 12) -> list[str]:
    """A small valid CARMEN log of ``ROBOTLASER1`` lines (a 270° laser of 271 beams, 10 m,
    which ``FLASER`` cannot describe), as lines. Fields of a line: 2 start_angle, 4
    angular_resolution, 5 maximum_range, 8 num_readings, 9... the readings, then
    num_remissions (0), laser pose, robot pose, ..., ipc_timestamp host logger_timestamp."""
    import tempfile

    from fhslam.io import write_carmen
    from fhslam.sim import LaserParams, paper_world, simulate

    laser = LaserParams(n_beams=271, fov_deg=270.0, max_range=10.0)
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "base.clf"
        write_carmen(simulate(paper_world(), seed=0, max_scans=n_scans, laser=laser), p)
        return [ln for ln in p.read_text().splitlines() if not ln.startswith("#")]


BASE_RL = _base_robotlaser1()
RL_LINES = [i for i, ln in enumerate(BASE_RL) if ln.startswith("ROBOTLASER1")]
"""Indices (0-based) of BASE_RL's laser lines; the file line is index + 1."""


def _clf(lines: list[str]) -> str:
    return "\n".join(lines) + "\n"


def _edit_scan(
    k: int, edit: Callable[[list[str]], list[str]], base: list[str] | None = None
) -> tuple[str, int]:
    """BASE (or BASE_RL, ``base=BASE_RL``) with the k-th laser line's fields edited; and
    that line's number in the file."""
    lines = list(BASE if base is None else base)
    i = (SCAN_LINES if base is None else RL_LINES)[k]
    lines[i] = " ".join(edit(lines[i].split()))
    return _clf(lines), i + 1


def _edit_rl(k: int, edit: Callable[[list[str]], list[str]]) -> tuple[str, int]:
    """BASE_RL with the k-th ROBOTLASER1 line's fields edited; and that line's number."""
    return _edit_scan(k, edit, BASE_RL)


def _set_field(index: int, value: str) -> Callable[[list[str]], list[str]]:
    def edit(f: list[str]) -> list[str]:
        f[index] = value
        return f

    return edit


def _set_reading(k: int, value: str) -> tuple[str, int]:
    def edit(f: list[str]) -> list[str]:
        f[2 + 40] = value  # the 41st reading
        return f

    return _edit_scan(k, edit)


def _set_times(times: list[float], base: list[str] | None = None) -> str:
    """BASE (or BASE_RL) with the laser lines' timestamps (ipc, logger) set to ``times``."""
    lines = list(BASE if base is None else base)
    for i, t in zip(SCAN_LINES if base is None else RL_LINES, times, strict=False):
        f = lines[i].split()
        f[-3] = f[-1] = repr(t)
        lines[i] = " ".join(f)
    return _clf(lines)


def _odometry_jump(k: int, metres: float) -> str:
    """BASE with the odometry (and laser pose) of laser lines k, k+1, ... moved ``metres``."""
    lines = list(BASE)
    for i in SCAN_LINES[k:]:
        f = lines[i].split()
        n = int(f[1])
        for j in (2 + n, 2 + n + 3):  # laser x, odometry x
            f[j] = repr(float(f[j]) + metres)
        lines[i] = " ".join(f)
    return _clf(lines)


def _wide_scan(n: int) -> str:
    """A log of two scans of ``n`` beams each (a wall 2 m ahead)."""
    r = " ".join(["2.0"] * n)
    return "".join(f"FLASER {n} {r} 0.{k} 0 0 0.{k} 0 0 {k}.0 host {k}.0\n" for k in range(2))


def _all_max_range(scans: slice = slice(None)) -> str:
    """BASE with every reading of every scan (or of ``scans``) at the laser's no-return code
    (81.91 m)."""
    lines = list(BASE)
    for i in SCAN_LINES[scans]:
        f = lines[i].split()
        n = int(f[1])
        f[2 : 2 + n] = ["81.91"] * n
        lines[i] = " ".join(f)
    return _clf(lines)


class _Fifo:
    """A named pipe in a case's files (nothing ever writes into it: opening it blocks)."""


FIFO = _Fifo()

PNG = b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + bytes(range(256)) * 4
BINARY = zlib.compress(bytes(range(256)) * 64)

WORLD = {
    "name": "box",
    "walls": [[0, 0, 6, 0], [6, 0, 6, 4], [6, 4, 0, 4], [0, 4, 0, 0]],
    "route": [[1, 1], [5, 1], [5, 3]],
}


def _world(**changes) -> str:
    w = dict(WORLD, **changes)
    return json.dumps({k: v for k, v in w.items() if v is not None})


TRUTH = "".join(f"{0.2 * k:.1f} {0.1 * k} 0 0\n" for k in range(10))
"""A trajectory of 10 poses, also used as ground truth."""


# --------------------------------------------------------------------------------------------
# Cases


@dataclass
class Case:
    """A command line run on files written into the case's folder.

    ``files`` maps a file name to its content (text or bytes; a name ending in ``/`` is a
    folder, the content :data:`FIFO` a named pipe). In ``argv``, ``{d}`` stands for the
    folder. ``expect`` is ``"error"`` or ``"warn"``; ``names`` must appear in the message
    (the file and, where there is one, the line; ``{d}`` as above), ``outputs`` are the
    files the command writes when it succeeds.
    """

    id: str
    argv: list[str]
    files: dict[str, str | bytes | _Fifo]
    expect: str
    names: list[str]
    outputs: tuple[str, ...] = ()


def _slam(
    name: str, content: str | bytes, expect: str = "error", names=None, method="odometry", **kw
) -> Case:
    """``fhslam slam LOG --method odometry`` (the reader's cases: fast, no SLAM involved);
    ``method``: another method (``None``: the default)."""
    chosen = [] if method is None else ["--method", method]
    return Case(
        id=kw.pop("id"),
        argv=["slam", "{d}/" + name, *chosen, "--trajectory", "{d}/" + OUT, "--quiet"],
        files={name: content},
        expect=expect,
        names=names if names is not None else [name],
        outputs=(OUT,) if expect == "warn" else (),
    )


def _log_cases() -> list[Case]:
    cases = []
    for value, what in [
        ("abc", "not-a-number"),
        ("nan", "nan"),
        ("inf", "inf"),
        ("-1.5", "negative"),
        ("1e308", "huge"),
    ]:
        content, line = _set_reading(3, value)
        expect = "error" if what == "not-a-number" else "warn"
        cases.append(
            _slam("log.clf", content, expect, names=[f"log.clf:{line}"], id=f"clf-range-{what}")
        )
    content, line = _edit_scan(2, lambda f: f[: len(f) // 2])
    cases.append(_slam("log.clf", content, names=[f"log.clf:{line}"], id="clf-truncated-line"))
    content, line = _edit_scan(2, lambda f: [f[0], str(int(f[1]) + 1), *f[2:]])
    cases.append(_slam("log.clf", content, names=[f"log.clf:{line}"], id="clf-beam-count+1"))
    content, line = _edit_scan(2, lambda f: [f[0], str(int(f[1]) - 1), *f[2:]])
    cases.append(_slam("log.clf", content, names=[f"log.clf:{line}"], id="clf-beam-count-1"))
    content, line = _edit_scan(1, lambda f: [f[0], "181.5", *f[2:]])
    cases.append(_slam("log.clf", content, names=[f"log.clf:{line}"], id="clf-beam-count-float"))
    content, line = _edit_scan(1, lambda f: [*f[:-6], "nan", *f[-5:]])
    cases.append(_slam("log.clf", content, names=[f"log.clf:{line}"], id="clf-pose-nan"))
    whole = _clf(BASE)
    last = whole.rindex("FLASER")
    cut = whole[: last + (len(whole) - last) // 2]  # the last laser line cut in half, no EOL
    cases += [
        _slam("log.clf", "", id="clf-empty"),
        _slam("log.clf", "# nothing but a comment\n", id="clf-comments-only"),
        _slam("log.clf", cut, names=[f"log.clf:{SCAN_LINES[-1] + 1}"], id="clf-truncated-file"),
        _slam("log.clf", BINARY, id="clf-binary"),
        _slam("log.clf", PNG, id="clf-png-renamed"),
        _slam("log.png", PNG, id="png"),
        _slam("log.clf", _wide_scan(100_000), "warn", id="clf-100000-beams"),
        _slam("log.clf", _wide_scan(0), id="clf-zero-beams"),
        _slam("log.clf", _clf(BASE[: SCAN_LINES[0] + 1]), "warn", id="clf-single-scan"),
        _slam("log.clf", _odometry_jump(5, 1e6), "warn", ["log.clf:"], id="clf-odometry-jump"),
        _slam("log.clf", _set_times([0, 1, 2, 3, 2.5, 4, 5]), "warn", id="clf-time-backwards"),
        _slam("log.clf", _set_times([0, 1, 2, 2, 3, 4, 5]), "warn", id="clf-time-repeated"),
        _slam(
            "log.clf",
            _set_times([0, 1, 2] + [1e9 + k for k in range(9)]),
            "warn",
            names=[f"log.clf:{SCAN_LINES[3] + 1}: time leaps forward"],
            id="clf-time-leap",
        ),
        _slam("log.clf", _all_max_range(), "warn", id="clf-all-no-return"),
    ]
    # The SLAM methods themselves on what the reader accepts with a warning.
    some_empty = _all_max_range(slice(4, 7))
    for method in (None, "fht", "ekf"):
        m = method or "default"
        cases += [
            _slam("log.clf", _clf(BASE[: SCAN_LINES[0] + 1]), "warn", method=method,
                  id=f"{m}-single-scan"),
            _slam("log.clf", _all_max_range(), "warn", method=method, id=f"{m}-all-no-return"),
            _slam("log.clf", some_empty, "warn", method=method, id=f"{m}-3-scans-no-return"),
            _slam("log.clf", _odometry_jump(5, 1e6), "warn", method=method,
                  id=f"{m}-odometry-jump"),
            _slam("log.clf", _set_times([0, 1, 2, 3, 2.5, 4, 5]), "warn", method=method,
                  id=f"{m}-time-backwards"),
        ]  # fmt: skip
    cases.append(
        _slam("log.clf", _wide_scan(100_000), "warn", method=None, id="default-100000-beams")
    )
    return cases + _robotlaser1_cases()


def _robotlaser1_cases() -> list[Case]:
    """``ROBOTLASER1`` lines: malformed ones, readings no laser gives, and a header that
    states what no laser has (a maximum_range of 0, a resolution of 0 or 100 rad: errors, not
    a traceback or silence)."""
    n = int(BASE_RL[RL_LINES[0]].split()[8])
    cases = []
    for value, what in [("abc", "not-a-number"), ("nan", "nan"), ("inf", "inf"),
                        ("-1.5", "negative")]:  # fmt: skip
        content, line = _edit_rl(3, _set_field(9 + 40, value))
        expect = "error" if what == "not-a-number" else "warn"
        cases.append(
            _slam("log.clf", content, expect, names=[f"log.clf:{line}"], id=f"rl-range-{what}")
        )
    edits = {  # of the third laser line
        "rl-truncated-line": lambda f: f[: len(f) // 2],
        "rl-beam-count+1": _set_field(8, str(n + 1)),
        "rl-beam-count-1": _set_field(8, str(n - 1)),
        "rl-beam-count-float": _set_field(8, f"{n}.5"),
        "rl-remission-count-5": _set_field(9 + n, "5"),
        "rl-pose-nan": _set_field(9 + n + 4, "nan"),
    }
    for case_id, edit in edits.items():
        content, line = _edit_rl(2, edit)
        cases.append(_slam("log.clf", content, names=[f"log.clf:{line}"], id=case_id))
    headers = {  # of every laser line alike (the first one is named)
        "rl-header-not-a-number": (3, "wide"),
        "rl-max-range-0": (5, "0"),
        "rl-max-range-negative": (5, "-5"),
        "rl-max-range-nan": (5, "nan"),
        "rl-max-range-1e308": (5, "1e308"),
        "rl-resolution-0": (4, "0"),
        "rl-resolution-negative": (4, "-0.0174533"),
        "rl-resolution-100-rad": (4, "100"),
        "rl-start-angle-in-degrees": (2, "-135"),
    }
    first = f"log.clf:{RL_LINES[0] + 1}:"
    for case_id, (index, value) in headers.items():
        lines = list(BASE_RL)
        for i in RL_LINES:
            lines[i] = " ".join(_set_field(index, value)(lines[i].split()))
        cases.append(_slam("log.clf", _clf(lines), names=[first], id=case_id))
    whole = _clf(BASE_RL)
    last = whole.rindex("ROBOTLASER1")
    cut = whole[: last + (len(whole) - last) // 2]
    cases += [
        _slam("log.clf", cut, names=[f"log.clf:{RL_LINES[-1] + 1}"], id="rl-truncated-file"),
        _slam("log.clf", _set_times([0, 1, 2] + [1e9 + k for k in range(9)], BASE_RL),
              "warn", names=[f"log.clf:{RL_LINES[3] + 1}: time leaps forward"],
              id="rl-time-leap"),
        _slam("log.clf", _set_times([0, 1, 2, 1.5] + [3 + k for k in range(8)], BASE_RL),
              "warn", names=[f"log.clf:{RL_LINES[3] + 1}: time goes backwards"],
              id="rl-time-backwards"),
    ]  # fmt: skip
    return cases


def _bag(name: str, **kw) -> bytes:
    import tempfile

    from test_rosbag import write_bag

    with tempfile.TemporaryDirectory() as d:
        return write_bag(Path(d) / name, **kw).read_bytes()


def _bag_cases() -> list[Case]:
    whole = _bag("g.bag", scans=6)
    nan, inf = float("nan"), float("inf")

    def readings(value: float) -> Callable:
        return lambda k, a: np.full(len(a), value)

    def some(value: float) -> Callable:  # the wall, with every other beam at value
        return lambda k, a: np.where(np.arange(len(a)) % 2 == 0, 2.0, value)

    scan0, odom = ["t.bag", "scan 0 of topic '/scan'"], ["t.bag", "odometry message"]
    return [
        _slam("t.bag", whole[: len(whole) // 2], id="bag-truncated"),
        _slam("t.bag", whole[:13], id="bag-magic-only"),
        _slam("t.bag", _bag("n.bag", odom=False), id="bag-no-odometry"),
        _slam("t.bag", _bag("b.bag", scans=4, stamps=[10, 11, 13, 12]), "warn",
              id="bag-time-backwards"),
        _slam("t.bag", _bag("r.bag", scans=4, stamps=[10, 11, 11, 12]), "warn",
              id="bag-time-repeated"),
        _slam("t.bag", _bag("l.bag", scans=4, stamps=[10, 11, 10**9, 10**9 + 1]), "warn",
              ["t.bag: scan 2"], id="bag-time-leap"),
        # readings: NaN and inf are REP 117's codes (no return), negative ones none
        _slam("t.bag", _bag("a.bag", ranges=readings(nan)), "warn", id="bag-ranges-all-nan"),
        _slam("t.bag", _bag("a.bag", ranges=readings(inf)), "warn", id="bag-ranges-all-inf"),
        _slam("t.bag", _bag("a.bag", ranges=some(-1.0)), "warn", id="bag-ranges-negative"),
        _slam("t.bag", _bag("a.bag", ranges=some(1e6)), "warn", id="bag-ranges-1e6"),
        # what no laser states, no odometry gives
        _slam("t.bag", _bag("m.bag", range_max=0.0), names=scan0, id="bag-range-max-0"),
        _slam("t.bag", _bag("m.bag", range_max=-1.0), names=scan0, id="bag-range-max-negative"),
        _slam("t.bag", _bag("m.bag", range_max=nan), names=scan0, id="bag-range-max-nan"),
        _slam("t.bag", _bag("m.bag", range_max=inf), names=scan0, id="bag-range-max-inf"),
        _slam("t.bag", _bag("i.bag", increment=0.0), names=scan0, id="bag-increment-0"),
        _slam("t.bag", _bag("i.bag", increment=10.0), names=scan0, id="bag-increment-10-rad"),
        _slam("t.bag", _bag("i.bag", increment=nan), names=scan0, id="bag-increment-nan"),
        _slam("t.bag", _bag("o.bag", beams=1), names=scan0, id="bag-one-beam"),
        _slam("t.bag", _bag("o.bag", odom_x=lambda k: nan if k == 1 else 0.1 * k),
              names=[*odom, "message 1"], id="bag-odometry-nan"),
        _slam("t.bag", _bag("q.bag", quaternion=(0, 0, 0, nan)), names=odom,
              id="bag-quaternion-nan"),
        _slam("t.bag", _bag("q.bag", quaternion=(0, 0, 0, 0)), names=odom,
              id="bag-quaternion-zero"),
        _slam("t.bag", _bag("q.bag", mount=(0.1, 0.0, (0, 0, 0, 0))),
              names=["t.bag", "/tf_static"], id="bag-mount-quaternion-zero"),
    ]  # fmt: skip


def _path_cases() -> list[Case]:
    good = _clf(BASE)
    slam = ["slam", "{d}/log.clf", "--method", "odometry"]
    return [
        Case("log-missing", ["slam", "{d}/none.clf", "--trajectory", "{d}/" + OUT], {},
             "error", ["none.clf"]),
        Case("log-is-a-folder", ["slam", "{d}/logs", "--trajectory", "{d}/" + OUT],
             {"logs/": ""}, "error", ["logs"]),
        Case("unknown-dataset", ["slam", "nosuchlog", "--trajectory", "{d}/" + OUT], {},
             "error", ["nosuchlog"]),
        Case("info-missing", ["info", "{d}/none.clf"], {}, "error", ["none.clf"]),
        # a named pipe is refused unopened: opening it (as is_bag would) hangs the command
        Case("log-is-a-fifo", ["slam", "{d}/ff", "--trajectory", "{d}/" + OUT], {"ff": FIFO},
             "error", ["ff: is not a regular file"]),
        Case("info-fifo", ["info", "{d}/ff"], {"ff": FIFO}, "error", ["ff: is not a regular"]),
        Case("info-fifo-bag", ["info", "{d}/ff.bag"], {"ff.bag": FIFO}, "error",
             ["ff.bag: is not a regular file"]),
        Case("info-fifo-db3", ["info", "{d}/ff.db3"], {"ff.db3": FIFO}, "error",
             ["ff.db3: is not a regular file"]),
        Case("bench-fifo", ["bench", "--log", "{d}/ff", "--quiet"], {"ff": FIFO}, "error",
             ["ff: is not a regular file"]),
        # a registered dataset with relations only: an error, not a traceback
        Case("slam-relations-only-dataset", ["slam", "mit-killian", "--trajectory",
             "{d}/" + OUT], {}, "error", ["dataset 'mit-killian' has only relations"]),
        Case("info-relations-only-dataset", ["info", "mit-killian"], {}, "error",
             ["dataset 'mit-killian' has only relations", "--relations mit-killian"]),
        Case("bench-relations-only-dataset", ["bench", "--log", "mit-killian", "--quiet"], {},
             "error", ["dataset 'mit-killian' has only relations"]),
        Case("output-is-the-input", [*slam, "--trajectory", "{d}/log.clf"],
             {"log.clf": good}, "error", ["log.clf"]),
        Case("output-twice", [*slam, "--trajectory", "{d}/o.txt", "--map", "{d}/o.txt"],
             {"log.clf": good}, "error", ["o.txt"]),
        Case("output-is-a-folder", [*slam, "--trajectory", "{d}/outdir"],
             {"log.clf": good, "outdir/": ""}, "error", ["outdir"]),
        Case("output-in-a-missing-folder", [*slam, "--trajectory", "{d}/no/such/o.txt"],
             {"log.clf": good}, "error", ["o.txt"]),
        Case("output-under-a-file", [*slam, "--trajectory", "{d}/log.clf/o.txt"],
             {"log.clf": good}, "error", ["o.txt"]),
    ]  # fmt: skip


def _evaluate(name: str, content: str | bytes, names: list[str], id: str, **kw) -> Case:
    """``fhslam evaluate`` of a bad trajectory, truth, relations or map file."""
    which = kw.get("which", "trajectory")
    files = {"est.txt": TRUTH, "truth.txt": TRUTH, "world.json": _world()}
    argv = ["evaluate", "{d}/est.txt", "--truth", "{d}/truth.txt"]
    if which == "trajectory":
        files["est.txt"] = content
    elif which == "truth":
        files["truth.txt"] = content
    elif which == "relations":
        files[name] = content
        argv = ["evaluate", "{d}/est.txt", "--relations", "{d}/" + name]
    elif which == "map":
        files[name] = content
        argv += ["--world", "{d}/world.json", "--map", "{d}/" + name]
    return Case(id, argv, files, kw.get("expect", "error"), names)


def _map(*lines) -> str:
    return json.dumps({"lines": list(lines)}).replace("1e999", "Infinity")


def _map_line(**changes) -> dict:
    line = {"sp": [0.0, 0.0], "ep": [6.0, 0.0], "rho": 0.0, "theta": -1.5707963, "n": 3}
    line.update(changes)
    return line


def _evaluate_cases() -> list[Case]:
    rel = "10.0 10.4 0.1 0 0 0 0 0\n"
    return [
        _evaluate("est.txt", "", ["est.txt"], "trajectory-empty"),
        _evaluate("est.txt", BINARY, ["est.txt"], "trajectory-binary"),
        _evaluate("est.txt", TRUTH.replace("0.4 0.2", "0.4 abc"), ["est.txt:3"],
                  "trajectory-not-a-number"),
        _evaluate("est.txt", TRUTH.replace("0.4 0.2 0 0", "nan 0.2 0 0"), ["est.txt:3"],
                  "trajectory-nan-timestamp"),
        _evaluate("est.txt", TRUTH.replace("0.4 0.2 0 0", "0.4 0.2 0"), ["est.txt:3"],
                  "trajectory-three-columns"),
        _evaluate("est.txt", TRUTH.replace("0.4 0.2 0 0", "0.4 1e999 0 0"), ["est.txt:3"],
                  "trajectory-inf"),
        _evaluate("est.txt", TRUTH.replace("0.4 0.2", "0.2 0.1"), ["est.txt:3"],
                  "trajectory-repeated-time", expect="warn"),  # the same pose twice
        _evaluate("est.txt", TRUTH.replace("0.4 0.2", "0.2 0.2"), ["est.txt:3", "line 2"],
                  "trajectory-repeated-time-other-pose"),
        _evaluate("est.txt", TRUTH.replace("0.4 0.2", "0.1 0.2"), ["est.txt:3"],
                  "trajectory-time-backwards", expect="warn"),
        _evaluate("truth.txt", "".join(f"{100 + k} 0 0 0\n" for k in range(10)), ["truth.txt"],
                  "truth-unmatched-times", which="truth"),
        _evaluate("r.relations", "", ["r.relations"], "relations-empty", which="relations"),
        _evaluate("r.relations", "10.0 10.4 0.1 0 0\n", ["r.relations:1"],
                  "relations-five-columns", which="relations"),
        _evaluate("r.relations", rel.replace("0.1", "nan"), ["r.relations:1"],
                  "relations-nan", which="relations"),
        _evaluate("r.relations", rel, ["r.relations"], "relations-unmatched-times",
                  which="relations"),
        _evaluate("r.relations", PNG, ["r.relations"], "relations-png", which="relations"),
        _evaluate("m.json", "{not json", ["m.json"], "map-not-json", which="map"),
        _evaluate("m.json", BINARY, ["m.json"], "map-binary", which="map"),
        _evaluate("m.json", '{"lines": 5}', ["m.json"], "map-lines-not-a-list", which="map"),
        _evaluate("m.json", _map(_map_line(sp=[1e999, 0])), ["m.json"], "map-inf", which="map"),
        _evaluate("m.json", _map(_map_line(ep=[1e308, 0])), ["m.json"], "map-1e308",
                  which="map"),
        _evaluate("m.json", _map({"sp": [0, 0]}), ["m.json"], "map-missing-key", which="map"),
        _evaluate("m.json", _map(_map_line(rho=-1)), ["m.json"], "map-negative-rho",
                  which="map"),
        Case("evaluate-world-missing", ["evaluate", "{d}/t.txt", "--truth", "{d}/t.txt",
             "--world", "{d}/w.json", "--map", "{d}/m.json"],
             {"t.txt": TRUTH, "m.json": _map(_map_line())}, "error", ["w.json"]),
    ]  # fmt: skip


def _simulate(name: str, content: str | bytes, names: list[str], id: str) -> Case:
    return Case(
        id,
        ["simulate", "{d}/" + name, "--log", "{d}/o.clf", "--truth", "{d}/o.txt"],
        {name: content},
        "error",
        names,
    )


def _world_cases() -> list[Case]:
    w = "w.json"
    walls = WORLD["walls"]
    return [
        _simulate(w, "", [w], "world-empty"),
        _simulate(w, "{", [w], "world-not-json"),
        _simulate(w, BINARY, [w], "world-binary"),
        _simulate(w, PNG, [w], "world-png"),
        _simulate(w, "[1, 2]", [w], "world-not-an-object"),
        _simulate(w, _world(walls=None), [w, "walls"], "world-no-walls"),
        _simulate(w, _world(route=None), [w, "route"], "world-no-route"),
        _simulate(w, _world(walls=[]), [w], "world-empty-walls"),
        _simulate(w, _world(walls=[*walls, [2, 2, 2, 2]]), [w], "world-zero-length-wall"),
        _simulate(w, _world(walls=[*walls, [2, 2, 2]]), [w], "world-wall-three-numbers"),
        _simulate(w, _world(walls=[[0, 0, "a", 0], *walls[1:]]), [w], "world-wall-text"),
        _simulate(w, _world(route=[[1, 1], [5, "x"]]), [w], "world-route-text"),
        _simulate(w, _world(route=[[1, 1]]), [w], "world-one-point-route"),
        _simulate(w, _world(route=[[0, 2], [5, 2]]), [w], "world-start-on-a-wall"),
        _simulate(w, _world(route=[[-50, -50], [5, 1]]), [w], "world-start-outside"),
        _simulate(w, _world(route=[[1, 1], [8, 1]]), [w], "world-route-through-a-wall"),
        _simulate(w, _world(route=[[1, 1], [1e308, 1]]), [w], "world-route-1e308"),
        _simulate(w, _world(walls=[*walls, [0, 0, 1e308, 0]]), [w], "world-wall-1e308"),
        _simulate(w, _world().replace("[1, 1]", "[NaN, 1]"), [w], "world-route-nan"),
        _simulate(w, _world().replace("[0, 0, 6, 0]", "[0, 0, Infinity, 0]"), [w],
                  "world-wall-inf"),
        _simulate(w, _world().replace("[0, 0, 6, 0]", f"[0, 0, {'9' * 5000}, 0]"), [w],
                  "world-wall-5000-digits"),
        _simulate(w, _world().replace("[0, 0, 6, 0]", "[0, 0, 1e400, 0]"), [w],
                  "world-wall-1e400"),
        _simulate(w, _world(walls="@").replace('"@"', "[" * 100_000 + "]" * 100_000),
                  [w, "nested"], "world-nested-100000-deep"),
        Case("world-missing", ["simulate", "{d}/none.json", "--log", "{d}/o.clf",
             "--truth", "{d}/o.txt"], {}, "error", ["none.json"]),
        Case("world-unknown-builtin", ["simulate", "nosuchworld", "--log", "{d}/o.clf",
             "--truth", "{d}/o.txt"], {}, "error", ["nosuchworld"]),
        Case("simulate-output-is-the-world", ["simulate", "{d}/w.json", "--log", "{d}/w.json",
             "--truth", "{d}/o.txt"], {w: _world()}, "error", [w]),
    ]  # fmt: skip


def _bench_cases() -> list[Case]:
    log = {"log.clf": _clf(BASE)}
    bench = ["bench", "--log", "{d}/log.clf", "--quiet"]
    return [
        Case("bench-scans-0", [*bench, "--scans", "0"], log, "error", ["--scans"]),
        Case("bench-repeats-0", [*bench, "--repeats", "0"], log, "error", ["--repeats"]),
        Case("bench-repeats-negative", [*bench, "--repeats", "-2"], log, "error", ["--repeats"]),
        Case("bench-bad-log", ["bench", "--log", "{d}/log.clf", "--quiet"],
             {"log.clf": BINARY}, "error", ["log.clf"]),
        Case("info-binary", ["info", "{d}/log.clf"], {"log.clf": BINARY}, "error", ["log.clf"]),
    ]  # fmt: skip


CASES = _log_cases() + _bag_cases() + _path_cases() + _evaluate_cases() + _world_cases()
CASES += _bench_cases()


# --------------------------------------------------------------------------------------------
# Running a case


class _Timeout(BaseException):
    """Not an Exception, which the command reports as an internal error (exit status 1)."""


def _alarm(signum, frame):
    raise _Timeout


def _snapshot(d: Path) -> dict[str, bytes | None]:
    """Every file under ``d`` (relative name -> bytes; folders -> None)."""
    return {
        str(p.relative_to(d)): (p.read_bytes() if p.is_file() else None)
        for p in sorted(d.rglob("*"))
    }


def _materialise(case: Case, d: Path) -> list[str]:
    for name, content in case.files.items():
        p = d / name
        if name.endswith("/"):
            p.mkdir()
        elif content is FIFO:
            os.mkfifo(p)
        elif isinstance(content, bytes):
            p.write_bytes(content)
        else:
            p.write_text(content)
    return [a.replace("{d}", str(d)) for a in case.argv]


def _run(case: Case, argv: list[str], capsys) -> tuple[int, str, str]:
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(TIMEOUT)
    try:
        code = main(argv)
    except _Timeout:
        pytest.fail(f"{case.id}: no answer within {TIMEOUT} s (a hang)")
    except SystemExit as e:  # argparse's own usage errors
        code = e.code
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    out, err = capsys.readouterr()
    return code, out, err


def _check(case: Case, d: Path, inputs, code: int, out: str, err: str) -> None:
    """The contract of the module docstring, for a case run in folder ``d``."""
    after = _snapshot(d)
    names = [n.replace("{d}", str(d)) for n in case.names]
    lines = err.splitlines()
    for name, content in inputs.items():  # no input changed, none removed
        assert after.get(name, b"<removed>") == content, f"{case.id}: input {name} changed"
    new = sorted(set(after) - set(inputs))
    assert not [n for n in new if n.endswith(".tmp")], f"{case.id}: temporary files left: {new}"

    if case.expect == "error":
        assert code == 2, f"{case.id}: exit {code}, stderr {err!r}"
        assert len(lines) == 1 and lines[0].startswith("fhslam: error: "), err
        for n in names:
            assert n in lines[0], f"{case.id}: {n!r} not named in {lines[0]!r}"
        assert new == [], f"{case.id}: output written despite the error: {new}"
        assert out == "", f"{case.id}: stdout {out!r} despite the error"
    else:
        assert code == 0, f"{case.id}: exit {code}, stderr {err!r}"
        assert lines and all(ln.startswith("fhslam: warning: ") for ln in lines), err
        for n in names:
            assert any(n in ln for ln in lines), f"{case.id}: {n!r} not named in {err!r}"
        assert new == sorted(case.outputs), f"{case.id}: outputs {new}"


@pytest.mark.skipif(not hasattr(signal, "SIGALRM"), reason="the time limit needs SIGALRM")
@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_every_hostile_input_ends_cleanly(case, tmp_path, capsys):
    if FIFO in case.files.values() and not hasattr(os, "mkfifo"):
        pytest.skip("no named pipes on this platform")
    argv = _materialise(case, tmp_path)
    inputs = _snapshot(tmp_path)
    code, out, err = _run(case, argv, capsys)
    _check(case, tmp_path, inputs, code, out, err)


SAMPLE = [
    "clf-range-nan",
    "clf-binary",
    "bag-truncated",
    "output-is-the-input",
    "world-binary",
    "log-is-a-fifo",
]


@pytest.mark.parametrize("case_id", SAMPLE)
def test_the_installed_command_on_a_sample_of_the_corpus(case_id, tmp_path):
    """The same contract for a separate process (``python -m fhslam.cli``), which also
    catches what an in-process run cannot: a crash of the interpreter, a hang inside
    compiled code (the time limit kills the process)."""
    case = next(c for c in CASES if c.id == case_id)
    argv = _materialise(case, tmp_path)
    inputs = _snapshot(tmp_path)
    r = subprocess.run(
        [sys.executable, "-m", "fhslam.cli", *argv],
        capture_output=True,
        text=True,
        timeout=TIMEOUT,
    )
    _check(
        case, tmp_path, inputs, r.returncode, r.stdout if case.expect == "error" else "", r.stderr
    )


def test_the_corpus_covers_every_command_and_both_endings():
    commands = {c.argv[0] for c in CASES}
    assert commands == {"slam", "info", "evaluate", "simulate", "bench"}
    assert sum(c.expect == "warn" for c in CASES) >= 5
    assert len(CASES) >= 80
    assert len({c.id for c in CASES}) == len(CASES)
    assert all(c.names for c in CASES)
