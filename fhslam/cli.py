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
"""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

EXIT_BAD_INPUT = 2
EXIT_INTERNAL_ERROR = 1
"""Exit status after a bug inside the package (an exception other than bad input)."""
EXIT_INTERRUPTED = 130
"""Exit status after Ctrl-C (SIGINT): 128 + 2, as a shell reports it."""
EXIT_BROKEN_PIPE = 141
"""Exit status when the reader of standard output went away (``| head``), without a message:
128 + 13 (SIGPIPE), as a shell reports a command that the signal ended."""

SLAM_METHODS = ("fht", "graph", "classical", "ekf", "odometry")
"""The ``--method`` choices of ``slam`` and ``bench`` (:data:`fhslam.pipeline.METHODS`)."""

MAX_LAPS = 100
"""Largest ``simulate --laps``: a hundred laps of the paper world are 92,000 scans."""

MAX_BENCH_SCANS = 1000
"""Largest ``bench --scans`` without ``--log``: scans per held-out world (each has 300-400)."""

MAX_REPEATS = 1000
"""Largest ``bench --repeats``."""

SIMULATE_PROGRESS_SCANS = 5000
"""``simulate`` shows progress bars for routes of more scans than this (about a second)."""

PROFILE_TOP = 25
"""Functions listed by ``--profile``."""

DEBUG_HELP = "show the traceback of an internal error (a bug) instead of its one line"

PROFILE_HELP = (
    f"run under cProfile and print the top {PROFILE_TOP} functions by cumulative time "
    "(pstats) to stderr after the normal output"
)


def _simulate(args: argparse.Namespace) -> None:
    from fhslam.errors import InputError
    from fhslam.io import write_carmen, write_relations, write_trajectory
    from fhslam.io.files import check_outputs, output_batch, output_name, writes_to_stdout
    from fhslam.metrics import sample_relations
    from fhslam.sim import OdometryNoise, load_world, simulate
    from fhslam.sim.simulate import check_scan_limit, is_closed_route
    from fhslam.sim.world import BUILTIN_WORLDS

    if args.seed < 0:
        raise InputError(f"--seed must be a non-negative integer, got {args.seed}")
    if not 1 <= args.laps <= MAX_LAPS:
        raise InputError(f"--laps must be between 1 and {MAX_LAPS}, got {args.laps}")
    builtin = args.world in BUILTIN_WORLDS or args.world.startswith("random:")
    check_outputs(
        {"--log": args.log, "--truth": args.truth, "--relations": args.relations},
        {"the input world file": None if builtin else args.world},
        to_stdout=("--log", "--truth", "--relations"),
    )
    world = load_world(args.world)
    if args.laps > 1 and not is_closed_route(world.route):
        raise InputError(
            f"--laps {args.laps}: world {world.name!r} has an open route (from "
            f"{world.route[0].tolist()} to {world.route[-1].tolist()}); only a closed route "
            "can be driven more than once"
        )
    n = check_scan_limit(world, args.laps, source=None if builtin else str(args.world))
    noise = OdometryNoise.drifting() if args.odometry == "drifting" else OdometryNoise()
    progress = not args.quiet and n > SIMULATE_PROGRESS_SCANS
    log = simulate(world, seed=args.seed, odometry=noise, laps=args.laps, progress=progress)
    with output_batch():  # both files or neither
        write_carmen(log, args.log)
        write_trajectory(
            args.truth,
            log.timestamps,
            log.truth,
            header=f"ground truth of {world.name!r}, seed {args.seed}: timestamp x y theta",
        )
        if args.relations is not None:
            rel = sample_relations(log.timestamps, log.truth)
            write_relations(
                args.relations,
                *rel,
                header=f"relations sampled from the truth of {world.name!r}, seed "
                f"{args.seed} (fhslam.metrics.sample_relations): timestamp1 timestamp2 x y z "
                "roll pitch yaw",
            )
    log_to, truth_to = output_name(args.log), output_name(args.truth)
    also = (
        ""
        if args.relations is None
        else f", {len(rel[0])} relations to {output_name(args.relations)}"
    )
    print(
        f"wrote {len(log)} scans to {log_to} and the true poses to {truth_to}{also}",
        file=sys.stderr if writes_to_stdout(args.log, args.truth, args.relations) else sys.stdout,
    )


def _load(args: argparse.Namespace):
    from fhslam.datasets import load_log

    return load_log(
        args.log, args.scan_topic, args.odom_topic, args.download, max_range=args.max_range
    )


_OFFSET_SOURCES = {
    "PARAM": "from the log's PARAM lines",
    "laser pose": "from the laser poses of the log's laser lines",
    "none": "none stated in the log: the laser at the robot's origin",
    "tf_static": "from the bag's /tf_static base_link -> laser (zero if none)",
    "dataset": "the dataset's correction of its file's mount (fhslam.datasets.MOUNT_NOTES)",
    None: "source not recorded by the reader",
}


def _laser_offset_line(log) -> str:
    """``info``'s line on the laser's mount in use (``Log.laser_offset``) and its source,
    to 0.1 mm and 0.0001° (a mount read off printed laser poses carries their rounding)."""
    import math

    x, y, theta = (float(v) for v in log.laser_offset)
    x, y, deg = (round(v, 4) + 0.0 for v in (x, y, math.degrees(theta)))  # + 0.0: no "-0"
    source = getattr(log, "laser_offset_source", None)
    where = _OFFSET_SOURCES.get(source, source)
    return f"laser offset x {x:g} m, y {y:g} m, theta {deg:g} deg ({where})"


def _info(args: argparse.Namespace) -> None:
    from fhslam.evaluate import log_summary

    log = _load(args)
    s = log_summary(log)
    print(f"{args.log}: {s.n_scans} scans of {s.n_beams} beams")
    print(f"time span {s.duration:.1f} s, odometry path {s.odometry_path:.1f} m")
    code = "none found" if s.no_return is None else f"{s.no_return:g} m"
    given = " (--max-range)" if args.max_range is not None else ""
    print(f"max range {s.max_range:g} m{given}; no-return reading: {code}")
    print(_laser_offset_line(log))
    print(f"fast Hough lines per scan (median of {s.n_sampled} scans): {s.median_lines:g}")


def _stats_rows(stats: dict[str, object]) -> str:
    """The evaluate table: one row per metric, columns rmse mean median std min max."""
    cols = ("rmse", "mean", "median", "std", "min", "max")
    lines = [f"{'':<16}" + "".join(f"{c:>10}" for c in cols)]
    for label, st in stats.items():
        lines.append(f"{label:<16}" + "".join(f"{getattr(st, c):>10.4f}" for c in cols))
    return "\n".join(lines)


def _evaluate(args: argparse.Namespace) -> None:
    """``fhslam evaluate``: :func:`fhslam.evaluate.evaluate_truth` (``--truth``) or
    :func:`fhslam.evaluate.evaluate_relations` (``--relations``), printed."""
    import json

    from fhslam.errors import InputError
    from fhslam.evaluate import evaluate_relations, evaluate_truth
    from fhslam.io.files import check_outputs

    if args.plot is not None:  # before any work (_plot_errors checks the found relations)
        reference = args.truth if args.relations is None else args.relations
        check_outputs(
            {"--plot": args.plot}, {"the trajectory": args.trajectory, "the reference": reference}
        )
        _plot_format(args.plot)
    if args.relations is not None:
        given = [
            opt
            for opt, value in (
                ("--world", args.world),
                ("--map", args.map),
                ("--delta", args.delta),
                ("--align", args.align or None),
            )
            if value is not None
        ]
        if given:
            raise InputError(f"{', '.join(given)}: only with --truth, not with --relations")
        max_diff = 0.001 if args.max_diff is None else args.max_diff
        rep = evaluate_relations(args.trajectory, args.relations, max_diff)
        if args.plot is not None:
            _plot_errors(args, rep.relations, max_diff)
        if args.json:
            print(json.dumps(rep.as_dict(), allow_nan=False))
            return
        e = rep.error
        print(
            f"{args.trajectory} vs {rep.relations} "
            f"(relation and pose timestamps matched within {max_diff:g} s)"
        )
        print(
            f"translational error: {e.trans_mean:.4f} ± {e.trans_std:.4f} m, "
            f"squared {e.trans_sq_mean:.4f} ± {e.trans_sq_std:.4f} m²"
        )
        print(
            f"rotational error:    {e.rot_mean_deg:.3f} ± {e.rot_std_deg:.3f} deg, "
            f"squared {e.rot_sq_mean_deg:.3f} ± {e.rot_sq_std_deg:.3f} deg²"
        )
        print(f"{e.n_used} of {e.n_total} relations used")
        if args.plot is not None:
            print(f"wrote a picture of the errors to {args.plot}")
        return

    if (args.world is None) != (args.map is None):
        given, missing = ("--world", "--map") if args.map is None else ("--map", "--world")
        raise InputError(f"{given} needs {missing}: the map is compared with the world's walls")
    delta = 1 if args.delta is None else args.delta
    max_diff = 0.01 if args.max_diff is None else args.max_diff
    if delta > 1:
        _check_delta(args.trajectory, args.truth, max_diff, delta)
    rep = evaluate_truth(
        args.trajectory,
        args.truth,
        args.world,
        args.map,
        max_diff=max_diff,
        delta=delta,
        align=args.align,
    )
    if args.plot is not None:
        _plot_errors(args, args.truth, max_diff)
    if args.json:
        print(json.dumps(rep.as_dict(), allow_nan=False))
        return
    print(
        f"{args.trajectory} vs {args.truth}: {rep.n_poses} poses matched "
        f"({rep.n_est} estimated, {rep.n_truth} true)"
    )
    labels = {"ate": "ATE (m)", "rpe_trans": "RPE trans (m)", "rpe_rot": "RPE rot (deg)"}
    if args.align:
        labels["ate"] = "ATE aligned (m)"
    print(_stats_rows({labels[k]: v for k, v in rep.stats.items()}))
    print(f"RPE over {rep.n_rpe_pairs} pairs {delta} frame(s) apart")
    if rep.map:
        err, cov = rep.map["map_error"], rep.map["map_coverage"]
        print(
            f"map {args.map}: {rep.map['n_map_lines']} lines, map error "
            + ("n/a" if err is None else f"{err:.4f} m")
            + ", coverage "
            + ("n/a" if cov is None else f"{100 * cov:.1f} %")
            + f" of {rep.map['n_observed_points']} observed wall points"
        )
    if args.plot is not None:
        print(f"wrote a picture of the errors to {args.plot}")


def _plot_errors(args: argparse.Namespace, reference: Path, max_diff: float) -> None:
    """Draw ``fhslam evaluate``'s errors into the picture ``args.plot`` (PNG, PDF or SVG, by
    its extension): against the relations file or the truth file ``reference`` (already read
    once, so known to be good)."""
    import matplotlib

    matplotlib.use("Agg")

    from fhslam.figures import pose_errors_figure, relation_errors_figure
    from fhslam.io import read_relations, read_trajectory
    from fhslam.io.files import check_outputs

    inputs = {"the trajectory": args.trajectory, "the reference": reference}
    check_outputs({"--plot": args.plot}, inputs)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # evaluated above: its warnings were shown then
        t, poses = read_trajectory(args.trajectory)
        title = Path(args.trajectory).name
        if args.relations is not None:
            fig = relation_errors_figure(t, poses, *read_relations(reference), max_diff, title)
        else:
            t_ref, ref = read_trajectory(reference)
            fig = pose_errors_figure(t, poses, t_ref, ref, max_diff, args.align, title)
    _save_figure(fig, args.plot)


def _check_delta(trajectory: Path, truth: Path, max_diff: float, delta: int) -> None:
    """Refuse an RPE ``--delta`` that is not below the number of matched poses (the pairs it
    needs do not exist); fewer than 2 matched poses are left to ``evaluate_truth``'s error."""
    from fhslam.errors import InputError
    from fhslam.io import read_trajectory
    from fhslam.metrics import associate

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # evaluate_truth reads them again and warns then
        t_est, _ = read_trajectory(trajectory)
        t_ref, _ = read_trajectory(truth)
    n = len(associate(t_est, t_ref, max_diff=max_diff)[0])
    if n >= 2 and delta >= n:
        raise InputError(
            f"--delta {delta}: the RPE pairs poses {delta} frames apart, but only {n} poses of "
            f"{trajectory} match {truth}; give a --delta from 1 to {n - 1}"
        )


