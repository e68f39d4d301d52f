"""The workbook in a real browser: JupyterLab from this environment, driven in headless Chromium
(Debian's ``chromium`` and ``chromium-driver``; never a downloaded browser) through Selenium.

For every notebook, as a student would: open it, Run All, and require no error output, every
figure rendered, no solution given away (no "correct" verdict anywhere in the page, no output
under a solution cell), every widget live and each explorer's figure changing when a slider
moves; then answer every exercise wrong (the check must say "not yet") and right (it must say
"correct"), typing into the exercise cell and running it and its check.

The notebooks run from a copy in a temporary folder, so nothing here changes them. Skipped,
with the reason, where Chromium, ChromeDriver or Selenium are missing, unless
``FHSLAM_BROWSER_TESTS=1`` (set by ``.ci/run``, which installs them) makes that a failure.
"""

from __future__ import annotations

import ast
import json
import os
import re
import shutil
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import nbformat
import pytest

from fhslam.datasets import search_dirs

CHROMIUM, CHROMEDRIVER = Path("/usr/bin/chromium"), Path("/usr/bin/chromedriver")
NOTEBOOKS = sorted((Path(__file__).parents[1] / "notebooks").glob("[0-9][0-9]_*.ipynb"))
HEADING = re.compile(r"## Exercise (\d+)\.(\d+) \((predict|implement|interpret)\) — \S")
EXPLORERS = {"02": 1, "03": 1, "04": 1, "05": 1, "06": 1}  # at least, per notebook
RUN_ALL_TIMEOUT = 900  # s, per notebook, on a loaded 2-core machine
REQUIRED = os.environ.get("FHSLAM_BROWSER_TESTS") == "1"


def _missing() -> str | None:
    if not CHROMIUM.exists() or not CHROMEDRIVER.exists():
        return "Debian's chromium and chromium-driver are not installed"
    try:
        import selenium  # noqa: F401
    except ImportError:
        return "selenium is not installed"
    return None


if _missing():
    if REQUIRED:
        raise RuntimeError(f"FHSLAM_BROWSER_TESTS=1 but {_missing()}")
    pytest.skip(
        f"browser test: {_missing()} (apt-get install chromium chromium-driver; .ci/run does)",
        allow_module_level=True,
    )

from selenium import webdriver  # noqa: E402
from selenium.common.exceptions import StaleElementReferenceException  # noqa: E402
from selenium.webdriver.chrome.service import Service  # noqa: E402
from selenium.webdriver.common.action_chains import ActionChains  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.common.keys import Keys  # noqa: E402
from selenium.webdriver.support.ui import WebDriverWait  # noqa: E402

#: JupyterLab replaces elements as it re-renders (a prompt going from [*] to [3], an output
#: updated in place): what is read while waiting is read by JavaScript in one go, and a wait
#: that meets an element replaced under it tries again instead of failing.
STALE = (StaleElementReferenceException,)


def _wait(driver, timeout: float, poll_frequency: float = 0.5) -> WebDriverWait:
    """``WebDriverWait`` that tries again where an element was replaced under it."""
    return WebDriverWait(driver, timeout, poll_frequency, ignored_exceptions=STALE)


