"""Opening inputs and writing outputs: errors naming the path, no half-written files."""

from __future__ import annotations

import os

import pytest

from fhslam.errors import InputError, MissingInputError
from fhslam.io import read_map, read_trajectory, write_map
from fhslam.io.files import atomic_output, check_outputs, input_path


def test_missing_input_is_missing_input_error_and_file_not_found(tmp_path):
    p = tmp_path / "nope.txt"
    with pytest.raises(MissingInputError, match=r"nope\.txt: no such file") as e:
        read_trajectory(p)
    assert isinstance(e.value, FileNotFoundError) and isinstance(e.value, InputError)
    assert e.value.filename == str(p)


def test_a_directory_is_not_an_input_file(tmp_path):
    with pytest.raises(InputError, match="is a directory, not a map file"):
        read_map(tmp_path)
    with pytest.raises(InputError, match="is a directory, not a file"):
        input_path(tmp_path)


def test_atomic_output_leaves_nothing_when_the_writer_fails(tmp_path):
    out = tmp_path / "out.txt"
    out.write_text("old\n")
    with pytest.raises(RuntimeError), atomic_output(out) as f:
        f.write("half")
        raise RuntimeError("interrupted")
    assert out.read_text() == "old\n"  # the old file stands, no temporary left behind
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.txt"]


def test_atomic_output_replaces_the_file_when_complete(tmp_path):
    out = tmp_path / "out.txt"
    with atomic_output(out) as f:
        f.write("new\n")
    assert out.read_text() == "new\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.txt"]


def test_unwritable_output_names_the_path(tmp_path):
    with pytest.raises(InputError, match=r"m\.json: cannot write"):
        write_map(tmp_path / "missing" / "m.json", [])
    with pytest.raises(InputError, match="is a directory"):
        write_map(tmp_path, [])


@pytest.mark.skipif(os.geteuid() == 0, reason="root may read any file")
def test_unreadable_input_names_the_path(tmp_path):
    p = tmp_path / "t.txt"
    p.write_text("0 0 0 0\n")
    p.chmod(0)
    with pytest.raises(InputError, match=r"t\.txt: cannot read"):
        read_trajectory(p)


def test_check_outputs_refuses_an_input_by_any_name(tmp_path, monkeypatch):
    log = tmp_path / "run.clf"
    log.write_text("x\n")
    os.link(log, tmp_path / "hard.clf")
    os.symlink(log, tmp_path / "soft.clf")
    monkeypatch.chdir(tmp_path)
    for name in (
        "run.clf",
        "./run.clf",
        str(log),
        "hard.clf",
        "soft.clf",
        "../" + tmp_path.name + "/run.clf",
    ):
        with pytest.raises(
            InputError, match=r"--trajectory .*: is the input log; .*nothing was written"
        ):
            check_outputs({"--trajectory": name}, {"the input log": log})
    assert log.read_text() == "x\n"


def test_check_outputs_refuses_one_output_twice_and_accepts_distinct_ones(tmp_path):
    with pytest.raises(InputError, match=r"--map .*t\.txt: also given as --trajectory"):
        check_outputs({"--trajectory": tmp_path / "t.txt", "--map": tmp_path / "t.txt"}, {})
    # distinct outputs, an output that does not exist yet, options not given, an input
    # that is not a file (a built-in world's name): all accepted
    check_outputs(
        {"--trajectory": tmp_path / "t.txt", "--map": None, "--log": tmp_path / "new.clf"},
        {"the input world file": None, "the input log": "intel"},
    )
    assert not (tmp_path / "t.txt").exists()


def _readers():
    """Every reader of a file the ``fhslam`` command takes, as ``(name, call)``."""
    from fhslam.datasets import load_log
    from fhslam.io import read_bag, read_carmen, read_graph, read_relations
    from fhslam.sim import load_world

    return [
        ("load_log", load_log),
        ("read_carmen", read_carmen),
        ("read_bag", read_bag),
        ("read_trajectory", read_trajectory),
        ("read_relations", read_relations),
        ("read_map", read_map),
        ("read_graph", read_graph),
        ("load_world", load_world),
    ]


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
@pytest.mark.parametrize("suffix", ["", ".clf", ".bag", ".db3", ".json", ".txt"])
def test_no_reader_opens_a_fifo(tmp_path, suffix):
    """``mkfifo ff; fhslam info ff`` must not hang for ever, as it would if ``is_bag`` opened
    the FIFO (waiting for a writer) before any reader checked it is a regular file. Every
    reader refuses it, naming it, without opening it; ``is_bag`` says no."""
    import signal

    from fhslam.io import is_bag

    fifo = tmp_path / f"ff{suffix}"
    os.mkfifo(fifo)

    class Blocked(Exception):  # not an OSError, which a reader might catch
        pass

    def hang(signum, frame):
        raise Blocked("a reader opened the FIFO and blocked")

    previous = signal.signal(signal.SIGALRM, hang)
    signal.alarm(10)
    try:
        assert not is_bag(fifo)
        for name, read in _readers():
            with pytest.raises(InputError, match=rf"ff{suffix}: is not a regular file") as e:
                read(fifo)
            assert not isinstance(e.value, MissingInputError), name
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
