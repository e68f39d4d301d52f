"""Hostile inputs each run through the ``fhslam`` command, with the contract of
``tests/test_hostile.py``: an error is exit status 2 and exactly one line
``fhslam: error: ...`` naming the file; a warning is exit status 0 and one line
``fhslam: warning: ...`` naming the file; no input changes by a byte; nothing hangs.

- A CARMEN log that starts with a UTF-8 byte-order mark reads as it does without one.
- ``--plot`` writes the format its extension names (.png, .pdf, .svg); any other extension,
  or none, is refused before any work, naming the option, the path and the formats.
- A CARMEN log is read as a stream, in pieces of at most ``MAX_LINE`` characters: memory
  follows the scans kept, not the file. Lines that are not text (NUL bytes, bytes that are
  not UTF-8, a line longer than ``MAX_LINE``) are skipped with one warning naming the file,
  the line and byte where they start and how many bytes; the lines after them are read.
- ``$FHSLAM_DATA`` naming a file, or nothing, is refused when a dataset is looked up.
- A trajectory or truth file that repeats a timestamp with another pose is refused, naming
  both lines and the timestamp; a timestamp repeated with the same pose is read, warned of.
"""

from __future__ import annotations

import codecs
import gzip
import io
import json
import subprocess
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

from fhslam.cli import main
from fhslam.io import read_carmen, read_trajectory, write_carmen
from fhslam.io.carmen import MAX_LINE
from fhslam.sim import paper_world, simulate

SCANS = 12
"""Scans of the test log (the paper world, seed 0)."""


def _log_text(n_scans: int = SCANS) -> str:
    """A small valid CARMEN log of the paper world (``write_carmen``: comment lines, three
    ``PARAM`` lines, then an ``ODOM`` and a ``FLASER`` line per scan)."""
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "base.clf"
        write_carmen(simulate(paper_world(), seed=0, max_scans=n_scans), p)
        return p.read_text()


BASE = _log_text()
LINES = BASE.splitlines(keepends=True)
LASER = [i for i, ln in enumerate(LINES) if ln.startswith("FLASER")]
"""Indices (0-based) of BASE's laser lines; the file line is index + 1."""

TRUTH = "".join(f"{0.2 * k:.1f} {0.1 * k} 0 0\n" for k in range(10))
"""A trajectory of 10 poses (line k + 1: timestamp 0.2 k), also used as ground truth."""

EST = "".join(f"{0.2 * k:.1f} {0.1 * k + 0.01 * (k % 3)} 0 0\n" for k in range(10))
"""TRUTH with errors of up to 2 cm."""


def fhslam(argv: list, capsys) -> tuple[int, str, str]:
    """``fhslam ARGV`` in this process: exit status, stdout, stderr."""
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def error_line(code: int, err: str, *names) -> str:
    """Exit status 2 and one line ``fhslam: error: ...`` naming each of ``names``."""
    lines = err.splitlines()
    assert code == 2, (code, err)
    assert len(lines) == 1 and lines[0].startswith("fhslam: error: "), err
    for name in names:
        assert str(name) in lines[0], (name, lines[0])
    return lines[0]


def warning_line(code: int, err: str, *names) -> str:
    """Exit status 0 and one line ``fhslam: warning: ...`` naming each of ``names``."""
    lines = err.splitlines()
    assert code == 0, (code, err)
    assert len(lines) == 1 and lines[0].startswith("fhslam: warning: "), err
    for name in names:
        assert str(name) in lines[0], (name, lines[0])
    return lines[0]


def _state(p: Path) -> object:
    st = p.stat()
    return p.read_bytes() if st.st_size < 1 << 24 else (st.st_size, st.st_mtime_ns)


@contextmanager
def inputs_kept(folder: Path):
    """The files in ``folder`` before the block are there after it, unchanged."""
    before = {p: _state(p) for p in folder.rglob("*") if p.is_file()}
    yield
    for p, state in before.items():
        assert p.is_file() and _state(p) == state, f"input {p} changed"


