"""``fhslam simulate``: drive the simulated robot through a world and write the CARMEN log
of its scans and odometry, its true poses and, if asked, benchmark relations sampled from
them."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from fhslam.cli.common import WORLDS_HELP

NAME = "simulate"
OUTPUTS = ("--log", "--truth")
"""The output options named after Ctrl-C."""

MAX_LAPS = 100
"""Largest ``simulate --laps``: a hundred laps of the paper world are 92,000 scans."""

SIMULATE_PROGRESS_SCANS = 5000
"""``simulate`` shows progress bars for routes of more scans than this (about a second)."""


def add_parser(sub) -> argparse.ArgumentParser:
    """Add ``simulate``'s sub-parser to ``sub``."""
    p = sub.add_parser(NAME, help="simulate a world: CARMEN log plus ground truth")
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
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> None:
    """Simulate ``args.world`` and write the log, the truth and the relations."""
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
