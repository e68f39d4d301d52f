"""``fhslam info``: summarise a laser log: its scans and beams, time span and odometry
path, maximum range and no-return reading, the laser's mount, and the fast Hough lines per
scan."""

from __future__ import annotations

import argparse

from fhslam.cli.common import log_arguments, read_log

NAME = "info"
OUTPUTS: tuple[str, ...] = ()
"""The output options named after Ctrl-C: none."""

_OFFSET_SOURCES = {
    "PARAM": "from the log's PARAM lines",
    "laser pose": "from the laser poses of the log's laser lines",
    "none": "none stated in the log: the laser at the robot's origin",
    "tf_static": "from the bag's /tf_static base_link -> laser (zero if none)",
    "dataset": "the dataset's correction of its file's mount (fhslam.datasets.MOUNT_NOTES)",
    None: "source not recorded by the reader",
}


def add_parser(sub) -> argparse.ArgumentParser:
    """Add ``info``'s sub-parser to ``sub``."""
    p = sub.add_parser(
        NAME, help="summarise a log: scans, beams, max range, no-return code, lines per scan"
    )
    log_arguments(p)
    p.set_defaults(run=run)
    return p


def _laser_offset_line(log) -> str:
    """``info``'s line on the laser's mount in use (``Log.laser_offset``) and its source,
    to 0.1 mm and 0.0001° (a mount read off printed laser poses carries their rounding)."""
    import math

    x, y, theta = (float(v) for v in log.laser_offset)
    x, y, deg = (round(v, 4) + 0.0 for v in (x, y, math.degrees(theta)))  # + 0.0: no "-0"
    source = getattr(log, "laser_offset_source", None)
    where = _OFFSET_SOURCES.get(source, source)
    return f"laser offset x {x:g} m, y {y:g} m, theta {deg:g} deg ({where})"


def run(args: argparse.Namespace) -> None:
    """Read ``args.log`` and print its summary (:func:`fhslam.evaluate.log_summary`)."""
    from fhslam.evaluate import log_summary

    log = read_log(args)
    s = log_summary(log)
    print(f"{args.log}: {s.n_scans} scans of {s.n_beams} beams")
    print(f"time span {s.duration:.1f} s, odometry path {s.odometry_path:.1f} m")
    code = "none found" if s.no_return is None else f"{s.no_return:g} m"
    given = " (--max-range)" if args.max_range is not None else ""
    print(f"max range {s.max_range:g} m{given}; no-return reading: {code}")
    print(_laser_offset_line(log))
    print(f"fast Hough lines per scan (median of {s.n_sampled} scans): {s.median_lines:g}")