# JupyterLab settings for the test: every cell in the page (no virtual scrolling), no news
SETTINGS = {
    "@jupyterlab/notebook-extension/tracker.jupyterlab-settings": {"windowingMode": "none"},
    "@jupyterlab/apputils-extension/notification.jupyterlab-settings": {
        "fetchNews": "false",
        "checkForUpdates": False,
    },
}


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """A JupyterLab server on a copy of the notebooks: (base url, token, folder)."""
    root = tmp_path_factory.mktemp("lab")
    work, settings = root / "notebooks", root / "settings"
    work.mkdir()
    for path in NOTEBOOKS:
        shutil.copy(path, work / path.name)
    shutil.copytree(NOTEBOOKS[0].parent / "results", work / "results")  # what they load
    for name, value in SETTINGS.items():
        target = settings / name
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(json.dumps(value))
    env = dict(os.environ)
    env.pop("MPLBACKEND", None)  # the notebooks draw inline
    data = [str(d) for _, d in search_dirs() if d.is_dir()]
    if data and "FHSLAM_DATA" not in env:  # the copy is no longer beside shared/data
        env["FHSLAM_DATA"] = data[0]
    port, token = _free_port(), "fhslam-browser-test"
    server = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "jupyter",
            "lab",
            "--no-browser",
            "--allow-root",
            "--ip=127.0.0.1",
            f"--port={port}",
            f"--IdentityProvider.token={token}",
            f"--ServerApp.root_dir={work}",
            f"--LabApp.user_settings_dir={settings}",
            f"--LabApp.workspaces_dir={root / 'workspaces'}",
        ],
        env=env,
        stdout=(root / "server.log").open("w"),
        stderr=subprocess.STDOUT,
    )
    base = f"http://127.0.0.1:{port}"
    try:
        for _ in range(240):
            if server.poll() is not None:
                pytest.fail(f"jupyter lab exited: {(root / 'server.log').read_text()[-2000:]}")
            try:
                urllib.request.urlopen(f"{base}/api/status?token={token}", timeout=2)
                break
            except OSError:
                time.sleep(0.5)
        else:
            pytest.fail("jupyter lab did not answer within 120 s")
        yield base, token, work
    finally:
        server.terminate()
        try:
            server.wait(timeout=20)
        except subprocess.TimeoutExpired:
            server.kill()


@pytest.fixture(scope="module")
def browser():
    options = webdriver.ChromeOptions()
    options.binary_location = str(CHROMIUM)
    for arg in (
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-dev-shm-usage",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--window-size=1400,1000",
    ):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service(str(CHROMEDRIVER)), options=options)
    driver.set_script_timeout(60)
    yield driver
    driver.quit()


# --- driving JupyterLab ------------------------------------------------------------------


def _cells(driver):
    return driver.find_elements(By.CSS_SELECTOR, ".jp-NotebookPanel:not(.lm-mod-hidden) .jp-Cell")


def _status(driver) -> str:
    return driver.execute_script(
        "const e = document.querySelector('.jp-Notebook-ExecutionIndicator');"
        "return e ? e.getAttribute('data-status') : 'none';"
    )


def _prompts(driver) -> list[str]:
    """The input prompts' texts (``[3]:``, ``[*]:``), read at once."""
    return driver.execute_script(
        "return Array.from(document.querySelectorAll('.jp-InputPrompt'), p => p.innerText.trim());"
    )


def _wait_idle(driver, timeout: float) -> None:
    """Until the kernel is idle and no code cell waits to run ("[*]")."""

    def idle(d) -> bool:
        return _status(d) == "idle" and not any("*" in p for p in _prompts(d))

    time.sleep(0.5)
    _wait(driver, timeout, poll_frequency=0.5).until(idle)


def _menu(driver, top: str, item: str) -> None:
    for label in driver.find_elements(By.CSS_SELECTOR, ".lm-MenuBar-itemLabel"):
        if label.text == top:
            label.click()
            break
    else:
        raise AssertionError(f"no menu {top!r}")
    _wait(driver, 10).until(
        lambda d: [
            e for e in d.find_elements(By.CSS_SELECTOR, ".lm-Menu-itemLabel") if e.text == item
        ]
    )
    items = driver.find_elements(By.CSS_SELECTOR, ".lm-Menu-itemLabel")
    next(e for e in items if e.text == item).click()


def _output_text(cell) -> str:
    return cell.parent.execute_script(
        "return Array.from(arguments[0].querySelectorAll('.jp-OutputArea-output'),"
        " e => e.innerText.trim()).join('\\n');",
        cell,
    )


def _outputs(cell) -> int:
    """How many outputs the cell's output area holds (shown or collapsed)."""
    return len(cell.find_elements(By.CSS_SELECTOR, ".jp-OutputArea-output"))


