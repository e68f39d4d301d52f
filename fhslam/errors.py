"""The package's errors for bad input: what a user hands it, as opposed to a bug.

Every reader, name lookup and writer of :mod:`fhslam` reports bad input by raising an
:class:`InputError` (a :class:`ValueError`) whose message names the file and, where it
applies, the line: ``"{path}:{line}: {what is wrong}"``. The ``fhslam`` command prints such an
error as one line and exits with status 2; it catches nothing else, so an exception of any
other type is a bug inside the package and shows its traceback.
"""

from __future__ import annotations

__all__ = ["InputError", "InputWarning", "MissingInputError"]


class InputError(ValueError):
    """Bad input: a malformed or unreadable file, an unknown name, an output that cannot be
    written. The message names what and where."""


class MissingInputError(FileNotFoundError, InputError):
    """An input file (or dataset) that does not exist. Also a :class:`FileNotFoundError`,
    with ``filename`` set where one is known."""

    def __init__(self, message: str, filename: str | None = None) -> None:
        super().__init__(message)
        self.filename = filename

    def __str__(self) -> str:  # the message, not OSError's "[Errno ...] ..." layout
        return str(self.args[0])


class InputWarning(UserWarning):
    """Readable but implausible input, read as documented (time running backwards, an
    odometry jump, readings no laser gives, a scan without a return). The message names the
    file and, where it applies, the line; the ``fhslam`` command prints it as one line
    ``fhslam: warning: ...`` and goes on."""
