"""The workbook's notebooks as files: run them, pair them with plain-text sources, and copy
them for a class.

- :func:`run_notebook` executes a notebook in a fresh kernel and writes it back with its new
  outputs (atomically: an interrupted run leaves the old file), timing every cell;
  ``fhslam run-notebooks`` does it for the whole folder — the one command that regenerates
  the committed outputs. What changes from run to run without the notebook changing is not
  kept, or does not count: the cells' execution times are left out, printed text is kept in
  one piece per stream, the widgets' random model ids are renumbered in a fixed order, and the
  outputs of cells tagged ``timing`` (times measured on the machine) are left out of the
  comparison with the file. A notebook whose outputs come out the same otherwise is not
  written at all, so that re-running unchanged notebooks leaves ``git status`` clean.
- Every notebook ``NN_topic.ipynb`` is paired with ``NN_topic.py``, its plain-text source in
  jupytext's percent format (cells separated by ``# %%`` lines, markdown as comments, tags
  kept), so that a change to a notebook reads as a diff of its ``.py``. :func:`pair` writes
  the ``.py`` from the ``.ipynb`` (``run_notebook`` does it too); after editing the ``.py``
  by hand, ``jupytext --sync notebooks/NN_topic.py`` carries the change into the notebook,
  keeping its outputs. The pairing is stated in each notebook's metadata, so JupyterLab with
  the jupytext extension saves both files.
- :func:`student_copy` writes the notebooks without their solution cells and outputs; the
  sentence of the exercises that points to the solution (:data:`SOLUTION_NOTE`) says instead
  that the copy has none (:data:`STUDENT_NOTE`).
"""

from __future__ import annotations

import json
import re
import time
import uuid
from dataclasses import dataclass
from os import PathLike
from pathlib import Path

from fhslam.errors import InputError
from fhslam.io.files import atomic_output, output_batch, output_folder, reading

__all__ = [
    "FORMATS",
    "RESULTS",
    "SOLUTION_NOTE",
    "STUDENT_NOTE",
    "TIMING",
    "NotebookRun",
    "notebooks_in",
    "pair",
    "paired_path",
    "paired_text",
    "run_notebook",
    "student_copy",
]

#: The pairing, as jupytext writes it in a notebook's metadata: the notebook and its
#: percent-format ``.py``; the ``.py``'s header leaves out jupytext's version, so that another
#: jupytext release does not change every file.
FORMATS = "ipynb,py:percent"

#: The folder beside the notebooks holding the results they load (``fhslam sweep --out``,
#: ``fhslam slam``), too slow to compute in a notebook.
RESULTS = "results"
_JUPYTEXT = {
    "formats": FORMATS,
    "notebook_metadata_filter": "-jupytext.text_representation.jupytext_version",
}

#: The tag of a cell whose outputs are times measured on the machine: they differ from run to
#: run, so :func:`run_notebook` does not write a notebook for them alone.
TIMING = "timing"

#: The sentence of every exercise's task that points to its solution cell, in the notebooks;
#: :func:`student_copy` replaces it with :data:`STUDENT_NOTE`.
SOLUTION_NOTE = "A solution is hidden under the check (click the collapsed cell to show it)."

#: What the student copy says instead of :data:`SOLUTION_NOTE`.
STUDENT_NOTE = "This copy of the workbook comes without the solutions."


def notebooks_in(folder: str | PathLike[str]) -> list[Path]:
    """The notebooks ``*.ipynb`` of ``folder``, sorted by name (their teaching order)."""
    src = Path(folder)
    if src.exists() and not src.is_dir():
        raise InputError(f"{src}: is a file, not a folder of notebooks")
    if not src.is_dir():
        raise InputError(f"{src}: no such folder of notebooks")
    found = sorted(src.glob("*.ipynb"))
    if not found:
        raise InputError(f"{src}: no notebooks (*.ipynb) in this folder")
    return found


def _read(path: Path):
    import nbformat

    try:
        return nbformat.read(path, as_version=4)
    except Exception as e:  # nbformat raises several types for a broken file
        raise InputError(f"{path}: not a readable notebook ({e})") from None


def paired_path(path: str | PathLike[str]) -> Path:
    """The plain-text source paired with notebook ``path``: the same name, ``.py``."""
    return Path(path).with_suffix(".py")


