"""The ``fhslam`` command (the contract is in DESIGN.md).

Bad input — a missing or malformed file, an unknown world — ends with one line on stderr,
``fhslam: error: <file>:<line>: <what>``, and exit status 2; never a traceback.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

EXIT_BAD_INPUT = 2


def _simulate(args: argparse.Namespace) -> None:
    from fhslam.io import write_carmen, write_trajectory
    from fhslam.sim import OdometryNoise, load_world, simulate

    world = load_world(args.world)
    noise = OdometryNoise.drifting() if args.odometry == "drifting" else OdometryNoise()
    log = simulate(world, seed=args.seed, odometry=noise, laps=args.laps)
    write_carmen(log, args.log)
    write_trajectory(
        args.truth,
        log.timestamps,
        log.truth,
        header=f"ground truth of {world.name!r}, seed {args.seed}: timestamp x y theta",
    )
    print(f"wrote {len(log)} scans to {args.log} and the true poses to {args.truth}")


def _info(args: argparse.Namespace) -> None:
    import numpy as np

    from fhslam.extraction import extract_lines
    from fhslam.io import read_carmen
    from fhslam.scan import scan_to_points

    log = read_carmen(args.log)
    step = np.hypot(*np.diff(log.odometry[:, :2], axis=0).T).sum()
    sample = range(0, len(log), max(1, len(log) // 200))
    n_lines = [
        len(extract_lines(scan_to_points(log.ranges[k], log.angles, log.max_range)[0]))
        for k in sample
    ]
    print(f"{args.log}: {len(log)} scans of {len(log.angles)} beams")
    print(f"time span {log.timestamps[-1] - log.timestamps[0]:.1f} s, odometry path {step:.1f} m")
    print(f"fast Hough lines per scan (median of {len(n_lines)} scans): {np.median(n_lines):g}")


def _stats_rows(stats: dict[str, object]) -> str:
    """The evaluate table: one row per metric, columns rmse mean median std min max."""
    cols = ("rmse", "mean", "median", "std", "min", "max")
    lines = [f"{'':<16}" + "".join(f"{c:>10}" for c in cols)]
    for label, st in stats.items():
        lines.append(f"{label:<16}" + "".join(f"{getattr(st, c):>10.4f}" for c in cols))
    return "\n".join(lines)


def _evaluate(args: argparse.Namespace) -> None:
    """Trajectory (and map) errors against the ground truth, or the relations error.

    With ``--truth``: poses are paired by timestamp (``fhslam.metrics.associate``, within
    ``--max-diff`` s, default 0.01). ATE is not aligned unless ``--align``: the SLAM starts
    at the true first pose. With ``--world`` and ``--map``, the map is compared with the
    world's walls: ``map_error`` is the mean distance of the map segments to the walls, and
    ``map_coverage`` the share of the observed wall points within 5 cm of the map. Nothing is
    simulated for it: the observed points are the noise-free hits of the paper's laser (181
    beams over 180 degrees, 8 m) cast into the world from every 5th pose of the truth file.

    With ``--relations``: the Kümmerle et al. (2009) relations error of the trajectory
    (``fhslam.metrics.relations_error``, relation stamps matched to pose stamps within
    ``--max-diff`` s, default 0.001), as mean ± std of the absolute and the squared
    translational (m, m²) and rotational (deg, deg²) errors, Hess et al. (2016) Table II.
    """
    import json
    import math

    from fhslam import metrics
    from fhslam.io import read_map, read_relations, read_trajectory

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
            raise ValueError(f"{', '.join(given)}: only with --truth, not with --relations")
        max_diff = 0.001 if args.max_diff is None else args.max_diff
        t_est, est = read_trajectory(args.trajectory)
        from fhslam.data import find_dataset

        args.relations = find_dataset(args.relations, kind="relations")
        t1, t2, rel = read_relations(args.relations)
        try:
            rerr = metrics.relations_error(t_est, est, t1, t2, rel, max_diff=max_diff)
        except ValueError as e:
            raise ValueError(f"{args.trajectory} and {args.relations}: {e}") from None
        if args.json:
            out: dict[str, float | int] = {
                f"relations_{k}": v
                for k, v in rerr.as_dict().items()
                if k not in ("n_used", "n_total")
            }
            out.update(relations_used=rerr.n_used, relations_total=rerr.n_total)
            print(json.dumps(out, allow_nan=False))
            return
        print(
            f"{args.trajectory} vs {args.relations} "
            f"(relation and pose timestamps matched within {max_diff:g} s)"
        )
        print(
            f"translational error: {rerr.trans_mean:.4f} ± {rerr.trans_std:.4f} m, "
            f"squared {rerr.trans_sq_mean:.4f} ± {rerr.trans_sq_std:.4f} m²"
        )
        print(
            f"rotational error:    {rerr.rot_mean_deg:.3f} ± {rerr.rot_std_deg:.3f} deg, "
            f"squared {rerr.rot_sq_mean_deg:.3f} ± {rerr.rot_sq_std_deg:.3f} deg²"
        )
        print(f"{rerr.n_used} of {rerr.n_total} relations used")
        return

    max_diff = 0.01 if args.max_diff is None else args.max_diff
    delta = 1 if args.delta is None else args.delta
    if (args.world is None) != (args.map is None):
        given, missing = ("--world", "--map") if args.map is None else ("--map", "--world")
        raise ValueError(f"{given} needs {missing}: the map is compared with the world's walls")
    t_est, est = read_trajectory(args.trajectory)
    t_ref, ref = read_trajectory(args.truth)
    i_est, i_ref = metrics.associate(t_est, t_ref, max_diff=max_diff)
    if len(i_est) < 2:
        raise ValueError(
            f"{args.trajectory} and {args.truth}: only {len(i_est)} poses have matching "
            f"timestamps (within {max_diff:g} s); at least 2 are needed"
        )
    e, r = est[i_est], ref[i_ref]
    stats = {
        "ate": metrics.ate(e, r, align=args.align),
        "rpe_trans": metrics.rpe(e, r, delta=delta),
        "rpe_rot": metrics.rpe_rot_deg(e, r, delta=delta),
    }
    result: dict[str, float | int | None] = {}
    for name, st in stats.items():
        unit = "_deg" if name == "rpe_rot" else ""
        result.update({f"{name}_{k}{unit}": v for k, v in st.as_dict().items()})
    result.update(n_poses=len(i_est), n_est=len(t_est), n_truth=len(t_ref))
    result["n_rpe_pairs"] = len(metrics.rpe_pairs(len(e), delta))

    if args.world is not None:
        from fhslam.sim import load_world

        world = load_world(args.world)
        lines = read_map(args.map)
        observed = metrics.visible_wall_points(world.walls, ref, every=5)
        error = metrics.map_error(lines, world.walls)
        result.update(
            map_error=None if math.isnan(error) else error,
            map_coverage=metrics.map_coverage(lines, observed) if len(observed) else None,
            n_map_lines=len(lines),
            n_observed_points=len(observed),
        )

    if args.json:
        print(json.dumps(result, allow_nan=False))
        return
    print(
        f"{args.trajectory} vs {args.truth}: {len(i_est)} poses matched "
        f"({len(t_est)} estimated, {len(t_ref)} true)"
    )
    labels = {"ate": "ATE (m)", "rpe_trans": "RPE trans (m)", "rpe_rot": "RPE rot (deg)"}
    if args.align:
        labels["ate"] = "ATE aligned (m)"
    print(_stats_rows({labels[k]: v for k, v in stats.items()}))
    print(f"RPE over {result['n_rpe_pairs']} pairs {delta} frame(s) apart")
    if args.world is not None:
        err, cov = result["map_error"], result["map_coverage"]
        print(
            f"map {args.map}: {len(lines)} lines, map error "
            + ("n/a" if err is None else f"{err:.4f} m")
            + ", coverage "
            + ("n/a" if cov is None else f"{100 * cov:.1f} %")
            + f" of {len(observed)} observed wall points"
        )


def _reproduce(args: argparse.Namespace) -> None:
    import matplotlib

    matplotlib.use("Agg")
    from fhslam.figures import reproduce

    for path in reproduce(args.out):
        print(path)


def _slam(args: argparse.Namespace) -> None:
    from fhslam.data import load_log
    from fhslam.io import write_map, write_trajectory
    from fhslam.slam import run_slam

    log = load_log(args.log, args.scan_topic, args.odom_topic, args.download)
    result = run_slam(log, args.method, progress=not args.quiet and len(log) > 200)
    # Everything is computed before anything is written: bad input leaves no half files.
    write_trajectory(
        args.trajectory,
        result.timestamps,
        result.poses,
        header=f"fhslam slam --method {args.method} {args.log}: timestamp x y theta",
    )
    if args.map is not None:
        write_map(args.map, result.map)
    extra = f" and {len(result.map)} map lines to {args.map}" if args.map else ""
    print(f"wrote {len(result.poses)} poses to {args.trajectory}{extra}")


def _bench(args: argparse.Namespace) -> None:
    from fhslam.bench import format_slam_table, format_table, run_bench, run_slam_bench

    rows = run_bench(scans_per_world=args.scans, repeats=args.repeats, progress=not args.quiet)
    print(format_table(rows))
    print()
    print(format_slam_table(run_slam_bench()))


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="fhslam",
        description="Fast-Hough-transform line SLAM for 2D laser scans (teaching workbook).",
    )
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("simulate", help="simulate a world: CARMEN log plus ground truth")
    p.add_argument("world", help="built-in world ('paper', 'random:SEED') or a world JSON file")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--log", required=True, type=Path, help="output CARMEN log (.clf)")
    p.add_argument("--truth", required=True, type=Path, help="output truth file")
    p.add_argument(
        "--odometry",
        choices=("default", "drifting"),
        default="default",
        help="odometry noise: default (~1 m drift on the paper route) or drifting (2-6 m)",
    )
    p.add_argument("--laps", type=int, default=1, help="drive a closed route this many times")
    p.set_defaults(run=_simulate)

    p = sub.add_parser("slam", help="run SLAM on a log: trajectory and line map")
    p.add_argument(
        "log", help="CARMEN log (.clf), ROS 1/2 bag, or a dataset name (intel, aces, ...)"
    )
    p.add_argument("--scan-topic", help="LaserScan topic of a bag (default: found by type)")
    p.add_argument("--odom-topic", help="Odometry topic of a bag (default: found by type)")
    p.add_argument(
        "--download",
        action="store_true",
        help="fetch a named dataset into the user cache if no local copy is found",
    )
    p.add_argument(
        "--method",
        choices=("fht", "graph", "classical", "ekf", "odometry"),
        default="fht",
        help="fht: fast-Hough SLAM, the paper's procedure (default); graph: the same as the "
        "front end of a pose graph with scan-matched keyframes and loop closures (for long "
        "real logs such as intel); classical: fht with OpenCV's classical Hough as Loop 1; "
        "ekf: EKF line SLAM (filterpy); odometry: dead reckoning",
    )
    p.add_argument("--trajectory", required=True, type=Path, help="output: timestamp x y theta")
    p.add_argument("--map", type=Path, help="output map JSON (reference lines)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(run=_slam)

    p = sub.add_parser("info", help="summarise a CARMEN log: scans, beams, lines per scan")
    p.add_argument("log", type=Path, help="CARMEN text log (.clf)")
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
    p.add_argument(
        "--world", help="built-in world ('paper', 'random:SEED') or world JSON file (--truth)"
    )
    p.add_argument("--map", type=Path, help="map JSON of the run (needs --world and --truth)")
    p.add_argument(
        "--max-diff",
        type=float,
        default=None,
        help="largest timestamp difference of matched poses, s (default 0.01 with --truth, "
        "0.001 with --relations)",
    )
    p.add_argument(
        "--delta", type=int, default=None, help="RPE frame distance (default 1; --truth only)"
    )
    p.add_argument(
        "--align", action="store_true", help="SE(2)-align the estimate before ATE (--truth only)"
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(run=_evaluate)

    p = sub.add_parser("reproduce", help="write the paper's figures as PNG files")
    p.add_argument("--out", default="figures", type=Path, help="output folder (default figures)")
    p.set_defaults(run=_reproduce)

    p = sub.add_parser("bench", help="time and score every line extractor on the same scans")
    p.add_argument("--scans", type=int, default=25, help="scans per held-out world (default 25)")
    p.add_argument("--repeats", type=int, default=9, help="timed calls per scan (default 9)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(run=_bench)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        args.run(args)
    except FileNotFoundError as e:
        name = e.filename if e.filename is not None else e
        print(f"fhslam: error: no such file: {name}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except (ValueError, OSError) as e:
        message = " ".join(str(e).split())  # one line, whatever the message
        print(f"fhslam: error: {message}", file=sys.stderr)
        return EXIT_BAD_INPUT
    return 0


if __name__ == "__main__":
    sys.exit(main())
