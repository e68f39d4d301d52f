"""Line-detection scores against the simulator's true walls.

After Nguyen, Gächter, Martinelli, Tomatis and Siegwart, "A comparison of line extraction
algorithms using 2D laser rangefinder for indoor mobile robotics", IROS 2005, Table II:

- **TruePos** = matched lines / true lines,
- **FalsePos** = (extracted lines - matched lines) / extracted lines,
- **rms Δρ**, **rms Δθ** over the matched pairs, in the sensor frame.

A *true line* is a run of consecutive beams that hit the same wall (a wall hidden in part by
an obstacle gives two true lines), with at least ``min_hits`` beams. Runs with fewer beams
are "don't care": a line on one of them counts neither as a hit nor as a false positive,
so extractors with a lower support threshold are not penalised for finding them.

An extracted line *matches* the true line that holds the majority of its supporting beams
(at least ``min_share``), if its (ρ, θ) lies within ``max_drho`` / ``max_dtheta_deg`` of
the true wall. Each true line matches at most one extracted line (the best supported);
further lines on it are false positives (a split wall).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from fhslam.lines import Line


class HessianLine(Protocol):
    """A true line in Hessian form, e.g. :class:`fhslam.sim.TrueLine`."""

    @property
    def rho(self) -> float: ...

    @property
    def theta(self) -> float: ...


@dataclass(frozen=True)
class DetectionScores:
    """Nguyen et al. (2005) line-detection scores over a set of scans."""

    true_pos_rate: float
    false_pos_rate: float
    rms_drho: float
    rms_dtheta_deg: float
    n_true: int
    n_found: int
    n_matched: int
    n_ignored: int

    def as_dict(self) -> dict[str, float | int]:
        return dict(self.__dict__)


def line_difference(
    rho_a: float, theta_a: float, rho_b: float, theta_b: float
) -> tuple[float, float]:
    """Distance |Δρ| (m) and angle |Δθ| (rad, in [0, pi/2]) between two lines in Hessian form.

    Handles the ambiguity of a line through (or near) the origin, where ``(ρ, θ)`` and
    ``(-ρ, θ + pi)`` are the same line.
    """
    d = np.mod(theta_a - theta_b + np.pi, 2 * np.pi) - np.pi
    if abs(d) <= np.pi / 2:
        return abs(rho_a - rho_b), abs(d)
    return abs(rho_a + rho_b), np.pi - abs(d)


@dataclass
class _Tally:
    n_true: int = 0
    n_found: int = 0
    n_matched: int = 0
    n_ignored: int = 0

    def __post_init__(self) -> None:
        self.drho: list[float] = []
        self.dtheta: list[float] = []


def match_scan(
    lines: Sequence[Line],
    beams: ArrayLike,
    truth: Sequence[HessianLine],
    run_of_beam: ArrayLike,
    max_drho: float = 0.10,
    max_dtheta_deg: float = 5.0,
    min_share: float = 0.5,
) -> list[int | None]:
    """Match the lines extracted from one scan to its true lines.

    Parameters
    ----------
    lines : sequence of Line
        Extracted lines, in the laser frame, with ``inliers`` indexing the scan's points.
    beams : array-like of int, shape (N,)
        Beam index of every point (from :func:`fhslam.scan.scan_to_points`).
    truth, run_of_beam
        From :func:`fhslam.sim.true_lines`.

    Returns
    -------
    list
        Per extracted line: the index of its true line, ``-1`` for "don't care" (a short
        run), or ``None`` for a false positive.
    """
    b = np.asarray(beams, dtype=np.intp)
    rob = np.asarray(run_of_beam, dtype=np.intp)
    result: list[int | None] = [None] * len(lines)
    candidates = []
    for i, line in enumerate(lines):
        runs = rob[b[line.inliers]]
        if len(runs) == 0:
            continue
        values, counts = np.unique(runs, return_counts=True)
        k = int(np.argmax(counts))
        run, share = int(values[k]), counts[k] / len(runs)
        if share < min_share or run == -1:
            continue
        if run == -2:
            result[i] = -1
            continue
        drho, dth = line_difference(line.rho, line.theta, truth[run].rho, truth[run].theta)
        if drho <= max_drho and np.degrees(dth) <= max_dtheta_deg:
            candidates.append((int(counts[k]), i, run))
    taken: set[int] = set()
    for _count, i, run in sorted(candidates, key=lambda c: (-c[0], c[1])):
        if run not in taken:
            taken.add(run)
            result[i] = run
    return result


def detection_scores(
    scans: Iterable[tuple[Sequence[Line], ArrayLike, Sequence[HessianLine], ArrayLike]],
    **match_kwargs: float,
) -> DetectionScores:
    """Nguyen et al. (2005) scores over scans given as ``(lines, beams, truth, run_of_beam)``."""
    t = _Tally()
    for lines, beams, truth, rob in scans:
        res = match_scan(lines, beams, truth, rob, **match_kwargs)
        t.n_true += len(truth)
        t.n_ignored += sum(r == -1 for r in res)
        t.n_found += sum(r != -1 for r in res)
        for line, r in zip(lines, res, strict=True):
            if r is not None and r >= 0:
                t.n_matched += 1
                drho, dth = line_difference(line.rho, line.theta, truth[r].rho, truth[r].theta)
                t.drho.append(drho)
                t.dtheta.append(dth)
    return DetectionScores(
        true_pos_rate=t.n_matched / t.n_true if t.n_true else float("nan"),
        false_pos_rate=(t.n_found - t.n_matched) / t.n_found if t.n_found else 0.0,
        rms_drho=float(np.sqrt(np.mean(np.square(t.drho)))) if t.drho else float("nan"),
        rms_dtheta_deg=float(np.degrees(np.sqrt(np.mean(np.square(t.dtheta)))))
        if t.dtheta
        else float("nan"),
        n_true=t.n_true,
        n_found=t.n_found,
        n_matched=t.n_matched,
        n_ignored=t.n_ignored,
    )
