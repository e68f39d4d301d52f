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
        help="only these dataset names (default: every benchmark log): their runs and draws; "
        "the other logs' rows and the worlds' are kept",
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help="a small subset (MIT CSAIL; one log of the paper world in two frames, with range "
        "noise, dropped scans and a last-bit draw): minutes instead of an hour or more on 2 cores",
    )
    p.add_argument("--no-draws", action="store_true", help="no runs over draws")
    p.add_argument(
        "--draw-seed",
        type=int,
        metavar="SEED",
        help="the seed the draws' seeds come from (default: a fresh one, printed first; give "
        "it to repeat a benchmark's draws)",
    )
    p.add_argument("--jobs", type=int, default=-1, help="worker processes for the draws")
    p.add_argument("--scheduler", metavar="ADDRESS", help=SCHEDULER_HELP + " (the draws)")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> None:
    """Run the benchmark and print the results table."""
    from dataclasses import replace

    from fhslam.experiments.benchmark import DRAWS, QUICK_DRAWS, results_table, run_benchmark

    draws = None
    if not args.no_draws:
        draws = (QUICK_DRAWS if args.quick else DRAWS).seeded()
        if args.draw_seed is not None:
            draws = replace(draws, seed=args.draw_seed)
        if args.logs:
            draws = replace(
                draws,
                logs=tuple(n for n in args.logs if n in draws.logs),
                sparse_logs=tuple(n for n in args.logs if n in draws.sparse_logs),
                worlds=(),
            )
        print(f"draws: seed {draws.seed} (to repeat them: --draw-seed {draws.seed})", flush=True)
    with on_cluster(args.scheduler):
        rows = run_benchmark(
            args.out,
            logs=args.logs,
            draws=draws,
            quick=args.quick,
            n_jobs=args.jobs,
            progress=not args.quiet,
        )
    print(results_table(rows))
    print(f"wrote {args.out}")