def _reproduce(args: argparse.Namespace) -> None:
    import matplotlib

    matplotlib.use("Agg")
    from fhslam.figures import reproduce

    for path in reproduce(args.out, what=f"--out {args.out}"):
        print(path)


@contextmanager
def _profiling(enabled: bool) -> Iterator[None]:
    """Run the body under cProfile (if ``enabled``) and, once it has finished without error,
    print the top :data:`PROFILE_TOP` functions by cumulative time to stderr."""
    if not enabled:
        yield
        return
    import cProfile
    import pstats

    profile = cProfile.Profile()
    profile.enable()
    try:
        yield
    finally:
        profile.disable()
    sys.stdout.flush()
    stats = pstats.Stats(profile, stream=sys.stderr)
    stats.sort_stats(pstats.SortKey.CUMULATIVE).print_stats(PROFILE_TOP)


def _slam(args: argparse.Namespace) -> None:
    import fhslam.datasets  # noqa: F401  (imported before --profile starts: not what it shows)
    from fhslam.errors import InputError, InputWarning
    from fhslam.io import write_graph, write_map, write_trajectory
    from fhslam.io.files import check_outputs, output_batch, output_name, writes_to_stdout
    from fhslam.pipeline import keyframe_graph, make_backend, run_backend, run_slam

    if args.graph is not None and args.method != "graph":
        raise InputError(
            f"--graph: only with --method graph; the {args.method} method keeps no keyframe "
            "graph (nothing was written)"
        )
    if args.set and args.method != "graph":
        raise InputError(
            f"--set: only with --method graph; set the {args.method} method's parameters in "
            "Python (nothing was written)"
        )
    params = _graph_params(args.set) if args.set else None
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
    _plot_format(args.plot)
    # an output on standard output gets it alone: the messages go to stderr then
    report = sys.stderr if writes_to_stdout(args.trajectory, args.map, args.graph) else sys.stdout
    with _profiling(args.profile):
        log = _load(args)
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
        print(
            "wrote " + ", ".join(wrote[:-1]) + (" and " if len(wrote) > 1 else "") + wrote[-1],
            file=report,
        )


