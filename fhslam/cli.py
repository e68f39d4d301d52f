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
    from fhslam.sim import load_world, simulate

    world = load_world(args.world)
    log = simulate(world, seed=args.seed)
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

    from fhslam.extraction import extract_lines, scan_to_points
    from fhslam.io import read_carmen

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


def _reproduce(args: argparse.Namespace) -> None:
    import matplotlib

    matplotlib.use("Agg")
    from fhslam.figures import reproduce

    for path in reproduce(args.out):
        print(path)


def _bench(args: argparse.Namespace) -> None:
    from fhslam.bench import format_table, run_bench

    rows = run_bench(scans_per_world=args.scans, repeats=args.repeats, progress=not args.quiet)
    print(format_table(rows))


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
    p.set_defaults(run=_simulate)

    p = sub.add_parser("info", help="summarise a CARMEN log: scans, beams, lines per scan")
    p.add_argument("log", type=Path, help="CARMEN text log (.clf)")
    p.set_defaults(run=_info)

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
