"""Outputs that are not regular files, run through the ``fhslam`` command.

An output that exists and is not a regular file -- a device, a named pipe (FIFO), a pipe
named by ``/dev/fd/N`` -- is written in place: it stays what it was, and a failed write to it
(``/dev/full``, a closed pipe) ends in exit status 2 and one line naming it. ``-`` is standard
output for the text outputs of ``slam`` and ``simulate``, for one output only. A name too long
for the file system is refused in one line before any work; a name that is long but valid is
written. A file name the locale cannot decode (a UTF-8 name under ``LC_ALL=C``) is written.
"""

from __future__ import annotations

import os
import socket
import stat
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

from fhslam.io import read_trajectory, write_carmen
from fhslam.sim import paper_world, simulate

SCANS = 30
"""Scans of the test log: a run of ``slam --method odometry`` on it takes well under a second."""


def command(*args: str) -> list[str]:
    """The ``fhslam`` command line, as a user runs it."""
    return [sys.executable, "-m", "fhslam.cli", *args]


def run(*args: str, env: dict[str, str] | None = None, **kw) -> subprocess.CompletedProcess:
    return subprocess.run(
        command(*args), capture_output=True, text=True, timeout=120, env=env, **kw
    )


def one_line_error(err: str, *names: str) -> None:
    """``err`` is exactly one line ``fhslam: error: ...`` naming each of ``names``."""
    assert "Traceback" not in err and "Exception ignored" not in err, err
    assert err.startswith("fhslam: error: ") and err.count("\n") == 1, err
    for name in names:
        assert name in err, (name, err)


def files(folder: Path) -> list[str]:
    """Every name in ``folder``, hidden temporary files included."""
    return sorted(p.name for p in folder.iterdir())


@pytest.fixture(scope="module")
def clf(tmp_path_factory) -> Path:
    """The paper world's first :data:`SCANS` scans (seed 0) as a CARMEN log."""
    folder = tmp_path_factory.mktemp("logs")
    whole = folder / "whole.clf"
    write_carmen(simulate(paper_world(), seed=0), whole)
    lines = whole.read_text().splitlines(keepends=True)
    head = [x for x in lines if x.startswith(("#", "PARAM"))]
    data = [x for x in lines if not x.startswith(("#", "PARAM"))]
    path = folder / "tiny.clf"
    path.write_text("".join(head + data[: 2 * SCANS]))
    return path


def slam(clf: Path, *outputs: str, **kw) -> subprocess.CompletedProcess:
    return run("slam", str(clf), "--method", "odometry", "--quiet", *outputs, **kw)


@pytest.fixture(scope="module")
def reference(clf, tmp_path_factory) -> str:
    """The trajectory that ``slam --method odometry`` writes to a regular file."""
    out = tmp_path_factory.mktemp("reference") / "t.txt"
    r = slam(clf, "--trajectory", str(out))
    assert r.returncode == 0, r.stderr
    text = out.read_text()
    assert text.count("\n") == SCANS + 1  # the header and a pose per scan
    return text


def device(folder: Path, name: str, minor: int) -> tuple[Path, int]:
    """A private character device ``name`` in ``folder`` (memory devices: 3 null, 7 full),
    and its device number; the test is skipped where nodes cannot be made."""
    path = folder / name
    rdev = os.makedev(1, minor)
    try:
        os.mknod(path, 0o666 | stat.S_IFCHR, rdev)
    except (OSError, AttributeError) as e:
        pytest.skip(f"cannot make a device node here ({e})")
    return path, rdev


def assert_device(path: Path, rdev: int) -> None:
    st = os.lstat(path)
    assert stat.S_ISCHR(st.st_mode) and st.st_rdev == rdev, path


# --------------------------------------------------------------------------------------------
# Devices


def test_a_null_device_output_is_written_to_not_replaced(clf, tmp_path):
    null, rdev = device(tmp_path, "null", 3)
    r = slam(clf, "--trajectory", str(null), "--map", str(tmp_path / "m.json"))
    assert r.returncode == 0, r.stderr
    assert f"to {null}" in r.stdout
    assert_device(null, rdev)
    assert files(tmp_path) == ["m.json", "null"]  # no temporary file left