def _slam(log: Path, out: Path) -> list:
    return ["slam", log, "--method", "odometry", "--trajectory", out, "--quiet"]


# --------------------------------------------------------------------------------------------
# A byte-order mark


@pytest.mark.parametrize("start", ["comment", "PARAM", "FLASER"])
def test_a_byte_order_mark_at_the_start_of_a_log_is_read_past(tmp_path, capsys, start):
    """The log's first line (a comment, a ``PARAM`` or a laser line) reads with the mark as
    without it: the same scans, the same mount, the same trajectory."""
    first = {"comment": 0, "PARAM": next(i for i, s in enumerate(LINES) if s[0] == "P")}
    text = "".join(LINES[first.get(start, LASER[0]) :])
    plain, marked = tmp_path / "plain.clf", tmp_path / "marked.clf"
    plain.write_text(text)
    marked.write_bytes(codecs.BOM_UTF8 + text.encode())
    with inputs_kept(tmp_path):
        for log in (plain, marked):
            code, _, err = fhslam(_slam(log, tmp_path / f"{log.stem}.txt"), capsys)
            assert code == 0 and err == "", err
    a, b = read_carmen(plain), read_carmen(marked)
    assert len(b) == SCANS
    for field in ("timestamps", "ranges", "angles", "odometry", "laser_offset"):
        assert np.array_equal(getattr(a, field), getattr(b, field)), field
    assert (a.max_range, a.laser_offset_source) == (b.max_range, b.laser_offset_source)
    t_plain, p_plain = read_trajectory(tmp_path / "plain.txt")
    t_marked, p_marked = read_trajectory(tmp_path / "marked.txt")
    assert len(t_marked) == SCANS
    assert np.array_equal(t_plain, t_marked) and np.array_equal(p_plain, p_marked)


# --------------------------------------------------------------------------------------------
# The format of --plot


MAGIC = {".png": b"\x89PNG\r\n\x1a\n", ".pdf": b"%PDF-", ".svg": b"<?xml"}


def _evaluate_files(folder: Path) -> tuple[Path, Path]:
    est, truth = folder / "est.txt", folder / "truth.txt"
    est.write_text(EST)
    truth.write_text(TRUTH)
    return est, truth


@pytest.mark.parametrize("ext", [".png", ".pdf", ".svg", ".PDF"])
def test_evaluate_plot_is_written_in_the_format_of_its_extension(tmp_path, capsys, ext):
    est, truth = _evaluate_files(tmp_path)
    pictures = [tmp_path / f"errors{ext}", tmp_path / f"again{ext}"]
    with inputs_kept(tmp_path):
        for picture in pictures:
            code, out, err = fhslam(["evaluate", est, "--truth", truth, "--plot", picture], capsys)
            assert code == 0 and err == "", err
            assert out.endswith(f"wrote a picture of the errors to {picture}\n")
    data = pictures[0].read_bytes()
    assert data.startswith(MAGIC[ext.lower()]) and len(data) > 5_000
    if ext == ".svg":
        assert b"<svg" in data[:1000]
    assert pictures[1].read_bytes() == data  # no date, no version: the same bytes each time
    assert b"Matplotlib" not in data and b"matplotlib.org" not in data


