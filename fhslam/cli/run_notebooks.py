"""``fhslam run-notebooks``: run the notebooks, each in a fresh kernel, and write them back
with their new outputs and their paired ``.py`` sources; or, with ``--pair-only``, write only
the sources."""

from __future__ import annotations

import argparse
from pathlib import Path

from fhslam.cli.common import positive

NAME = "run-notebooks"
OUTPUTS: tuple[str, ...] = ()
"""The output options named after Ctrl-C: none (the notebook being run is named instead)."""

DESCRIPTION = (
    "Execute each notebook (all of NOTEBOOKS, or those whose names start with "
    "the numbers given) in a fresh kernel, in its own folder, and write it back with its "
    "new outputs and its paired plain-text source (NN_topic.py, jupytext percent format), "
    "only where an output changed (measured times and widget ids do not count). "
    "Prints each notebook's Run All time and its slowest cell. A cell that raises stops "
    "the run with a one-line error naming the notebook and the cell; that notebook is "
    "left as it was. With --pair-only, nothing is run: only the .py sources are written."
)


def add_parser(sub) -> argparse.ArgumentParser:
    """Add ``run-notebooks``' sub-parser to ``sub``."""
    p = sub.add_parser(
        NAME,
        help="run the notebooks and write them back with fresh outputs and paired .py sources",
        description=DESCRIPTION,
    )
    p.add_argument("only", nargs="*", metavar="NN", help="notebook numbers, e.g. 03 08")
    p.add_argument(
        "--notebooks",
        type=Path,
        default=Path("notebooks"),
        help="folder of the notebooks (default notebooks)",
    )
    p.add_argument(
        "--timeout", type=positive("seconds"), default=600.0, help="seconds per cell (default 600)"
    )
    p.add_argument("--pair-only", action="store_true", help="write the .py sources, run nothing")
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> None:
    """Run (or only pair) the chosen notebooks, one line each; ``args.in_progress`` is the
    notebook being worked on, named if interrupted."""
    from fhslam.errors import InputError
    from fhslam.io.files import check_folder_writable
    from fhslam.workbook import notebooks_in, pair, paired_path, run_notebook

    found = notebooks_in(args.notebooks)
    chosen = [p for p in found if not args.only or any(p.name.startswith(n) for n in args.only)]
    missing = [n for n in args.only if not any(p.name.startswith(n) for p in found)]
    if missing:
        raise InputError(f"{args.notebooks}: no notebook starts with {', '.join(missing)}")
    # the notebooks and their .py are written back there: checked before minutes of running
    check_folder_writable(args.notebooks, f"--notebooks {args.notebooks}")
    for path in chosen:
        args.in_progress = path  # named by main() if interrupted: left as it was
        if args.pair_only:
            py = paired_path(path)
            before = py.read_text(encoding="utf-8") if py.is_file() else None
            pair(path)  # writes the .py only where it differs
            print(
                f"{py}: {'up to date' if py.read_text(encoding='utf-8') == before else 'written'}"
            )
        else:
            print(run_notebook(path, timeout=args.timeout), flush=True)
    args.in_progress = None