def paired_text(nb) -> str:
    """The percent-format ``.py`` source of notebook ``nb`` (an ``nbformat`` node), with the
    pairing set in its metadata."""
    import jupytext

    nb.metadata["jupytext"] = dict(_JUPYTEXT)
    return jupytext.writes(nb, fmt="py:percent")


_WIDGET_STATE = "application/vnd.jupyter.widget-state+json"
_WIDGET_VIEW = "application/vnd.jupyter.widget-view+json"
_MODEL = re.compile(r"IPY_MODEL_([0-9a-zA-Z_-]+)")


def _widgets(nb) -> tuple[dict, list[dict]]:
    """The widget states saved in ``nb``'s metadata (model id -> state) and the widget views
    in its outputs, in order."""
    state = nb.metadata.get("widgets", {}).get(_WIDGET_STATE, {}).get("state", {})
    views = [
        o["data"][_WIDGET_VIEW]
        for c in nb.cells
        for o in c.get("outputs", [])
        if isinstance(o.get("data", {}).get(_WIDGET_VIEW), dict)
    ]
    return state, views


def _shown(state: dict, views: list[dict]) -> list[str]:
    """The models the ``views`` show, then the models each refers to, depth first."""
    order: list[str] = []

    def visit(model: str) -> None:
        if model in state and model not in order:
            order.append(model)
            for ref in _MODEL.findall(json.dumps(state[model], sort_keys=True)):
                visit(ref)

    for view in views:
        visit(view.get("model_id", ""))
    return order


def _renumber_widgets(nb) -> None:
    """Give the widgets saved in ``nb`` (their state in the metadata, their views in the
    outputs) model ids in a fixed order instead of the kernel's random ones: the views' models
    in the order of the outputs, then the models each refers to, depth first; any left over in
    the order of their state with the ids left out."""
    state, views = _widgets(nb)
    order = _shown(state, views)
    rest = sorted(
        (m for m in state if m not in order),
        key=lambda m: _MODEL.sub("", json.dumps(state[m], sort_keys=True)),
    )
    order += [m for m in _shown(state, [{"model_id": m} for m in rest]) if m not in order]
    new = {m: uuid.uuid5(uuid.NAMESPACE_URL, f"fhslam-widget-{i}").hex for i, m in enumerate(order)}

    def renamed(value):
        if isinstance(value, str):
            return _MODEL.sub(lambda m: f"IPY_MODEL_{new.get(m[1], m[1])}", value)
        if isinstance(value, list):
            return [renamed(v) for v in value]
        if isinstance(value, dict):
            return {k: renamed(v) for k, v in value.items()}
        return value

    if state:
        nb.metadata["widgets"][_WIDGET_STATE]["state"] = {new[m]: renamed(state[m]) for m in order}
    for view in views:
        view["model_id"] = new.get(view.get("model_id"), view.get("model_id"))


def _normalize(nb) -> None:
    """Leave out of ``nb`` what a run changes by itself: the cells' execution times (kept in
    their metadata by nbclient), how a cell's printed text happened to be cut into pieces on
    its way from the kernel (consecutive pieces of one stream joined, as they are shown) and
    the widgets' random model ids (renumbered)."""
    for c in nb.cells:
        c.get("metadata", {}).pop("execution", None)
        joined: list = []
        for o in c.get("outputs", []):
            last = joined[-1] if joined else None
            if (
                o.get("output_type") == "stream"
                and last is not None
                and last.get("output_type") == "stream"
                and last.get("name") == o.get("name")
            ):
                last["text"] += o["text"]
            else:
                joined.append(o)
        if "outputs" in c:
            c.outputs = joined
    _renumber_widgets(nb)


def _comparable(nb) -> str:
    """``nb`` as text without what differs between two runs of an unchanged notebook: the
    volatile parts (:func:`_normalize`), the outputs of the cells tagged :data:`TIMING`, and
    the state of widgets no other output shows (a progress bar's rate, say)."""
    import copy

    import nbformat

    nb = copy.deepcopy(nb)
    _normalize(nb)
    for c in nb.cells:
        if TIMING in c.get("metadata", {}).get("tags", []):
            c.outputs = []
    state, views = _widgets(nb)
    if state:
        shown = set(_shown(state, views))
        nb.metadata["widgets"][_WIDGET_STATE]["state"] = {
            m: s for m, s in state.items() if m in shown
        }
    return nbformat.writes(nb)


