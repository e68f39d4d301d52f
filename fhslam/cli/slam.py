"""``fhslam slam``: run a SLAM method over a laser log and write the trajectory and, if
asked, the line map, the keyframe graph and a picture of the run; the log can be degraded
first (range noise, dropped scans, clutter, odometry perturbed in its last bit)."""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

from fhslam.cli.common import (
    add_method_argument,
    degrade_arguments,
    log_arguments,
    method_params,
    plot_format,
    random_seed,
    read_log,
    save_figure,
)

NAME = "slam"
OUTPUTS = ("--trajectory", "--map", "--graph")
"""The output options named after Ctrl-C."""


def add_parser(sub) -> argparse.ArgumentParser:
    """Add ``slam``'s sub-parser to ``sub``."""
    p = sub.add_parser(NAME, help="run SLAM on a log: trajectory and line map")
    log_arguments(p)
    add_method_argument(
        p,
        "--method",
        default="graph",
        help="graph (default): pose-graph SLAM with scan-to-map tracking, verified loop "
        "closures and a map of fast Hough lines, the same defaults for every log; fht: "
        "fast-Hough SLAM, the paper's step-by-step procedure; baselines: classical (fht "
        "with OpenCV's classical Hough as Loop 1), ekf (EKF line SLAM, filterpy), odometry "
        "(dead reckoning)",
    )
    p.add_argument("--trajectory", required=True, type=Path, help="output: timestamp x y theta")
    p.add_argument("--map", type=Path, help="output map JSON (reference lines)")
    p.add_argument(
        "--graph",
        type=Path,
        help="output keyframe-graph JSON (--method graph only): each keyframe's timestamp and "
        "world-frame pose, each accepted loop closure's keyframes, score and whether it is "
        "still active",
    )
    p.add_argument(
        "--plot",
        type=Path,
        help="output picture (PNG, PDF or SVG by its extension): the map, the trajectory and "
        "the odometry (the truth where the log has it; a graph run's loop closures)",
    )
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="set a parameter of the method (graph: fhslam.slam.GraphSlamParams, groups keyframes, "
        "tracker, edges, loops, search, optimiser; fht and classical: fhslam.slam.SlamParams; "
        "ekf: fhslam.slam.EKFParams) as NAME or GROUP.NAME (repeat for more), e.g. --set "
        "loops.min_score=0.6, or --method fht --set extraction.cluster_gap=0.3; the trajectory's "
        "header records it",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    g = p.add_argument_group(
        "robustness checks",
        "degrade the log before the run (fhslam.sim.degrade, fhslam.sim.perturb_odometry); "
        "the trajectory's header names what was done",
    )
    degrade_arguments(g)
    g.add_argument(
        "--last-bit",
        type=random_seed,
        metavar="SEED",
        help="multiply the odometry by (1 + 1e-15 e), e standard normal drawn with SEED: what "
        "the same code on another CPU does",
    )
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> None:
    """Run ``args.method`` over the log and write its outputs, all or none."""
    from fhslam.errors import InputWarning
    from fhslam.io.files import check_outputs, writes_to_stdout
    from fhslam.pipeline import keyframe_graph, make_backend, run_backend, run_slam

    params = _checked_params(args)
    check_outputs(
        {
            "--trajectory": args.trajectory,
            "--map": args.map,
            "--graph": args.graph,
            "--plot": args.plot,
        },
        {"the input log": args.log},
        to_stdout=("--trajectory", "--map", "--graph"),
    )
    plot_format(args.plot)
    # an output on standard output gets it alone: the messages go to stderr then
    report = sys.stderr if writes_to_stdout(args.trajectory, args.map, args.graph) else sys.stdout
    log = read_log(args)
    log, degraded = _degraded(log, args)
    if degraded:
        print(f"{args.log}: {degraded}", file=report)
    if len(log) == 1:
        warnings.warn(
            f"{args.log}: a single scan: nothing to match it with; the trajectory is its "
            "odometry pose",
            InputWarning,
            stacklevel=1,
        )
    progress = not args.quiet and len(log) > 200
    graph = None
    if args.method != "graph" or (args.graph is None and args.plot is None):
        result = run_slam(log, args.method, params, progress=progress)
    else:
        backend = make_backend(args.method, params)
        result = run_backend(backend, log, progress, desc=f"{args.method} {log.name}")
        graph = keyframe_graph(backend, log)
    wrote = _write_outputs(args, log, result, graph, degraded)
    print(
        "wrote " + ", ".join(wrote[:-1]) + (" and " if len(wrote) > 1 else "") + wrote[-1],
        file=report,
    )


