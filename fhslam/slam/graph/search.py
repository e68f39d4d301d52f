"""The global search of the default SLAM (:class:`~fhslam.slam.GraphFastHoughSLAM`).

Once the robot has travelled ``search.after`` metres without a loop closure, every
``search.every`` keyframes the last ``search.keyframes`` keyframes' clouds are matched
(branch and bound over the coarse grid, then the fine grid) against the clouds of every
keyframe at least ``search.after`` metres of travel older, within a window that grows with
the travel since the last closure (``loops.growth``; at least 3 m, at most
``search.max_window``) and ``± search.window_deg`` around a guess: the graph's estimate, once
the local search no longer reaches (its radius at ``loops.max_radius``), and where the
odometry since the last closure puts the robot (a tracker fooled among people does not fool
the odometry), if that lies more than half a window away.

A match is taken only if it scores at least ``search.min_score``, is unique (nothing more
than ``loops.window`` metres away scores over ``GLOBAL_MAX_AMBIGUITY`` of it) and refines
point-to-line like a local closure; and then only as a hypothesis, until the match of a
query that shares no keyframe with its own agrees with it (within ``GLOBAL_CONSISTENCY``
metres and ``GLOBAL_CONSISTENCY_DEG`` degrees) scoring at least ``search.confirm_score``;
both then enter the graph. After a closure that ended ``L`` metres without one, the search
goes on as if still ``L`` metres out for the next ``GLOBAL_LOOKBACK × L`` metres: the old map
around the place found may be bent, and the next old place may lie far off.

The class here is a part of :class:`~fhslam.slam.GraphFastHoughSLAM` (a mixin).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from fhslam.geometry import compose, relative
from fhslam.scanmatch import PointMap, match_clouds, refine, voxel_downsample
from fhslam.slam.graph.closure import GLOBAL_MAX_AMBIGUITY, LOOP_MAX_WINDOW, LOOP_OPTIMIZE_CHI2

__all__ = ["GlobalSearch"]

# Fixed by the method (measured; not parameters):
GLOBAL_CONSISTENCY = 0.3
"""How far (metres) the match that confirms a hypothesis may place its keyframe from where
the hypothesis does: after a long blind stretch both hit an old map that may be bent."""
GLOBAL_CONSISTENCY_DEG = 3.0
"""... and how far in heading, degrees."""
GLOBAL_LOOKBACK = 1.0
"""After a global closure that ended ``L`` metres without one, the search stays as wide for
``GLOBAL_LOOKBACK × L`` metres more."""


class GlobalSearch:
    """The global search of :class:`~fhslam.slam.GraphFastHoughSLAM` (see the module
    docs)."""

    def _search_globally(self, i: int, poses) -> bool:
        """The global search (see ``search.every``): a match is held as a hypothesis until a
        match from a query that shares no keyframe with its own agrees with it; then both
        enter the graph, it is optimised, and True is returned."""
        p = self.params
        h = self._hypothesis
        if h is not None and i - h[1] > p.search.keyframes + p.search.every:
            h = self._hypothesis = None  # not confirmed in time
        if h is None and i - self._last_global < p.search.every:
            return False
        if h is not None and i - h[1] < p.search.keyframes:
            return False  # the next query must share no keyframe with the hypothesis's
        self._last_global = i
        # a hypothesis is confirmed by a match that agrees with it at the lower score
        low = p.search.min_score if h is None else min(p.search.min_score, p.search.confirm_score)
        g = self._global_match(i, poses, low)
        if g is None:
            return False
        tol = (GLOBAL_CONSISTENCY, GLOBAL_CONSISTENCY_DEG)
        if h is None or not self._agree(h, g, poses, tol):
            if g[4] >= p.search.min_score:
                self._hypothesis = g
            return False
        self._hypothesis = None
        closed = [self._add_loop(*x[:5]) for x in (h, g)]
        blind = self._path[i] - self._last_loop_path
        if not (self._path[i] < self._blind[1] and self._blind[0] > blind):
            self._blind = (blind, self._path[i] + GLOBAL_LOOKBACK * blind)
        self._last_loop_path = self._path[i]
        self._pending = []
        if self._graph.chi2(np.array(closed)).max() >= LOOP_OPTIMIZE_CHI2:
            self._optimize()
        return True

    def _travelled(self, i: int) -> float:
        """Metres the global search counts as travelled since the last closure at keyframe
        ``i`` (``GLOBAL_LOOKBACK``: at least the blind stretch the last global closure ended,
        while its look-back lasts)."""
        d = self._path[i] - self._last_loop_path
        blind, until = self._blind
        return max(d, blind) if self._path[i] < until else d

    def _global_guesses(self, i: int, poses, win: float) -> list[NDArray[np.float64]]:
        """Where the global search looks for keyframe ``i`` (its pose in its own frame):
        the graph's estimate, once the local search no longer reaches far enough (its radius
        at ``loops.max_radius``), and where the odometry since the last closure puts it (the
        keyframe at the last closure moved by the odometry's motion since), unless that
        lies within half the window of the estimate."""
        p = self.params
        reach = (p.loops.max_radius - p.loops.radius) / p.loops.growth
        local = self._travelled(i) < reach  # the local search still grows
        guesses = [] if local else [np.zeros(3)]
        a = int(np.searchsorted(self._path[: i + 1], self._last_loop_path))
        odo = compose(poses[a], relative(self._kf_odometry[a], self._kf_odometry[i]))
        g = relative(poses[i], odo)
        if np.hypot(g[0], g[1]) > win / 2 or abs(np.degrees(g[2])) > p.search.window_deg / 2:
            guesses.append(g)
        return guesses

    def _global_match(self, i: int, poses, min_score: float):
        """Match the last ``search.keyframes`` keyframes up to ``i`` against all keyframes
        ``search.after`` metres of travel older, around each guess in turn (see
        ``search.every``); returns a closure ``(j, i, z, information, score, where it puts
        keyframe i)`` or None."""
        p = self.params
        path = np.asarray(self._path[: i + 1])
        older = np.flatnonzero(path <= path[i] - p.search.after)
        travelled = self._travelled(i)
        win = min(p.search.max_window, max(LOOP_MAX_WINDOW, p.loops.growth * travelled))
        views = self._looks(poses, i)
        looks = [*views[max(0, i - 2) :].mean(axis=0), 0.0]  # where the query looks
        query = self._submap(i, range(max(0, i - p.search.keyframes + 1), i + 1), poses)[0]
        if len(query) < 10:
            return None
        for guess in self._global_guesses(i, poses, win):
            at = compose(compose(poses[i], guess), relative(poses[i], looks))[:2]
            old = older[np.hypot(*(views[older] - at).T) <= win + p.keyframes.max_range]
            if not len(old):
                continue
            target = voxel_downsample(self._submap(i, old, poses)[0], 0.05)
            if len(target) < 10:
                continue
            m = match_clouds(
                target, query, guess, win, p.search.window_deg, prior=(0.0, 0.0),
                exclude=(p.loops.window, GLOBAL_MAX_AMBIGUITY), min_coarse=min_score,
            )  # fmt: skip
            if m.score >= min_score and m.runner_up <= 0:
                break  # else: too low, or not unique
        else:
            return None
        # The closure's old keyframe: the one that looked nearest where the query looks, at
        # the match; refined against the old keyframes around it, in its frame.
        placed = compose(compose(poses[i], m.pose), relative(poses[i], looks))[:2]
        near = np.hypot(*(views[old] - placed).T)
        j = int(old[np.argmin(near)])
        if near.min() > p.keyframes.max_range:
            return None  # placed where no old keyframe looked
        pts, nrm = self._submap(j, old[near <= p.keyframes.max_range], poses)
        guess = relative(poses[j], compose(poses[i], m.pose))
        ref = refine(PointMap.build(pts, nrm), voxel_downsample(query, 0.05), guess)
        return self._verified(j, i, ref, guess, m.score, poses)