def test_two_outputs_may_both_go_to_one_null_device(clf, tmp_path):
    null, rdev = device(tmp_path, "null", 3)
    r = slam(clf, "--trajectory", str(null), "--map", str(null))
    assert r.returncode == 0, r.stderr
    assert_device(null, rdev)


def test_a_full_device_ends_in_one_line_and_no_output(clf, tmp_path):
    full, rdev = device(tmp_path, "full", 7)
    r = slam(clf, "--trajectory", str(full), "--map", str(tmp_path / "m.json"))
    assert r.returncode == 2 and r.stdout == ""
    one_line_error(r.stderr, f"{full}: cannot write (No space left on device)")
    assert_device(full, rdev)
    assert files(tmp_path) == ["full"]  # the map, renamed after the stream, is not written


def test_standard_output_on_a_full_device_ends_in_one_line(clf, tmp_path):
    full, _ = device(tmp_path, "full", 7)
    with open(full, "w") as out:
        r = subprocess.run(
            command("slam", str(clf), "--method", "odometry", "--quiet", "--trajectory", "-"),
            stdout=out,
            stderr=subprocess.PIPE,
            text=True,
            timeout=120,
        )
    assert r.returncode == 2
    one_line_error(r.stderr, "standard output: cannot write (No space left on device)")


# --------------------------------------------------------------------------------------------
# Pipes


def read_all(fd_or_path, into: list[bytes]) -> threading.Thread:
    """A thread that reads ``fd_or_path`` (a descriptor or a FIFO) to its end into ``into``."""

    def read():
        with open(fd_or_path, "rb") as f:
            into.append(f.read())

    thread = threading.Thread(target=read, daemon=True)
    thread.start()
    return thread


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
def test_a_fifo_receives_the_trajectory_and_stays_a_fifo(clf, tmp_path, reference):
    fifo = tmp_path / "t.fifo"
    os.mkfifo(fifo)
    got: list[bytes] = []
    reader = read_all(fifo, got)
    r = slam(clf, "--trajectory", str(fifo))
    reader.join(timeout=60)
    assert r.returncode == 0, r.stderr
    assert got == [reference.encode()]
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert files(tmp_path) == ["t.fifo"]


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
def test_a_fifo_without_a_reader_does_not_block_the_output_check(clf, tmp_path):
    fifo = tmp_path / "t.fifo"
    os.mkfifo(fifo)
    r = slam(clf, "--trajectory", str(fifo), "--map", str(tmp_path / "no" / "m.json"))
    assert r.returncode == 2
    one_line_error(r.stderr, "--map", "cannot write (no such folder")


@pytest.mark.skipif(not Path("/dev/fd").is_dir(), reason="no /dev/fd here")
def test_a_pipe_named_by_dev_fd_receives_the_trajectory(clf, reference):
    r_fd, w_fd = os.pipe()
    got: list[bytes] = []
    reader = read_all(r_fd, got)
    try:
        r = slam(clf, "--trajectory", f"/dev/fd/{w_fd}", pass_fds=(w_fd,))
    finally:
        os.close(w_fd)
    reader.join(timeout=60)
    assert r.returncode == 0, r.stderr
    assert got == [reference.encode()]
    assert f"to /dev/fd/{w_fd}" in r.stdout


@pytest.mark.skipif(not Path("/dev/fd").is_dir(), reason="no /dev/fd here")
def test_a_closed_pipe_ends_in_one_line(clf):
    r_fd, w_fd = os.pipe()
    os.close(r_fd)  # nobody reads: the write fails with EPIPE
    try:
        r = slam(clf, "--trajectory", f"/dev/fd/{w_fd}", pass_fds=(w_fd,))
    finally:
        os.close(w_fd)
    assert r.returncode == 2
    one_line_error(r.stderr, f"/dev/fd/{w_fd}: cannot write (Broken pipe)")


def test_a_socket_is_refused_before_the_work(clf, tmp_path):
    path = tmp_path / "s.sock"
    with socket.socket(socket.AF_UNIX) as s:
        s.bind(str(path))
        r = slam(clf, "--trajectory", str(path))
    assert r.returncode == 2
    one_line_error(r.stderr, f"--trajectory {path}: is a socket")


# --------------------------------------------------------------------------------------------
# Standard output


