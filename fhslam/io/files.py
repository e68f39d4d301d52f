"""Opening input files and writing output files, with errors a user can act on.

Every reader of :mod:`fhslam` opens its file through :func:`input_path` and
:func:`reading`, and every writer through :func:`atomic_output`, so that

- a missing input is a :class:`~fhslam.errors.MissingInputError` naming the path, a directory
  or an unreadable file an :class:`~fhslam.errors.InputError`;
- an output that is a regular file (or does not exist yet) is written to a temporary file
  beside it and renamed into place only once complete: a failed or interrupted write leaves
  no half-written file, and an output that cannot be written is an
  :class:`~fhslam.errors.InputError` naming the path;
- an output that exists and is not a regular file -- a device such as ``/dev/null``, a named
  pipe (FIFO), a descriptor such as ``/dev/fd/3`` or ``/dev/stdout`` (also of a shell's
  process substitution ``>(gzip > t.gz)``) -- is a *stream*: it is opened and written in
  place, never replaced, renamed over or removed. Its content is kept in memory until complete
  and then written in one go, so a failed writer sends it nothing; a failed write (``/dev/full``'s
  "No space left on device", a closed pipe's "Broken pipe") is an InputError naming the path.
  Opening a FIFO waits for its reader, as for any program. A socket cannot be opened: it is
  refused naming the path;
- the output ``-`` is standard output, a stream as above (a file named ``-`` is ``./-``);
  text goes out as the same UTF-8 bytes a file would hold;
- text is written as UTF-8; a file name's bytes that the locale could not decode (Python
  keeps them as surrogate escapes, e.g. a name in UTF-8 under ``LC_ALL=C``) are written as
  those bytes where they are UTF-8, and as ``\\xNN`` escapes where not, so every text output
  is valid UTF-8;
- a command checks its outputs with :func:`check_outputs` before it reads or computes
  anything: an output that is one of its inputs (or another output) is refused, so that no
  input is ever overwritten, and so is one that cannot be written (its folder missing or not
  writable, checked by creating and removing a file there; a name too long for the file
  system; a socket; ``-`` where the command does not allow it, or for two outputs), so that
  no work is lost; a stream is checked without opening it, so a FIFO does not block the check;
- a command that writes several files writes them inside :func:`output_batch`: each is
  written to its temporary file, and all are renamed into place only once every one is
  complete, so that a failure (or Ctrl-C) leaves none of them; :func:`output_folder` does the
  same for a command that writes into a folder it may create. A stream in a batch cannot be
  taken back: it is written when the batch commits, before the files are renamed, so a
  failure or Ctrl-C before then sends it nothing, and a failed write to it leaves none of the
  files; only a rename failing after it (the folder changed since the check) leaves the stream
  written without the files.

Telling a stream from a file, and writing a stream in place, is the job of
:mod:`fhslam.io.special_outputs`; its public names are importable from here too.
"""

from __future__ import annotations

import codecs
import itertools
import os
import tempfile
from collections.abc import Collection, Iterator
from contextlib import contextmanager, suppress
from contextvars import ContextVar
from dataclasses import dataclass, field
from io import BytesIO, TextIOWrapper
from pathlib import Path
from typing import IO

from fhslam.errors import InputError, MissingInputError
from fhslam.io.special_outputs import (
    STDOUT,
    _is_char_device,
    _is_stdout,
    _output_kind,
    _write_stream,
    output_name,
    writes_to_stdout,
)

__all__ = [
    "STDOUT",
    "atomic_output",
    "check_folder_writable",
    "check_outputs",
    "input_path",
    "output_batch",
    "output_folder",
    "output_name",
    "reading",
    "writes_to_stdout",
]

ENCODING_ERRORS = "fhslam.filenames"
"""The codec error handler of every text output (see the module docs)."""