def _graph_params(pairs: list[str]):
    """The :class:`~fhslam.slam.GraphSlamParams` of ``slam --set NAME=VALUE`` options: the
    defaults, with each named number or switch (a field of type bool, int or float) set;
    ``tracker.NAME`` names one of its :class:`~fhslam.slam.tracker.TrackerParams`."""
    import math
    from dataclasses import fields

    from fhslam.errors import InputError, ParameterError
    from fhslam.slam import GraphSlamParams
    from fhslam.slam.tracker import TrackerParams

    def kinds_of(cls, prefix=""):
        return {prefix + f.name: getattr(f.type, "__name__", str(f.type)) for f in fields(cls)}

    kinds = {**kinds_of(GraphSlamParams), **kinds_of(TrackerParams, "tracker.")}
    settable = sorted(n for n, k in kinds.items() if k in ("bool", "int", "float"))
    values: dict[str, object] = {}
    tracker: dict[str, object] = {}
    for pair in pairs:
        name, sep, text = (x.strip() for x in pair.partition("="))
        if not sep or not name or not text:
            raise InputError(f"--set {pair!r}: expected NAME=VALUE, e.g. loop_target_keyframes=4")
        kind = kinds.get(name)
        if kind not in ("bool", "int", "float"):
            raise InputError(
                f"--set {pair!r}: {name!r} is not a number or switch of GraphSlamParams "
                f"(or, as tracker.NAME, of its TrackerParams); one of: {', '.join(settable)}"
            )
        try:
            if kind == "bool":
                if text.lower() not in ("true", "false", "1", "0", "yes", "no", "on", "off"):
                    raise ValueError(text)
                value: object = text.lower() in ("true", "1", "yes", "on")
            else:
                value = int(text) if kind == "int" else float(text)
                if not math.isfinite(value):
                    raise ValueError(text)
        except ValueError:
            wanted = {"bool": "true or false", "int": "an integer", "float": "a finite number"}
            raise InputError(f"--set {pair!r}: {name} takes {wanted[kind]}, got {text!r}") from None
        if name.startswith("tracker."):
            tracker[name.removeprefix("tracker.")] = value
        else:
            values[name] = value
    try:
        if tracker:
            values["tracker"] = TrackerParams(**tracker)
        return GraphSlamParams(**values)
    except ParameterError as e:  # out of its range: name the --set that gave it
        key = ("tracker." if e.owner == "TrackerParams" else "") + e.name
        given = [p for p in pairs if p.partition("=")[0].strip() == key]
        raise InputError(f"--set {given[-1] if given else key!r}: {e}") from None
    except ValueError as e:
        raise InputError(f"--set: {e}") from None


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


