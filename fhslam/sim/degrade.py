"""Degrade a log as a harsher world would: lost laser messages, clutter returns, range noise;
perturb its odometry in the last bit, as another CPU would; thin it to one scan per metre
or half radian, as published "corrected" logs are (:func:`sparsify`).

:func:`degrade` and :func:`perturb_odometry` work on any :class:`~fhslam.io.log.Log`,
simulated or read from a file; the ground truth and wall hits of a simulated log follow the
kept scans. They make the robustness checks (``fhslam slam LOG --range-noise 0.001``,
``--drop-scans 0.1``, ``--last-bit 1``).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from fhslam.io.log import Log

CLUTTER_MIN_RANGE = 0.3
"""Nearest clutter return, metres (about the closest a person or chair gets to the laser)."""

CLUTTER_MAX_FRACTION = 0.9
"""Farthest clutter return, as a fraction of the beam's own (wall) range."""


def _check_non_negative(name: str, value: float, unit: str = "") -> float:
    what = f"{name} must be a finite number{unit} >= 0, got {value!r}"
    if isinstance(value, bool):
        raise ValueError(what)
    try:
        f = float(value)
    except (TypeError, ValueError):
        raise ValueError(what) from None
    if not (np.isfinite(f) and f >= 0):
        raise ValueError(what)
    return f


def _check_seed(seed) -> int:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a whole number >= 0, got {seed!r}")
    return int(seed)


def _check_fraction(name: str, value: float) -> float:
    if isinstance(value, bool):
        raise ValueError(f"{name} must be a number in [0, 1), got {value!r}")
    try:
        f = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number in [0, 1), got {value!r}") from None
    if not 0.0 <= f < 1.0:  # also rejects NaN
        raise ValueError(f"{name} must be in [0, 1), got {value!r}")
    return f


def check_degradation(
    drop_fraction: float = 0.0,
    clutter_fraction: float = 0.0,
    seed: int = 0,
    range_noise: float = 0.0,
) -> tuple[float, float, int, float]:
    """:func:`degrade`'s arguments checked (and as floats and an int), so that a caller
    about to start many runs can refuse bad ones first; raises as :func:`degrade` does."""
    return (
        _check_fraction("drop_fraction", drop_fraction),
        _check_fraction("clutter_fraction", clutter_fraction),
        _check_seed(seed),
        _check_non_negative("range_noise", range_noise, " of metres"),
    )


def degrade(
    log: Log,
    drop_fraction: float = 0.0,
    clutter_fraction: float = 0.0,
    seed: int = 0,
    resolution: float = 0.001,
    range_noise: float = 0.0,
) -> Log:
    """A copy of ``log`` with scans lost, clutter returns added and noise on the ranges.

    1. **Dropped scans.** ``round(drop_fraction * (T - 1))`` scans (Python's ``round``),
       chosen at random but never the first, are removed entirely: their timestamp, ranges,
       odometry, and (if present) truth and hits rows, as if the laser messages were lost.
       The kept scans keep their own timestamps, so the log has gaps in time.
    2. **Clutter.** In every kept scan, a ``clutter_fraction`` share of the valid beams
       (finite, ``0 < range < max_range``) reads a return short of the wall, as from people
       or chairs: range uniform in ``[0.3 m, 0.9 * r]``, where ``r`` is the beam's range in
       ``log`` (both ends lowered to ``0.9 * r`` if that is below 0.3 m), rounded to
       ``resolution``. Their ``hits`` become -1 (no wall). The number of clutter beams in a
       scan with ``n`` valid beams is ``clutter_fraction * n`` rounded up or down at random
       (up with probability its fractional part), so the share over a log is unbiased.

    3. **Range noise.** Every valid range that is not clutter gets Gaussian noise of standard
       deviation ``range_noise`` metres (not rounded), kept 1 µm inside ``(0, max_range)``:
       a wall stays a return. Drawn for all scans before any are dropped.

    The random choices are fixed by ``seed`` and independent of one another: the noise
    changes no dropped scan or clutter beam, and a larger
    ``drop_fraction`` drops a superset of the scans a smaller one drops, a larger
    ``clutter_fraction`` clutters a superset of the beams, and a beam's clutter range does
    not depend on either fraction. Clutter is drawn for all scans before any are dropped.

    Parameters
    ----------
    log : Log
        The log to degrade; it is not modified.
    drop_fraction : float
        Share of the scans after the first to remove, in [0, 1).
    clutter_fraction : float
        Share of each kept scan's valid beams to turn into clutter, in [0, 1).
    seed : int
        Seed of the random choices.
    resolution : float
        Clutter ranges are rounded to multiples of this, metres (the LMS200's 1 mm); 0 keeps
        them unrounded. Ranges that are neither clutter nor noisy are copied unchanged.
    range_noise : float
        Standard deviation of the noise on the ranges, metres, 0 or more (0: none).

    Returns
    -------
    Log
        A new log with ``T - round(drop_fraction * (T - 1))`` scans, the same ``name``,
        ``angles``, ``max_range`` and ``world``; arrays are copies.

    Raises
    ------
    ValueError
        If a fraction is outside [0, 1) or not a number, ``resolution`` or ``range_noise``
        is negative or not a finite number, or ``seed`` is not a whole number >= 0.
    """
    drop, clutter, seed, sigma = check_degradation(
        drop_fraction, clutter_fraction, seed, range_noise
    )
    if not (np.isfinite(resolution) and resolution >= 0):
        raise ValueError(f"resolution must be >= 0, got {resolution!r}")
    # Three independent streams; the first two are what they were before range noise.
    drop_rng, clutter_rng, noise_rng = (
        np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(3)
    )
    t, b = log.ranges.shape

    # Clutter, drawn for all T scans with every random number used whatever the fractions.
    ranges = log.ranges.copy()
    hits = None if log.hits is None else log.hits.copy()
    keys = clutter_rng.random((t, b))  # beam order of selection: smallest key first
    round_up = clutter_rng.random(t)  # stochastic rounding of the per-scan count
    position = clutter_rng.random((t, b))  # where in [low, high] a clutter return lies
    with np.errstate(invalid="ignore"):
        valid = np.isfinite(ranges) & (ranges > 0) & (ranges < log.max_range)
    count = np.floor(clutter * valid.sum(axis=1) + round_up).astype(np.intp)  # (T,)
    rank = np.argsort(np.argsort(np.where(valid, keys, np.inf), axis=1), axis=1)
    is_clutter = valid & (rank < count[:, None])
    r = ranges[is_clutter]
    high = CLUTTER_MAX_FRACTION * r
    low = np.minimum(CLUTTER_MIN_RANGE, high)
    fake = low + position[is_clutter] * (high - low)
    if resolution > 0:
        # Round to the sensor's step (twice: the second removes float dust); never up to r.
        fake = np.round(np.round(fake / resolution) * resolution, 9)
        fake = np.where(fake >= r, r - resolution, fake)
        fake = np.maximum(fake, resolution)
    ranges[is_clutter] = fake
    if hits is not None:
        hits[is_clutter] = -1

    # Range noise, on every valid beam that is not clutter, inside (0, max_range).
    if sigma > 0:
        noisy = valid & ~is_clutter
        r = ranges[noisy] + noise_rng.normal(0.0, sigma, int(noisy.sum()))
        # the simulator's margin without rounding (fhslam.sim.laser.add_range_noise)
        ranges[noisy] = np.clip(r, 1e-6, log.max_range - 1e-6)

    # Dropped scans: a random order of scans 1..T-1, the first n of which are lost.
    n_drop = round(drop * max(t - 1, 0))
    order = drop_rng.permutation(np.arange(1, max(t, 1)))
    keep = np.ones(t, dtype=bool)
    keep[order[:n_drop]] = False

    return _select(log, keep, ranges, hits)