def _undecoded_bytes(e: UnicodeError) -> tuple[bytes, int]:
    """Codec error handler :data:`ENCODING_ERRORS`: surrogate escapes (bytes a file name had
    that the locale could not decode) become those bytes where they are UTF-8, ``\\xNN``
    escapes where not; any other unencodable character a ``\\uNNNN`` escape."""
    if not isinstance(e, UnicodeEncodeError):
        raise e
    out, raw = [], bytearray()
    for c in e.object[e.start : e.end]:
        if "\udc80" <= c <= "\udcff":
            raw.append(ord(c) - 0xDC00)
            continue
        out.append(raw.decode("utf-8", "backslashreplace").encode("utf-8"))
        out.append(c.encode("ascii", "backslashreplace"))
        raw.clear()
    out.append(raw.decode("utf-8", "backslashreplace").encode("utf-8"))
    return b"".join(out), e.end


codecs.register_error(ENCODING_ERRORS, _undecoded_bytes)


def input_path(path: str | os.PathLike[str], what: str = "") -> Path:
    """``path`` as a :class:`~pathlib.Path` after checking it names an existing file.

    Raises
    ------
    MissingInputError
        If nothing exists at ``path`` (the message says ``what`` was looked for).
    InputError
        If ``path`` is a directory or another non-file, or cannot be looked up (a name too
        long for the file system).
    """
    p = Path(path)
    what = f"{what} file" if what else "file"
    try:
        exists = p.exists()
    except OSError as e:
        raise InputError(f"{p}: cannot read ({e.strerror or e})") from None
    if not exists:
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


def _is_file(p: Path) -> bool:
    """Whether ``p`` is a regular file (False where it cannot be looked up)."""
    try:
        return p.is_file()
    except OSError:
        return False


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
    try:
        exists, is_dir = d.exists(), d.is_dir()
    except OSError as e:
        raise InputError(f"{what}: cannot write (folder {d}: {e.strerror or e})") from None
    if not exists:
        raise InputError(f"{what}: cannot write (no such folder {d})")
    if not is_dir:
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
    to_stdout: Collection[str] = (),
) -> None:
    """Refuse outputs that would overwrite an input or each other, or cannot be written.

    ``outputs`` and ``inputs`` map how the user gave each path (an option such as
    ``"--log"``, or a description such as ``"the input world file"``) to the path; ``None``
    entries (an option not given, an input that is not a file, e.g. a built-in world's
    name) are skipped. Each output must name a file (not a directory) in an existing folder
    where a file can be created (:func:`check_folder_writable`), or an existing stream (a
    device, a FIFO, a descriptor: accepted without opening it or probing its folder; two
    outputs may name one character device, such as ``/dev/null``). ``-`` (standard output) is
    accepted for the outputs named in ``to_stdout``, and for one output only.

    Raises
    ------
    InputError
        Naming the output and what it would overwrite or why it cannot be written; call this
        before anything is read, computed or written.
    """
    given = {what: p for what, p in outputs.items() if p is not None}
    dashes = [what for what, p in given.items() if _is_stdout(p)]
    for what in dashes:
        if what not in to_stdout:
            raise InputError(
                f"{what} -: this output cannot go to standard output; give a file name "
                "(./- for a file named -)"
            )
    if len(dashes) > 1:
        raise InputError(
            f"{' and '.join(f'{what} -' for what in dashes)}: only one output can go to "
            "standard output (nothing was written)"
        )
    files = {what: Path(p) for what, p in given.items() if not _is_stdout(p)}
    seen: list[tuple[str, Path]] = [
        (what, Path(p)) for what, p in inputs.items() if p is not None and _is_file(Path(p))
    ]
    for what, path in files.items():
        for other, q in seen:
            if _same_file(path, q) and not _is_char_device(path):
                role = "also given as" if other.startswith("--") else "is"
                raise InputError(
                    f"{what} {path}: {role} {other}; an output must not overwrite an input "
                    "or another output (nothing was written)"
                )
        seen.append((what, path))
    for what, path in files.items():
        if _output_kind(path, f"{what} {path}") == "file":
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


@dataclass
class _Batch:
    """An open :func:`output_batch`: its completed temporary files with their targets, and
    its streams' targets with their content, in the order written."""

    renames: list[tuple[Path, Path]] = field(default_factory=list)
    streams: list[tuple[str | Path, bytes]] = field(default_factory=list)


