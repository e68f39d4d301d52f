"""Opening input files and writing output files, with errors a user can act on.

Every reader of :mod:`fhslam` opens its file through :func:`input_path` and
:func:`reading`, and every writer through :func:`atomic_output`, so that

- a missing input is a :class:`~fhslam.errors.MissingInputError` naming the path, a directory
  or an unreadable file an :class:`~fhslam.errors.InputError`;
- an output is written to a temporary file beside it and renamed into place only once
  complete: a failed or interrupted write leaves no half-written file, and an output that
  cannot be written is an :class:`~fhslam.errors.InputError` naming the path;
- a command checks its outputs with :func:`check_outputs` before it reads or computes
  anything: an output that is one of its inputs (or another output) is refused, so that no
  input is ever overwritten, and so is one that cannot be written (its folder missing or not
  writable, checked by creating and removing a file there), so that no work is lost;
- a command that writes several files writes them inside :func:`output_batch`: each is
  written to its temporary file, and all are renamed into place only once every one is
  complete, so that a failure (or Ctrl-C) leaves none of them; :func:`output_folder` does the
  same for a command that writes into a folder it may create.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from contextvars import ContextVar
from pathlib import Path
from typing import IO

from fhslam.errors import InputError, MissingInputError

__all__ = [
    "atomic_output",
    "check_folder_writable",
    "check_outputs",
    "input_path",
    "output_batch",
    "output_folder",
    "reading",
]


def input_path(path: str | os.PathLike[str], what: str = "") -> Path:
    """``path`` as a :class:`~pathlib.Path` after checking it names an existing file.

    Raises
    ------
    MissingInputError
        If nothing exists at ``path`` (the message says ``what`` was looked for).
    InputError
        If ``path`` is a directory or another non-file.
    """
    p = Path(path)
    what = f"{what} file" if what else "file"
    if not p.exists():
        raise MissingInputError(f"{p}: no such {what}", str(p))
    if not p.is_file():
        kind = "a directory" if p.is_dir() else "not a regular file"
        raise InputError(f"{p}: is {kind}, not a {what}")
    return p


def _same_file(a: Path, b: Path) -> bool:
    """Whether ``a`` and ``b`` name one file (also through links), existing or not."""
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
    except OSError:
        pass
    return a.resolve() == b.resolve()


def check_folder_writable(folder: str | os.PathLike[str], what: str) -> None:
    """Check that files can be created in the existing folder ``folder`` by creating and
    removing one there (permissions alone do not tell: root ignores them, an immutable or
    read-only-mounted folder refuses even root).

    Raises
    ------
    InputError
        ``"{what}: cannot write (folder {folder}: {reason})"``, or ``"... (no such folder
        {folder})"``, ``"... ({folder} is not a folder)"``.
    """
    d = Path(folder)
    if not d.exists():
        raise InputError(f"{what}: cannot write (no such folder {d})")
    if not d.is_dir():
        raise InputError(f"{what}: cannot write ({d} is not a folder)")
    try:
        fd, probe = tempfile.mkstemp(prefix=".fhslam-probe-", dir=d)
    except OSError as e:
        raise InputError(f"{what}: cannot write (folder {d}: {e.strerror or e})") from None
    os.close(fd)
    os.unlink(probe)


def check_outputs(
    outputs: dict[str, str | os.PathLike[str] | None],
    inputs: dict[str, str | os.PathLike[str] | None],
) -> None:
    """Refuse outputs that would overwrite an input or each other, or cannot be written.

    ``outputs`` and ``inputs`` map how the user gave each path (an option such as
    ``"--log"``, or a description such as ``"the world file"``) to the path; ``None``
    entries (an option not given, an input that is not a file, e.g. a built-in world's
    name) are skipped. Each output must name a file (not a directory) in an existing folder
    where a file can be created (:func:`check_folder_writable`).

    Raises
    ------
    InputError
        Naming the output and what it would overwrite or why it cannot be written; call this
        before anything is read, computed or written.
    """
    seen: list[tuple[str, Path]] = [
        (what, Path(p)) for what, p in inputs.items() if p is not None and Path(p).is_file()
    ]
    for what, p in outputs.items():
        if p is None:
            continue
        path = Path(p)
        for other, q in seen:
            if _same_file(path, q):
                role = "also given as" if other.startswith("--") else "is"
                raise InputError(
                    f"{what} {path}: {role} {other}; an output must not overwrite an input "
                    "or another output (nothing was written)"
                )
        seen.append((what, path))
    for what, p in outputs.items():
        if p is None:
            continue
        path = Path(p)
        if path.is_dir():
            raise InputError(f"{what} {path}: is a directory; give a file name for the output")
        check_folder_writable(path.parent, f"{what} {path}")


@contextmanager
def reading(path: str | os.PathLike[str]) -> Iterator[None]:
    """Turn an :class:`OSError` raised while reading ``path`` into an
    :class:`~fhslam.errors.InputError` naming it (e.g. permission denied)."""
    try:
        yield
    except FileNotFoundError as e:
        raise MissingInputError(f"{path}: no such file", str(path)) from e
    except OSError as e:
        raise InputError(f"{path}: cannot read ({e.strerror or e})") from None


_BATCH: ContextVar[list[tuple[Path, Path]] | None] = ContextVar("_BATCH", default=None)
"""The open :func:`output_batch`'s completed temporary files and their targets, or None."""