def _type_and_run(driver, cell, source: str) -> None:
    """Replace the cell's code with one line ``source`` and run it (Shift+Enter)."""
    editor = cell.find_element(By.CSS_SELECTOR, ".cm-content")
    driver.execute_script("arguments[0].scrollIntoView({block: 'center'})", editor)
    editor.click()
    ActionChains(driver).key_down(Keys.CONTROL).send_keys("a").key_up(Keys.CONTROL).perform()
    ActionChains(driver).send_keys(Keys.DELETE).send_keys(source).perform()
    ActionChains(driver).key_down(Keys.SHIFT).send_keys(Keys.ENTER).key_up(Keys.SHIFT).perform()
    _wait_idle(driver, 120)


def _run_cell(driver, cell) -> None:
    driver.execute_script("arguments[0].scrollIntoView({block: 'center'})", cell)
    cell.find_element(By.CSS_SELECTOR, ".jp-InputPrompt").click()
    ActionChains(driver).key_down(Keys.SHIFT).send_keys(Keys.ENTER).key_up(Keys.SHIFT).perform()
    _wait_idle(driver, 120)


# --- what a student types -----------------------------------------------------------------


def _check_call(source: str) -> ast.Call:
    calls = [
        n
        for n in ast.walk(ast.parse(source))
        if isinstance(n, ast.Call)
        and isinstance(n.func, ast.Name)
        and n.func.id.startswith("check")
    ]
    assert len(calls) == 1, f"expected one check_... call in {source!r}"
    return calls[0]


def answers(task: str, check: str, solution: str) -> tuple[str, str]:
    """One wrong and one right answer for an exercise, each one line for its cell: the
    student's name ``my_x`` is the first argument of the check cell's check call; the right
    answer is the solution cell's ``solution_x`` (live after Run All); the wrong one a
    function returning None or the number -12345."""
    name = _check_call(check).args[0]
    assert isinstance(name, ast.Name), f"the check's first argument is not a name: {check!r}"
    assert name.id.startswith("my_"), f"the student's name is not my_...: {check!r}"
    right = "solution_" + name.id[3:]
    assert re.search(rf"^(def {right}\b|{right} =)", solution, re.M), (
        f"the solution cell defines no {right}: {solution!r}"
    )
    if re.search(rf"def {name.id}\b", task):
        wrong = f"{name.id} = lambda *args, **kwargs: None"
    else:
        wrong = f"{name.id} = -12345.0"
    return wrong, f"{name.id} = {right}"


def exercises(nb):
    for i, cell in enumerate(nb.cells):
        if cell.cell_type == "markdown" and HEADING.match(cell.source):
            yield HEADING.match(cell.source)[0][3:], i


def test_answers_are_derived_from_the_check_and_solution_cells():
    task = "def my_f(x):\n    raise NotImplementedError"
    check = "from fhslam.exercises.nb02 import check_f\n\nprint(check_f(my_f, data))"
    solution = "# Solution\ndef solution_f(x):\n    return x"
    assert answers(task, check, solution) == (
        "my_f = lambda *args, **kwargs: None",
        "my_f = solution_f",
    )
    assert answers("my_x = ...", "print(check_x(my_x))", '# Solution\nsolution_x = "b"') == (
        "my_x = -12345.0",
        "my_x = solution_x",
    )
    with pytest.raises(AssertionError, match="defines no solution_x"):
        answers("my_x = ...", "print(check_x(my_x))", 'print(check_x("b"))')


