"""Verified local loop closures of the default SLAM (:class:`~fhslam.slam.GraphFastHoughSLAM`).

A completed keyframe is matched (correlative search, then point-to-line refinement) against
the ``loops.candidates`` old keyframes that looked nearest the same place (the means of
their clouds: driving a corridor back the other way, a 180° laser sees what keyframes a few
metres *ahead* saw); the search radius and window grow with the travel since the last
closure. A match enters the graph only with a fine score of at least ``loops.min_score`` and
``LOOP_MIN_PAIRS`` points on a line within ``LOOP_MAX_RMS``, with a Cauchy kernel; after each
optimisation a closure whose error stays above ``loops.max_chi2`` is switched off.

A closure that would move its keyframe far (``loops.confirm_distance``), or whose match is not
unique, is *held* until another agrees with it: one from a query and against a target that
share no keyframe with its own (one door off in a corridor, a single match looks as good as
the right one, and so does the next query's against the same target), or a unique repeat that
moves the keyframe little, within ``LOOP_REPEAT_CONFIRM``.

The class here is a part of :class:`~fhslam.slam.GraphFastHoughSLAM` (a mixin): it reads
the SLAM's graph, keyframe clouds and paths.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from fhslam.geometry import compose, relative
from fhslam.scanmatch import Refinement, match_clouds, refine, voxel_downsample

__all__ = ["LoopClosing", "LoopClosure"]

# Fixed by the method (measured; not parameters):
LOOP_MAX_WINDOW = 3.0
"""The local search's window grows to at most this, ± metres."""
LOOP_MIN_PAIRS = 50
"""A closure's refinement pairs at least this many query points with a line..."""
LOOP_MAX_RMS = 0.03
"""... at an rms distance of at most this, metres."""
LOOP_KERNEL = 3.0
"""Cauchy kernel scale of loop edges (Mahalanobis units): one at the 95 % bound of a
three-dimensional χ² keeps more than half its weight."""
LOOP_OPTIMIZE_CHI2 = 9.0
"""Closures that already agree with the estimate (squared Mahalanobis error below this, the
97 % bound of a three-dimensional χ²) are added without optimising at once."""
LOOP_CONFIRM_DEG = 3.0
"""A closure that would turn its keyframe more than this (degrees) is held, too."""
LOOP_UNIQUE_RADIUS = 0.3
"""A match is unique when nothing farther than this (metres, in x or y) scores within
``GLOBAL_MAX_AMBIGUITY`` of it; one that is not is held."""
GLOBAL_MAX_AMBIGUITY = 0.8
"""The share of a match's score a runner-up may reach for the match to be unique."""
LOOP_CONSISTENCY_DEG = 2.0
"""Two held closures agree within ``loops.consistency`` metres and this many degrees."""
LOOP_CONFIRM_WINDOW = 10
"""A held closure lapses after this many keyframes without confirmation."""
LOOP_REPEAT_CONFIRM = 0.02
"""Two unique held closures from different queries that move their keyframe by at most three
times ``loops.confirm_distance`` confirm each other when they agree within this (metres; and
0.5 degrees): on a single return to a place no independent closure comes."""


@dataclass(frozen=True, eq=False)
class LoopClosure:
    """An accepted loop closure: keyframe ``new`` seen from the older keyframe ``old``."""

    old: int
    new: int
    pose: NDArray[np.float64]
    score: float
    edge: int = -1
    """Its edge in :attr:`GraphFastHoughSLAM.graph`."""


class HeldClosure(NamedTuple):
    """A local closure waiting for confirmation (:meth:`LoopClosing._confirms`): the closure
    of ``_verified``, whether its match was ambiguous (``LOOP_UNIQUE_RADIUS``) and how far
    (metres) it moves keyframe ``i``."""

    j: int
    i: int
    z: NDArray
    information: NDArray
    score: float
    where: NDArray  # where it puts keyframe i
    ambiguous: bool
    shift: float