_INTERRUPTED = [False]
"""Whether Ctrl-C was pressed since :func:`watch_interrupts` began (a list: set in place)."""

_COMMITTED = [0]
"""Outputs renamed into place since :func:`watch_interrupts` began."""


@contextmanager
def watch_interrupts() -> Iterator[None]:
    """Remember a Ctrl-C (SIGINT) that arrives inside the ``with`` block, so that no output is
    renamed into place after it, even where Python swallowed its :class:`KeyboardInterrupt`.

    SIGINT raises KeyboardInterrupt wherever Python happens to be, and where that is a
    callback from C (numba's compiler calls back into Python through ctypes) or a
    destructor, Python prints "Exception ignored" and goes on: the command would finish and
    write its outputs after the user pressed Ctrl-C. Inside this block SIGINT still raises
    KeyboardInterrupt, but is also recorded; :func:`atomic_output` and :func:`output_batch`
    raise KeyboardInterrupt instead of renaming once one was recorded, and a swallowed one is
    not printed (``sys.unraisablehook``). Only in the main thread (elsewhere a no-op).
    """
    import signal
    import sys
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def on_sigint(signum, frame):
        _INTERRUPTED[0] = True
        raise KeyboardInterrupt

    def unraisable(u, default=sys.unraisablehook):
        if not isinstance(u.exc_value, KeyboardInterrupt):
            default(u)

    before = _INTERRUPTED[0], _COMMITTED[0]
    _INTERRUPTED[0], _COMMITTED[0] = False, 0
    old_handler, old_hook = signal.signal(signal.SIGINT, on_sigint), sys.unraisablehook
    sys.unraisablehook = unraisable
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old_handler)
        sys.unraisablehook = old_hook
        _INTERRUPTED[0], _COMMITTED[0] = before


def interrupted_before_output() -> bool:
    """Whether Ctrl-C was pressed inside the current :func:`watch_interrupts` block before
    any output was renamed into place (after that, the outputs stand complete)."""
    return _INTERRUPTED[0] and _COMMITTED[0] == 0


def _commit_allowed() -> None:
    """Raise :class:`KeyboardInterrupt` if Ctrl-C was pressed (and perhaps swallowed)."""
    if _INTERRUPTED[0]:
        raise KeyboardInterrupt


