"""The workbook's notebooks as files: run them, pair them with plain-text sources, and copy
them for a class.

- :func:`run_notebook` executes a notebook in a fresh kernel and writes it back with its new
  outputs (atomically: an interrupted run leaves the old file), timing every cell;
  ``fhslam run-notebooks`` does it for the whole folder — the one command that regenerates
  the committed outputs.
- Every notebook ``NN_topic.ipynb`` is paired with ``NN_topic.py``, its plain-text source in
  jupytext's percent format (cells separated by ``# %%`` lines, markdown as comments, tags
  kept), so that a change to a notebook reads as a diff of its ``.py``. :func:`pair` writes
  the ``.py`` from the ``.ipynb`` (``run_notebook`` does it too); after editing the ``.py``
  by hand, ``jupytext --sync notebooks/NN_topic.py`` carries the change into the notebook,
  keeping its outputs. The pairing is stated in each notebook's metadata, so JupyterLab with
  the jupytext extension saves both files.
- :func:`student_copy` writes the notebooks without their solution cells and outputs.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from os import PathLike
from pathlib import Path

from fhslam.errors import InputError
from fhslam.io.files import atomic_output, output_batch, output_folder, reading

__all__ = [
    "FORMATS",
    "RESULTS",
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


def _write(nb, path: Path) -> None:
    import nbformat

    text = paired_text(nb)  # sets the pairing in nb's metadata first
    with output_batch():  # the notebook and its .py together, or neither
        with atomic_output(path) as f:
            nbformat.write(nb, f)
        with atomic_output(paired_path(path)) as f:
            f.write(text)


def pair(path: str | PathLike[str]) -> Path:
    """Write the ``.py`` paired with notebook ``path`` (and the pairing into the notebook's
    metadata); returns the ``.py``'s path."""
    p = Path(path)
    _write(_read(p), p)
    return paired_path(p)


@dataclass(frozen=True)
class NotebookRun:
    """One notebook run: ``seconds`` for Run All, and the slowest code cell's ``index`` (in
    the notebook, from 0) and ``seconds``."""

    path: Path
    seconds: float
    slowest_cell: int
    slowest_seconds: float

    def __str__(self) -> str:
        return (
            f"{self.path}: Run All {self.seconds:.1f} s, slowest cell "
            f"{self.slowest_cell} ({self.slowest_seconds:.1f} s)"
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
    back with the new outputs and its paired ``.py``. A cell that raises (or kills the
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
    _write(nb, p)
    return NotebookRun(p, seconds, index, slow)


def _is_solution(cell: dict) -> bool:
    return "solution" in cell.get("metadata", {}).get("tags", [])


def student_copy(source: str | PathLike[str], out: str | PathLike[str]) -> list[tuple[Path, int]]:
    """Write every notebook of folder ``source`` to folder ``out`` without its solution cells
    (cells tagged ``solution``) and without outputs; returns ``(path, solutions removed)`` per
    notebook. ``out`` must not be ``source``. The copies are not paired with a ``.py``; the
    results the notebooks load (folder ``results``) are copied with them.

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
