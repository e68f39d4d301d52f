"""Hostile conditions for what tests/test_hostile.py's corpus does not run: ``reproduce``,
``sweep``, ``student-copy`` and ``run-notebooks`` given outputs they cannot write or inputs
that are broken, the commands' outputs checked before any work and written all or none, and
Ctrl-C.

The contract is the corpus's (its docstring; fhslam/cli.py's): bad input ends in exit
status 2 and one line ``fhslam: error: ...`` naming the path, with nothing written and no
input changed; Ctrl-C (SIGINT) ends in exit status 130 and one line
``fhslam: interrupted; ...`` naming what was not written, with no traceback and no file left.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import nbformat
import pytest
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

from fhslam.cli import main
from fhslam.errors import InputError
from fhslam.io import write_carmen
from fhslam.io.files import check_outputs, output_batch, output_folder
from fhslam.sim import paper_world, simulate

NOTEBOOKS = Path(__file__).parents[1] / "notebooks"


def command(*args: str) -> list[str]:
    """The ``fhslam`` command line, as a user runs it."""
    return [sys.executable, "-m", "fhslam.cli", *args]


def run(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(command(*args), capture_output=True, text=True, timeout=300, cwd=cwd)


def one_line_error(err: str, *names: str) -> None:
    """``err`` is exactly one line ``fhslam: error: ...`` naming each of ``names``."""
    assert "Traceback" not in err, err
    assert err.startswith("fhslam: error: ") and err.count("\n") == 1, err
    for name in names:
        assert name in err, (name, err)


def files(folder: Path) -> list[str]:
    """Every path under ``folder``, relative, hidden temporary files included."""
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


@pytest.fixture
def lock():
    """Make a folder unwritable, undone after the test: ``chmod 555`` as a user; as root (who
    ignores permissions) ``chattr +i``, or the test is skipped where that is refused."""
    undo: list[list[str]] = []

    def make(folder: Path) -> Path:
        if os.geteuid() != 0:
            folder.chmod(0o555)
            undo.append(["chmod", "755", str(folder)])
        else:
            if subprocess.run(["chattr", "+i", str(folder)], capture_output=True).returncode:
                pytest.skip("root without chattr +i: every folder is writable")
            undo.append(["chattr", "-i", str(folder)])
        try:
            (folder / ".probe").touch()
        except OSError:
            return folder
        (folder / ".probe").unlink()  # pragma: no cover (a file system that ignores both)
        pytest.skip("no way to make a folder unwritable here")

    yield make
    for cmd in undo:
        subprocess.run(cmd, check=True)


@pytest.fixture
def unwritable(tmp_path, lock) -> Path:
    """An existing empty folder ``ro`` in which no file can be created."""
    (tmp_path / "ro").mkdir()
    return lock(tmp_path / "ro")


@pytest.fixture(scope="module")
def paper_clf(tmp_path_factory) -> Path:
    """The paper world's 916 scans (seed 0) as a CARMEN log."""
    path = tmp_path_factory.mktemp("logs") / "paper.clf"
    write_carmen(simulate(paper_world(), seed=0), path)
    return path


def tiny_notebook(path: Path, *code: str) -> Path:
    nb = new_notebook(cells=[new_markdown_cell("# A test"), *(new_code_cell(c) for c in code)])
    nb.metadata["kernelspec"] = {
        "name": "python3",
        "display_name": "Python 3",
        "language": "python",
    }
    nbformat.write(nb, path)
    return path


# --------------------------------------------------------------------------------------------
# The helpers: check an output before any work, write several all or none


def test_check_outputs_refuses_an_output_it_cannot_write(tmp_path, unwritable):
    (tmp_path / "f").write_text("a file\n")
    cases = {
        unwritable
        / "m.json": f"--map {unwritable / 'm.json'}: cannot write (folder {unwritable}: ",
        tmp_path / "no" / "m.json": f"cannot write (no such folder {tmp_path / 'no'})",
        tmp_path / "f" / "m.json": f"cannot write ({tmp_path / 'f'} is not a folder)",
        tmp_path: f"--map {tmp_path}: is a directory; give a file name for the output",
    }
    for path, message in cases.items():
        with pytest.raises(InputError) as e:
            check_outputs({"--trajectory": tmp_path / "t.txt", "--map": path}, {})
        assert message in str(e.value)
    check_outputs({"--trajectory": tmp_path / "t.txt", "--map": None}, {})
    assert files(tmp_path) == ["f", "ro"]  # the probe file is gone


