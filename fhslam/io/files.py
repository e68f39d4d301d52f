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
  input is ever overwritten.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO

from fhslam.errors import InputError, MissingInputError

__all__ = ["atomic_output", "check_outputs", "input_path", "reading"]


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


def check_outputs(
    outputs: dict[str, str | os.PathLike[str] | None],
    inputs: dict[str, str | os.PathLike[str] | None],
) -> None:
    """Refuse outputs that would overwrite an input or each other.

    ``outputs`` and ``inputs`` map how the user gave each path (an option such as
    ``"--log"``, or a description such as ``"the world file"``) to the path; ``None``
    entries (an option not given, an input that is not a file, e.g. a built-in world's
    name) are skipped.

    Raises
    ------
    InputError
        Naming the output and what it would overwrite; call this before anything is written.
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


@contextmanager
def atomic_output(path: str | os.PathLike[str], mode: str = "w") -> Iterator[IO]:
    """Open ``path`` for writing so that it appears only complete (see the module docs).

    Yields a file object (text, UTF-8, for ``mode="w"``; bytes for ``"wb"``) on a temporary
    file in the same folder, renamed to ``path`` when the ``with`` block ends normally;
    removed if it raises (including :class:`KeyboardInterrupt`).

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
        os.replace(tmp, p)
    except OSError as e:
        tmp.unlink(missing_ok=True)
        raise InputError(f"{p}: cannot write ({e.strerror or e})") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
