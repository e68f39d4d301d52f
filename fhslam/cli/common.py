"""What several commands share: argument types and options, reading a log, pictures,
``--profile``, the SLAM methods' names and a method's ``--set NAME=VALUE``.

Nothing heavy is imported here at module level: the parser is built, and ``--help``
answered, without NumPy, numba or matplotlib.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

PROFILE_TOP = 25
"""Functions listed by ``--profile``."""

PROFILE_HELP = (
    f"run under cProfile and print the top {PROFILE_TOP} functions by cumulative time "
    "(pstats) to stderr after the normal output"
)

WORLDS_HELP = "'paper', 'hall', 'corridor', 'ring', 'offices', 'campus', 'random:SEED'"
"""The built-in worlds (:data:`fhslam.sim.world.BUILTIN_WORLDS`), named here so that the help
does not import the simulator."""


# --------------------------------------------------------------------------------------------
# Argument types


def number(ok, what: str):
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


def positive(unit: str):
    """An argparse type: a positive finite number of ``unit``."""
    return number(lambda v: 0 < v < float("inf"), f"a positive number of {unit}")


def non_negative(unit: str):
    """An argparse type: a finite number of ``unit``, 0 or more."""
    return number(lambda v: 0 <= v < float("inf"), f"a finite number of {unit} >= 0")


def whole(minimum: int):
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


positive_metres = positive("metres")
non_negative_seconds = non_negative("seconds")
fraction = number(lambda v: 0 <= v < 1, "a share from 0 up to (not including) 1")
random_seed = whole(0)
positive_int = whole(1)


class _MethodNames(Sequence[str]):
    """The names of the SLAM methods, the keys of :data:`fhslam.pipeline.METHODS` in its
    order, looked up when first asked for: building the parser does not import the pipeline
    (and with it numba and OpenCV); checking a ``--method`` given or printing the help
    does."""

    def _names(self) -> tuple[str, ...]:
        from fhslam.pipeline import METHODS

        return tuple(METHODS)

    def __getitem__(self, index):
        return self._names()[index]

    def __len__(self) -> int:
        return len(self._names())


METHOD_NAMES: Sequence[str] = _MethodNames()
"""The ``--method`` choices of ``slam`` and ``bench`` (``--methods`` of ``sweep``)."""


def add_method_argument(p, *flags: str, **kwargs) -> argparse.Action:
    """Add an option whose choices are :data:`METHOD_NAMES`. They are set on the option
    after ``add_argument``, which would otherwise read them at once (to check a metavar)."""
    action = p.add_argument(*flags, **kwargs)
    action.choices = METHOD_NAMES
    return action


# --------------------------------------------------------------------------------------------
# Options of several commands


def log_arguments(p: argparse.ArgumentParser) -> None:
    """The options of every command that reads a laser log (``slam``, ``info``)."""
    p.add_argument(
        "log", help="CARMEN log (.clf), ROS 1/2 bag, or a dataset name (intel, aces, ...)"
    )
    p.add_argument("--scan-topic", help="LaserScan topic of a bag (default: found by type)")
    p.add_argument("--odom-topic", help="Odometry topic of a bag (default: found by type)")
    p.add_argument(
        "--max-range",
        type=positive_metres,
        help="the laser's maximum range, m: readings at or beyond it are no returns "
        "(default: the bag's range_max or the log's detected no-return reading)",
    )
    p.add_argument(
        "--download",
        action="store_true",
        help="fetch a named dataset into the user cache if no local copy is found",
    )


def read_log(args: argparse.Namespace):
    """The log of :func:`log_arguments`' options (:func:`fhslam.datasets.load_log`)."""
    from fhslam.datasets import load_log

    return load_log(
        args.log, args.scan_topic, args.odom_topic, args.download, max_range=args.max_range
    )