def test_an_output_batch_writes_all_or_none(tmp_path):
    from fhslam.io import write_map, write_trajectory

    old = tmp_path / "t.txt"
    old.write_text("old\n")
    for error in (InputError("a later output failed"), KeyboardInterrupt()):
        with pytest.raises(type(error)), output_batch():
            write_trajectory(old, [0.0], [[0.0, 0.0, 0.0]])
            write_map(tmp_path / "m.json", [])
            raise error
        assert files(tmp_path) == ["t.txt"] and old.read_text() == "old\n"
    with output_batch():
        write_trajectory(old, [0.0], [[0.0, 0.0, 0.0]])
        with output_batch():  # nested: joins the outer one
            write_map(tmp_path / "m.json", [])
        assert files(tmp_path) == sorted(
            ["t.txt", f".t.txt.{os.getpid()}.tmp", f".m.json.{os.getpid()}.tmp"]
        )
    assert files(tmp_path) == ["m.json", "t.txt"] and old.read_text() != "old\n"


class _SwallowsCtrlC:
    """Presses Ctrl-C while Python runs its destructor, where the KeyboardInterrupt is
    printed as "Exception ignored" and swallowed (as in numba's ctypes callbacks)."""

    def __del__(self):
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(1000):  # the handler runs between bytecodes, here
            pass


def test_a_swallowed_ctrl_c_still_stops_every_output(tmp_path, capsys):
    from fhslam.io import write_map, write_trajectory
    from fhslam.io.files import interrupted_before_output, watch_interrupts

    handler = signal.getsignal(signal.SIGINT)
    with watch_interrupts():
        _SwallowsCtrlC()  # deleted at once: Ctrl-C pressed and swallowed
        assert interrupted_before_output()
        with pytest.raises(KeyboardInterrupt), output_batch():
            write_map(tmp_path / "m.json", [])
        with pytest.raises(KeyboardInterrupt):
            write_trajectory(tmp_path / "t.txt", [0.0], [[0.0, 0.0, 0.0]])
    assert files(tmp_path) == []
    assert capsys.readouterr().err == ""  # the swallowed interrupt is not printed either
    assert signal.getsignal(signal.SIGINT) is handler  # restored
    with watch_interrupts():  # a new command starts with no interrupt
        write_map(tmp_path / "m.json", [])
        _SwallowsCtrlC()  # after the output: it stands
        assert not interrupted_before_output()
    assert files(tmp_path) == ["m.json"]


def test_an_output_folder_it_created_is_removed_if_the_work_fails(tmp_path):
    out = tmp_path / "a" / "figs"
    with pytest.raises(KeyboardInterrupt), output_folder(out, "--out") as d, output_batch():
        (d / "sub").mkdir()
        with open(d / "sub" / "x.png", "w"):  # a file written there outside the batch stays
            pass
        raise KeyboardInterrupt
    assert files(tmp_path) == ["a", "a/figs", "a/figs/sub", "a/figs/sub/x.png"]
    (out / "sub" / "x.png").unlink()
    with pytest.raises(RuntimeError), output_folder(out / "new", "--out") as d:
        (d / "sub").mkdir()
        raise RuntimeError
    assert files(tmp_path) == ["a", "a/figs", "a/figs/sub"]  # made by the first block only
    with pytest.raises(InputError), output_folder(tmp_path / "b" / "c" / "d", "--out"):
        raise InputError("bad input")
    assert files(tmp_path) == ["a", "a/figs", "a/figs/sub"]  # b and c made for d: gone too


# --------------------------------------------------------------------------------------------
# Outputs that cannot be written: refused before the work (not slam running the whole log,
# writing the trajectory, then failing on the map; nor sweep failing after the whole sweep)