PLOT_FORMATS = {".png": "png", ".pdf": "pdf", ".svg": "svg"}
"""The formats of a picture (``--plot``), by the extension of its file name."""

_PLOT_METADATA = {
    "png": {"Software": None},
    "pdf": {"Creator": None, "Producer": None, "CreationDate": None},
    "svg": {"Creator": None, "Date": None},
}
"""No date and no matplotlib version in a picture: one figure, the same bytes."""


def _plot_format(path: Path | None, option: str = "--plot") -> str | None:
    """The format of the picture ``path`` (:data:`PLOT_FORMATS`), ``None`` without one.

    Raises
    ------
    InputError
        Naming ``option``, the path and the formats, for any other extension or none: call
        it before any work.
    """
    from fhslam.errors import InputError

    if path is None:
        return None
    suffix = Path(path).suffix
    fmt = PLOT_FORMATS.get(suffix.lower())
    if fmt is None:
        has = f"not {suffix}" if suffix else "it has none"
        raise InputError(
            f"{option} {path}: the picture's format is given by the file name's extension, "
            f"one of {', '.join(PLOT_FORMATS)} ({has}); nothing was written"
        )
    return fmt


def _save_figure(fig, path: Path) -> None:
    """Write a figure to ``path`` (whole or not at all) in the format of its extension
    (:func:`_plot_format`: PNG at 100 dpi, PDF or SVG), then close it."""
    import matplotlib.pyplot as plt

    from fhslam.io.files import atomic_output

    try:
        fmt = _plot_format(path)
        with atomic_output(path, "wb") as f, plt.rc_context({"svg.hashsalt": "fhslam"}):
            fig.savefig(f, format=fmt, dpi=100, bbox_inches="tight", metadata=_PLOT_METADATA[fmt])
    finally:
        plt.close(fig)