def degrade_arguments(g, seed_default: int | None = 0) -> None:
    """``slam``'s and ``sweep``'s options for :func:`fhslam.sim.degrade` (``sweep`` tells
    an unset ``--degrade-seed``, None, from 0)."""
    g.add_argument(
        "--range-noise",
        type=non_negative("metres"),
        default=0.0,
        metavar="M",
        help="Gaussian noise of M metres (standard deviation) on every valid range",
    )
    g.add_argument(
        "--drop-scans",
        type=fraction,
        default=0.0,
        metavar="F",
        help="drop this share of the scans (never the first), as lost laser messages",
    )
    g.add_argument(
        "--clutter",
        type=fraction,
        default=0.0,
        metavar="F",
        help="this share of each scan's valid beams returns short, as from people or chairs",
    )
    g.add_argument(
        "--degrade-seed",
        type=random_seed,
        default=seed_default,
        metavar="N",
        help="seed of the noise, dropped scans and clutter (default 0)",
    )


# --------------------------------------------------------------------------------------------
# Pictures (--plot)

PLOT_FORMATS = {".png": "png", ".pdf": "pdf", ".svg": "svg"}
"""The formats of a picture (``--plot``), by the extension of its file name."""

_PLOT_METADATA = {
    "png": {"Software": None},
    "pdf": {"Creator": None, "Producer": None, "CreationDate": None},
    "svg": {"Creator": None, "Date": None},
}
"""No date and no matplotlib version in a picture: one figure, the same bytes."""


def plot_format(path: Path | None, option: str = "--plot") -> str | None:
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


def save_figure(fig, path: Path) -> None:
    """Write a figure to ``path`` (whole or not at all) in the format of its extension
    (:func:`plot_format`: PNG at 100 dpi, PDF or SVG), then close it."""
    import matplotlib.pyplot as plt

    from fhslam.io.files import atomic_output

    try:
        fmt = plot_format(path)
        with atomic_output(path, "wb") as f, plt.rc_context({"svg.hashsalt": "fhslam"}):
            fig.savefig(f, format=fmt, dpi=100, bbox_inches="tight", metadata=_PLOT_METADATA[fmt])
    finally:
        plt.close(fig)


# --------------------------------------------------------------------------------------------
# --profile


@contextmanager
def profiling(enabled: bool) -> Iterator[None]:
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


# --------------------------------------------------------------------------------------------
# --set NAME=VALUE: a method's parameters

_KINDS = (bool, int, float)
"""The types of a field that ``--set`` sets: switches and numbers."""

_WANTED = {bool: "true or false", int: "an integer", float: "a finite number"}

_SWITCH = dict.fromkeys(("true", "1", "yes", "on"), True)
_SWITCH |= dict.fromkeys(("false", "0", "no", "off"), False)
"""The words of a switch's value, any case."""


def _kind(hint) -> tuple[type | None, bool]:
    """The type ``--set`` parses for a field of type ``hint`` (one of :data:`_KINDS`, else
    ``None``) and whether ``None`` is allowed too (``float | None``, ``Optional[int]``)."""
    import types
    import typing

    if hint in _KINDS:
        return hint, False
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        args = typing.get_args(hint)
        rest = [a for a in args if a is not type(None)]
        if len(rest) == 1 and rest[0] in _KINDS and type(None) in args:
            return rest[0], True
    return None, False


def _settable(cls: type, prefix: str = "", groups: dict[str, type] | None = None):
    """Each number and switch of the parameters ``cls`` (a dataclass) by its dotted name,
    with its :func:`_kind`; a field that is itself a dataclass of parameters is a group, its
    own fields named ``GROUP.NAME`` (any depth). Also fills ``groups``: prefix -> class."""
    import dataclasses
    import typing

    groups = {} if groups is None else groups
    groups[prefix] = cls
    hints = typing.get_type_hints(cls)
    kinds: dict[str, tuple[type, bool]] = {}
    for f in dataclasses.fields(cls):
        hint = hints[f.name]
        if isinstance(hint, type) and dataclasses.is_dataclass(hint):
            kinds |= _settable(hint, f"{prefix}{f.name}.", groups)
            continue
        kind, optional = _kind(hint)
        if kind is not None:
            kinds[prefix + f.name] = (kind, optional)
    return kinds