def _text_of(path: Path) -> str:
    """The text of the file ``path`` (an :class:`~fhslam.errors.InputError` naming it if it
    cannot be read)."""
    with reading(path):
        return path.read_text(encoding="utf-8")


def _write(nb, path: Path) -> bool:
    """Write notebook ``nb`` to ``path`` and its paired ``.py`` beside it, each only where it
    differs from the file there: the notebook not at all if it differs only in what a run
    changes by itself (:func:`_comparable`). Returns whether the notebook was written."""
    import nbformat

    _normalize(nb)
    text = paired_text(nb)  # sets the pairing in nb's metadata first
    py = paired_path(path)
    old = _read(path) if path.exists() else None
    write_nb = old is None or _comparable(old) != _comparable(nb)
    write_py = not py.is_file() or _text_of(py) != text  # not a file: its write says why
    with output_batch():  # the notebook and its .py together, or neither
        if write_nb:
            with atomic_output(path) as f:
                nbformat.write(nb, f)
        if write_py:
            with atomic_output(py) as f:
                f.write(text)
    return write_nb


def pair(path: str | PathLike[str]) -> Path:
    """Write the ``.py`` paired with notebook ``path`` (and the pairing into the notebook's
    metadata, if it lacks it); returns the ``.py``'s path."""
    p = Path(path)
    _write(_read(p), p)
    return paired_path(p)


@dataclass(frozen=True)
class NotebookRun:
    """One notebook run: ``seconds`` for Run All, the slowest code cell's ``index`` (in the
    notebook, from 0) and ``seconds``, and whether the notebook was ``written`` (not when its
    outputs came out as they were)."""

    path: Path
    seconds: float
    slowest_cell: int
    slowest_seconds: float
    written: bool = True

    def __str__(self) -> str:
        return (
            f"{self.path}: Run All {self.seconds:.1f} s, slowest cell "
            f"{self.slowest_cell} ({self.slowest_seconds:.1f} s)"
            + ("" if self.written else "; outputs unchanged, not written")
        )


def _cell_seconds(cell) -> float:
    from datetime import datetime

    t = cell.get("metadata", {}).get("execution", {})
    try:
        start = datetime.fromisoformat(t["iopub.execute_input"].replace("Z", "+00:00"))
        end = datetime.fromisoformat(t["shell.execute_reply"].replace("Z", "+00:00"))
    except (KeyError, ValueError):
        return 0.0
    return (end - start).total_seconds()


def run_notebook(path: str | PathLike[str], timeout: float = 600.0) -> NotebookRun:
    """Execute notebook ``path`` in a fresh ``python3`` kernel, in its own folder, and write it
    back with the new outputs and its paired ``.py`` — unless the outputs came out as they were
    (apart from execution times, widget ids and the outputs of cells tagged :data:`TIMING`):
    then the notebook is left as it is. A cell that raises (or kills the
    kernel) stops the run: the error is an :class:`~fhslam.errors.InputError` naming the
    notebook and the cell, and the file is left as it was. ``timeout`` is per cell, in
    seconds. The kernel's own log (its stderr: connection warnings, and its tracebacks when
    it is shut down mid-cell) is kept out of the terminal.

    Raises
    ------
    InputError
        For an unreadable notebook, a cell that fails or times out, a kernel that dies.
    KeyboardInterrupt
        On Ctrl-C (SIGINT; also SIGTERM) while it runs: nbclient shuts the kernel down, and
        whatever that raises inside nbclient is reported as the interrupt it is.
    """
    import subprocess

    from nbclient import NotebookClient
    from nbclient.exceptions import CellExecutionError, CellTimeoutError, DeadKernelError

    p = Path(path)
    nb = _read(p)
    running: list[int] = []
    client = NotebookClient(
        nb,
        timeout=timeout,
        kernel_name="python3",
        resources={"metadata": {"path": str(p.parent.resolve())}},
        record_timing=True,
        on_cell_start=lambda cell, cell_index: running.append(cell_index),
    )
    t0 = time.perf_counter()
    try:
        client.execute(stderr=subprocess.DEVNULL)
    except BaseException as e:
        # nbclient handles SIGINT itself, by shutting the kernel down: the cell then fails
        # with DeadKernelError and the cleanup with an AssertionError. Its handler leaves this
        # attribute behind (nbclient 0.5-0.10).
        if getattr(client, "_async_cleanup_kernel_future", None) is not None:
            raise KeyboardInterrupt from None
        if isinstance(e, CellExecutionError | CellTimeoutError):
            failed = next(
                (
                    i
                    for i, c in enumerate(nb.cells)
                    if any(o.get("output_type") == "error" for o in c.get("outputs", []))
                ),
                None,
            )
            where = f"cell {failed}" if failed is not None else "a cell"
            last = str(e).strip().splitlines()[-1] if str(e).strip() else type(e).__name__
            raise InputError(f"{p}: {where} failed: {last}") from None
        if isinstance(e, DeadKernelError):
            where = f"cell {running[-1]}" if running else "starting the kernel"
            raise InputError(
                f"{p}: the kernel died in {where} (its process ended: a crash, os._exit, out "
                "of memory)"
            ) from None
        raise
    seconds = time.perf_counter() - t0
    times = [(_cell_seconds(c), i) for i, c in enumerate(nb.cells) if c.cell_type == "code"]
    slow, index = max(times, default=(0.0, -1))
    written = _write(nb, p)
    return NotebookRun(p, seconds, index, slow, written)


