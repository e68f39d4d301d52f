"""The workbook's files: every notebook paired with its plain-text source, the command that
re-runs the notebooks and writes their outputs, and its errors."""

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
