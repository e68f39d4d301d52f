"""numba for the package's compiled kernels, with an on-disk cache wherever it is installed.

Every module with kernels imports ``njit`` (and whatever else of numba it needs) from here,
never from numba itself: importing this module settles where numba caches the compiled
kernels before numba is first imported, as numba reads ``NUMBA_CACHE_DIR`` once, when it is.

numba caches a kernel beside its source, in the package's ``__pycache__`` folders, or in the
user's cache folder (``~/.cache/numba``); where neither can be written (a package installed
by root, run by a user whose home is not writable) ``@njit(cache=True)`` fails with "cannot
cache function ...: no locator available" and no kernel can even be defined. So, where
the folders that numba would take cannot be written (``NUMBA_CACHE_DIR`` if set, else the
package's ``__pycache__`` folders), this module sets ``NUMBA_CACHE_DIR`` to the first of
these that can be: ``$XDG_CACHE_HOME/fhslam/numba``, ``~/.cache/fhslam/numba``, and a
folder of the user's own in the temporary folder, ``fhslam-numba-<uid>`` (created private,
and taken only while it is: compiled code is loaded from it). Where none can, the kernels
are compiled without a cache, anew in every process (some seconds for each command), with
one :class:`CacheWarning` that says so.
"""

from __future__ import annotations

import os
import stat
import sys
import tempfile
import warnings
from pathlib import Path

__all__ = ["CACHE_DIR", "CACHING", "CacheWarning", "intrinsic", "njit", "types"]

KERNEL_FOLDERS = tuple(Path(__file__).parent / d for d in ("", "extraction", "scanmatch"))
"""The package's folders with compiled kernels: numba caches them in their ``__pycache__``."""


class CacheWarning(UserWarning):
    """No writable folder for numba's cache: the kernels are compiled in every process."""


def _writable(folder: Path) -> bool:
    """Whether ``folder`` exists or can be made, and a file can be written in it (numba's
    own test of a cache folder)."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=folder).close()
    except OSError:
        return False
    return True


def _private(folder: Path) -> bool:
    """Whether ``folder`` in a shared temporary folder is this user's alone (made so if it
    does not exist): a real folder, not a link, owned by the user and writable by no one
    else. Any other user could place compiled code there for this one to load."""
    try:
        folder.mkdir(mode=0o700, exist_ok=True)
        st = folder.lstat()
    except OSError:
        return False
    return (
        stat.S_ISDIR(st.st_mode)
        and st.st_uid == os.getuid()
        and not st.st_mode & (stat.S_IWGRP | stat.S_IWOTH)
        and _writable(folder)
    )


def _fallbacks(environ) -> list[tuple[Path, bool]]:
    """The cache folders tried, in order, each with whether it must be private."""
    out = []
    xdg = environ.get("XDG_CACHE_HOME", "")
    if xdg and Path(xdg).is_absolute():
        out.append((Path(xdg) / "fhslam" / "numba", False))
    home = environ.get("HOME", "")
    if not home:
        try:
            home = str(Path.home())
        except (RuntimeError, KeyError):  # no HOME and no entry in the password database
            home = ""
    if home and Path(home).is_absolute():
        out.append((Path(home) / ".cache" / "fhslam" / "numba", False))
    if hasattr(os, "getuid"):  # POSIX: a per-user folder in the shared temporary folder
        out.append((Path(tempfile.gettempdir()) / f"fhslam-numba-{os.getuid()}", True))
    return out


def cache_folder(
    environ=os.environ, kernel_folders: tuple[Path, ...] = KERNEL_FOLDERS
) -> tuple[Path | None, bool]:
    """Where numba should cache the kernels: ``(folder, caching)``. ``(None, True)``: where
    numba would by itself (``NUMBA_CACHE_DIR``, else the package's ``__pycache__``), as it
    can be written; ``(folder, True)``: set ``NUMBA_CACHE_DIR`` to ``folder``;
    ``(None, False)``: nowhere, compile without a cache."""
    given = environ.get("NUMBA_CACHE_DIR", "")
    if given and _writable(Path(given)):
        return None, True
    if all(_writable(d / "__pycache__") for d in kernel_folders):
        return None, True  # numba's next choice after an unwritable NUMBA_CACHE_DIR
    for folder, private in _fallbacks(environ):
        if _private(folder) if private else _writable(folder):
            return folder, True
    return None, False


def _configure() -> tuple[str | None, bool]:
    if "numba" in sys.modules:  # imported before the package: numba has read its settings
        from numba.core import config

        environ = {**os.environ, "NUMBA_CACHE_DIR": config.CACHE_DIR or ""}
    else:
        config, environ = None, os.environ
    folder, caching = cache_folder(environ)
    if folder is not None:
        os.environ["NUMBA_CACHE_DIR"] = str(folder)  # also for worker processes
        if config is not None:
            config.CACHE_DIR = str(folder)
    elif not caching:
        tried = [environ.get("NUMBA_CACHE_DIR") or "the package's __pycache__ folders"]
        tried += [str(f) for f, _ in _fallbacks(environ)]
        warnings.warn(
            "no writable folder for numba's cache of the compiled kernels (tried "
            + ", ".join(tried)
            + "): they are compiled anew in every run; set NUMBA_CACHE_DIR to a writable "
            "folder",
            CacheWarning,
            stacklevel=3,
        )
    return os.environ.get("NUMBA_CACHE_DIR"), caching


CACHE_DIR, CACHING = _configure()
"""Where numba caches the kernels (``None``: beside their sources), and whether it does."""

import numba  # noqa: E402  (after NUMBA_CACHE_DIR is settled)
from numba import types  # noqa: E402
from numba.core.extending import intrinsic  # noqa: E402


def njit(*args, **options):
    """:func:`numba.njit`, with ``cache=True`` dropped where no cache folder can be written
    (:data:`CACHING`)."""
    if not CACHING:
        options["cache"] = False
    return numba.njit(*args, **options)