class LoopClosing:
    """The local loop-closure search of :class:`~fhslam.slam.GraphFastHoughSLAM` (see the
    module docs)."""

    def _close_loops(self, i: int) -> None:
        """Look for closures of the complete keyframe ``i`` (the global search first, when
        due), add the verified ones, hold or confirm the doubtful ones."""
        p = self.params
        if p.loops.candidates == 0 or i <= p.loops.min_gap:
            return
        poses = self._graph.poses
        drift = p.loops.growth * (self._path[i] - self._last_loop_path)
        if p.search.every and self._far(i) and self._search_globally(i, poses):
            return  # closed: the local search goes on from the next keyframe
        cands = self._candidates(i, poses, min(p.loops.max_radius, p.loops.radius + drift))
        if not cands:
            return
        query = self._submap(i, range(max(0, i - 2), i + 1), poses)[0]
        if len(query) < 10:
            return
        closed, held = self._match_candidates(i, cands, query, poses, drift)
        if closed:
            self._pending = []  # the estimate is confirmed as it stands
        self._pending = [h for h in self._pending if i - h.i <= LOOP_CONFIRM_WINDOW]
        for h in held:
            # an independent one that agrees (or a unique repeat)
            support = [g for g in self._pending if self._confirms(g, h, poses)]
            if support:
                for g in [*support, h]:
                    closed.append(self._add_loop(*g[:5]))
                self._pending = [g for g in self._pending if not any(g is x for x in support)]
            else:
                self._pending.append(h)
        if closed:
            self._end_blind(i, [lc.old for lc in self._loops[-len(closed) :]])
            if self._graph.chi2(np.array(closed)).max() >= LOOP_OPTIMIZE_CHI2:
                self._optimize()

    def _candidates(self, i: int, poses, radius: float) -> list[int]:
        """The old keyframes that looked within ``radius`` of where keyframe ``i``'s query
        (keyframes ``i - 2 .. i``) looks, nearest first; where a keyframe looked is its
        cloud's mean, placed at its pose."""
        p = self.params
        n_old = i - p.loops.min_gap + 1  # keyframes old enough to be candidates
        views = self._looks(poses, i)
        d = np.hypot(*(views[:n_old] - views[max(0, i - 2) :].mean(axis=0)).T)
        order = np.argsort(d, kind="stable")[: p.loops.candidates]
        return [int(j) for j in order if d[j] <= radius]

    def _match_candidates(self, i: int, cands, query, poses, drift: float):
        """Match keyframe ``i``'s ``query`` against each candidate's target: the closures to
        add at once (their edges) and those to hold (:class:`HeldClosure`)."""
        p = self.params
        # Right after a loop closure the pose is known well: search a small window only.
        tracking = bool(self._loops) and self._loops[-1].new == i - 1
        win = p.tracker.window if tracking else min(LOOP_MAX_WINDOW, p.loops.window + drift)
        win_deg = p.tracker.window_deg + 2 if tracking else p.loops.window_deg
        q_refine = voxel_downsample(query, 0.05)
        closed, held = [], []
        for j in cands[:1] if tracking else cands:
            if not tracking and self._failed.get(j) == i - 1:
                continue  # failed for the previous keyframe: tried again the next time
            members = self._target(j, i)
            cached = self.loop_targets.get(
                poses, members, lambda j=j, m=members: self._submap(j, m, poses)
            )
            target = cached.points
            if len(target) < 10:
                continue
            m = match_clouds(
                target, query, relative(poses[j], poses[i]), win, win_deg,
                exclude=None if tracking else (LOOP_UNIQUE_RADIUS, GLOBAL_MAX_AMBIGUITY),
                exclude_min_score=p.loops.min_score,
            )  # fmt: skip
            if m.score < p.loops.min_score:
                self._failed[j] = i
                continue
            ref = refine(self.loop_targets.point_map(cached), q_refine, m.pose)
            c = self._verified(j, i, ref, m.pose, m.score, poses)
            if c is None:
                continue
            move = c[5] - poses[i]  # how far the closure moves keyframe i
            shift, ambiguous = float(np.hypot(move[0], move[1])), bool(m.runner_up > 0)
            if not tracking and (
                ambiguous  # not unique (LOOP_UNIQUE_RADIUS)
                or shift > p.loops.confirm_distance
                or abs(np.degrees(np.angle(np.exp(1j * move[2])))) > LOOP_CONFIRM_DEG
            ):
                held.append(HeldClosure(*c, ambiguous, shift))
                continue
            closed.append(self._add_loop(*c[:5]))
        return closed, held

    def _far(self, i: int) -> bool:
        """Whether keyframe ``i`` lies ``search.after`` metres or more past the last
        closure, so that the global search runs."""
        return self._path[i] - self._last_loop_path >= self.params.search.after

    def _end_blind(self, i: int, olds) -> None:
        """Book keyframe ``i``'s local closures to keyframes ``olds``: they end the blind
        stretch (the travel since the last closure) unless every one of them lies
        ``search.after`` metres or more into it, tying the robot to a place as lost as
        itself."""
        inner = all(self._path[j] - self._last_loop_path >= self.params.search.after for j in olds)
        if not inner:
            self._last_loop_path = self._path[i]

    def _verified(self, j: int, i: int, ref: Refinement, matched, score: float, poses):
        """The closure ``(j, i, z, information, score, where it puts keyframe i)`` from a
        match of keyframe ``i``'s query against ``j``'s target at ``matched``, refined to
        ``ref``; None if the refinement pairs too few points or too loosely. The refined
        pose is taken unless it wandered more than 5 cm from the match."""
        if ref.n_matched < LOOP_MIN_PAIRS or ref.rms > LOOP_MAX_RMS:
            return None
        z = ref.pose if np.hypot(*(ref.pose[:2] - matched[:2])) <= 0.05 else matched
        return j, i, z, self._information(ref, float(z[2])), score, compose(poses[j], z)

    def _add_loop(self, j: int, i: int, z, info, score: float) -> int:
        e = self._graph.add_edge(j, i, z, info, LOOP_KERNEL, kind="loop")
        self._loops.append(LoopClosure(j, i, z, score, e))
        return e

    def _target(self, j: int, i: int, half: int | None = None) -> range:
        """The keyframes of candidate ``j``'s target for keyframe ``i``'s query: ``j`` and
        ``half`` (default ``loops.target_keyframes``) on either side, none within
        ``loops.min_gap`` of ``i``."""
        p = self.params
        k = p.loops.target_keyframes if half is None else half
        return range(max(0, j - k), min(j + k + 1, i - p.loops.min_gap + 1))

    def _independent(self, g, h) -> bool:
        """Whether held closures ``g`` and ``h`` share no keyframe in their queries
        (keyframes ``i - 2 .. i``) nor in the cores of their targets (:meth:`_target` with
        three keyframes on either side; with whole targets of 10 keyframes, two queries
        ``LOOP_CONFIRM_WINDOW`` keyframes apart could never confirm each other)."""
        a, b = self._target(g[0], g[1], 3), self._target(h[0], h[1], 3)
        return abs(g[1] - h[1]) >= 3 and max(a.start, b.start) >= min(a.stop, b.stop)

    def _confirms(self, g: HeldClosure, h: HeldClosure, poses) -> bool:
        """Whether held closure ``g`` confirms held closure ``h``: independent of it and
        agreeing within ``loops.consistency``; or both unique, neither moving its keyframe
        more than three times ``loops.confirm_distance``, from different queries, and
        agreeing within ``LOOP_REPEAT_CONFIRM`` metres and 0.5 degrees."""
        if self._independent(g, h) and self._agree(g, h, poses):
            return True
        return (
            not (g.ambiguous or h.ambiguous)
            and max(g.shift, h.shift) <= 3 * self.params.loops.confirm_distance
            and g.i != h.i
            and self._agree(g, h, poses, (LOOP_REPEAT_CONFIRM, 0.5))
        )

    def _agree(self, g, h, poses, tol=None) -> bool:
        """Whether held closures ``g`` and ``h`` place keyframe ``h``'s ``i`` alike (``g``'s
        placement carried along the graph): within ``tol`` (metres, degrees; default
        ``loops.consistency``, ``LOOP_CONSISTENCY_DEG``)."""
        dist, deg = tol or (self.params.loops.consistency, LOOP_CONSISTENCY_DEG)
        carried = compose(g[5], relative(poses[g[1]], poses[h[1]]))
        d = carried - h[5]
        return bool(
            np.hypot(d[0], d[1]) <= dist and abs(np.degrees(np.angle(np.exp(1j * d[2])))) <= deg
        )
