"""Outputs that are not regular files: standard output, devices, pipes, descriptors.

An output that exists and is not a regular file -- a device such as ``/dev/null``, a named
pipe (FIFO), a descriptor such as ``/dev/fd/3`` or ``/dev/stdout`` (also of a shell's process
substitution ``>(gzip > t.gz)``), even where the descriptor leads to a regular file -- is a
*stream* (:func:`_output_kind`): it is written in place, never replaced, renamed over or
removed, by :func:`_write_stream` once its content is complete (:mod:`fhslam.io.files` holds
it in memory until then). The output :data:`STDOUT` (``-``) is standard output, a stream
too (a file named ``-`` is ``./-``), named ``"standard output"`` in messages
(:func:`output_name`); :func:`writes_to_stdout` tells a command that an output goes there,
so that its messages go to stderr.

Bad outputs: a directory or a socket (which cannot be opened for writing) is refused, an
:class:`~fhslam.errors.InputError` naming the path, as is a path that cannot be looked up
(a name too long). A failed write (``/dev/full``'s "No space left on device", a closed
pipe's "Broken pipe", a path that cannot be opened) is an InputError naming the path; after
a failed write to standard output, standard output is pointed at the null device, so that
Python's flush at exit does not fail again.
"""

from __future__ import annotations

import errno
import os
import re
import stat
import sys
from contextlib import suppress
from pathlib import Path

from fhslam.errors import InputError

STDOUT = "-"
"""The output name that means standard output."""


def _is_stdout(path: object) -> bool:
    """Whether ``path`` is :data:`STDOUT` (``"-"``, also as a Path)."""
    return isinstance(path, str | os.PathLike) and os.fspath(path) == STDOUT


def output_name(path: str | os.PathLike[str]) -> str:
    """``path`` as a message names it: ``"standard output"`` for ``-``."""
    return "standard output" if _is_stdout(path) else str(path)


def writes_to_stdout(*paths: str | os.PathLike[str] | None) -> bool:
    """Whether an output among ``paths`` goes to this process's standard output: ``-``, or a
    name of the pipe or file that standard output is (``/dev/stdout``). A command prints its
    messages to stderr then, so that they do not mix with the output (a terminal, where both
    show, is not counted)."""
    try:
        out = os.fstat(sys.stdout.fileno())
    except (AttributeError, OSError, ValueError):  # no real stdout (captured, closed)
        out = None
    for p in paths:
        if p is None:
            continue
        if _is_stdout(p):
            return True
        if out is None or stat.S_ISCHR(out.st_mode):
            continue
        with suppress(OSError, ValueError):
            if os.path.samestat(os.stat(p), out):
                return True
    return False


_DESCRIPTOR_FOLDER = re.compile(r"/proc/(?:self|thread-self|\d+)(?:/task/\d+)?/fd")
"""A process's folder of open descriptors, where ``/dev/fd`` and ``/dev/stdout`` lead."""


def _names_a_descriptor(p: Path) -> bool:
    """Whether ``p`` is, or leads through symbolic links to, an open descriptor of a process
    (``/dev/fd/3``, ``/dev/stdout``, ``/proc/self/fd/1``): a stream, even where it is a
    regular file, since its folder is no place for a temporary file."""
    q = os.path.abspath(p)
    for _ in range(40):  # the kernel's limit on links followed
        folder = os.path.realpath(os.path.dirname(q))
        if _DESCRIPTOR_FOLDER.fullmatch(folder):
            return True
        try:
            link = os.readlink(q)
        except OSError:  # not a link
            return False
        q = os.path.abspath(os.path.join(folder, link))
    return False


def _output_kind(p: Path, what: str) -> str:
    """``"stream"`` if the output ``p`` exists and is not a regular file or names a
    descriptor (written in place), ``"file"`` if it is a regular file or does not exist
    (written to a temporary file and renamed); ``what`` names it in errors.

    Raises
    ------
    InputError
        If ``p`` is a directory or a socket, or cannot be looked up (a name too long).
    """
    try:
        st = os.stat(p)
    except (FileNotFoundError, NotADirectoryError):
        return "file"  # a new file; its folder is checked where it is created
    except OSError as e:
        if e.errno == errno.ELOOP:  # a loop of links: replaced by the file, as a link is
            return "file"
        raise InputError(f"{what}: cannot write ({e.strerror or e})") from None
    if stat.S_ISDIR(st.st_mode):
        raise InputError(f"{what}: is a directory; give a file name for the output")
    if stat.S_ISSOCK(st.st_mode):
        raise InputError(
            f"{what}: is a socket, which cannot be opened for writing; give a file, a pipe "
            "or - (standard output)"
        )
    if not stat.S_ISREG(st.st_mode) or _names_a_descriptor(p):
        return "stream"
    return "file"


def _is_char_device(p: Path) -> bool:
    try:
        return stat.S_ISCHR(os.stat(p).st_mode)
    except OSError:
        return False


def _write_stream(target: str | Path, data: bytes) -> None:
    """Write ``data`` to the stream ``target`` in place (``-``: standard output, not closed).

    Raises
    ------
    InputError
        ``"{target}: cannot write ({reason})"``, e.g. no space left on the device, a broken
        pipe, or a path that cannot be opened.
    """
    if _is_stdout(target):
        try:
            sys.stdout.flush()
            out = getattr(sys.stdout, "buffer", None)
            if out is None:  # a text-only stand-in (tests): the same text
                sys.stdout.write(data.decode("utf-8", "surrogateescape"))
            else:
                out.write(data)
            sys.stdout.flush()
        except OSError as e:
            _abandon_stdout()
            raise InputError(f"standard output: cannot write ({e.strerror or e})") from None
        return
    try:
        with open(target, "wb") as f:
            f.write(data)
    except OSError as e:
        raise InputError(f"{target}: cannot write ({e.strerror or e})") from None


def _abandon_stdout() -> None:
    """Point standard output at the null device after a write to it failed (a closed pipe, a
    full disk), so that Python's flush at exit does not fail again with a traceback-like
    "Exception ignored" message."""
    with suppress(AttributeError, OSError, ValueError):
        fd = sys.stdout.fileno()
        null = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(null, fd)
        finally:
            os.close(null)
