"""The workbook's files: every notebook paired with its plain-text source, the command that
re-runs the notebooks and writes their outputs, and its errors."""

import json
from pathlib import Path

import nbformat
import pytest
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

from fhslam.cli import main
from fhslam.errors import InputError
from fhslam.workbook import FORMATS, notebooks_in, pair, paired_path, paired_text, run_notebook

FOLDER = Path(__file__).parents[1] / "notebooks"


@pytest.mark.parametrize("path", notebooks_in(FOLDER), ids=lambda p: p.name[:2])
def test_every_notebook_is_paired_with_its_py_source(path):
    nb = nbformat.read(path, as_version=4)
    assert nb.metadata.get("jupytext", {}).get("formats") == FORMATS, path.name
    py = paired_path(path)
    assert py.exists(), f"{py.name} missing: run `fhslam run-notebooks --pair-only`"
    assert py.read_text() == paired_text(nb), (
        f"{py.name} is not {path.name}'s source: run `fhslam run-notebooks --pair-only` "
        f"(or `jupytext --sync {py}` after editing the .py)"
    )


def test_the_py_source_reads_back_as_the_notebook():
    import jupytext

    path = notebooks_in(FOLDER)[1]
    nb = nbformat.read(path, as_version=4)
    back = jupytext.reads(paired_path(path).read_text(), fmt="py:percent")
    assert [c.source for c in back.cells] == [c.source for c in nb.cells]
    assert [c.metadata.get("tags") for c in back.cells] == [
        c.metadata.get("tags") for c in nb.cells
    ]
    hidden = [
        c.metadata.get("jupyter") for c in nb.cells if "solution" in c.metadata.get("tags", [])
    ]
    assert hidden and hidden == [
        c.metadata.get("jupyter") for c in back.cells if "solution" in c.metadata.get("tags", [])
    ]


def tiny(folder: Path, code: str = "x = 6 * 7\nprint(x)") -> Path:
    nb = new_notebook(cells=[new_markdown_cell("# A test"), new_code_cell(code)])
    nb.metadata["kernelspec"] = {
        "name": "python3",
        "display_name": "Python 3",
        "language": "python",
    }
    path = folder / "01_tiny.ipynb"
    nbformat.write(nb, path)
    return path


def test_run_notebook_writes_outputs_timing_and_the_pair(tmp_path):
    path = tiny(tmp_path, "from pathlib import Path\nprint(6 * 7, Path.cwd().name)")
    run = run_notebook(path, timeout=120)
    nb = nbformat.read(path, as_version=4)
    assert nb.cells[1].outputs[0].text == f"42 {tmp_path.name}\n"  # ran in its own folder
    assert run.slowest_cell == 1 and 0 <= run.slowest_seconds <= run.seconds
    assert str(run).startswith(f"{path}: Run All ")
    assert paired_path(path).read_text() == paired_text(nb)
    assert "# %%\nfrom pathlib import Path" in paired_path(path).read_text()


def test_a_failing_cell_is_named_and_leaves_the_notebook_as_it_was(tmp_path):
    path = tiny(tmp_path, "1 / 0")
    before = path.read_bytes()
    with pytest.raises(InputError, match=r"01_tiny.ipynb: cell 1 failed: .*ZeroDivisionError"):
        run_notebook(path, timeout=120)
    assert path.read_bytes() == before and not paired_path(path).exists()


def test_the_command(tmp_path, capsys):
    path = tiny(tmp_path)
    assert main(["run-notebooks", "--notebooks", str(tmp_path), "--pair-only"]) == 0
    assert capsys.readouterr().out == f"{paired_path(path)}: written\n"
    assert not nbformat.read(path, as_version=4).cells[1].outputs  # nothing was run
    assert main(["run-notebooks", "--notebooks", str(tmp_path), "--pair-only"]) == 0
    assert capsys.readouterr().out == f"{paired_path(path)}: up to date\n"
    assert main(["run-notebooks", "01", "--notebooks", str(tmp_path)]) == 0
    assert "01_tiny.ipynb: Run All" in capsys.readouterr().out
    assert nbformat.read(path, as_version=4).cells[1].outputs[0].text == "42\n"
    assert main(["run-notebooks", "07", "--notebooks", str(tmp_path)]) == 2
    assert "no notebook starts with 07" in capsys.readouterr().err
    assert main(["run-notebooks", "--notebooks", str(tmp_path / "none")]) == 2
    assert "no such folder" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["run-notebooks", "--timeout", "0"])
    assert "positive number of seconds" in capsys.readouterr().err


