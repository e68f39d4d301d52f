"""``fhslam sweep``: every SLAM method on many simulated runs of a world (seeds x
odometry-noise levels), in parallel, summarised per level and method; or, with ``--log``,
SLAM on a real log as read and on degraded copies of it, measured against its benchmark
relations: the robustness bound."""

from __future__ import annotations

import argparse
from pathlib import Path

from fhslam.cli.common import (
    METHOD_NAMES,
    SCHEDULER_HELP,
    add_method_argument,
    degrade_arguments,
    method_params,
    on_cluster,
    plot_format,
    random_seed,
    save_figure,
)

NAME = "sweep"
OUTPUTS = ("--out", "--plot")
"""The output options named after Ctrl-C."""

DESCRIPTION = (
    "Simulate WORLD with each seed and odometry-noise level (low, medium, "
    "high) and run every SLAM method on each log, in parallel; print the median ATE, map "
    "error and time per level and method. With --out, write every run as CSV: notebook "
    "07 shows the committed notebooks/results/sweep_paper.csv. With --log, run SLAM "
    "(default: the graph method) on a real log as read and on copies degraded with seeds "
    "0..N-1 (--range-noise, --drop-scans, --clutter; or --last-bit-draws), each measured "
    "against the log's benchmark relations, and count the runs whose relation error "
    "moved by more than 25 % or 1 cm (whichever is larger) from the run on the log as "
    "read: the robustness bound."
)