def test_a_png_plot_is_the_png_it_always_was(tmp_path, capsys):
    """The PNG is matplotlib's at 100 dpi, bbox "tight", without the Software chunk: the
    figures drawn with it do not change by a byte."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fhslam.figures import pose_errors_figure

    est, truth = _evaluate_files(tmp_path)
    png = tmp_path / "errors.png"
    code, _, err = fhslam(["evaluate", est, "--truth", truth, "--plot", png], capsys)
    assert code == 0 and err == ""
    t, poses = read_trajectory(est)
    t_ref, ref = read_trajectory(truth)
    fig = pose_errors_figure(t, poses, t_ref, ref, 0.01, False, est.name)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100, bbox_inches="tight", metadata={"Software": None})
    plt.close(fig)
    assert png.read_bytes() == buf.getvalue()


@pytest.mark.parametrize("ext", [".pdf", ".svg"])
def test_slam_plot_is_written_in_the_format_of_its_extension(tmp_path, capsys, ext):
    log = tmp_path / "log.clf"
    log.write_text(BASE)
    picture = tmp_path / f"run{ext}"
    with inputs_kept(tmp_path):
        code, out, err = fhslam([*_slam(log, tmp_path / "t.txt"), "--plot", picture], capsys)
    assert code == 0 and err == "", err
    assert out.endswith(f"and a picture of the run to {picture}\n")
    assert picture.read_bytes().startswith(MAGIC[ext])
    assert len(read_trajectory(tmp_path / "t.txt")[0]) == SCANS


def test_sweep_plot_is_written_in_the_format_of_its_extension(tmp_path, capsys):
    from fhslam.geometry import relative

    log = simulate(paper_world(), seed=0, max_scans=30)
    clf, relations = tmp_path / "s.clf", tmp_path / "s.relations"
    write_carmen(log, clf)
    rows = []
    for a in range(0, len(log) - 5, 3):
        r = relative(log.truth[a], log.truth[a + 5])
        stamps = log.timestamps[a], log.timestamps[a + 5]
        rows.append(" ".join(repr(float(v)) for v in (*stamps, r[0], r[1], 0, 0, 0, r[2])))
    relations.write_text("\n".join(rows) + "\n")
    svg = tmp_path / "runs.svg"
    argv = ["sweep", "--log", clf, "--relations", relations, "--range-noise", "0.001", "--seeds",
            "1", "--jobs", "1", "--methods", "odometry", "--quiet", "--plot", svg]  # fmt: skip
    with inputs_kept(tmp_path):
        code, out, err = fhslam(argv, capsys)
    assert code == 0 and err == "", err
    assert out.endswith(f"wrote a picture of the runs to {svg}\n")
    data = svg.read_bytes()
    assert data.startswith(MAGIC[".svg"]) and b"<svg" in data[:1000]


BAD_PICTURES = ["errors.jpg", "errors", "errors.png.gz", "errors.", "errors.eps"]


def _refused_plot(err: str, picture: Path) -> None:
    line = error_line(2, err, f"--plot {picture}", ".png, .pdf, .svg")
    assert "extension" in line


@pytest.mark.parametrize("name", BAD_PICTURES)
def test_evaluate_refuses_another_plot_format_before_any_work(tmp_path, capsys, name):
    """The trajectory does not exist: the picture is refused before it is looked for."""
    truth = tmp_path / "truth.txt"
    truth.write_text(TRUTH)
    picture = tmp_path / name
    with inputs_kept(tmp_path):
        for ref in (["--truth", truth], ["--relations", truth]):
            code, out, err = fhslam(
                ["evaluate", tmp_path / "no.txt", *ref, "--plot", picture], capsys
            )
            assert code == 2 and out == ""
            _refused_plot(err, picture)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["truth.txt"]


@pytest.mark.parametrize("name", BAD_PICTURES)
def test_slam_refuses_another_plot_format_before_any_work(tmp_path, capsys, name):
    """The log does not exist: the picture is refused before it is read (and the trajectory
    is not written)."""
    picture = tmp_path / name
    code, out, err = fhslam([*_slam(tmp_path / "no.clf", tmp_path / "t.txt"), "--plot", picture],
                            capsys)  # fmt: skip
    assert code == 2 and out == ""
    _refused_plot(err, picture)
    assert list(tmp_path.iterdir()) == []


def test_sweep_refuses_another_plot_format_before_any_run(tmp_path, capsys, monkeypatch):
    from fhslam.experiments import robustness

    monkeypatch.setattr(robustness, "_one", lambda *a, **k: pytest.fail("a run started"))
    log = tmp_path / "log.clf"
    log.write_text(BASE)
    relations = tmp_path / "log.relations"
    relations.write_text("0.0 0.1 0 0 0 0 0 0\n")
    picture = tmp_path / "runs.gif"
    argv = ["sweep", "--log", log, "--relations", relations, "--range-noise", "0.001",
            "--seeds", "1", "--jobs", "1", "--quiet", "--plot", picture]  # fmt: skip
    with inputs_kept(tmp_path):
        code, out, err = fhslam(argv, capsys)
    assert code == 2 and out == ""
    _refused_plot(err, picture)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["log.clf", "log.relations"]


# --------------------------------------------------------------------------------------------
# Reading a log as a stream; what is not text


def _sparse_possible(folder: Path) -> bool:
    """Whether a file extended by truncate() takes no room in ``folder``'s file system."""
    probe = folder / "probe"
    with open(probe, "wb") as f:
        f.truncate(64 << 20)
    sparse = getattr(probe.stat(), "st_blocks", None)
    probe.unlink()
    return sparse is not None and sparse * 512 < 1 << 20