def test_slam_refuses_an_unwritable_map_folder_before_reading_the_log(
    paper_clf, tmp_path, unwritable, monkeypatch, capsys
):
    import fhslam.cli.slam

    out = tmp_path / "out.txt"
    argv = ["slam", str(paper_clf), "--trajectory", str(out), "--map", str(unwritable / "m.json")]
    r = run(*argv)
    assert r.returncode == 2 and r.stdout == ""
    one_line_error(r.stderr, f"--map {unwritable / 'm.json'}: cannot write (folder {unwritable}")
    assert files(tmp_path) == ["ro"]
    monkeypatch.setattr(fhslam.cli.slam, "read_log", lambda args: pytest.fail("the log was read"))
    assert main(argv) == 2
    one_line_error(capsys.readouterr().err, "cannot write")


@pytest.mark.parametrize("which", ["--log", "--truth"])
def test_simulate_refuses_an_unwritable_output_before_simulating(
    tmp_path, unwritable, monkeypatch, capsys, which
):
    import fhslam.sim

    monkeypatch.setattr(fhslam.sim, "simulate", lambda *a, **k: pytest.fail("simulated"))
    paths = {"--log": tmp_path / "p.clf", "--truth": tmp_path / "t.txt"}
    paths[which] = unwritable / "x"
    assert main(["simulate", "paper", *(str(v) for kv in paths.items() for v in kv)]) == 2
    one_line_error(capsys.readouterr().err, f"{which} {unwritable / 'x'}: cannot write")
    assert files(tmp_path) == ["ro"]


def test_sweep_refuses_an_unwritable_out_folder_before_the_sweep(
    tmp_path, unwritable, monkeypatch, capsys
):
    from fhslam.experiments import compare

    monkeypatch.setattr(compare, "slam_sweep", lambda **kw: pytest.fail("the sweep ran"))
    assert main(["sweep", "--seeds", "1", "--out", str(unwritable / "s.csv")]) == 2
    one_line_error(capsys.readouterr().err, f"--out {unwritable / 's.csv'}: cannot write")
    (tmp_path / "f").write_text("")
    assert main(["sweep", "--seeds", "1", "--out", str(tmp_path / "f" / "s.csv")]) == 2
    one_line_error(capsys.readouterr().err, f"cannot write ({tmp_path / 'f'} is not a folder)")


def test_sweep_refuses_a_world_beyond_the_scan_limit_before_the_sweep(tmp_path, capsys):
    world = tmp_path / "long.json"
    world.write_text(
        '{"name": "long", "walls": [[0, 0, 100000, 0], [0, 4, 100000, 4]], '
        '"route": [[1, 2], [99999, 2]]}'
    )
    assert main(["sweep", "--world", str(world), "--seeds", "1", "--out", str(tmp_path / "s")]) == 2
    one_line_error(
        capsys.readouterr().err,
        f"world {world} ('long'): its route of 99,998 m",
        "the limit is 500,000 scans",
    )
    assert files(tmp_path) == ["long.json"]


def test_sweep_warns_once_of_an_unknown_world_key(tmp_path):
    world = tmp_path / "box.json"
    world.write_text(
        '{"name": "box", "walls": [[0, 0, 6, 0], [6, 0, 6, 4], [6, 4, 0, 4], '
        '[0, 4, 0, 0]], "route": [[1, 1], [5, 1], [5, 3]], "strat": [1, 1, 0]}'
    )
    r = run(
        "sweep",
        "--world",
        str(world),
        "--seeds",
        "2",
        "--levels",
        "low",
        "--methods",
        "odometry",
        "--jobs",
        "2",
        "--quiet",
    )
    assert r.returncode == 0 and r.stdout.startswith("2 runs: 2 seeds x 1 levels x 1 methods")
    assert r.stderr == (
        f"fhslam: warning: {world}: unknown key 'strat' ignored; a world has "
        "'name', 'walls', 'route', 'start'\n"
    )


# --------------------------------------------------------------------------------------------
# reproduce (one-line errors, not FileExistsError, PermissionError, FileNotFoundError
# tracebacks)


def test_reproduce_refuses_a_file_as_its_folder(tmp_path, monkeypatch, capsys):
    import fhslam.figures.paper

    monkeypatch.setattr(fhslam.figures.paper, "paper_log", lambda seed: pytest.fail("drew"))
    f = tmp_path / "f.png"
    f.write_bytes(b"png")
    assert main(["reproduce", "--out", str(f)]) == 2
    one_line_error(capsys.readouterr().err, f"--out {f}: is a file, not a folder")
    assert f.read_bytes() == b"png" and files(tmp_path) == ["f.png"]