def add_parser(sub) -> argparse.ArgumentParser:
    """Add ``sweep``'s sub-parser to ``sub``."""
    p = sub.add_parser(
        NAME,
        help="every SLAM method on seeds x odometry-noise levels of a simulated world, or on "
        "degraded copies of a real log",
        description=DESCRIPTION,
    )
    p.add_argument("--world", help="world to simulate (default paper)")
    p.add_argument(
        "--log",
        help="a real laser log (CARMEN file, ROS bag or dataset name: intel, aces, ...) "
        "instead of a simulated world",
    )
    p.add_argument(
        "--relations",
        help="--log: its benchmark relations file, or a dataset name (default: the dataset's "
        "own when --log is a dataset name)",
    )
    p.add_argument(
        "--seeds",
        type=int,
        default=20,
        help="seeds 0..N-1 per level; with --log, the degradation's seeds (default 20)",
    )
    p.add_argument(
        "--levels",
        nargs="+",
        choices=("low", "medium", "high"),
        help="odometry-noise levels (default all three)",
    )
    add_method_argument(
        p, "--methods", nargs="+", help="SLAM methods (default all; with --log, graph)"
    )
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="set a parameter of fhslam.slam.GraphSlamParams as GROUP.NAME for the graph "
        "method's runs, as `fhslam slam --set` does (repeat for more); --out's CSV records "
        "them in its settings column",
    )
    p.add_argument("--jobs", type=int, default=-1, help="worker processes (default: all cores)")
    p.add_argument("--scheduler", metavar="ADDRESS", help=SCHEDULER_HELP)
    p.add_argument("--out", type=Path, help="write every run to this CSV file")
    p.add_argument(
        "--plot",
        type=Path,
        metavar="RUNS.png",
        help="--log: draw every run's relation error against the run on the log as read and "
        "the robustness bound, 25 %% or 1 cm (fhslam.figures.sweep_errors_figure; PNG, PDF or "
        "SVG by the extension)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    _robustness_arguments(p)
    p.set_defaults(run=run)
    return p


def _robustness_arguments(p: argparse.ArgumentParser) -> None:
    """``sweep``'s group of options that degrade every log before its runs."""
    g = p.add_argument_group(
        "robustness checks",
        "degrade every simulated log (or --log's) before its runs, as `fhslam slam` does "
        "(fhslam.sim.degrade, fhslam.sim.perturb_odometry); the CSV file records it",
    )
    degrade_arguments(g, seed_default=None)
    g.add_argument(
        "--last-bit-draws",
        type=random_seed,
        default=0,
        metavar="K",
        help="also run each log with its odometry multiplied by (1 + 1e-15 e), e drawn with "
        "seeds 1..K: what the same code does on other CPUs (default 0: as simulated only)",
    )


def run(args: argparse.Namespace) -> None:
    """The simulated sweep (:func:`fhslam.experiments.compare.slam_sweep`), or with
    ``--log`` the log's (:func:`_log_sweep`), printed and, with ``--out``, written."""
    from fhslam.errors import InputError
    from fhslam.experiments import compare
    from fhslam.io.files import check_outputs
    from fhslam.sim import load_world
    from fhslam.sim.simulate import check_scan_limit
    from fhslam.sim.world import BUILTIN_WORLDS

    if not 1 <= args.seeds <= 1000:
        raise InputError(f"--seeds must be between 1 and 1000, got {args.seeds}")
    if args.last_bit_draws > 100:
        raise InputError(f"--last-bit-draws must be at most 100, got {args.last_bit_draws}")
    if args.jobs == 0:
        raise InputError("--jobs must not be 0 (-1: all cores)")
    methods = args.methods or (["graph"] if args.log is not None else list(METHOD_NAMES))
    if args.set and "graph" not in methods:
        raise InputError("--set: only with the graph method among --methods")
    params = method_params("graph", args.set) if args.set else None
    if args.log is not None:
        _log_sweep(args, methods, params)
        return
    if args.relations is not None:
        raise InputError("--relations: only with --log")
    if args.plot is not None:
        raise InputError("--plot: only with --log")
    world_name = "paper" if args.world is None else args.world
    world = load_world(world_name)  # a bad world is an error before any worker starts
    builtin = world_name in BUILTIN_WORLDS or world_name.startswith("random:")
    check_scan_limit(world, source=None if builtin else world_name)
    # and an output that cannot be written (a directory, no such folder, a read-only one),
    # before the hours of work
    check_outputs({"--out": args.out}, {"the world file": None if builtin else world_name})
    with on_cluster(args.scheduler):
        rows = _world_sweep(args, world_name, methods, params)
    if args.out is not None:
        compare.save_sweep(rows, args.out)
    if args.set:  # not in the file: its columns are fixed (notebook 07 reads it)
        print("the graph method with " + " ".join(f"--set {x}" for x in args.set))
    print(compare.format_summary(rows))


def _world_sweep(args: argparse.Namespace, world_name: str, methods: list[str], params):
    """:func:`fhslam.experiments.compare.slam_sweep` with the options of ``args``."""
    from fhslam.experiments import compare

    return compare.slam_sweep(
        world=world_name,
        seeds=range(args.seeds),
        levels=args.levels or ["low", "medium", "high"],
        methods=methods,
        n_jobs=args.jobs,
        progress=not args.quiet,
        range_noise=args.range_noise,
        drop_fraction=args.drop_scans,
        clutter_fraction=args.clutter,
        degrade_seed=0 if args.degrade_seed is None else args.degrade_seed,
        last_bit_draws=args.last_bit_draws,
        params=params,
    )


def _log_sweep(args: argparse.Namespace, methods: list[str], params) -> None:
    """``fhslam sweep --log``: :func:`fhslam.experiments.robustness.log_sweep`, printed."""
    from fhslam.errors import InputError
    from fhslam.experiments import robustness
    from fhslam.io.files import check_outputs

    given = [
        opt
        for opt, value in (
            ("--world", args.world),
            ("--levels", args.levels),
            ("--degrade-seed", args.degrade_seed),
        )
        if value is not None
    ]
    if given:
        raise InputError(
            f"{', '.join(given)}: not with --log (its own odometry; --seeds N draws the "
            "degradation with seeds 0..N-1)"
        )
    check_outputs(
        {"--out": args.out, "--plot": args.plot}, {"--log": args.log, "--relations": args.relations}
    )
    plot_format(args.plot)
    with on_cluster(args.scheduler):
        rows = robustness.log_sweep(
            args.log,
            args.relations,
            seeds=range(args.seeds),
            range_noise=args.range_noise,
            drop_fraction=args.drop_scans,
            clutter_fraction=args.clutter,
            last_bit_draws=args.last_bit_draws,
            methods=methods,
            params=params,
            n_jobs=args.jobs,
            progress=not args.quiet,
        )
    if args.out is not None:
        robustness.save_log_sweep(rows, args.out)
    print(robustness.format_log_sweep(rows))
    if args.plot is not None:
        _plot_runs(args.plot, rows)
        print(f"wrote a picture of the runs to {args.plot}")


def _plot_runs(path: Path, rows) -> None:
    """Draw the log sweep's runs (:func:`fhslam.figures.sweep_errors_figure`) into the
    picture ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    from fhslam.experiments import robustness
    from fhslam.figures import sweep_errors_figure

    degraded = next((r for r in rows if not r.reference), rows[0])
    title = f"{rows[0].log}: {robustness.degradation_text(degraded)}"
    bounds = robustness.RELATIVE_BOUND, robustness.ABSOLUTE_BOUND
    save_figure(sweep_errors_figure(rows, *bounds, title), path)
