"""``fhslam benchmark``: every measurement notebook 09 shows and the README's results table,
remade by one command (:func:`fhslam.experiments.benchmark.run_benchmark`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from fhslam.cli.common import SCHEDULER_HELP, on_cluster

NAME = "benchmark"
OUTPUTS = ("--out",)
"""The output options named after Ctrl-C."""


def add_parser(sub) -> argparse.ArgumentParser:
    """Add ``benchmark``'s sub-parser to ``sub``."""
    p = sub.add_parser(
        NAME,
        help="run every benchmark log (graph, fht, odometry) and the runs over draws; write "
        "the results notebook 09 loads",
    )
    p.add_argument(
        "--out",
        default=Path("notebooks/results"),
        type=Path,
        help="results folder (default notebooks/results)",
    )
    p.add_argument(
        "--logs",
        nargs="+",
        metavar="NAME",
        help="dataset names (default: every benchmark log); the other logs' rows are kept",
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help="a small subset (MIT CSAIL; one seed of the paper world, clean and degraded, one "
        "last-bit draw each): minutes instead of 15-30 on 2 cores",
    )
    p.add_argument("--no-draws", action="store_true", help="no runs over draws")
    p.add_argument("--jobs", type=int, default=-1, help="worker processes for the draws")
    p.add_argument("--scheduler", metavar="ADDRESS", help=SCHEDULER_HELP + " (the draws)")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> None:
    """Run the benchmark and print the results table."""
    from fhslam.experiments.benchmark import results_table, run_benchmark

    kwargs = {"draws": None} if args.no_draws else {}
    with on_cluster(args.scheduler):
        rows = run_benchmark(
            args.out,
            logs=args.logs,
            quick=args.quick,
            n_jobs=args.jobs,
            progress=not args.quiet,
            **kwargs,
        )
    print(results_table(rows))
    print(f"wrote {args.out}")
