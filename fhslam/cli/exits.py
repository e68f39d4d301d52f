"""How a command ends when it does not simply finish: its exit statuses, warnings as one line
each, the line after Ctrl-C, and a reader of standard output that went away."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

EXIT_BAD_INPUT = 2
"""Exit status after bad input (:class:`fhslam.errors.InputError`)."""
EXIT_INTERNAL_ERROR = 1
"""Exit status after a bug inside the package (an exception other than bad input)."""
EXIT_INTERRUPTED = 130
"""Exit status after Ctrl-C (SIGINT): 128 + 2, as a shell reports it."""
EXIT_BROKEN_PIPE = 141
"""Exit status when the reader of standard output went away (``| head``), without a message:
128 + 13 (SIGPIPE), as a shell reports a command that the signal ended."""


def show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Every warning as one line on stderr. The package's warnings about its input
    (:class:`fhslam.errors.InputWarning`, and other ``UserWarning``\\s it issues, e.g. the
    EKF baseline's landmark limit) name the file themselves; any other (a NumPy overflow, a
    SciPy ill-conditioned matrix) also gets its category and the code that raised it."""
    text = " ".join(str(message).split())
    if not issubclass(category, UserWarning):
        text += f" [{category.__name__} at {Path(filename).name}:{lineno}]"
    print(f"fhslam: warning: {text}", file=sys.stderr)


def interrupted(args: argparse.Namespace, outputs: tuple[str, ...]) -> str:
    """The line printed after Ctrl-C: what was not written (outputs appear all or none) of
    the command's ``outputs``, its output options (``out``: a positional argument); or the
    file that a command working through several files (``args.in_progress``) left as it
    was."""
    path = getattr(args, "in_progress", None)
    if path:
        return f"interrupted; {path} left as it was"
    given = [
        f"{opt} {value}" if opt.startswith("-") else str(value)
        for opt in outputs
        if (value := getattr(args, opt.lstrip("-").replace("-", "_"))) is not None
    ]
    return f"interrupted; nothing written to {', '.join(given)}" if given else "interrupted"


def reader_gone(stream) -> bool:
    """Whether the reader of ``stream``, a pipe, has closed it; then anything still buffered
    for it is dropped (Python would report it at exit). Unknown (a captured stream, no
    ``select.poll``): False."""
    import os
    import select

    try:
        poll = select.poll()
        poll.register(stream.fileno(), select.POLLOUT)
        if not any(events & select.POLLERR for _, events in poll.poll(0)):
            return False
        os.dup2(os.open(os.devnull, os.O_WRONLY), stream.fileno())
    except (AttributeError, OSError, ValueError):  # io.UnsupportedOperation is both
        return False
    return True


def after_interrupt(e: BaseException) -> bool:
    """Whether ``e`` is Ctrl-C's KeyboardInterrupt or was raised because of one: landing in
    C code that called back into Python (numba loading a compiled function from its cache),
    it comes out as a SystemError whose cause is the KeyboardInterrupt."""
    seen: set[int] = set()
    while e is not None and id(e) not in seen:
        if isinstance(e, KeyboardInterrupt):
            return True
        seen.add(id(e))
        e = e.__cause__ or e.__context__
    return False