# --- the test -----------------------------------------------------------------------------


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name[:2])
def test_notebook_in_jupyterlab(path, lab, browser):
    base, token, _ = lab
    driver = browser
    nb = nbformat.read(path, as_version=4)
    driver.get(f"{base}/lab/tree/{path.name}?token={token}&reset")
    _wait(driver, 120).until(lambda d: len(_cells(d)) == len(nb.cells))
    _wait(driver, 120).until(lambda d: _status(d) == "idle")

    # Run All: no error, every figure drawn
    t0 = time.perf_counter()
    _menu(driver, "Run", "Run All Cells")
    _wait_idle(driver, RUN_ALL_TIMEOUT)
    seconds = time.perf_counter() - t0
    cells = _cells(driver)
    errors = [
        _output_text(c)[-300:]
        for c in cells
        if c.find_elements(By.CSS_SELECTOR, "[data-mime-type='application/vnd.jupyter.stderr']")
        and "Traceback" in _output_text(c)
    ]
    assert not errors, f"{path.name}: error output after Run All: {errors}"
    prompts = _prompts(driver)
    code = [c for c in nb.cells if c.cell_type == "code"]
    shown = [c for c in code if not c.metadata.get("jupyter", {}).get("source_hidden")]
    assert sum(bool(re.search(r"\[\d+\]", p)) for p in prompts) == len(shown), prompts
    images = driver.find_elements(By.CSS_SELECTOR, ".jp-OutputArea-output img")
    stored = sum("image/png" in o.get("data", {}) for c in code for o in c.get("outputs", []))
    assert len(images) >= stored, f"{path.name}: {len(images)} figures drawn, {stored} stored"
    broken = [
        i
        for i in images
        if not driver.execute_script(
            "return arguments[0].complete && arguments[0].naturalWidth > 0", i
        )
    ]
    assert not broken, f"{path.name}: {len(broken)} figures not rendered"
    print(f"{path.name}: Run All {seconds:.0f} s in JupyterLab, {len(images)} figures")

    # no solution given away: the checks of the unfilled cells say "not attempted", and the
    # solution cells, run too, show nothing (no verdict, no number)
    page = driver.find_element(By.TAG_NAME, "body").text
    assert "✅ correct" not in page and "❌ not yet" not in page, f"{path.name}: a verdict shows"
    said = [c for c in nb.cells if "check" in c.metadata.get("tags", [])]
    assert page.count("⏳ not attempted yet") == len(said), f"{path.name}: checks not run"
    solutions = [i for i, c in enumerate(nb.cells) if "solution" in c.metadata.get("tags", [])]
    shown = {i: _output_text(cells[i]) for i in solutions if _outputs(cells[i])}
    assert not shown, f"{path.name}: solution cells with an output after Run All: {shown}"

    # widgets: rendered as widgets (not as text), each explorer's figure follows its sliders
    assert "interactive(children=" not in driver.find_element(By.TAG_NAME, "body").text
    explorers = [c for c in _cells(driver) if c.find_elements(By.CSS_SELECTOR, ".widget-slider")]
    for explorer in explorers:

        def figures(d, explorer=explorer):
            return d.execute_script(
                "return Array.from(arguments[0].querySelectorAll('img'), i => i.src);", explorer
            )

        before = figures(driver)
        assert before, f"{path.name}: an explorer without a figure"
        # the first slider (every explorer's first control changes its figure), one step
        handle = explorer.find_element(By.CSS_SELECTOR, ".widget-slider .noUi-handle")
        driver.execute_script("arguments[0].scrollIntoView({block: 'center'})", handle)
        t0 = time.perf_counter()
        handle.click()
        ActionChains(driver).send_keys(Keys.ARROW_RIGHT).perform()
        _wait(driver, 60, poll_frequency=0.05).until(
            lambda d, before=before: figures(d) not in ([], before)
        )
        print(f"{path.name}: explorer redrawn {time.perf_counter() - t0:.2f} s after a key")
    assert len(explorers) >= EXPLORERS.get(path.name[:2], 0), f"{path.name}: explorers missing"

    # exercises: a wrong answer is refused, a right one accepted
    for title, i in exercises(nb):
        task, check, solution = (nb.cells[i + k].source for k in (1, 2, 3))
        for answer, mark in zip(
            answers(task, check, solution), ("❌ not yet", "✅ correct"), strict=True
        ):
            _type_and_run(driver, _cells(driver)[i + 1], answer)
            _run_cell(driver, _cells(driver)[i + 2])
            said = _output_text(_cells(driver)[i + 2])
            assert said.startswith(mark), f"{path.name}, {title}: {answer!r} gave {said!r}"
            assert "Traceback" not in said and said.count("\n") == 0, said