def test_reproduce_refuses_a_folder_it_cannot_write_or_create(unwritable, monkeypatch, capsys):
    import fhslam.figures.paper

    monkeypatch.setattr(fhslam.figures.paper, "paper_log", lambda seed: pytest.fail("drew"))
    assert main(["reproduce", "--out", str(unwritable)]) == 2
    one_line_error(capsys.readouterr().err, f"--out {unwritable}: cannot write (folder ")
    assert main(["reproduce", "--out", str(unwritable / "figs")]) == 2
    one_line_error(
        capsys.readouterr().err, f"--out {unwritable / 'figs'}: cannot create the folder"
    )
    assert list(unwritable.iterdir()) == []


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux's /proc")
def test_reproduce_into_proc_is_one_line(capsys):
    assert main(["reproduce", "--out", "/proc/figs"]) == 2
    one_line_error(capsys.readouterr().err, "--out /proc/figs: cannot create the folder")


def test_reproduce_that_fails_midway_leaves_no_figure_and_no_folder(tmp_path, monkeypatch):
    import fhslam.figures.paper

    def broken():
        raise RuntimeError("a bug in figure 6")

    monkeypatch.setattr(fhslam.figures.paper, "fig06_line_attributes", broken)
    with pytest.raises(RuntimeError, match="figure 6"):
        fhslam.figures.paper.reproduce(tmp_path / "figs")  # figures 1-5 were drawn by then
    assert files(tmp_path) == []


# --------------------------------------------------------------------------------------------
# student-copy (one-line errors, not FileExistsError, PermissionError tracebacks; a broken
# notebook leaves no copies of the notebooks before it)


def test_student_copy_refuses_a_file_as_its_folder(tmp_path, capsys):
    f = tmp_path / "f"
    f.write_text("mine\n")
    assert main(["student-copy", str(f), "--notebooks", str(NOTEBOOKS)]) == 2
    one_line_error(capsys.readouterr().err, f"{f}: is a file, not a folder")
    assert f.read_text() == "mine\n" and files(tmp_path) == ["f"]


def test_student_copy_refuses_a_folder_it_cannot_write_or_create(unwritable, capsys):
    assert main(["student-copy", str(unwritable / "out"), "--notebooks", str(NOTEBOOKS)]) == 2
    one_line_error(capsys.readouterr().err, f"{unwritable / 'out'}: cannot create the folder")
    assert main(["student-copy", str(unwritable), "--notebooks", str(NOTEBOOKS)]) == 2
    one_line_error(capsys.readouterr().err, f"{unwritable}: cannot write (folder {unwritable}")
    assert list(unwritable.iterdir()) == []


@pytest.mark.parametrize("out_exists", [False, True])
def test_student_copy_reads_every_notebook_before_writing_any(tmp_path, capsys, out_exists):
    src = tmp_path / "nb"
    src.mkdir()
    tiny_notebook(src / "02_good.ipynb", "x = 1")
    (src / "03_broken.ipynb").write_bytes(b"\x89PNG\r\n")
    out = tmp_path / "out"
    if out_exists:
        out.mkdir()
    assert main(["student-copy", str(out), "--notebooks", str(src)]) == 2
    one_line_error(capsys.readouterr().err, f"{src / '03_broken.ipynb'}: not a readable notebook")
    assert files(tmp_path) == ["nb", "nb/02_good.ipynb", "nb/03_broken.ipynb"] + (
        ["out"] if out_exists else []
    )


def test_student_copy_interrupted_leaves_no_copy(tmp_path, monkeypatch, capsys):
    import fhslam.workbook

    real = fhslam.workbook.atomic_output
    calls = []

    def interrupted_on_the_third(path, mode="w"):
        calls.append(path)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(path, mode)

    monkeypatch.setattr(fhslam.workbook, "atomic_output", interrupted_on_the_third)
    out = tmp_path / "class"
    assert main(["student-copy", str(out), "--notebooks", str(NOTEBOOKS)]) == 130
    assert capsys.readouterr().err == f"fhslam: interrupted; nothing written to {out}\n"
    assert files(tmp_path) == []