def _is_solution(cell: dict) -> bool:
    return "solution" in cell.get("metadata", {}).get("tags", [])


def student_copy(source: str | PathLike[str], out: str | PathLike[str]) -> list[tuple[Path, int]]:
    """Write every notebook of folder ``source`` to folder ``out`` without its solution cells
    (cells tagged ``solution``) and without outputs, :data:`SOLUTION_NOTE` replaced by
    :data:`STUDENT_NOTE` in its text; returns ``(path, solutions removed)`` per notebook.
    ``out`` must not be ``source``. The copies are not paired with a ``.py``; the results the
    notebooks load (folder ``results``) are copied with them.

    Every notebook is read and checked before anything is written, and the copies appear
    together once all are written, or none (:func:`~fhslam.io.files.output_batch`): a broken
    notebook, an ``out`` that is a file or cannot be written, or Ctrl-C leaves no copy (and
    no folder created for it).

    Raises
    ------
    InputError
        Naming the folder or the notebook that is wrong.
    """
    import nbformat

    src, dst = Path(source), Path(out)
    notebooks = notebooks_in(src)
    if dst.exists() and dst.resolve() == src.resolve():
        raise InputError(f"{dst}: is the source folder; the student copy must go elsewhere")
    if dst.exists() and not dst.is_dir():
        raise InputError(f"{dst}: is a file, not a folder; give a folder for the student copy")
    copies = []
    for path in notebooks:  # every notebook read and stripped first: a broken one stops all
        nb = _read(path)
        kept = [c for c in nb.cells if not _is_solution(c)]
        removed = len(nb.cells) - len(kept)
        nb.cells = kept
        nb.metadata.pop("jupytext", None)
        for c in nb.cells:
            if c.cell_type == "code":
                c.outputs, c.execution_count = [], None
            elif c.cell_type == "markdown":
                c.source = c.source.replace(SOLUTION_NOTE, STUDENT_NOTE)
        try:
            text = nbformat.writes(nb)
        except Exception as e:  # nbformat raises several types for an invalid notebook
            raise InputError(f"{path}: not a valid notebook ({e})") from None
        copies.append((path.name, text if text.endswith("\n") else text + "\n", removed))
    results = src / RESULTS
    files = {}  # the results read before anything is written too (a few MB)
    for p in sorted(results.rglob("*")) if results.is_dir() else []:
        if p.is_file():
            with reading(p):
                files[p.relative_to(results)] = p.read_bytes()
    with output_folder(dst, str(dst)), output_batch():
        for name, text, _ in copies:
            with atomic_output(dst / name) as f:
                f.write(text)
        for relative, data in files.items():
            target = dst / RESULTS / relative
            try:
                target.parent.mkdir(parents=True, exist_ok=True)
            except OSError as e:
                raise InputError(f"{target.parent}: cannot create ({e.strerror or e})") from None
            with atomic_output(target, "wb") as f:
                f.write(data)
    return [(dst / name, removed) for name, _, removed in copies]
