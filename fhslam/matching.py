"""Loop 2 of the paper: are two feature lines the same wall? and merging them (Figs. 7-11).

Paper, "Match of feature lines": two lines are similar when all four conditions hold:

(a) their observation direction ``dir`` is the same: the robot sees both from the same side;
(b) the intersection angle of the two lines is below a threshold;
(c) the distance from the endpoints of one segment to the other line is below a threshold;
(d) projecting one segment onto the other, the projection has a common part with it.

The tests are made symmetric (``similar(a, b) == similar(b, a)``): (c) takes the largest of
the four endpoint-to-line distances and (d) the smaller of the two projected overlaps. They
are also invariant under a rigid motion of the frame (lines and pose moved together): each
is an angle, a distance or a side, never a difference of ``rho`` or ``theta``. For (a) this
needs care: ``dir`` is measured against the line's own normal, which points away from the
origin, so two observations of a wall through (or near) the origin can have opposite
normals and opposite ``dir`` from the same side. The side is therefore compared as the unit
normal from each line towards the robot, ``-dir n``: (a) holds when
``dir_a dir_b (n_a . n_b) > 0`` (or the robot lies on both lines, ``dir = 0``). For lines
whose normals agree, as the paper's lines away from the origin, this is the paper's
``dir_a == dir_b``.

"Mergence of straight lines" (Fig. 11): the new segment is projected onto the reference
line, the reference is extended to the union of both extents, and the line is refitted with
each segment weighted by its support.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.errors import Range, check_ranges
from fhslam.geometry import (
    as_pose,
    normalize_line,
    observation,
    point_on_line,
    position_on_line,
    tls_normal_angle,
)
from fhslam.lines import Line


@dataclass(frozen=True)
class MatchParams:
    """Thresholds of the four similarity conditions (paper, "Match of feature lines").

    Attributes
    ----------
    max_angle_deg : float
        (b) Largest intersection angle between two similar lines, degrees.
    max_distance : float
        (c) Largest distance from an endpoint of one segment to the other line, metres.
    min_overlap : float
        (d) Smallest common part of a segment's projection and the other segment, metres.
        Negative values also accept segments on the same line separated by a gap up to
        ``-min_overlap`` (a wall seen in pieces).
    """

    max_angle_deg: float = 5.0
    max_distance: float = 0.15
    min_overlap: float = 0.0

    RANGES: ClassVar[dict[str, Range]] = {
        "max_angle_deg": Range(0.0, 90.0, open_low=True, cap=False, unit="degrees"),
        "max_distance": Range(0.0, 100.0, open_low=True, unit="m"),
        "min_overlap": Range(-100.0, 100.0, unit="m"),
    }
    """The range of each number (:class:`fhslam.errors.Range`), checked when the parameters
    are made; "at most": a limit of plausibility."""

    def __post_init__(self) -> None:
        check_ranges(self, self.RANGES)


@dataclass(frozen=True)
class Similarity:
    """Conditions (a)-(d) for one pair of lines, and the numbers behind them."""

    same_direction: bool
    angle_ok: bool
    distance_ok: bool
    overlap_ok: bool
    angle_deg: float
    distance: float
    overlap: float

    @property
    def similar(self) -> bool:
        return self.same_direction and self.angle_ok and self.distance_ok and self.overlap_ok

    def __str__(self) -> str:
        mark = {True: "yes", False: "no "}
        return (
            f"(a) same direction: {mark[self.same_direction]}  "
            f"(b) angle {self.angle_deg:5.1f}°: {mark[self.angle_ok]}  "
            f"(c) distance {self.distance:.3f} m: {mark[self.distance_ok]}  "
            f"(d) overlap {self.overlap:+.3f} m: {mark[self.overlap_ok]}  "
            f"-> {'similar' if self.similar else 'not similar'}"
        )


@dataclass(frozen=True)
class _Segs:
    """Lines as arrays: normals (K, 2), rho (K,), endpoints (K, 2) x2."""

    n: NDArray[np.float64]
    theta: NDArray[np.float64]
    rho: NDArray[np.float64]
    sp: NDArray[np.float64]
    ep: NDArray[np.float64]

    @classmethod
    def of(cls, lines: Sequence[Line]) -> _Segs:
        theta = np.array([ln.theta for ln in lines], dtype=float)
        return cls(
            n=np.column_stack([np.cos(theta), np.sin(theta)]).reshape(-1, 2),
            theta=theta,
            rho=np.array([ln.rho for ln in lines], dtype=float),
            sp=np.array([ln.sp for ln in lines], dtype=float).reshape(-1, 2),
            ep=np.array([ln.ep for ln in lines], dtype=float).reshape(-1, 2),
        )


def _directions(s: _Segs, pose: NDArray[np.float64] | None, lines: Sequence[Line]) -> NDArray:
    if pose is not None:
        return observation(s.rho, s.theta, pose[0], pose[1])[0]
    if any(ln.dir is None for ln in lines):
        raise ValueError("condition (a) needs each line's dir: pass pose=, or lines with dir")
    return np.array([ln.dir for ln in lines], dtype=int)


def _overlap(a: _Segs, b: _Segs) -> NDArray[np.float64]:
    """(A, B) length of the common part of each a-segment projected onto each b-segment."""
    u = np.column_stack([-b.n[:, 1], b.n[:, 0]])  # direction of b
    tb0, tb1 = np.einsum("bk,bk->b", b.sp, u), np.einsum("bk,bk->b", b.ep, u)
    ta0, ta1 = a.sp @ u.T, a.ep @ u.T
    lo = np.maximum(np.minimum(ta0, ta1), np.minimum(tb0, tb1))
    hi = np.minimum(np.maximum(ta0, ta1), np.maximum(tb0, tb1))
    return hi - lo


def similarity_matrix(
    new: Sequence[Line],
    refs: Sequence[Line],
    params: MatchParams | None = None,
    pose: ArrayLike | None = None,
) -> dict[str, NDArray]:
    """Conditions (a)-(d) for every pair (new[i], refs[j]), vectorised.

    Parameters
    ----------
    new, refs : sequence of Line
        Lines in one frame (e.g. the world frame).
    params : MatchParams, optional
    pose : array-like, shape (3,), optional
        Robot pose in that frame for the observation directions; without it each line's own
        ``dir`` is used (each measured against that line's own normal, as
        :meth:`Line.observed_from` gives it).

    Returns
    -------
    dict of ndarray, each shape (len(new), len(refs))
        ``same_direction``, ``angle_ok``, ``distance_ok``, ``overlap_ok``, ``similar`` (bool)
        and ``angle_deg``, ``distance``, ``overlap`` (float).
    """
    params = params or MatchParams()
    p = None if pose is None else as_pose(pose)
    a, b = _Segs.of(new), _Segs.of(refs)
    dir_a, dir_b = _directions(a, p, new), _directions(b, p, refs)
    dot = a.n @ b.n.T
    # (a) the robot on the same side of both lines: the normals towards it, -dir n, agree.
    both_on = (dir_a[:, None] == 0) & (dir_b[None, :] == 0)
    same_side = dir_a[:, None] * dir_b[None, :] * np.sign(dot) > 0
    cos = np.clip(np.abs(dot), 0.0, 1.0)
    angle = np.degrees(np.arccos(cos))
    # (c) all four endpoint-to-other-line distances; the largest decides.
    d_ab = np.maximum(np.abs(a.sp @ b.n.T - b.rho), np.abs(a.ep @ b.n.T - b.rho))
    d_ba = np.maximum(np.abs(b.sp @ a.n.T - a.rho), np.abs(b.ep @ a.n.T - a.rho)).T
    distance = np.maximum(d_ab, d_ba)
    overlap = np.minimum(_overlap(a, b), _overlap(b, a).T)
    out = {
        "same_direction": same_side | both_on,
        "angle_ok": angle <= params.max_angle_deg,
        "distance_ok": distance <= params.max_distance,
        "overlap_ok": overlap >= params.min_overlap,
        "angle_deg": angle,
        "distance": distance,
        "overlap": overlap,
    }
    out["similar"] = (
        out["same_direction"] & out["angle_ok"] & out["distance_ok"] & out["overlap_ok"]
    )
    return out


def similarity(
    a: Line, b: Line, params: MatchParams | None = None, pose: ArrayLike | None = None
) -> Similarity:
    """The per-condition report for one pair of lines (as the paper gives for Figs. 7-10)."""
    m = similarity_matrix([a], [b], params, pose)
    return Similarity(**{k: v[0, 0].item() for k, v in m.items() if k != "similar"})


def similar(
    a: Line, b: Line, params: MatchParams | None = None, pose: ArrayLike | None = None
) -> bool:
    """Whether two lines satisfy all four similarity conditions (a)-(d)."""
    return similarity(a, b, params, pose).similar


def match_lines(
    new: Sequence[Line],
    refs: Sequence[Line],
    params: MatchParams | None = None,
    pose: ArrayLike | None = None,
) -> NDArray[np.intp]:
    """For each new line, the index of its most similar reference line, or -1.

    Among the similar references the one with the smallest ``distance + angle`` (1° counted
    as 1 cm) wins; two new lines may match the same reference (a wall seen in two pieces).
    """
    if not new:
        return np.zeros(0, dtype=np.intp)
    if not refs:
        return np.full(len(new), -1, dtype=np.intp)
    m = similarity_matrix(new, refs, params, pose)
    cost = np.where(m["similar"], m["distance"] + 0.01 * m["angle_deg"], np.inf)
    best = cost.argmin(axis=1)
    return np.where(np.isfinite(cost[np.arange(len(new)), best]), best, -1)


def _moments(line: Line) -> tuple[float, NDArray, NDArray]:
    """Weight, mean and scatter of ``line.n`` points spread evenly along the segment."""
    w = float(max(line.n, 1))
    d = line.ep - line.sp
    return w, 0.5 * (line.sp + line.ep), w * np.outer(d, d) / 12.0


def merge(ref: Line, new: Line) -> Line:
    """Merge a new segment into a similar reference line (paper Fig. 11).

    The line is refitted by total least squares to both segments, each taken as its support
    ``n`` spread evenly along it (so the longer-supported reference moves less); the four
    endpoints are projected onto the refitted line and the result spans their extremes,
    oriented like the reference. For collinear segments the result does not depend on the
    order of merging, and merging a segment already covered changes nothing but ``n``.
    """
    (w1, m1, s1), (w2, m2, s2) = _moments(ref), _moments(new)
    w = w1 + w2
    mean = (w1 * m1 + w2 * m2) / w
    scatter = s1 + s2 + w1 * np.outer(m1 - mean, m1 - mean) + w2 * np.outer(m2 - mean, m2 - mean)
    theta = tls_normal_angle(scatter[0, 0], scatter[1, 1], scatter[0, 1])
    if np.cos(theta - ref.theta) < 0:  # keep the reference's side
        theta += np.pi
    rho, theta = (float(v) for v in normalize_line(mean @ [np.cos(theta), np.sin(theta)], theta))
    t = position_on_line(np.array([ref.sp, ref.ep, new.sp, new.ep]), theta)
    lo, hi = (t.min(), t.max()) if t[0] <= t[1] else (t.max(), t.min())
    sp, ep = point_on_line(rho, theta, np.array([lo, hi]))
    return Line(
        rho=rho,
        theta=theta,
        n=ref.n + new.n,
        length=float(abs(hi - lo)),
        sp=sp,
        ep=ep,
        rms=max(ref.rms, new.rms),
    )
