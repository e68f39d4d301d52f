"""The ``fhslam`` command, and its contract with the user.

Bad input — a missing or malformed file, an unknown world — ends with one line on stderr,
``fhslam: error: <file>:<line>: <what>``, and exit status 2; never a traceback. Every command
checks that it can write each of its outputs before it reads or computes anything, and writes
them all or none (:mod:`fhslam.io.files`); an output that is a device or a pipe (``/dev/null``,
a FIFO, ``/dev/fd/N``) is written in place, and ``-`` is standard output for the text outputs
of ``simulate`` and ``slam`` (one of them; the command's messages go to stderr then). Ctrl-C
ends a command with one line, ``fhslam: interrupted; ...`` naming what was not written, and
exit status 130. Any other failure is a bug inside the package: one line, ``fhslam: internal
error: <type>: <message> (please report it; ...)``, and exit status 1; ``fhslam --debug ...``
(or ``--debug`` after the command) shows its traceback instead.

Each command is a module of this package (:data:`COMMANDS`) with its name ``NAME``, its
output options ``OUTPUTS`` (named after Ctrl-C), ``add_parser(sub)`` adding its sub-parser,
and ``run(args)``; what several share is in :mod:`fhslam.cli.common`, how a command ends in
:mod:`fhslam.cli.exits`.
"""

from __future__ import annotations

import argparse
import sys
import warnings

from fhslam.cli import (
    bench,
    benchmark,
    evaluate,
    info,
    reproduce,
    run_notebooks,
    simulate,
    slam,
    student_copy,
    sweep,
)
from fhslam.cli.common import WORLDS_HELP
from fhslam.cli.exits import (
    EXIT_BAD_INPUT,
    EXIT_BROKEN_PIPE,
    EXIT_INTERNAL_ERROR,
    EXIT_INTERRUPTED,
    after_interrupt,
    interrupted,
    reader_gone,
    show_warning,
)

__all__ = ["COMMANDS", "WORLDS_HELP", "build_parser", "main"]

COMMANDS = (
    simulate,
    slam,
    info,
    evaluate,
    reproduce,
    bench,
    benchmark,
    sweep,
    student_copy,
    run_notebooks,
)
"""The commands' modules, in the order of the help."""

DEBUG_HELP = "show the traceback of an internal error (a bug) instead of its one line"


def build_parser() -> argparse.ArgumentParser:
    """The parser of ``fhslam [--debug] COMMAND ...``: each command's sub-parser sets
    ``args.run``, the function that runs it."""
    parser = argparse.ArgumentParser(
        prog="fhslam",
        description="Fast-Hough-transform line SLAM for 2D laser scans (teaching workbook).",
    )
    parser.add_argument("--debug", action="store_true", help=DEBUG_HELP)
    sub = parser.add_subparsers(dest="command", required=True)
    for command in COMMANDS:
        command.add_parser(sub)
    for command in sub.choices.values():  # also after the command; SUPPRESS: keep one before
        command.add_argument(
            "--debug", action="store_true", default=argparse.SUPPRESS, help=DEBUG_HELP
        )
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run ``fhslam`` with the arguments ``argv`` (default: the command line's); the exit
    status."""
    with warnings.catch_warnings():  # a warning on import (numba's cache): one line too
        warnings.showwarning = show_warning
        from fhslam.errors import InputError
        from fhslam.io.files import interrupted_before_output, watch_interrupts

    for stream in (sys.stdout, sys.stderr):  # a path the locale cannot encode: escaped
        if getattr(stream, "errors", None) == "strict" and hasattr(stream, "reconfigure"):
            stream.reconfigure(errors="backslashreplace")
    with warnings.catch_warnings():  # checking a --method imports the pipeline
        warnings.showwarning = show_warning
        args = build_parser().parse_args(argv)
    try:
        with watch_interrupts(), warnings.catch_warnings():
            # implausible but readable input: one line each, the input named
            warnings.showwarning = show_warning
            args.run(args)
            if interrupted_before_output():  # Ctrl-C swallowed somewhere (watch_interrupts)
                raise KeyboardInterrupt
    except InputError as e:  # bad input; anything else is a bug (below)
        message = " ".join(str(e).split())  # one line, whatever the message
        print(f"fhslam: error: {message}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except BaseException as e:  # the outputs' temporary files are already removed
        if isinstance(e, BrokenPipeError) and reader_gone(sys.stdout):  # `... | head -1`
            return EXIT_BROKEN_PIPE
        sys.stdout.flush()
        if after_interrupt(e):  # Ctrl-C
            outputs = {c.NAME: c.OUTPUTS for c in COMMANDS}.get(args.command, ())
            print(f"fhslam: {interrupted(args, outputs)}", file=sys.stderr)
            return EXIT_INTERRUPTED
        if args.debug or not isinstance(e, Exception):  # SystemExit, GeneratorExit: as they are
            raise
        message = " ".join(str(e).split())
        print(
            f"fhslam: internal error: {type(e).__name__}{': ' if message else ''}{message} "
            "(please report it; run again with --debug for the traceback)",
            file=sys.stderr,
        )
        return EXIT_INTERNAL_ERROR
    return 0