MEASURE = """\
import json, resource, subprocess, sys
r = subprocess.run(sys.argv[1:], capture_output=True, text=True, timeout=300)
rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
print(json.dumps([r.returncode, r.stdout, r.stderr, rss]))
"""
"""Run a command in a process of its own and report its peak memory (``ru_maxrss``: the
largest child of this one process, which has no other)."""


@pytest.mark.skipif(sys.platform == "win32", reason="needs the resource module")
def test_a_log_with_gigabytes_of_nul_bytes_is_read_in_bounded_memory(tmp_path):
    """Five good scans, then 2 GiB of NUL bytes (a sparse file: written in no time; 200 MB
    of real NUL bytes where the file system has no sparse files): ``fhslam info`` reports
    the five scans and warns of the NUL bytes, naming the line, the byte where they start
    and how many; its memory stays far below the file's size."""
    good = _log_text(5).encode()
    size = (2 << 30) if _sparse_possible(tmp_path) else 200_000_000
    log = tmp_path / "log.clf"
    with open(log, "wb") as f:
        f.write(good)
        f.truncate(size)
    with inputs_kept(tmp_path):
        r = subprocess.run(
            [sys.executable, "-c", MEASURE, sys.executable, "-m", "fhslam.cli", "info", str(log)],
            capture_output=True,
            text=True,
            timeout=600,
        )
    assert r.returncode == 0, r.stderr
    code, out, err, rss = json.loads(r.stdout)
    peak = rss * (1 if sys.platform == "darwin" else 1024)  # bytes on macOS, else KiB
    line = good.count(b"\n") + 1
    warning_line(
        code,
        err,
        f"{log}:{line}: skipped {size - len(good)} bytes that are not text (NUL bytes) from "
        f"byte {len(good)} (line {line}) to the end of the file",
        "the 5 laser scans",
    )
    assert out.startswith(f"{log}: 5 scans of 181 beams\n"), out
    assert peak < min(500e6, size / 4), f"peak memory {peak / 1e6:.0f} MB for {size} bytes"


def test_unreadable_lines_in_the_middle_are_skipped_with_one_warning(tmp_path, capsys):
    """NUL bytes, bytes that are not UTF-8 and a line longer than MAX_LINE, between the
    fourth and fifth scan: every scan is read, and one warning names the stretch."""
    cut = LASER[3] + 1
    head = "".join(LINES[:cut]).encode()
    junk = [
        b"\x00" * 5000 + b"\n",
        bytes(range(128, 256)) * 10 + b"\n",
        b"x" * (MAX_LINE + 10) + b"\n",
    ]
    log = tmp_path / "log.clf"
    log.write_bytes(head + b"".join(junk) + "".join(LINES[cut:]).encode())
    first = head.count(b"\n") + 1
    end = len(head) + sum(map(len, junk))
    with inputs_kept(tmp_path):
        code, _, err = fhslam(_slam(log, tmp_path / "t.txt"), capsys)
    line = warning_line(
        code,
        err,
        f"{log}:{first}: skipped {sum(map(len, junk))} bytes that are not text",
        f"in 3 lines from byte {len(head)} (line {first}) to byte {end} (line {first + 2})",
        f"the {SCANS} laser scans",
    )
    for why in ("NUL bytes", "not UTF-8", f"a line of more than {MAX_LINE} characters"):
        assert why in line
    assert len(read_trajectory(tmp_path / "t.txt")[0]) == SCANS