# --------------------------------------------------------------------------------------------
# run-notebooks


def test_run_notebooks_refuses_a_file_and_an_unwritable_folder_before_running(
    tmp_path, lock, monkeypatch, capsys
):
    import fhslam.workbook

    monkeypatch.setattr(fhslam.workbook, "run_notebook", lambda *a, **k: pytest.fail("ran"))
    nb = tiny_notebook(tmp_path / "01_tiny.ipynb", "print(1)")
    before = nb.read_bytes()
    assert main(["run-notebooks", "--notebooks", str(nb)]) == 2
    one_line_error(capsys.readouterr().err, f"{nb}: is a file, not a folder of notebooks")
    lock(tmp_path)
    for extra in ([], ["--pair-only"]):
        assert main(["run-notebooks", "--notebooks", str(tmp_path), *extra]) == 2
        one_line_error(capsys.readouterr().err, f"--notebooks {tmp_path}: cannot write")
    assert nb.read_bytes() == before and files(tmp_path) == ["01_tiny.ipynb"]


def test_run_notebooks_names_the_cell_that_killed_the_kernel(tmp_path, capsys):
    nb = tiny_notebook(tmp_path / "01_die.ipynb", "print(1)", "import os\nos._exit(3)")
    before = nb.read_bytes()
    assert main(["run-notebooks", "--notebooks", str(tmp_path), "--timeout", "120"]) == 2
    one_line_error(capsys.readouterr().err, f"{nb}: the kernel died in cell 2 (its process ended")
    assert nb.read_bytes() == before and files(tmp_path) == ["01_die.ipynb"]


def test_a_notebook_and_its_py_are_written_together_or_not_at_all(tmp_path, capsys):
    nb = tiny_notebook(tmp_path / "01_tiny.ipynb", "print(1)")
    before = nb.read_bytes()
    (tmp_path / "01_tiny.py").mkdir()  # the .py cannot be written: nor is the notebook
    assert main(["run-notebooks", "--notebooks", str(tmp_path), "--pair-only"]) == 2
    one_line_error(capsys.readouterr().err, f"{tmp_path / '01_tiny.py'}: is a directory")
    assert nb.read_bytes() == before and files(tmp_path) == ["01_tiny.ipynb", "01_tiny.py"]


# --------------------------------------------------------------------------------------------
# Ctrl-C (not a 30-line KeyboardInterrupt traceback, nor sweep's warnings of leaked
# semaphores, nor run-notebooks' three tracebacks). Each command is started as a separate
# process, sent SIGINT once it is under way (as a terminal does: to its whole process group,
# workers and kernels included), and must end with one line and exit status 130.

BAR = re.compile(r"\d+%\|")


def interrupt(argv: list[str], started, cwd: Path, settle: float = 0.5):
    """Run ``fhslam argv`` in ``cwd``; once ``started(stdout, stderr)`` is true (polled), wait
    ``settle`` seconds and send SIGINT to its process group. Returns (status, stdout, the
    stderr lines that are not progress bars)."""
    p = subprocess.Popen(
        command(*argv),
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
    )
    out, err = b"", b""
    for stream in (p.stdout, p.stderr):
        os.set_blocking(stream.fileno(), False)
    t0 = time.monotonic()
    try:
        while not started(out.decode(errors="replace"), err.decode(errors="replace")):
            assert p.poll() is None, f"ended before it was interrupted: {err.decode()}"
            assert time.monotonic() - t0 < 120, "never started"
            out += p.stdout.read() or b""
            err += p.stderr.read() or b""
            time.sleep(0.05)
        time.sleep(settle)
        os.killpg(p.pid, signal.SIGINT)
        for stream in (p.stdout, p.stderr):
            os.set_blocking(stream.fileno(), True)
        rest_out, rest_err = p.communicate(timeout=120)
    finally:
        if p.poll() is None:  # pragma: no cover (hung: fail, but leave nothing running)
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
    lines = re.split(r"[\r\n]", (err + rest_err).decode(errors="replace"))
    return p.returncode, (out + rest_out).decode(), [s for s in lines if s and not BAR.search(s)]