def _write_plot(path: Path, log, result, method: str, graph) -> None:
    """Draw the run (:func:`fhslam.figures.slam_run_figure`) into the picture ``path`` (PNG,
    PDF or SVG, by its extension)."""
    import matplotlib

    matplotlib.use("Agg")

    from fhslam.figures import slam_run_figure

    _save_figure(slam_run_figure(log, result, method, graph), path)


def _bench(args: argparse.Namespace) -> None:
    import fhslam.pipeline  # noqa: F401  (imported before --profile starts: not what it shows)
    from fhslam.datasets import load_log
    from fhslam.errors import InputError
    from fhslam.experiments import bench

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
    with _profiling(args.profile):
        if args.log is None:
            rows = bench.run_bench(
                scans_per_world=25 if args.scans is None else args.scans,
                repeats=9 if args.repeats is None else args.repeats,
                progress=not args.quiet,
            )
            print(bench.format_table(rows))
            print()
            print(bench.format_slam_table(bench.run_slam_bench()))
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


def _number(ok, what: str):
    """An argparse type: a number for which ``ok(value)`` holds; else "must be ``what``"."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        if not ok(value):  # NaN fails every comparison
            raise argparse.ArgumentTypeError(f"must be {what}, got {text}")
        return value

    return parse


def _positive(unit: str):
    """An argparse type: a positive finite number of ``unit``."""
    return _number(lambda v: 0 < v < float("inf"), f"a positive number of {unit}")


def _non_negative(unit: str):
    """An argparse type: a finite number of ``unit``, 0 or more."""
    return _number(lambda v: 0 <= v < float("inf"), f"a finite number of {unit} >= 0")


_positive_metres = _positive("metres")
_non_negative_seconds = _non_negative("seconds")
_fraction = _number(lambda v: 0 <= v < 1, "a share from 0 up to (not including) 1")


def _whole(minimum: int):
    """An argparse type: a whole number ``minimum`` or more."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be a whole number >= {minimum}, got {text}")
        return value

    return parse


_seed = _whole(0)  # a random seed
_positive_int = _whole(1)


def _log_arguments(p: argparse.ArgumentParser) -> None:
    """The options of every command that reads a laser log (``slam``, ``info``)."""
    p.add_argument(
        "log", help="CARMEN log (.clf), ROS 1/2 bag, or a dataset name (intel, aces, ...)"
    )
    p.add_argument("--scan-topic", help="LaserScan topic of a bag (default: found by type)")
    p.add_argument("--odom-topic", help="Odometry topic of a bag (default: found by type)")
    p.add_argument(
        "--max-range",
        type=_positive_metres,
        help="the laser's maximum range, m: readings at or beyond it are no returns "
        "(default: the bag's range_max or the log's detected no-return reading)",
    )
    p.add_argument(
        "--download",
        action="store_true",
        help="fetch a named dataset into the user cache if no local copy is found",
    )


WORLDS_HELP = "'paper', 'hall', 'corridor', 'ring', 'offices', 'campus', 'random:SEED'"
"""The built-in worlds (:data:`fhslam.sim.world.BUILTIN_WORLDS`), named here so that the help
does not import the simulator."""