_BATCH: ContextVar[_Batch | None] = ContextVar("_BATCH", default=None)
"""The open :func:`output_batch`, or None."""

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

    A stream (a device, a pipe, standard output: see the module docs) cannot be taken back:
    its content is held until the block ends normally and then written, before the renames; if
    that write fails, no file is renamed. Only a rename failing after it leaves the stream
    written without the files.
    """
    if _BATCH.get() is not None:
        yield
        return
    batch = _Batch()
    token = _BATCH.set(batch)
    try:
        yield
    except BaseException:
        for tmp, _ in batch.renames:
            tmp.unlink(missing_ok=True)
        raise
    finally:
        _BATCH.reset(token)
    done: list[Path] = []
    try:
        _commit_allowed()
        for target, data in batch.streams:
            _write_stream(target, data)
            _COMMITTED[0] += 1
        for tmp, target in batch.renames:
            try:
                os.replace(tmp, target)
            except OSError as e:
                raise InputError(f"{target}: cannot write ({e.strerror or e})") from None
            done.append(target)
            _COMMITTED[0] += 1
    except BaseException:
        for tmp, _ in batch.renames:
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

    Yields a file object (text, UTF-8, for ``mode="w"``; bytes for ``"wb"``). For a regular
    file (or a new one) it is a temporary file in the same folder, renamed to ``path`` when
    the ``with`` block ends normally (or, inside an :func:`output_batch`, when the batch
    ends), and removed if it raises (including :class:`KeyboardInterrupt`). For a stream (a
    device, a FIFO, a descriptor such as ``/dev/fd/3``, or ``-`` for standard output) it is a
    buffer in memory, written to ``path`` in place when the block (or the batch) ends
    normally, and dropped if it raises.

    Raises
    ------
    InputError
        If the output cannot be created or written (no such folder, permission denied, disk
        full, a closed pipe, a name too long), naming ``path``.
    """
    if _is_stdout(path):
        yield from _stream_output(STDOUT, mode)
        return
    p = Path(path)
    if _output_kind(p, str(p)) == "stream":
        yield from _stream_output(p, mode)
        return
    tmp = _temporary_name(p)
    try:
        f = open(tmp, mode, **_text_options(mode))  # noqa: SIM115
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
            batch.renames.append((tmp, p))
    except OSError as e:
        tmp.unlink(missing_ok=True)
        raise InputError(f"{p}: cannot write ({e.strerror or e})") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _text_options(mode: str) -> dict[str, str | None]:
    """``open``'s encoding options for ``mode``: UTF-8 for text (see the module docs)."""
    return {} if "b" in mode else {"encoding": "utf-8", "errors": ENCODING_ERRORS}


_SHORT_NAMES = itertools.count()
"""Numbers the temporary files of outputs whose own name is near the length limit."""


def _temporary_name(p: Path) -> Path:
    """The temporary file of the output ``p``: ``.{name}.{pid}.tmp`` beside it, or, where that
    name would be too long for the file system, ``.fhslam.{pid}.{n}.tmp``."""
    name = f".{p.name}.{os.getpid()}.tmp"
    try:
        limit = os.pathconf(p.parent, "PC_NAME_MAX")
    except (OSError, ValueError):
        limit = 255
    if len(os.fsencode(name)) > limit:
        name = f".fhslam.{os.getpid()}.{next(_SHORT_NAMES)}.tmp"
    return p.with_name(name)


def _stream_output(target: str | Path, mode: str) -> Iterator[IO]:
    """:func:`atomic_output`'s body for a stream: a buffer, written to ``target`` when the
    ``with`` block (or the open batch) ends normally."""
    buffer = BytesIO()
    f: IO = (
        buffer if "b" in mode else TextIOWrapper(buffer, write_through=True, **_text_options(mode))
    )
    yield f
    f.flush()
    data = buffer.getvalue()
    batch = _BATCH.get()
    if batch is None:
        _commit_allowed()
        _write_stream(target, data)
        _COMMITTED[0] += 1
    else:
        batch.streams.append((target, data))