def test_slam_interrupted_prints_one_line_and_leaves_nothing(paper_clf, tmp_path):
    code, out, err = interrupt(
        ["slam", str(paper_clf), "--trajectory", "t.txt", "--map", "m.json"],
        lambda out, err: BAR.search(err),  # the progress bar: the SLAM is running
        tmp_path,
    )
    assert (code, out, err) == (
        130,
        "",
        ["fhslam: interrupted; nothing written to --trajectory t.txt, --map m.json"],
    )
    assert files(tmp_path) == []


def test_simulate_interrupted_prints_one_line_and_leaves_nothing(tmp_path):
    world = tmp_path / "long.json"
    world.write_text(
        '{"name": "long", "walls": [[0, 0, 2000, 0], [0, 4, 2000, 4]], '
        '"route": [[1, 2], [1999, 2]]}'
    )
    code, out, err = interrupt(
        ["simulate", "long.json", "--log", "o.clf", "--truth", "o.txt"],
        lambda out, err: "simulate long: driving" in err,
        tmp_path,
    )
    assert (code, out, err) == (
        130,
        "",
        ["fhslam: interrupted; nothing written to --log o.clf, --truth o.txt"],
    )
    assert files(tmp_path) == ["long.json"]


@pytest.mark.parametrize("settle", [0.0, 0.3, 2.0])
def test_sweep_interrupted_prints_one_line_and_no_leaked_semaphores(tmp_path, settle):
    # Ctrl-C reaches the workers too (the terminal's process group): while they start
    # (settle 0-0.3 s: a traceback from their imports in 5 of 5 runs before they were made
    # deaf to it) and between two tasks (2 s: a traceback from loky's loop, 1 CI run in ~10).
    argv = ["sweep", "--seeds", "30", "--levels", "low", "--methods", "odometry", "--jobs", "2"]
    code, out, err = interrupt(
        [*argv, "--out", "s.csv"], lambda out, err: "SLAM sweep" in err, tmp_path, settle
    )
    # Known and accepted (1 CI run in 2 once, never reproduced here in 40 runs): loky's
    # resource tracker, a process of its own, sometimes reports one of its semaphores as
    # leaked and then finds it already unlinked (FileNotFoundError): the parent removed it,
    # and the tracker missed the message. Nothing is left behind; the lines are loky's.
    leaked = set(
        re.findall(r"leaked semlock objects to clean up at shutdown: \{'([^']+)'", "\n".join(err))
    )
    gone = set(re.findall(r"resource_tracker: (\S+): FileNotFoundError", "\n".join(err)))
    assert leaked <= gone  # each one reported was in fact already removed
    if leaked:
        err = [
            e for e in err if not ("resource_tracker" in e or e.strip().startswith("warnings.warn"))
        ]
    assert (code, out, err) == (130, "", ["fhslam: interrupted; nothing written to --out s.csv"])
    assert files(tmp_path) == []


def test_reproduce_interrupted_leaves_no_figure_and_no_folder(tmp_path):
    code, out, err = interrupt(
        ["reproduce", "--out", "figs"], lambda out, err: (tmp_path / "figs").is_dir(), tmp_path
    )
    assert (code, out, err) == (130, "", ["fhslam: interrupted; nothing written to --out figs"])
    assert files(tmp_path) == []


def test_run_notebooks_interrupted_names_the_notebook_left_as_it_was(tmp_path):
    tiny_notebook(tmp_path / "01_quick.ipynb", "print(1)")
    slow = tiny_notebook(tmp_path / "02_slow.ipynb", "import time\ntime.sleep(100)")
    before = slow.read_bytes()
    code, out, err = interrupt(
        ["run-notebooks", "--notebooks", "."],
        lambda out, err: "01_quick.ipynb: Run All" in out,
        tmp_path,
        settle=3.0,
    )
    assert code == 130 and out.startswith("01_quick.ipynb: Run All")
    assert err == ["fhslam: interrupted; 02_slow.ipynb left as it was"]
    assert slow.read_bytes() == before
    assert files(tmp_path) == ["01_quick.ipynb", "01_quick.py", "02_slow.ipynb"]