def _degrade_arguments(g, seed_default: int | None = 0) -> None:
    """``slam``'s and ``sweep``'s options for :func:`fhslam.sim.degrade` (``sweep`` tells
    an unset ``--degrade-seed``, None, from 0)."""
    g.add_argument(
        "--range-noise",
        type=_non_negative("metres"),
        default=0.0,
        metavar="M",
        help="Gaussian noise of M metres (standard deviation) on every valid range",
    )
    g.add_argument(
        "--drop-scans",
        type=_fraction,
        default=0.0,
        metavar="F",
        help="drop this share of the scans (never the first), as lost laser messages",
    )
    g.add_argument(
        "--clutter",
        type=_fraction,
        default=0.0,
        metavar="F",
        help="this share of each scan's valid beams returns short, as from people or chairs",
    )
    g.add_argument(
        "--degrade-seed",
        type=_seed,
        default=seed_default,
        metavar="N",
        help="seed of the noise, dropped scans and clutter (default 0)",
    )


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fhslam",
        description="Fast-Hough-transform line SLAM for 2D laser scans (teaching workbook).",
    )
    parser.add_argument("--debug", action="store_true", help=DEBUG_HELP)
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("simulate", help="simulate a world: CARMEN log plus ground truth")
    p.add_argument("world", help=f"built-in world ({WORLDS_HELP}) or a world JSON file")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--log", required=True, type=Path, help="output CARMEN log (.clf)")
    p.add_argument("--truth", required=True, type=Path, help="output truth file")
    p.add_argument(
        "--relations",
        type=Path,
        help="also write benchmark relations sampled from the truth "
        "(fhslam.metrics.sample_relations), for `fhslam evaluate --relations`",
    )
    p.add_argument(
        "--odometry",
        choices=("default", "drifting"),
        default="default",
        help="odometry noise: default (~1 m drift on the paper route) or drifting (2-6 m)",
    )
    p.add_argument(
        "--laps",
        type=int,
        default=1,
        help=f"drive a closed route this many times (1 to {MAX_LAPS})",
    )
    p.add_argument(
        "--quiet",
        action="store_true",
        help=f"no progress bars (shown for routes of more than {SIMULATE_PROGRESS_SCANS} scans)",
    )
    p.set_defaults(run=_simulate)

    p = sub.add_parser("slam", help="run SLAM on a log: trajectory and line map")
    _log_arguments(p)
    p.add_argument(
        "--method",
        choices=SLAM_METHODS,
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
        help="--method graph: set a number or switch of fhslam.slam.GraphSlamParams, or as "
        "tracker.NAME of its scan tracker's TrackerParams (repeat for more), e.g. --set "
        "loop_target_keyframes=4 --set tracker.window=0.3; the trajectory's header records it",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--profile", action="store_true", help=PROFILE_HELP)
    g = p.add_argument_group(
        "robustness checks",
        "degrade the log before the run (fhslam.sim.degrade, fhslam.sim.perturb_odometry); "
        "the trajectory's header names what was done",
    )
    _degrade_arguments(g)
    g.add_argument(
        "--last-bit",
        type=_seed,
        metavar="SEED",
        help="multiply the odometry by (1 + 1e-15 e), e standard normal drawn with SEED: what "
        "the same code on another CPU does",
    )
    p.set_defaults(run=_slam)

    p = sub.add_parser(
        "info", help="summarise a log: scans, beams, max range, no-return code, lines per scan"
    )
    _log_arguments(p)
    p.set_defaults(run=_info)

    p = sub.add_parser(
        "evaluate",
        help="trajectory errors against ground truth (ATE, RPE, map) or benchmark relations",
        description=(
            "With --truth: compare an estimated trajectory with the ground truth, pose by "
            "pose matched by timestamp: ATE (no alignment unless --align) and RPE, in metres "
            "and degrees. With --world and --map also the map error (mean distance of the "
            "map's segments to the walls) and coverage (share of the wall points the laser "
            "saw that lie within 5 cm of the map). The seen wall points are not simulated: "
            "they are the noise-free hits of a 181-beam, 180 degree, 8 m laser cast into the "
            "world from every 5th true pose. "
            "With --relations: the relations error of Kuemmerle et al. (2009) against a "
            "Freiburg SLAM-benchmark .relations file, reported as in Hess et al. (2016), "
            "Table II: mean and std of the absolute and the squared translational (m, m^2) "
            "and rotational (deg, deg^2) errors."
        ),
    )
    p.add_argument("trajectory", type=Path, help="estimated trajectory (timestamp x y theta)")
    reference = p.add_mutually_exclusive_group(required=True)
    reference.add_argument("--truth", type=Path, help="ground-truth trajectory file")
    reference.add_argument(
        "--relations",
        help="benchmark relations file (timestamp1 timestamp2 x y z roll pitch yaw), or a "
        "dataset name (intel, aces, ...) to use its relations",
    )
    p.add_argument("--world", help=f"built-in world ({WORLDS_HELP}) or world JSON file (--truth)")
    p.add_argument("--map", type=Path, help="map JSON of the run (needs --world and --truth)")
    p.add_argument(
        "--max-diff",
        type=_non_negative_seconds,
        default=None,
        help="largest timestamp difference of matched poses, s (default 0.01 with --truth, "
        "0.001 with --relations)",
    )
    p.add_argument(
        "--delta",
        type=_positive_int,
        default=None,
        help="RPE frame distance, fewer than the matched poses (default 1; --truth only)",
    )
    p.add_argument(
        "--align", action="store_true", help="SE(2)-align the estimate before ATE (--truth only)"
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument(
        "--plot",
        type=Path,
        help="output picture (PNG, PDF or SVG by its extension): each relation's error over "
        "the run, coloured by the time between its poses (--relations); the trajectory and "
        "each pose's error over time (--truth)",
    )
    p.set_defaults(run=_evaluate)

    p = sub.add_parser("reproduce", help="write the paper's figures as PNG files")
    p.add_argument("--out", default="figures", type=Path, help="output folder (default figures)")
    p.set_defaults(run=_reproduce)

    p = sub.add_parser(
        "bench",
        help="time and score every line extractor on the same scans; with --log, where a "
        "SLAM method's time goes on a real log",
        description=(
            "Without --log: every line extractor timed and scored on the same scans of "
            "held-out simulated worlds, then the SLAM methods' steps per second on the paper "
            "world. With --log: one SLAM method run over that log; prints scans, wall time, "
            "scans per second and times real time, and per stage (extraction, tracking, "
            "local map, loop closure, optimisation, map, other; nested stages subtracted) the "
            "ms per scan, the share of the total and the ratio to a reference measured in the "
            "same run: the bare cv2.HoughLinesPointSet call on the log's scans, timed before "
            "and after the run, so that ratios compare across machines."
        ),
    )
    p.add_argument(
        "--log",
        help="run the real-log bench on this CARMEN log, ROS bag or dataset name (intel, ...)",
    )
    p.add_argument(
        "--method",
        choices=SLAM_METHODS,
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
        help="timed calls per scan (default 9); with --log: runs, medians reported (default 1)",
    )
    p.add_argument(
        "--max-range",
        type=_positive_metres,
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
    p.set_defaults(run=_bench)

    p = sub.add_parser(
        "sweep",
        help="every SLAM method on seeds x odometry-noise levels of a simulated world, or on "
        "degraded copies of a real log",
        description="Simulate WORLD with each seed and odometry-noise level (low, medium, "
        "high) and run every SLAM method on each log, in parallel; print the median ATE, map "
        "error and time per level and method. With --out, write every run as CSV: notebook "
        "07 shows the committed notebooks/results/sweep_paper.csv. With --log, run SLAM "
        "(default: the graph method) on a real log as read and on copies degraded with seeds "
        "0..N-1 (--range-noise, --drop-scans, --clutter; or --last-bit-draws), each measured "
        "against the log's benchmark relations, and count the runs whose relation error "
        "moved by more than 25 % or 1 cm (whichever is larger) from the run on the log as "
        "read: the robustness bound.",
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
    p.add_argument(
        "--methods",
        nargs="+",
        choices=SLAM_METHODS,
        help="SLAM methods (default all; with --log, graph)",
    )
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="set a number or switch of fhslam.slam.GraphSlamParams (tracker.NAME: of its "
        "TrackerParams) for the graph method's runs, as `fhslam slam --set` does (repeat for "
        "more); --out's CSV records them in its settings column",
    )
    p.add_argument("--jobs", type=int, default=-1, help="worker processes (default: all cores)")
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
    g = p.add_argument_group(
        "robustness checks",
        "degrade every simulated log (or --log's) before its runs, as `fhslam slam` does "
        "(fhslam.sim.degrade, fhslam.sim.perturb_odometry); the CSV file records it",
    )
    _degrade_arguments(g, seed_default=None)
    g.add_argument(
        "--last-bit-draws",
        type=_seed,
        default=0,
        metavar="K",
        help="also run each log with its odometry multiplied by (1 + 1e-15 e), e drawn with "
        "seeds 1..K: what the same code does on other CPUs (default 0: as simulated only)",
    )
    p.set_defaults(run=_sweep)

    p = sub.add_parser(
        "student-copy",
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
    p.set_defaults(run=_student_copy)

    p = sub.add_parser(
        "run-notebooks",
        help="run the notebooks and write them back with fresh outputs and paired .py sources",
        description="Execute each notebook (all of NOTEBOOKS, or those whose names start with "
        "the numbers given) in a fresh kernel, in its own folder, and write it back with its "
        "new outputs and its paired plain-text source (NN_topic.py, jupytext percent format), "
        "only where an output changed (measured times and widget ids do not count). "
        "Prints each notebook's Run All time and its slowest cell. A cell that raises stops "
        "the run with a one-line error naming the notebook and the cell; that notebook is "
        "left as it was. With --pair-only, nothing is run: only the .py sources are written.",
    )
    p.add_argument("only", nargs="*", metavar="NN", help="notebook numbers, e.g. 03 08")
    p.add_argument(
        "--notebooks",
        type=Path,
        default=Path("notebooks"),
        help="folder of the notebooks (default notebooks)",
    )
    p.add_argument(
        "--timeout", type=_positive("seconds"), default=600.0, help="seconds per cell (default 600)"
    )
    p.add_argument("--pair-only", action="store_true", help="write the .py sources, run nothing")
    p.set_defaults(run=_run_notebooks)
    for command in sub.choices.values():  # also after the command; SUPPRESS: keep one before
        command.add_argument(
            "--debug", action="store_true", default=argparse.SUPPRESS, help=DEBUG_HELP
        )
    return parser


def _run_notebooks(args: argparse.Namespace) -> None:
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


def _sweep(args: argparse.Namespace) -> None:
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
    methods = args.methods or (["graph"] if args.log is not None else list(SLAM_METHODS))
    if args.set and "graph" not in methods:
        raise InputError("--set: only with the graph method among --methods")
    params = _graph_params(args.set) if args.set else None
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
    rows = compare.slam_sweep(
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
    if args.out is not None:
        compare.save_sweep(rows, args.out)
    if args.set:  # not in the file: its columns are fixed (notebook 07 reads it)
        print("the graph method with " + " ".join(f"--set {x}" for x in args.set))
    print(compare.format_summary(rows))


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
    _plot_format(args.plot)
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
        import matplotlib

        matplotlib.use("Agg")
        from fhslam.figures import sweep_errors_figure

        degraded = next((r for r in rows if not r.reference), rows[0])
        title = f"{rows[0].log}: {robustness.degradation_text(degraded)}"
        bounds = robustness.RELATIVE_BOUND, robustness.ABSOLUTE_BOUND
        _save_figure(sweep_errors_figure(rows, *bounds, title), args.plot)
        print(f"wrote a picture of the runs to {args.plot}")


def _student_copy(args: argparse.Namespace) -> None:
    from fhslam.workbook import student_copy

    for path, removed in student_copy(args.notebooks, args.out):
        print(f"{path}: {removed} solution{'s' if removed != 1 else ''} removed")


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Every warning as one line on stderr. The package's warnings about its input
    (:class:`fhslam.errors.InputWarning`, and other ``UserWarning``\\s it issues, e.g. the
    EKF baseline's landmark limit) name the file themselves; any other (a NumPy overflow, a
    SciPy ill-conditioned matrix) also gets its category and the code that raised it."""
    text = " ".join(str(message).split())
    if not issubclass(category, UserWarning):
        text += f" [{category.__name__} at {Path(filename).name}:{lineno}]"
    print(f"fhslam: warning: {text}", file=sys.stderr)


_OUTPUTS = {
    "simulate": ("--log", "--truth"),
    "slam": ("--trajectory", "--map", "--graph"),
    "sweep": ("--out", "--plot"),
    "reproduce": ("--out",),
    "student-copy": ("out",),
}
"""Each command's output options (``out``: a positional argument), for the interrupt line."""


def _interrupted(args: argparse.Namespace) -> str:
    """The line printed after Ctrl-C: what was not written (outputs appear all or none)."""
    if args.command == "run-notebooks":
        path = getattr(args, "in_progress", None)
        return f"interrupted; {path} left as it was" if path else "interrupted"
    given = [
        f"{opt} {value}" if opt.startswith("-") else str(value)
        for opt in _OUTPUTS.get(args.command, ())
        if (value := getattr(args, opt.lstrip("-").replace("-", "_"))) is not None
    ]
    return f"interrupted; nothing written to {', '.join(given)}" if given else "interrupted"


def main(argv: list[str] | None = None) -> int:
    with warnings.catch_warnings():  # a warning on import (numba's cache): one line too
        warnings.showwarning = _show_warning
        from fhslam.errors import InputError
        from fhslam.io.files import interrupted_before_output, watch_interrupts

    for stream in (sys.stdout, sys.stderr):  # a path the locale cannot encode: escaped
        if getattr(stream, "errors", None) == "strict" and hasattr(stream, "reconfigure"):
            stream.reconfigure(errors="backslashreplace")
    args = build_parser().parse_args(argv)
    try:
        with watch_interrupts(), warnings.catch_warnings():
            # implausible but readable input: one line each, the input named
            warnings.showwarning = _show_warning
            args.run(args)
            if interrupted_before_output():  # Ctrl-C swallowed somewhere (watch_interrupts)
                raise KeyboardInterrupt
    except InputError as e:  # bad input; anything else is a bug (below)
        message = " ".join(str(e).split())  # one line, whatever the message
        print(f"fhslam: error: {message}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except BaseException as e:  # the outputs' temporary files are already removed
        if isinstance(e, BrokenPipeError) and _reader_gone(sys.stdout):  # `... | head -1`
            return EXIT_BROKEN_PIPE
        sys.stdout.flush()
        if _after_interrupt(e):  # Ctrl-C
            print(f"fhslam: {_interrupted(args)}", file=sys.stderr)
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


def _reader_gone(stream) -> bool:
    """Whether the reader of ``stream``, a pipe, has closed it; then anything still buffered
    for it is dropped (Python would report it at exit). Unknown (a captured stream, no
    ``select.poll``): False."""
    import os
    import select

    try:
        poll = select.poll()
        poll.register(stream.fileno(), select.POLLOUT)
        if not any(events & select.POLLERR for _, events in poll.poll(0)):
            return False
        os.dup2(os.open(os.devnull, os.O_WRONLY), stream.fileno())
    except (AttributeError, OSError, ValueError):  # io.UnsupportedOperation is both
        return False
    return True


def _after_interrupt(e: BaseException) -> bool:
    """Whether ``e`` is Ctrl-C's KeyboardInterrupt or was raised because of one: landing in
    C code that called back into Python (numba loading a compiled function from its cache),
    it comes out as a SystemError whose cause is the KeyboardInterrupt."""
    seen: set[int] = set()
    while e is not None and id(e) not in seen:
        if isinstance(e, KeyboardInterrupt):
            return True
        seen.add(id(e))
        e = e.__cause__ or e.__context__
    return False


if __name__ == "__main__":
    sys.exit(main())