def _checked_params(args: argparse.Namespace):
    """The method's parameters of ``--set`` (``None`` without any); refuses ``--graph``
    with another method than the graph."""
    from fhslam.errors import InputError

    if args.graph is not None and args.method != "graph":
        raise InputError(
            f"--graph: only with --method graph; the {args.method} method keeps no keyframe "
            "graph (nothing was written)"
        )
    return method_params(args.method, args.set) if args.set else None


def _write_outputs(args: argparse.Namespace, log, result, graph, degraded: str) -> list[str]:
    """Write the run's outputs, all or none, and say what each got."""
    from fhslam.io import write_graph, write_map, write_trajectory
    from fhslam.io.files import output_batch, output_name

    # Everything is computed before anything is written, and the files are renamed into
    # place together: bad input or a failed write leaves none of them.
    with output_batch():
        write_trajectory(
            args.trajectory,
            result.timestamps,
            result.poses,
            header=f"fhslam slam --method {args.method} "
            + "".join(f"--set {x} " for x in args.set)
            + f"{args.log}"
            + (f" ({degraded})" if degraded else "")
            + ": timestamp x y theta",
        )
        wrote = [f"{len(result.poses)} poses to {output_name(args.trajectory)}"]
        if args.map is not None:
            write_map(args.map, result.map)
            wrote.append(f"{len(result.map)} map lines to {output_name(args.map)}")
        if args.graph is not None:
            write_graph(args.graph, graph)
            wrote.append(
                f"{len(graph)} keyframes and {len(graph.active)} loop closures "
                f"({graph.n_active} active) to {output_name(args.graph)}"
            )
        if args.plot is not None:
            _write_plot(args.plot, log, result, args.method, graph)
            wrote.append(f"a picture of the run to {args.plot}")
    return wrote


def _degraded(log, args: argparse.Namespace):
    """The log as ``slam``'s robustness options make it, and what they did (``""``: none)."""
    from fhslam.sim import degrade, perturb_odometry

    done = []
    if args.range_noise or args.drop_scans or args.clutter:
        n = len(log)
        log = degrade(
            log,
            drop_fraction=args.drop_scans,
            clutter_fraction=args.clutter,
            seed=args.degrade_seed,
            range_noise=args.range_noise,
        )
        if args.range_noise:
            done.append(f"{1000 * args.range_noise:g} mm of range noise")
        if args.drop_scans:
            done.append(f"{n - len(log)} of {n} scans dropped")
        if args.clutter:
            done.append(f"{100 * args.clutter:g} % clutter")
        done[-1] += f" (seed {args.degrade_seed})"
    if args.last_bit is not None:
        log = perturb_odometry(log, args.last_bit)
        done.append(f"odometry x (1 + 1e-15 e), seed {args.last_bit}")
    return log, ", ".join(done)


def _write_plot(path: Path, log, result, method: str, graph) -> None:
    """Draw the run (:func:`fhslam.figures.slam_run_figure`) into the picture ``path`` (PNG,
    PDF or SVG, by its extension)."""
    import matplotlib

    matplotlib.use("Agg")

    from fhslam.figures import slam_run_figure

    save_figure(slam_run_figure(log, result, method, graph), path)