def test_slam_writes_the_trajectory_to_standard_output(clf, tmp_path, reference):
    r = slam(clf, "--trajectory", "-", "--map", str(tmp_path / "m.json"))
    assert r.returncode == 0, r.stderr
    assert r.stdout == reference  # the trajectory alone: the message went to stderr
    assert "poses to standard output" in r.stderr
    (tmp_path / "t.txt").write_text(r.stdout)
    (tmp_path / "ref.txt").write_text(reference)
    t, poses = read_trajectory(tmp_path / "t.txt")
    t_ref, poses_ref = read_trajectory(tmp_path / "ref.txt")
    np.testing.assert_array_equal(t, t_ref)
    np.testing.assert_array_equal(poses, poses_ref)
    assert (tmp_path / "m.json").is_file()


def test_slam_writes_the_map_to_standard_output(clf, tmp_path):
    r = slam(clf, "--trajectory", str(tmp_path / "t.txt"), "--map", "-")
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith('{"lines": [') and "map lines to standard output" in r.stderr


def test_simulate_writes_the_truth_to_standard_output(tmp_path):
    r = run("simulate", "paper", "--log", str(tmp_path / "p.clf"), "--truth", "-")
    assert r.returncode == 0, r.stderr
    assert "the true poses to standard output" in r.stderr
    t, _ = read_trajectory(write(tmp_path / "t.txt", r.stdout))
    assert len(t) == 916


def write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["slam", "LOG", "--trajectory", "-", "--map", "-"],
            "--trajectory - and --map -: only one output can go to standard output",
        ),
        (
            ["simulate", "paper", "--log", "-", "--truth", "-"],
            "--log - and --truth -: only one output can go to standard output",
        ),
        (
            ["slam", "LOG", "--trajectory", "T", "--plot", "-"],
            "--plot -: this output cannot go to standard output",
        ),
    ],
)
def test_standard_output_for_two_outputs_or_a_picture_is_refused(clf, tmp_path, args, message):
    args = [str(clf) if a == "LOG" else str(tmp_path / "t.txt") if a == "T" else a for a in args]
    r = run(*args)
    assert r.returncode == 2 and r.stdout == ""
    one_line_error(r.stderr, message)
    assert files(tmp_path) == []


# --------------------------------------------------------------------------------------------
# Long and undecodable names


def test_a_name_too_long_is_refused_in_one_line_before_the_work(clf, tmp_path):
    long = tmp_path / ("a" * 300 + ".txt")
    r = slam(clf, "--trajectory", str(tmp_path / "t.txt"), "--map", str(long))
    assert r.returncode == 2 and r.stdout == ""
    one_line_error(r.stderr, f"--map {long}: cannot write (File name too long)")
    assert files(tmp_path) == []


def test_a_long_name_near_the_limit_is_written(clf, tmp_path, reference):
    long = tmp_path / ("b" * 250)
    r = slam(clf, "--trajectory", str(long))
    assert r.returncode == 0, r.stderr
    assert long.read_text() == reference
    assert files(tmp_path) == [long.name]  # no temporary file left


def test_a_non_ascii_name_under_the_c_locale_is_written(clf, tmp_path):
    env = {k: v for k, v in os.environ.items() if not k.startswith(("LC_", "PYTHONIO"))}
    env.update(LC_ALL="C", PYTHONUTF8="0", LANG="C")
    log, truth = tmp_path / "é.clf", tmp_path / "vérité.txt"
    r = run("simulate", "paper", "--log", str(log), "--truth", str(truth), env=env)
    assert r.returncode == 0, r.stderr
    assert sorted(os.listdir(os.fsencode(tmp_path))) == sorted(
        ["é.clf".encode(), "vérité.txt".encode()]
    )
    out = tmp_path / "trajé.txt"
    r = run("slam", str(log), "--method", "odometry", "--quiet", "--trajectory", str(out), env=env)
    assert r.returncode == 0, r.stderr
    assert "Traceback" not in r.stderr
    assert f"{log}:".encode() in out.read_bytes()  # the header names the log, in UTF-8
    r = run("slam", str(log), "--method", "odometry", "--quiet", "--trajectory", "-", env=env)
    assert r.returncode == 0, r.stderr
    assert r.stdout == out.read_text()
