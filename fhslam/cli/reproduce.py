"""``fhslam reproduce``: write the paper's figures as PNG files into a folder."""

from __future__ import annotations

import argparse
from pathlib import Path

NAME = "reproduce"
OUTPUTS = ("--out",)
"""The output options named after Ctrl-C."""


def add_parser(sub) -> argparse.ArgumentParser:
    """Add ``reproduce``'s sub-parser to ``sub``."""
    p = sub.add_parser(NAME, help="write the paper's figures as PNG files")
    p.add_argument("--out", default="figures", type=Path, help="output folder (default figures)")
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> None:
    """Draw the figures (:func:`fhslam.figures.reproduce`) and print each file's path."""
    import matplotlib

    matplotlib.use("Agg")
    from fhslam.figures import reproduce

    for path in reproduce(args.out, what=f"--out {args.out}"):
        print(path)