def test_a_laser_line_cut_off_by_nul_bytes_is_skipped_with_a_warning(tmp_path, capsys):
    """A crash while logging: the last laser line half written, the rest of the file NUL
    bytes. The scans before it are read."""
    cut = LASER[7]
    head = "".join(LINES[:cut]).encode()
    half = LINES[cut][: len(LINES[cut]) // 2].encode()
    log = tmp_path / "log.clf"
    log.write_bytes(head + half + b"\x00" * 100_000)
    with inputs_kept(tmp_path):
        code, _, err = fhslam(_slam(log, tmp_path / "t.txt"), capsys)
    warning_line(
        code,
        err,
        f"{log}:{cut + 1}: skipped {len(half) + 100_000} bytes that are not text (NUL bytes)",
        f"from byte {len(head)} (line {cut + 1}) to the end of the file",
        "the 7 laser scans",
    )
    assert len(read_trajectory(tmp_path / "t.txt")[0]) == 7


def test_a_gzipped_log_is_read_as_it_is(tmp_path, capsys):
    plain, packed = tmp_path / "log.clf", tmp_path / "log.clf.gz"
    plain.write_text(BASE)
    packed.write_bytes(gzip.compress(BASE.encode(), mtime=0))
    for log in (plain, packed):
        code, _, err = fhslam(_slam(log, tmp_path / f"{log.name}.txt"), capsys)
        assert code == 0 and err == "", err
    a, b = (read_trajectory(tmp_path / f"{p.name}.txt") for p in (plain, packed))
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])


@pytest.mark.parametrize("cut", [0.5, 0.9])
def test_a_damaged_gzipped_log_is_one_line(tmp_path, capsys, cut):
    data = gzip.compress((BASE * 20).encode(), mtime=0)
    log = tmp_path / "log.clf.gz"
    log.write_bytes(data[: int(cut * len(data))])
    with inputs_kept(tmp_path):
        code, out, err = fhslam(_slam(log, tmp_path / "t.txt"), capsys)
    error_line(code, err, f"{log}: damaged gzip data", "cannot be read past it")
    assert out == "" and sorted(p.name for p in tmp_path.iterdir()) == ["log.clf.gz"]


@pytest.mark.parametrize("kind", ["gzip of no text", "NUL bytes only", "not UTF-8"])
def test_a_log_without_text_is_refused(tmp_path, capsys, kind):
    content = {
        "gzip of no text": gzip.compress(b"\x00" * 10_000, mtime=0),
        "NUL bytes only": b"\x00" * 10_000,
        "not UTF-8": bytes(range(128, 256)) * 100,
    }[kind]
    log = tmp_path / "log.clf"
    log.write_bytes(content)
    with inputs_kept(tmp_path):
        code, out, err = fhslam(_slam(log, tmp_path / "t.txt"), capsys)
    line = error_line(code, err, f"{log}: not a CARMEN text log", "no FLASER or ROBOTLASER1")
    assert out == "" and sorted(p.name for p in tmp_path.iterdir()) == ["log.clf"]
    if kind == "gzip of no text":
        assert "gzip-compressed" in line


# --------------------------------------------------------------------------------------------
# $FHSLAM_DATA


