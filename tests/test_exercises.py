"""The workbook's exercises: every notebook has at least three (predict, implement, interpret),
each laid out the same way; their checks speak in one line; every solution passes its check
without showing anything in the notebook; the student copy drops solutions.

Each notebook's own checks are tested in ``tests/test_exercises_nbNN.py``; nbval re-runs every
check cell (the unfilled template must say "not attempted yet") and every solution cell (it
must print nothing) against the outputs stored here; the solutions are checked here, in a run
of each notebook.
"""

import ast
import copy
import re
import subprocess
from pathlib import Path

import nbformat
import pytest
from nbformat.v4 import new_code_cell

from fhslam.cli import main
from fhslam.exercises import Feedback, Wrong, call, check_choice, check_value, exercise
from fhslam.workbook import SOLUTION_NOTE, STUDENT_NOTE

ALL_NOTEBOOKS = sorted((Path(__file__).parents[1] / "notebooks").glob("[0-9][0-9]_*.ipynb"))
RESEARCH = {"09_benchmarks.ipynb"}
"""Notebooks of measurements, not lessons: no exercises."""
NOTEBOOKS = [p for p in ALL_NOTEBOOKS if p.name not in RESEARCH]
"""The teaching notebooks, 01-08: each with its exercises."""
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


def check_call(source: str) -> ast.Call:
    """The one ``check_...(...)`` call of a check cell."""
    calls = [
        n
        for n in ast.walk(ast.parse(source))
        if isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id[:6] == "check_"
    ]
    assert len(calls) == 1, f"expected one check_... call in {source!r}"
    return calls[0]


def names(check: str) -> tuple[str, str]:
    """The student's name the check cell checks (``my_x``) and the solution's (``solution_x``)."""
    student = check_call(check).args[0]
    assert isinstance(student, ast.Name) and student.id.startswith("my_"), check
    return student.id, "solution_" + student.id[3:]


def defined(source: str) -> set[str]:
    """The names a cell binds at its top level (assignments and definitions)."""
    found = set()
    for node in ast.parse(source).body:
        if isinstance(node, ast.FunctionDef | ast.ClassDef):
            found.add(node.name)
        elif isinstance(node, ast.Assign | ast.AnnAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            found |= {n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name)}
    return found


def test_the_eight_teaching_notebooks_and_the_benchmarks_are_found():
    assert [p.name[:2] for p in NOTEBOOKS] == [f"{k:02d}" for k in range(1, 9)]
    assert [p.name for p in ALL_NOTEBOOKS if p not in NOTEBOOKS] == sorted(RESEARCH)


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
        # the solution defines solution_x for the student's my_x, and checks nothing: after
        # Run All no verdict and no number of the solution's shows (checked by the next test)
        _, name = names(check.source)
        assert name in defined(solution.source), f"{where}: the solution defines no {name}"
        assert "check" not in solution.source and "print(" not in solution.source, where
        # as stored (and re-run by nbval): the template is not attempted, the solution silent
        assert text(check).startswith("⏳ not attempted yet:"), where
        assert text(check).count("\n") == 1, where
        assert not solution.get("outputs"), f"{where}: the solution cell has an output"
        assert SOLUTION_NOTE in exercise_text(nb, n), where
    assert sum("solution" in tags(c) for c in nb.cells) == len(found), path.name
    errors = [c for c in nb.cells for o in c.get("outputs", []) if o.output_type == "error"]
    assert not errors, f"{path.name}: stored error output"


def exercise_text(nb, number: str) -> str:
    return next(md.source for n, _, (md, *_) in exercises(nb) if n == number)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name[:2])
def test_every_solution_passes_its_check(path):
    """Run All in a kernel, as nbval does, with one cell added after each solution cell: the
    check cell's call with the solution in place of the student's answer. Every one must say
    "correct"."""
    from nbclient import NotebookClient

    nb = nbformat.read(path, as_version=4)
    run = copy.deepcopy(nb)
    added = []
    for number, _, (_, _, check, solution) in exercises(nb):
        _, name = names(check.source)
        call_ = check_call(check.source)
        call_.args[0] = ast.Name(name, ast.Load())
        cell = new_code_cell(f"print({ast.unparse(call_)})")
        run.cells.insert(run.cells.index(solution) + 1 + len(added), cell)
        added.append((number, cell))
    client = NotebookClient(
        run,
        timeout=600,
        kernel_name="python3",
        resources={"metadata": {"path": str(path.parent)}},
    )
    client.execute(stderr=subprocess.DEVNULL)
    said = {number: text(cell).strip() for number, cell in added}
    wrong = {n: s for n, s in said.items() if not s.startswith("✅ correct:") or "\n" in s}
    assert not wrong, f"{path.name}: solutions that do not pass their check: {wrong}"


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
    assert len(lines) == len(ALL_NOTEBOOKS)
    for path in ALL_NOTEBOOKS:
        original = nbformat.read(path, as_version=4)
        copy = nbformat.read(out / path.name, as_version=4)
        n = sum("solution" in tags(c) for c in original.cells)
        assert f"{out / path.name}: {n} solution" in "\n".join(lines)
        assert not any("solution" in tags(c) for c in copy.cells)
        assert len(copy.cells) == len(original.cells) - n
        assert all(not c.get("outputs") for c in copy.cells if c.cell_type == "code")
        assert [c.source for c in copy.cells] == [
            c.source.replace(SOLUTION_NOTE, STUDENT_NOTE) if c.cell_type == "markdown" else c.source
            for c in original.cells
            if "solution" not in tags(c)
        ]
        # the copy says what it did: no solution hidden anywhere, the note in every exercise
        said = "\n".join(c.source for c in copy.cells if c.cell_type == "markdown")
        assert not re.search(r"solution[^.]*hidden|hidden under", said, re.I), path.name
        assert said.count(STUDENT_NOTE) == n, path.name
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
