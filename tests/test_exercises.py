"""The workbook's exercises: every notebook has at least three (predict, implement, interpret),
each laid out the same way; their checks speak in one line; the student copy drops solutions.

Each notebook's own checks are tested in ``tests/test_exercises_nbNN.py``; nbval re-runs every
check cell (the unfilled template must say "not attempted yet") and every solution cell (the
solution must pass its check) against the outputs stored here.
"""

import re
from pathlib import Path

import nbformat
import pytest

from fhslam.cli import main
from fhslam.exercises import Feedback, Wrong, call, check_choice, check_value, exercise

NOTEBOOKS = sorted((Path(__file__).parents[1] / "notebooks").glob("[0-9][0-9]_*.ipynb"))
HEADING = re.compile(r"## Exercise (\d+)\.(\d+) \((predict|implement|interpret)\) — \S")


def tags(cell) -> list[str]:
    return cell.get("metadata", {}).get("tags", [])


def text(cell) -> str:
    return "".join(o.get("text", "") for o in cell.get("outputs", []) if "text" in o)


def exercises(nb):
    """(number, kind, [markdown, exercise, check, solution]) per exercise heading."""
    for i, cell in enumerate(nb.cells):
        m = HEADING.match(cell.source) if cell.cell_type == "markdown" else None
        if m:
            yield f"{m[1]}.{m[2]}", m[3], nb.cells[i : i + 4]


def test_all_eight_notebooks_are_found():
    assert [p.name[:2] for p in NOTEBOOKS] == [f"{k:02d}" for k in range(1, 9)]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name[:2])
def test_every_notebook_has_three_kinds_of_exercise_laid_out_alike(path):
    nb = nbformat.read(path, as_version=4)
    found = list(exercises(nb))
    number = int(path.name[:2])
    assert len(found) >= 3, f"{path.name}: {len(found)} exercises"
    assert {kind for _, kind, _ in found} == {"predict", "implement", "interpret"}
    assert [n for n, _, _ in found] == [f"{number}.{k}" for k in range(1, len(found) + 1)]
    for n, _, (_, task, check, solution) in found:
        where = f"{path.name}, exercise {n}"
        assert tags(task) == ["exercise"], where
        assert "..." in task.source or "NotImplementedError" in task.source, where
        assert set(tags(check)) == {"check", "nbval-check-output"}, where
        assert set(tags(solution)) == {"solution", "nbval-check-output"}, where
        hidden = solution.metadata.get("jupyter", {})
        assert hidden.get("source_hidden") and hidden.get("outputs_hidden"), where
        assert solution.source.startswith("# Solution"), where
        # as stored (and re-run by nbval): the template is not attempted, the solution passes
        assert text(check).startswith("⏳ not attempted yet:"), where
        assert text(check).count("\n") == 1, where
        assert text(solution).splitlines()[-1].startswith("✅ correct:"), where
    assert sum("solution" in tags(c) for c in nb.cells) == len(found), path.name
    errors = [c for c in nb.cells for o in c.get("outputs", []) if o.output_type == "error"]
    assert not errors, f"{path.name}: stored error output"


def test_feedback_is_one_line_and_true_only_when_correct():
    assert bool(Feedback("correct", "fine")) and str(Feedback("correct", "a\n  b")) == (
        "✅ correct: a b"
    )
    assert not Feedback("wrong", "x") and str(Feedback("wrong", "x")) == "❌ not yet: x"
    assert not Feedback("not attempted", "x")
    with pytest.raises(ValueError, match="status"):
        Feedback("maybe", "x")


def test_call_turns_the_students_exceptions_into_one_line():
    def todo():
        raise NotImplementedError

    @exercise("my_f")
    def check(fn):
        return f"gave {call(fn)}"

    assert check(lambda: 3) and str(check(lambda: 3)) == "✅ correct: gave 3"
    assert check(todo).status == "not attempted" and "my_f" in check(todo).message
    assert check(...).status == "not attempted" and check(None).status == "not attempted"
    assert str(check(lambda: {}["k"])) == "❌ not yet: <lambda> raised KeyError: 'k'"

    @exercise("my_g")
    def strict(x):
        raise Wrong("no\nway")

    assert str(strict(1)) == "❌ not yet: no way"


def test_check_value_and_check_choice():
    assert check_value(1.04, 1.0, 0.05, "my_x")
    wrong = check_value(1.2, 1.0, 0.05, "my_x", " m", hint="Think.")
    assert wrong.status == "wrong" and wrong.message.endswith("Think.")
    assert check_value("1.0", 1.0, 0.05, "my_x")  # a number written as text is read
    assert check_value([1], 1.0, 0.05, "my_x").status == "wrong"
    assert check_value(float("nan"), 1.0, 0.05, "my_x").status == "wrong"
    why = {"a": "no.", "b": "yes."}
    assert check_choice("B", "b", why) and check_choice("a", "b", why).message == "(a): no."
    assert "one of 'a', 'b'" in check_choice("z", "b", why).message


def test_student_copy_removes_every_solution_and_output(tmp_path, capsys):
    out = tmp_path / "class"
    assert main(["student-copy", str(out), "--notebooks", str(NOTEBOOKS[0].parent)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == len(NOTEBOOKS)
    for path in NOTEBOOKS:
        original = nbformat.read(path, as_version=4)
        copy = nbformat.read(out / path.name, as_version=4)
        n = sum("solution" in tags(c) for c in original.cells)
        assert f"{out / path.name}: {n} solution" in "\n".join(lines)
        assert not any("solution" in tags(c) for c in copy.cells)
        assert len(copy.cells) == len(original.cells) - n
        assert all(not c.get("outputs") for c in copy.cells if c.cell_type == "code")
        assert [c.source for c in copy.cells] == [
            c.source for c in original.cells if "solution" not in tags(c)
        ]
    results = NOTEBOOKS[0].parent / "results"  # what the notebooks load comes along
    copied = sorted(p.relative_to(out / "results") for p in (out / "results").rglob("*"))
    assert copied == sorted(p.relative_to(results) for p in results.rglob("*"))


def test_student_copy_refuses_bad_folders(tmp_path, capsys):
    folder = str(NOTEBOOKS[0].parent)
    assert main(["student-copy", folder, "--notebooks", folder]) == 2
    assert "source folder" in capsys.readouterr().err
    assert main(["student-copy", str(tmp_path / "o"), "--notebooks", str(tmp_path / "no")]) == 2
    assert "no such folder" in capsys.readouterr().err
    (tmp_path / "empty").mkdir()
    assert main(["student-copy", str(tmp_path / "o"), "--notebooks", str(tmp_path / "empty")]) == 2
    assert "no notebooks" in capsys.readouterr().err
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "x.ipynb").write_text("{not json")
    assert main(["student-copy", str(tmp_path / "o"), "--notebooks", str(tmp_path / "bad")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("fhslam: error:") and "x.ipynb" in err and err.count("\n") == 1