def _parse_value(pair: str, name: str, text: str, kind: type, optional: bool) -> object:
    """The value of ``--set NAME=VALUE`` for a field of type ``kind`` (or ``None``, if
    ``optional`` and ``text`` says none)."""
    import math

    from fhslam.errors import InputError

    if optional and text.lower() == "none":
        return None
    try:
        if kind is bool:
            if text.lower() not in _SWITCH:
                raise ValueError(text)
            return _SWITCH[text.lower()]
        value = kind(text)
        if not math.isfinite(value):
            raise ValueError(text)
        return value
    except ValueError:
        wanted = _WANTED[kind] + (" or none" if optional else "")
        raise InputError(f"--set {pair!r}: {name} takes {wanted}, got {text!r}") from None


def _replaced(params, prefix: str, values: dict[str, object]):
    """``params`` with each of ``values`` under ``prefix`` set (its groups' first), by
    :func:`dataclasses.replace`: their checks run as for a ``params`` made in Python."""
    import dataclasses

    changes = {}
    for f in dataclasses.fields(params):
        key = prefix + f.name
        if key in values:
            changes[f.name] = values[key]
        elif any(k.startswith(key + ".") for k in values):
            changes[f.name] = _replaced(getattr(params, f.name), key + ".", values)
    return dataclasses.replace(params, **changes) if changes else params


def method_params(method: str, pairs: list[str]):
    """The parameters of SLAM method ``method`` (its :attr:`fhslam.pipeline.Method.params_type`,
    e.g. :class:`~fhslam.slam.GraphSlamParams`) of ``--set NAME=VALUE`` options: the
    defaults, with each named number or switch (a field of type bool, int or float, or one
    of those or None) set; ``GROUP.NAME`` names one of a group's, a field that is itself a
    dataclass of parameters (``loops.min_score``, ``extraction.cluster_gap``)."""
    from fhslam.errors import InputError, ParameterError
    from fhslam.pipeline import METHODS

    cls = METHODS[method].params_type
    if cls is None:
        raise InputError(f"--set: the {method} method takes no parameters")
    groups: dict[str, type] = {}
    kinds = _settable(cls, groups=groups)
    values: dict[str, object] = {}
    for pair in pairs:
        name, sep, text = (x.strip() for x in pair.partition("="))
        if not sep or not name or not text:
            raise InputError(f"--set {pair!r}: expected NAME=VALUE or GROUP.NAME=VALUE")
        if name not in kinds:
            named = ", ".join(f"{p}NAME: {c.__name__}" for p, c in groups.items() if p)
            raise InputError(
                f"--set {pair!r}: {name!r} is not a number or switch of {cls.__name__} or of "
                f"its groups ({named}); one of: {', '.join(sorted(kinds))}"
            )
        values[name] = _parse_value(pair, name, text, *kinds[name])
    try:
        return _replaced(cls(), "", values)
    except ParameterError as e:  # out of its range: name the --set that gave it
        keys = [p + e.name for p, c in groups.items() if c.__name__ == e.owner] or [e.name]
        given = [p for p in pairs if p.partition("=")[0].strip() in keys]
        raise InputError(f"--set {given[-1] if given else keys[0]!r}: {e}") from None
    except ValueError as e:
        raise InputError(f"--set: {e}") from None


# --------------------------------------------------------------------------------------------
# --scheduler ADDRESS: the parallel runs on a Dask cluster

SCHEDULER_HELP = (
    "run the parallel runs on the Dask cluster whose scheduler is at ADDRESS (e.g. "
    "tcp://10.0.0.5:8786; its workers need fhslam installed; pip install 'fhslam[cluster]') "
    "instead of this machine's cores"
)


def on_cluster(scheduler: str | None):
    """A context in which joblib's runs go to the Dask scheduler at ``scheduler``
    (:func:`fhslam.experiments.cluster.dask_cluster`), or stay on this machine (``None``)."""
    import contextlib

    if scheduler is None:
        return contextlib.nullcontext()
    from fhslam.experiments.cluster import dask_cluster

    return dask_cluster(scheduler)