def _select(log: Log, keep: np.ndarray, ranges: np.ndarray, hits: np.ndarray | None) -> Log:
    """The scans ``keep`` of ``log`` with these ``ranges`` and ``hits``; everything else (the
    laser's mount, its source, the world) is the log's own."""
    return replace(
        log,
        timestamps=log.timestamps[keep].copy(),
        ranges=ranges[keep].copy(),
        angles=log.angles.copy(),
        odometry=log.odometry[keep].copy(),
        truth=None if log.truth is None else log.truth[keep].copy(),
        hits=None if hits is None else hits[keep].copy(),
        angle_offsets=None if log.angle_offsets is None else log.angle_offsets[keep].copy(),
    )


LAST_BIT = 1e-15
"""The relative size of :func:`perturb_odometry`'s change: a few units in the last place of
a double (whose spacing is 2.2e-16 relative)."""


def perturb_odometry(log: Log, seed: int, relative: float = LAST_BIT) -> Log:
    """A copy of ``log`` whose odometry is multiplied by ``1 + relative * ε``, ``ε`` standard
    normal, one per value, drawn with ``seed``.

    With the default ``relative`` this is what the same code on another CPU does (fused
    multiply-adds, other library builds): a result that changes much under it is not
    robust. ``fhslam slam LOG --last-bit SEED`` runs it.

    Raises
    ------
    ValueError
        If ``relative`` is negative or not a finite number, or ``seed`` is not a whole
        number >= 0.
    """
    rel = _check_non_negative("relative", relative)
    seed = _check_seed(seed)
    eps = np.random.default_rng(seed).standard_normal(log.odometry.shape)
    return replace(log, odometry=log.odometry * (1 + rel * eps))


def sparsify(log: Log, distance: float = 1.0, angle: float = 0.5) -> Log:
    """A copy of ``log`` that keeps a scan only when the odometry has moved ``distance``
    metres or turned ``angle`` radians since the last scan kept, as many published
    "corrected" logs are thinned (the first scan is always kept).

    The odometry of the scans kept is the log's own: the motion between two kept scans is
    the odometry integrated over the scans dropped between them.

    Raises
    ------
    ValueError
        If ``distance`` or ``angle`` is not a finite number > 0.
    """
    d = _check_non_negative("distance", distance, " of metres")
    a = _check_non_negative("angle", angle, " of radians")
    if d == 0 or a == 0:
        raise ValueError(f"distance and angle must be > 0, got {distance!r} and {angle!r}")
    odo = log.odometry
    keep = np.zeros(len(odo), dtype=bool)
    last = None
    for i, pose in enumerate(odo):
        if last is not None:
            turn = abs(np.angle(np.exp(1j * (pose[2] - last[2]))))
            if np.hypot(pose[0] - last[0], pose[1] - last[1]) < d and turn < a:
                continue
        keep[i], last = True, pose
    return _select(log, keep, log.ranges, log.hits)
