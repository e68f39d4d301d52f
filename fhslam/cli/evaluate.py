"""``fhslam evaluate``: an estimated trajectory's errors against the ground truth (ATE, RPE
and, with the world and the run's map, the map's error and coverage) or against benchmark
relations (the relations error of Kuemmerle et al.), printed as text or JSON and, if asked,
drawn."""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

from fhslam.cli.common import (
    WORLDS_HELP,
    non_negative_seconds,
    plot_format,
    positive_int,
    save_figure,
)

NAME = "evaluate"
OUTPUTS: tuple[str, ...] = ()
"""The output options named after Ctrl-C: none."""

DESCRIPTION = (
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
)


def add_parser(sub) -> argparse.ArgumentParser:
    """Add ``evaluate``'s sub-parser to ``sub``."""
    p = sub.add_parser(
        NAME,
        help="trajectory errors against ground truth (ATE, RPE, map) or benchmark relations",
        description=DESCRIPTION,
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
        type=non_negative_seconds,
        default=None,
        help="largest timestamp difference of matched poses, s (default 0.01 with --truth, "
        "0.001 with --relations)",
    )
    p.add_argument(
        "--delta",
        type=positive_int,
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
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> None:
    """:func:`fhslam.evaluate.evaluate_truth` (``--truth``) or
    :func:`fhslam.evaluate.evaluate_relations` (``--relations``), printed."""
    from fhslam.io.files import check_outputs

    if args.plot is not None:  # before any work (_plot_errors checks the found relations)
        reference = args.truth if args.relations is None else args.relations
        check_outputs(
            {"--plot": args.plot}, {"the trajectory": args.trajectory, "the reference": reference}
        )
        plot_format(args.plot)
    if args.relations is not None:
        _against_relations(args)
    else:
        _against_truth(args)


def _against_relations(args: argparse.Namespace) -> None:
    """``evaluate --relations``: the relations error, printed."""
    import json

    from fhslam.errors import InputError
    from fhslam.evaluate import evaluate_relations

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


def _against_truth(args: argparse.Namespace) -> None:
    """``evaluate --truth``: ATE, RPE and the map's error, printed."""
    import json

    from fhslam.errors import InputError
    from fhslam.evaluate import evaluate_truth

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
    _print_truth_report(args, rep, delta)
    if args.plot is not None:
        print(f"wrote a picture of the errors to {args.plot}")


def _print_truth_report(args: argparse.Namespace, rep, delta: int) -> None:
    """The text of ``evaluate --truth``'s report ``rep``: the matched poses, the table of
    errors and the map's line."""
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


def _stats_rows(stats: dict[str, object]) -> str:
    """The evaluate table: one row per metric, columns rmse mean median std min max."""
    cols = ("rmse", "mean", "median", "std", "min", "max")
    lines = [f"{'':<16}" + "".join(f"{c:>10}" for c in cols)]
    for label, st in stats.items():
        lines.append(f"{label:<16}" + "".join(f"{getattr(st, c):>10.4f}" for c in cols))
    return "\n".join(lines)


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
    save_figure(fig, args.plot)


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
