"""The house: one-way layers, a lazy public API, README examples that run."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import fhslam

ROOT = Path(__file__).resolve().parents[1]


def _lint_imports() -> str | None:
    found = shutil.which("lint-imports") or shutil.which(
        "lint-imports", path=str(Path(sys.executable).parent)
    )
    return found


def test_import_linter_contracts_are_kept():
    """The layers and the "algorithms import no io, sim, metrics, matplotlib, tqdm" contract
    of pyproject.toml hold (import-linter)."""
    exe = _lint_imports()
    if exe is None:
        pytest.fail("lint-imports not found: install the test extra (pip install '.[test]')")
    r = subprocess.run([exe, "--no-cache"], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-2000:]
    assert "4 kept, 0 broken" in r.stdout


def test_the_algorithms_may_not_import_the_tools_of_files_and_notebooks():
    """The forbidden contract names the data, parallelism and widget libraries too."""
    import tomllib

    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    forbidden = [c for c in config["tool"]["importlinter"]["contracts"] if c["type"] == "forbidden"]
    assert len(forbidden) == 1
    assert {"fhslam.slam", "fhslam.scanmatch", "fhslam.extraction"} <= set(
        forbidden[0]["source_modules"]
    )
    assert {"joblib", "pooch", "rosbags", "ipywidgets", "matplotlib", "tqdm"} <= set(
        forbidden[0]["forbidden_modules"]
    )


def test_every_folder_with_compiled_kernels_is_known_to_the_cache_check():
    """numba caches a kernel in its module's ``__pycache__``: the check that those can be
    written (:func:`fhslam._numba.cache_folder`) must know every such folder."""
    from fhslam._numba import KERNEL_FOLDERS

    package = Path(fhslam.__file__).resolve().parent  # the installed copy, maybe not ROOT's
    known = {f.resolve().relative_to(package) for f in KERNEL_FOLDERS}
    folders = {
        p.parent.relative_to(package)
        for p in package.rglob("*.py")
        if "@njit" in p.read_text("utf-8")
    }
    assert folders and folders <= known, folders


MAX_MODULE_LINES = 600
MAX_FUNCTION_LINES = 80


def _code_lines(node) -> int:
    """A function's lines from ``def`` to its end, its docstring left out."""
    import ast

    n = node.end_lineno - node.lineno + 1
    first = node.body[0]
    value = getattr(first, "value", None)
    docstring = isinstance(value, ast.Constant) and isinstance(value.value, str)
    if isinstance(first, ast.Expr) and docstring:
        n -= first.end_lineno - first.lineno + 1
    return n


def test_no_module_over_600_lines_and_no_function_over_80():
    """Every module of the package is at most 600 lines, every function or method at most
    80 lines of code (its docstring not counted)."""
    import ast

    too_long = []
    for path in sorted((ROOT / "fhslam").rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        name = path.relative_to(ROOT).as_posix()
        if text.count("\n") > MAX_MODULE_LINES:
            too_long.append(f"{name}: {text.count(chr(10))} lines")
        for node in ast.walk(ast.parse(text)):
            function = isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
            if function and _code_lines(node) > MAX_FUNCTION_LINES:
                too_long.append(f"{name}:{node.lineno} {node.name}: {_code_lines(node)} lines")
    assert too_long == [], "\n".join(too_long)


def test_the_size_rule_counts_code_not_docstrings():
    import ast

    body = "\n".join(f"    x{k} = {k}" for k in range(79))
    short = ast.parse(f'def f():\n    """Doc\n    string."""\n{body}\n').body[0]
    assert _code_lines(short) == 80
    longer = ast.parse(f"def f():\n    y = 0\n{body}\n").body[0]
    assert _code_lines(longer) == 81


def test_import_fhslam_is_lazy():
    """``import fhslam`` loads none of the heavy dependencies; a name loads its module."""
    code = (
        "import sys, fhslam\n"
        "heavy = [m for m in ('numba', 'cv2', 'scipy', 'matplotlib', 'filterpy', 'fhslam.slam')"
        " if m in sys.modules]\n"
        "print(','.join(heavy))\n"
        "fhslam.ExtractionParams\n"
        "print('numba' in sys.modules)\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    before, after = r.stdout.splitlines()
    assert before == ""
    assert after == "True"


def test_only_the_ekf_baseline_loads_filterpy():
    """filterpy imports ``scipy.stats`` (0.35 s of every command's start): the pipeline and
    the command load it only when the EKF baseline runs."""
    code = (
        "import sys\n"
        "import fhslam.cli, fhslam.pipeline, fhslam.slam\n"
        "print('filterpy' in sys.modules, 'scipy.stats' in sys.modules)\n"
        "fhslam.pipeline.make_backend('ekf')._start(fhslam.geometry.as_pose([0, 0, 0]))\n"
        "print('filterpy' in sys.modules)\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert r.stdout.splitlines() == ["False False", "True"]


def test_public_api_names_resolve_and_unknown_names_fail():
    assert 20 <= len(fhslam.__all__) <= 35
    for name in fhslam.__all__:
        assert getattr(fhslam, name) is not None, name
    assert set(fhslam.__all__) <= set(dir(fhslam))
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        fhslam.nope  # noqa: B018


def _readme_python_blocks() -> list[str]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    return re.findall(r"```python\n(.*?)```", text, flags=re.DOTALL)


def test_readme_has_python_examples():
    assert len(_readme_python_blocks()) >= 1


@pytest.mark.parametrize("k", range(len(_readme_python_blocks())))
def test_readme_python_example_runs(k, tmp_path, monkeypatch, capsys):
    """Every ```python block of the README runs as written (in a scratch folder)."""
    monkeypatch.chdir(tmp_path)
    code = _readme_python_blocks()[k]
    exec(compile(code, f"README.md python block {k + 1}", "exec"), {"__name__": "__readme__"})
    assert capsys.readouterr().out.strip(), "a README example should print what it shows"


def _readme_commands() -> list[str]:
    """The ``fhslam`` command lines of the README's ```bash blocks, continuation lines
    joined (the set-up blocks, which install, are CI's own job)."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    commands = []
    for block in re.findall(r"```bash\n(.*?)```", text, flags=re.DOTALL):
        for line in block.replace("\\\n", " ").splitlines():
            if line.strip().startswith("fhslam "):
                commands.append(line.strip())
    return commands


def test_readme_has_command_line_examples():
    commands = _readme_commands()
    assert len(commands) >= 5
    assert any(c.startswith("fhslam simulate ") for c in commands)
    assert any(c.startswith("fhslam evaluate ") for c in commands)


def test_readme_command_line_examples_run(tmp_path, monkeypatch):
    """Every ``fhslam`` command of the README runs as written, in order, in a scratch folder
    (later ones read what earlier ones wrote), and exits 0."""
    import shlex

    from conftest import data_dir

    if data_dir() is None:
        pytest.skip("no real laser logs: the README's examples run on the shared logs")
    exe = Path(sys.executable).parent / "fhslam"
    env = {**__import__("os").environ, "FHSLAM_DATA": str(data_dir()), "MPLBACKEND": "Agg"}
    for command in _readme_commands():
        argv = [str(exe), *shlex.split(command)[1:]]
        r = subprocess.run(argv, cwd=tmp_path, env=env, capture_output=True, text=True)
        assert r.returncode == 0, f"{command}\n{r.stdout[-2000:]}{r.stderr[-2000:]}"
