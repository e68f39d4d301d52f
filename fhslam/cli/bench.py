"""``fhslam bench``: time and score every line extractor on the same simulated scans, and
the SLAM methods' steps per second; with ``--log``, where one SLAM method's time goes on a
real log, stage by stage."""

from __future__ import annotations

import argparse

from fhslam.cli.common import PROFILE_HELP, add_method_argument, positive_metres, profiling

NAME = "bench"
OUTPUTS: tuple[str, ...] = ()
"""The output options named after Ctrl-C: none."""

MAX_BENCH_SCANS = 1000
"""Largest ``bench --scans`` without ``--log``: scans per held-out world (each has 300-400)."""

MAX_REPEATS = 1000
"""Largest ``bench --repeats``."""

DESCRIPTION = (
    "Without --log: every line extractor timed and scored on the same scans of "
    "held-out simulated worlds, then the SLAM methods' steps per second on the paper "
    "world. With --log: one SLAM method run over that log; prints scans, wall time, "
    "scans per second and times real time, and per stage (extraction, tracking, "
    "local map, loop closure, optimisation, map, other; nested stages subtracted) the "
    "ms per scan, the share of the total and the ratio to a reference measured in the "
    "same run: the bare cv2.HoughLinesPointSet call on the log's scans, timed before "
    "and after the run, so that ratios compare across machines."
)


def add_parser(sub) -> argparse.ArgumentParser:
    """Add ``bench``'s sub-parser to ``sub``."""
    p = sub.add_parser(
        NAME,
        help="time and score every line extractor on the same scans; with --log, where a "
        "SLAM method's time goes on a real log",
        description=DESCRIPTION,
    )
    p.add_argument(
        "--log",
        help="run the real-log bench on this CARMEN log, ROS bag or dataset name (intel, ...)",
    )
    add_method_argument(
        p,
        "--method",
        help="with --log: the SLAM method (default graph; stages are measured for graph, fht "
        "and classical, the total only for ekf and odometry)",
    )
    p.add_argument(
        "--scans",
        type=int,
        metavar="N",
        help="scans per held-out world (default 25); with --log: only the log's first N scans "
        "(default all)",
    )
    p.add_argument(
        "--repeats",
        type=int,
        metavar="R",
        help="timed calls per scan (default 9) and runs of the paper world per SLAM method (at "
        "most 3); with --log: runs, medians reported (default 1)",
    )
    p.add_argument(
        "--max-range",
        type=positive_metres,
        metavar="M",
        help="with --log: the laser's maximum range, m (as for slam)",
    )
    p.add_argument(
        "--download",
        action="store_true",
        help="with --log: fetch a named dataset into the user cache if no local copy is found",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--profile", action="store_true", help=PROFILE_HELP)
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> None:
    """The extractor and SLAM benches, or with ``--log`` the real-log bench, printed."""
    import fhslam.pipeline  # noqa: F401  (imported before --profile starts: not what it shows)
    from fhslam.datasets import load_log
    from fhslam.experiments import bench

    _check_options(args)
    with profiling(args.profile):
        if args.log is None:
            rows = bench.run_bench(
                scans_per_world=25 if args.scans is None else args.scans,
                repeats=9 if args.repeats is None else args.repeats,
                progress=not args.quiet,
            )
            print(bench.format_table(rows))
            print()
            slam_repeats = 3 if args.repeats is None else min(args.repeats, 3)
            print(bench.format_slam_table(bench.run_slam_bench(repeats=slam_repeats)))
            return
        log = load_log(args.log, download=args.download, max_range=args.max_range)
        if args.scans is not None:
            log = bench.log_head(log, args.scans)
        result = bench.run_log_bench(
            log,
            args.method or "graph",
            repeats=1 if args.repeats is None else args.repeats,
            progress=not args.quiet,
        )
        print(bench.format_log_bench(result))


def _check_options(args: argparse.Namespace) -> None:
    """Refuse ``--scans`` and ``--repeats`` out of range, and the ``--log`` options
    without ``--log``."""
    from fhslam.errors import InputError

    for opt, value in (("--scans", args.scans), ("--repeats", args.repeats)):
        if value is not None and value < 1:
            raise InputError(f"{opt} must be a positive number, got {value}")
    if args.repeats is not None and args.repeats > MAX_REPEATS:
        raise InputError(f"--repeats must be between 1 and {MAX_REPEATS}, got {args.repeats}")
    if args.log is None and args.scans is not None and args.scans > MAX_BENCH_SCANS:
        raise InputError(
            f"--scans must be between 1 and {MAX_BENCH_SCANS} scans per held-out world, got "
            f"{args.scans}"
        )
    if args.log is None:
        given = [
            opt
            for opt, value in (
                ("--method", args.method),
                ("--max-range", args.max_range),
                ("--download", args.download or None),
            )
            if value is not None
        ]
        if given:
            raise InputError(f"{', '.join(given)}: only with --log")