@contextmanager
def output_batch() -> Iterator[None]:
    """Write several outputs all or none: every :func:`atomic_output` inside the ``with``
    block (also in the writers it calls, e.g. ``write_trajectory``) leaves its complete
    temporary file in place, and they are all renamed to their targets when the block ends
    normally. If the block raises (including :class:`KeyboardInterrupt`), every temporary file
    is removed and no output appears. Should a rename itself fail (the folder changed since),
    the outputs renamed before it are removed again and the error names the path. Batches
    nest: an inner one joins the outer.
    """
    if _BATCH.get() is not None:
        yield
        return
    pending: list[tuple[Path, Path]] = []
    token = _BATCH.set(pending)
    try:
        yield
    except BaseException:
        for tmp, _ in pending:
            tmp.unlink(missing_ok=True)
        raise
    finally:
        _BATCH.reset(token)
    done: list[Path] = []
    try:
        _commit_allowed()
        for tmp, target in pending:
            try:
                os.replace(tmp, target)
            except OSError as e:
                raise InputError(f"{target}: cannot write ({e.strerror or e})") from None
            done.append(target)
            _COMMITTED[0] += 1
    except BaseException:
        for tmp, _ in pending:
            tmp.unlink(missing_ok=True)
        for target in done:
            target.unlink(missing_ok=True)
        raise


@contextmanager
def output_folder(folder: str | os.PathLike[str], what: str) -> Iterator[Path]:
    """The output folder ``folder`` (``what`` names it in errors, e.g. ``"--out figs"``),
    created if missing, checked writable (:func:`check_folder_writable`); yields its path.

    If the ``with`` block raises (including :class:`KeyboardInterrupt`) and the folder was
    created here, it is removed again, with the empty folders inside it and the parents
    created for it (never a file: write the files in an :func:`output_batch` inside this
    block, so that none is left).

    Raises
    ------
    InputError
        If ``folder`` is a file, or cannot be created or written to, naming it.
    """
    d = Path(folder)
    if d.exists() and not d.is_dir():
        raise InputError(f"{what}: is a file, not a folder; give a folder for the output")
    created = []  # d and the parents made for it, innermost first
    p = d
    while not p.exists() and p != p.parent:
        created.append(p)
        p = p.parent
    if created:
        try:
            d.mkdir(parents=True)
        except OSError as e:
            raise InputError(f"{what}: cannot create the folder ({e.strerror or e})") from None
    try:
        check_folder_writable(d, what)
        yield d
    except BaseException:
        if created:
            for sub in sorted((q for q in d.rglob("*") if q.is_dir()), reverse=True):
                _remove_empty(sub)
            for q in created:
                _remove_empty(q)
        raise


def _remove_empty(folder: Path) -> None:
    with suppress(OSError):  # not empty: a file is never removed
        folder.rmdir()


@contextmanager
def atomic_output(path: str | os.PathLike[str], mode: str = "w") -> Iterator[IO]:
    """Open ``path`` for writing so that it appears only complete (see the module docs).

    Yields a file object (text, UTF-8, for ``mode="w"``; bytes for ``"wb"``) on a temporary
    file in the same folder, renamed to ``path`` when the ``with`` block ends normally (or,
    inside an :func:`output_batch`, when the batch ends); removed if it raises (including
    :class:`KeyboardInterrupt`).

    Raises
    ------
    InputError
        If the file cannot be created or written (no such folder, permission denied, disk
        full), naming ``path``.
    """
    p = Path(path)
    if p.is_dir():
        raise InputError(f"{p}: is a directory; give a file name for the output")
    tmp = p.with_name(f".{p.name}.{os.getpid()}.tmp")
    try:
        f = open(tmp, mode, encoding=None if "b" in mode else "utf-8")  # noqa: SIM115
    except OSError as e:
        raise InputError(f"{p}: cannot write ({e.strerror or e})") from None
    try:
        with f:
            yield f
        batch = _BATCH.get()
        if batch is None:
            _commit_allowed()
            os.replace(tmp, p)
            _COMMITTED[0] += 1
        else:
            batch.append((tmp, p))
    except OSError as e:
        tmp.unlink(missing_ok=True)
        raise InputError(f"{p}: cannot write ({e.strerror or e})") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