@pytest.mark.parametrize("what", ["a file", "nothing"])
def test_fhslam_data_that_is_not_a_folder_is_refused(tmp_path, capsys, monkeypatch, what):
    monkeypatch.chdir(tmp_path)
    env = tmp_path / "data.txt"
    if what == "a file":
        env.write_text("not a folder\n")
    monkeypatch.setenv("FHSLAM_DATA", str(env))
    problem = "is not a folder" if what == "a file" else "no such folder"
    est = tmp_path / "est.txt"
    est.write_text(TRUTH)
    with inputs_kept(tmp_path):
        for argv in (
            ["slam", "intel", "--trajectory", tmp_path / "t.txt", "--quiet"],
            ["evaluate", est, "--relations", "mit-csail"],
            ["info", "aces"],
        ):
            code, out, err = fhslam(argv, capsys)
            assert out == ""
            error_line(code, err, f"FHSLAM_DATA={env}: {problem}")
    assert not (tmp_path / "t.txt").exists()


def test_fhslam_data_is_not_consulted_for_a_log_given_by_its_path(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("FHSLAM_DATA", str(tmp_path / "no-such-folder"))
    log = tmp_path / "log.clf"
    log.write_text(BASE)
    code, _, err = fhslam(_slam(log, tmp_path / "t.txt"), capsys)
    assert code == 0 and err == ""


# --------------------------------------------------------------------------------------------
# A timestamp repeated with another pose


def _doubled(off: float) -> str:
    """TRUTH with each pose followed by a second one of its timestamp, ``off`` metres off."""
    return "".join(f"{ln}\n{ln.split()[0]} {float(ln.split()[1]) + off!r} 0 0\n"
                   for ln in TRUTH.splitlines())  # fmt: skip


@pytest.mark.parametrize("which", ["trajectory", "truth"])
def test_a_timestamp_repeated_with_another_pose_is_refused(tmp_path, capsys, which):
    """Each pose doubled, the second 100 m off: which is the pose at that time cannot be
    told: matching the first of each would score ATE 0 with half the poses 100 m off."""
    est, truth = tmp_path / "est.txt", tmp_path / "truth.txt"
    est.write_text(_doubled(100.0) if which == "trajectory" else TRUTH)
    truth.write_text(_doubled(100.0) if which == "truth" else TRUTH)
    bad = est if which == "trajectory" else truth
    with inputs_kept(tmp_path):
        code, out, err = fhslam(["evaluate", est, "--truth", truth], capsys)
    assert out == ""
    error_line(code, err, f"{bad}:2: timestamp 0.0 repeats that of line 1", "(and 9 more")


def test_a_timestamp_repeated_far_apart_with_another_pose_is_refused(tmp_path, capsys):
    """The repeat need not follow its twin: the last line repeats the third's stamp."""
    est, truth = tmp_path / "est.txt", tmp_path / "truth.txt"
    est.write_text(TRUTH + "0.4 0.2 0 0.5\n")  # the same place, turned 0.5 rad
    truth.write_text(TRUTH)
    for argv in (["--truth", truth], ["--relations", truth]):
        with inputs_kept(tmp_path):
            code, out, err = fhslam(["evaluate", est, *argv], capsys)
        assert out == ""
        error_line(code, err, f"{est}:11: timestamp 0.4 repeats that of line 3", "theta 0.5")


@pytest.mark.parametrize("off", [0.0, 1e-12])
def test_a_timestamp_repeated_with_the_same_pose_is_read_with_a_warning(tmp_path, capsys, off):
    est, truth = tmp_path / "est.txt", tmp_path / "truth.txt"
    est.write_text(_doubled(off))
    truth.write_text(TRUTH)
    with inputs_kept(tmp_path):
        code, out, err = fhslam(["evaluate", est, "--truth", truth], capsys)
    warning_line(code, err, f"{est}:2: the timestamp repeats", "read as it is")
    assert "ATE (m)" in out
