"""``fhslam student-copy``: copy the notebooks without their exercise solutions and without
outputs, for a class."""

from __future__ import annotations

import argparse
from pathlib import Path

NAME = "student-copy"
OUTPUTS = ("out",)
"""The output options named after Ctrl-C (``out``: the positional argument)."""


def add_parser(sub) -> argparse.ArgumentParser:
    """Add ``student-copy``'s sub-parser to ``sub``."""
    p = sub.add_parser(
        NAME,
        help="write the notebooks without their solutions, for a class",
        description="Copy every notebook of NOTEBOOKS to OUT without the exercise solutions "
        "(cells tagged 'solution') and without outputs, so that students run them themselves.",
    )
    p.add_argument("out", type=Path, help="output folder (created; must not be NOTEBOOKS)")
    p.add_argument(
        "--notebooks",
        type=Path,
        default=Path("notebooks"),
        help="folder of the notebooks (default notebooks)",
    )
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> None:
    """Write the copies (:func:`fhslam.workbook.student_copy`), one line each."""
    from fhslam.workbook import student_copy

    for path, removed in student_copy(args.notebooks, args.out):
        print(f"{path}: {removed} solution{'s' if removed != 1 else ''} removed")
