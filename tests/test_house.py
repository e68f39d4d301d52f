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
    assert "2 kept, 0 broken" in r.stdout


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
