"""Loop 3's map: the reference lines, and the one policy that grows them.

Paper, "Self calibration and map building": "According to the new pose calibrate some new
straight line segments detected and choose some of them as the new referenced straight lines"
and "Mergence of straight lines" (Fig. 11). Given the lines of a scan placed in the world at
the robot's (calibrated) pose and their association with the reference lines (Loop 2,
:meth:`ReferenceMap.associate`), :meth:`ReferenceMap.update`

- merges each matched line into its reference line (:func:`fhslam.matching.merge`) if both
  its endpoints lie within ``max_merge_residual`` of it (a worse pair was a wrong match and
  would corrupt the map);
- adds each unmatched line at least ``min_length`` long and supported by at least
  ``min_points`` scan points as a new reference line ("generally speaking we choose one or
  several longer straight lines").

The paper's step-by-step SLAM (:class:`fhslam.slam.FastHoughSLAM`) updates it scan by scan;
the pose-graph method (:class:`fhslam.slam.GraphFastHoughSLAM`) rebuilds it from its
keyframes at their optimised poses. Both use this one policy.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.geometry import point_segment_distance, signed_distance
from fhslam.lines import Line
from fhslam.matching import MatchParams, match_lines, merge

__all__ = ["ReferenceMap"]


class ReferenceMap:
    """The reference lines of a map (world frame) and the policy that grows them.

    Parameters
    ----------
    matching : MatchParams, optional
        Loop 2's thresholds, used by :meth:`associate`.
    min_length : float
        Shortest unmatched line that becomes a reference line, metres.
    min_points : int
        Fewest scan points supporting such a line.
    max_merge_residual : float
        A matched line is merged only if both its endpoints lie within this distance of the
        reference line, metres.
    """

    def __init__(
        self,
        matching: MatchParams | None = None,
        min_length: float = 0.6,
        min_points: int = 10,
        max_merge_residual: float = 0.05,
    ) -> None:
        self.matching = matching or MatchParams()
        self.min_length = float(min_length)
        self.min_points = int(min_points)
        self.max_merge_residual = float(max_merge_residual)
        self._lines: list[Line] = []
        self._ends = np.zeros((0, 4))  # [sp_x, sp_y, ep_x, ep_y] per reference line

    def __len__(self) -> int:
        return len(self._lines)

    def __getitem__(self, j: int) -> Line:
        return self._lines[j]

    @property
    def lines(self) -> list[Line]:
        """The reference lines (a copy of the list)."""
        return list(self._lines)

    def nearby(self, position: ArrayLike, reach: float) -> NDArray[np.intp]:
        """Indices of the reference lines with a point within ``reach`` of ``position``
        (x, y): the only ones a line seen from there can match (conditions (c) and (d))."""
        if not self._lines:
            return np.zeros(0, dtype=np.intp)
        p = np.asarray(position, dtype=float)[:2]
        dist = point_segment_distance(p, self._ends[:, :2], self._ends[:, 2:])
        return np.flatnonzero(dist <= reach)

    def associate(
        self,
        world: Sequence[Line],
        pose: ArrayLike,
        candidates: NDArray[np.intp] | None = None,
    ) -> NDArray[np.intp]:
        """Loop 2: for each line (world frame, seen from ``pose``) the index of its matching
        reference line, or -1 (:func:`fhslam.matching.match_lines`); only ``candidates``
        (indices, e.g. from :meth:`nearby`) are considered when given."""
        if candidates is None:
            return match_lines(world, self._lines, self.matching, pose)
        refs = [self._lines[j] for j in candidates]
        match = match_lines(world, refs, self.matching, pose)
        if len(candidates):
            match = np.where(match >= 0, candidates[np.maximum(match, 0)], -1)
        return match

    def update(self, world: Sequence[Line], match: ArrayLike) -> int:
        """Merge matched lines into their reference lines, add the long unmatched ones (see
        the module docs); returns how many reference lines were added.

        Parameters
        ----------
        world : sequence of Line
            A scan's lines in the world frame.
        match : array-like of int, shape (len(world),)
            Index of each line's reference line, -1 for none (:meth:`associate`).
        """
        match = np.asarray(match, dtype=np.intp)
        for ln, j in zip(world, match, strict=True):
            if j >= 0:
                ref = self._lines[j]
                off = np.abs(signed_distance(np.array([ln.sp, ln.ep]), ref.rho, ref.theta))
                if off.max() <= self.max_merge_residual:
                    merged = merge(ref, ln)
                    self._lines[j] = merged
                    self._ends[j] = [*merged.sp, *merged.ep]
        new = [
            ln
            for ln, j in zip(world, match, strict=True)
            if j < 0 and ln.length >= self.min_length and ln.n >= self.min_points
        ]
        self._lines.extend(new)
        rows = np.array([[*ln.sp, *ln.ep] for ln in new]).reshape(-1, 4)
        self._ends = np.vstack([self._ends, rows])
        return len(new)