def test_pair_of_an_unreadable_notebook_is_an_input_error(tmp_path):
    bad = tmp_path / "01_bad.ipynb"
    bad.write_text("{not json")
    with pytest.raises(InputError, match=r"01_bad\.ipynb: not a readable notebook"):
        pair(bad)


WIDGETS = """import ipywidgets as widgets
box = widgets.VBox([widgets.IntSlider(3, description="n"), widgets.HTML("<b>hi</b>")])
box"""


def test_a_rerun_that_changes_nothing_leaves_the_notebook_as_it_was(tmp_path):
    """Execution times, the widgets' random model ids and the outputs of a cell tagged
    ``timing`` differ from run to run: they do not make the notebook written again."""
    path = tiny(tmp_path, WIDGETS)
    nb = nbformat.read(path, as_version=4)
    timed = "import time\nprint(time.perf_counter())\nwidgets.HTML(f'{time.perf_counter()} s')"
    nb.cells.insert(1, new_code_cell(timed, metadata={"tags": ["timing"]}))  # a progress bar
    nb.cells[2].source = nb.cells[2].source.replace("import ipywidgets as widgets\n", "")
    nb.cells[1].source = "import ipywidgets as widgets\n" + nb.cells[1].source
    nbformat.write(nb, path)
    assert run_notebook(path, timeout=120).written
    first = path.read_bytes()
    saved = nbformat.read(path, as_version=4)
    assert all("execution" not in c.metadata for c in saved.cells)  # no times kept
    state = saved.metadata["widgets"]["application/vnd.jupyter.widget-state+json"]["state"]
    views = [
        o.data["application/vnd.jupyter.widget-view+json"]["model_id"]
        for c in saved.cells[1:]
        for o in c.outputs
        if "application/vnd.jupyter.widget-view+json" in o.get("data", {})
    ]
    assert len(views) == 2 and set(views) <= set(state)  # the progress bar and the box
    assert len(state) >= 6  # with the box's children and everyone's layout and style
    assert all(f"IPY_MODEL_{m}" in json.dumps(state) for m in state if m not in views)
    before = path.stat().st_mtime_ns, paired_path(path).stat().st_mtime_ns
    again = run_notebook(path, timeout=120)
    assert not again.written and str(again).endswith("outputs unchanged, not written")
    assert path.read_bytes() == first  # not even rewritten
    assert (path.stat().st_mtime_ns, paired_path(path).stat().st_mtime_ns) == before


def test_a_notebook_is_written_when_its_outputs_change_and_the_widget_ids_stay(tmp_path):
    path = tiny(tmp_path, WIDGETS)
    run_notebook(path, timeout=120)
    first = nbformat.read(path, as_version=4)
    nb = nbformat.read(path, as_version=4)
    nb.cells.append(new_code_cell("print(6 * 7)"))
    nbformat.write(nb, path)
    assert run_notebook(path, timeout=120).written
    second = nbformat.read(path, as_version=4)
    assert second.cells[2].outputs[0].text == "42\n"
    assert second.metadata["widgets"] == first.metadata["widgets"]  # the same ids again
    assert second.cells[1].outputs == first.cells[1].outputs
    assert "print(6 * 7)" in paired_path(path).read_text()


def test_pair_only_does_not_touch_an_unchanged_notebook(tmp_path):
    path = tiny(tmp_path)
    run_notebook(path, timeout=120)
    before = path.stat().st_mtime_ns, paired_path(path).stat().st_mtime_ns
    assert pair(path) == paired_path(path)
    assert (path.stat().st_mtime_ns, paired_path(path).stat().st_mtime_ns) == before


def test_printed_text_is_kept_as_shown_whatever_pieces_it_came_in(tmp_path):
    """The kernel sends a cell's printed text in pieces cut by timing: the notebook keeps one
    output per stream, as JupyterLab shows it, so that the cut does not change the file."""
    code = "import sys, time\nprint('a')\nsys.stdout.flush()\ntime.sleep(0.3)\nprint('b')"
    path = tiny(tmp_path, code)
    run_notebook(path, timeout=120)
    outputs = nbformat.read(path, as_version=4).cells[1].outputs
    assert [(o.output_type, o.name, o.text) for o in outputs] == [("stream", "stdout", "a\nb\n")]
