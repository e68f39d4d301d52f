"""Pose-graph SLAM with a map of fast Hough lines: the package's default method.

On a simulated world the paper's step-by-step calibration keeps the pose within centimetres
(:mod:`fhslam.slam.fht`). Real logs need more: odometry that glitches (a 85° heading jump
between two scans), rooms visited again after hundreds of metres, clutter that no straight
line describes. What this module adds, each measured (see :class:`GraphSlamParams`):

1. **Scan-to-map tracking** (:mod:`fhslam.slam.tracker`): every scan is placed against the
   points of the last ``submap_keyframes`` keyframes by an exhaustive correlative search
   around the odometry prediction, refined point-to-line; a search around the previous pose
   competes when the odometry looks wrong.
2. **Keyframes.** Every ``keyframe_distance`` metres or ``keyframe_angle_deg`` degrees of
   travel a keyframe starts; the scans until the next one are attached to it with their
   tracked poses relative to it, and their points form its cloud. The keyframe's fast Hough
   lines (Loop 1) are kept for the map.
3. **Edges weighted by their information.** An edge between consecutive keyframes carries
   the point-to-line refinement's information (its 3 x 3 Hessian, scaled to
   ``edge_points`` independent points of ``edge_sigma``) plus a weak odometry prior; in a
   corridor the scan constrains nothing along the axis and the edge says so. An edge across
   a doubtful scan carries the odometry alone: its information and its measurement, the
   odometry's motion between the two keyframes (not the doubtful track's), unless the
   odometry glitched on the way.
4. **Verified loop closures.** A completed keyframe is matched (correlative search, then
   point-to-line refinement) against up to ``loop_candidates`` old keyframes that looked at
   the same place (the means of their clouds, nearest the mean of the query's: driving a
   corridor back the other way, a 180° laser sees what keyframes a few metres *ahead* saw);
   the search radius and window grow with the distance travelled since the last closure. A
   match enters the graph only with a fine score of at least ``loop_min_score`` and at least
   ``loop_min_pairs`` points on a line within ``loop_max_rms``, with a Cauchy kernel; after each
   optimisation a closure whose error stays above ``loop_max_chi2`` (Mahalanobis) is
   switched off and the graph optimised again, so a few wrong closures cannot bend the
   trajectory. A closure that would move its keyframe far (``loop_confirm_distance``) waits
   until an independent one agrees with it, from a query and against a target that share no
   keyframe with its own: one door off in a corridor, or a corridor's width off where a
   corridor meets its start again, a single match looks as good as the right one, and so does
   the next query's against the same target.
5. **A global search** (``global_every``): the last few keyframes are matched against
   every old keyframe within a window that grows with the distance since the last closure,
   by branch and bound, around where the odometry since the last closure puts the robot
   (from ``global_after`` metres without a closure on: a tracker fooled among people does
   not fool the odometry) and, once the local search no longer reaches, around the graph's
   estimate (an odometry that glitched does not fool the tracker); a match must be unique
   and is held until a second one, from a query that shares no keyframe with it, agrees
   (the second may score less: a hypothesis is easier to confirm than to find). After a
   global closure that ended a long blind stretch the search stays as wide for as far again:
   the old map around the place found may be bent, and the next old place may lie far off.
6. **The map of reference lines** is built at the end by Loop 2 itself: each keyframe's fast
   Hough lines, placed at its optimised pose, are matched with and merged into the map
   (Fig. 11) - the paper's map, from better poses.

Each scan's pose is its keyframe's optimised pose composed with the scan's tracked pose
relative to the keyframe.

**Two threads.** The front end (tracking, keyframes, their clouds and lines) never reads the
graph: it tracks in its own frame. So the back end (adding each keyframe to the graph, its
loop closures, the optimisations) runs on a thread of its own, a keyframe behind, while the
front end tracks the next scans; the compiled kernels release the GIL, so on two cores the
halves overlap. The back end gets the same calls in the same order either way, and the
results are the same bit for bit (``background=False`` runs it in turn).

``fhslam slam LOG`` runs it (``method="graph"`` in :func:`fhslam.pipeline.run_slam`);
``method="fht"`` stays the paper's procedure.
"""

from __future__ import annotations

import contextlib
import queue
import threading
import weakref
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import ClassVar, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.errors import ParameterError, Range, check_ranges
from fhslam.extraction import extract_lines
from fhslam.geometry import as_pose, compose, inverse, relative, transform_points
from fhslam.lines import Line, transform_lines
from fhslam.posegraph import PoseGraph
from fhslam.reference_map import ReferenceMap
from fhslam.scan import Scan
from fhslam.scanmatch import (
    PointMap,
    Refinement,
    densify,
    match_clouds,
    refine,
    scan_normals,
    smooth_scan,
    voxel_downsample,
    voxel_index,
)
from fhslam.slam.base import FinalEstimate, StepResult
from fhslam.slam.fht import SlamParams
from fhslam.slam.tracker import ScanTracker, TrackerParams

__all__ = ["GraphFastHoughSLAM", "GraphSlamParams", "LoopClosure"]


@dataclass(frozen=True)
class GraphSlamParams:
    """Parameters of :class:`GraphFastHoughSLAM` (see the module docs).

    Attributes
    ----------
    tracker : TrackerParams
        Scan-to-map tracking.
    lines : SlamParams
        The paper's Loops 1 and 2: each keyframe's line extraction, and matching and merging
        of the map of reference lines.
    keyframe_distance : float
        Start a keyframe after this much travel, metres...
    keyframe_angle_deg : float
        ... or this much turning, degrees.
    cloud_max_range : float
        Points farther than this from the laser (metres) are not used.
    cloud_voxel : float
        A keyframe's cloud keeps one point per cell of this size, metres.
    smooth_clouds : bool
        Move each scan's points onto the line of their seven beam neighbours
        (:func:`fhslam.scanmatch.smooth_scan`, straight surfaces only) before they enter a
        keyframe's cloud, so that the range noise across a wall is averaged out of the map the scans
        are tracked against (not out of the scans themselves). It cuts the tracker's heading drift
        along straight corridors severalfold (96 m of the ``campus``'s corridor with perfect
        odometry and the simulator's 1 cm of range noise, seeds 0-3: 2.3-2.8 degrees and 1.9-2.4 m
        sideways at its end without, 0.5-0.86 degrees and 0.45-0.6 m with it; the ``ring``'s first
        straight 0.8-1.25 degrees, -0.03 to 0.48 with it). It needs ``global_consistency`` and
        ``loop_unique_radius``: with ``global_consistency`` at the local closures' 0.15 m the
        Freiburg hospital's return failed with it in 4 of 33 perturbed runs (3 without it), and
        without ``loop_unique_radius`` the harsh pillared hall came out at 5.77 cm (0.82 without
        it). With both, the default: all 32 perturbed hospital runs within the robustness bound (31
        with neither it nor ``loop_unique_radius``), the five shared logs within 1.5 %, and the
        120-run simulated yardstick (the ``paper``, ``offices``, ``hall``, ``corridor``,
        ``random:109`` and ``random:105`` worlds, seeds 0-4, clean and with 1 mm of range noise and
        10 % of the scans dropped, each also with its odometry perturbed in the last bit) at a mean
        of 1.11 cm (1.25 with neither).
    corner_deg : float
        The points filled in between two beams (:func:`fhslam.scanmatch.densify`) across
        a chord that turns by more than this from both neighbouring chords, degrees, get
        no normal: they cut a corner, and lie behind a convex one (in front of a concave
        one) by up to centimetres where the beams are far apart. The correlative search
        still scores them; the point-to-line refinements against keyframe clouds
        (tracking, pairs, loop closures) leave them out (the tracker's fallback against the
        previous scan, filled in as it goes, keeps them). 0, the default: every filled
        point keeps its chord's normal. Along the ``ring``'s corridors 20 takes most of the
        tracker's forward push out (the scale 0.20-0.24 % large -> 0.01-0.09 %), but the simulated
        yardstick and two of the shared logs lose, and the Freiburg hospital's return is missed in
        22 of its 30 perturbed runs.
    submap_keyframes : int
        Keyframes in the local map a scan is tracked against.
    max_doubtful : int
        A scan the tracker is not sure of (:attr:`fhslam.slam.tracker.Track.sure`) starts
        no keyframe, unless this many in a row were doubtful (new ground); an edge across a
        doubtful scan carries only the odometry prior.
    edge_sigma : float
        Standard deviation of a point-to-line distance, metres...
    edge_points : float
        ... and the number of independent points an edge's information counts: the
        refinement's Hessian is scaled to ``edge_points / (n · edge_sigma²)``.
    odometry_sigma : (float, float)
        The odometry prior added to each edge between consecutive keyframes: metres, degrees.
    pair_edges : bool
        Also join consecutive keyframes by two more edges, one each way: keyframe ``k``'s
        cloud refined against ``k - 1``'s, and ``k - 1``'s against ``k``'s (point-to-line
        from the tracked relative pose, each with its own information about the
        translation, :meth:`_pair_edges`; not where either keyframe's scans were doubtful,
        as the tracker's edge then carries the odometry alone). The tracker's edge places a
        scan against a map seen from behind it, and a map's filled points cut an alcove's
        or a door's corners from where it was seen: with range noise that pushes each
        keyframe a little ahead along a corridor, the same way every time, a scale that no
        loop closure can see (the ``ring``: its trajectory 0.20-0.26 % too large). Matched
        the other way round, the push is backwards, and somewhat larger (the 180° laser
        looks ahead in both clouds): with the tracker's edge the two balance it, measured,
        not derived: the ``ring`` (2 laps, seeds 0-3) 9.3, 10.9, 9.8, 9.6 cm -> 3.0, 1.8,
        5.8, 10.1 cm, its scale within 0.034 % (seed 3's error is a turn). Off by default: the
        shared logs and the Freiburg hospital's 32 perturbed runs hold with it, but the paper world
        loses (3 of the 120 simulated yardstick runs over 3 cm, none without). Each edge carries all
        of its information, unless ``pair_share``.
    pair_share : bool
        With ``pair_edges``: the tracker's edge and the pair edges made for the same two
        keyframes share the scans' information about the translation instead of each
        carrying all of it (they come from the same scans): with both pair edges, each of
        the three carries a third (the tracker's edge its odometry prior and heading in
        full), so that the graph weighs the scans against the loop closures as without
        pairs. The paper world's pairs repeat the tracker's errors where the scans mislead (after a
        turn, 2-5 cm at a few keyframes), and counted three times those outweighed the loop
        closures; shared, the 120-run simulated yardstick has 1 run over 3 cm (3 unshared, none
        without pairs) at a mean of 0.999 cm (1.082 unshared, 1.015 without), the ``ring`` (seeds
        0-3) 3.6, 3.6, 2.9, 7.5 cm; but the Freiburg hospital's dropped-scans seed 11 misses its
        return (2.09 m; the other 13 and the 16 runs with 1 mm of noise hold; unshared all 32 hold).
        Off by default.
    loop_radius : float
        Old keyframes that looked within this distance of where the keyframe looks are loop
        candidates (where a keyframe looks: the mean of its cloud, placed at the current
        estimate; the query's, of keyframes ``i - 2 .. i``, is the mean of theirs)...
    loop_growth : float
        ... plus this fraction of the distance travelled since the last closure (the drift
        since then), up to ``loop_max_radius``.
    loop_max_radius : float
        See ``loop_growth``.
    loop_min_gap : int
        Candidates are at least this many keyframes older.
    loop_target_keyframes : int
        A candidate ``j``'s target is the cloud of keyframes ``j - loop_target_keyframes ..
        j + loop_target_keyframes`` (none within ``loop_min_gap`` of the query), about 6 m
        of travel at 6. It should cover what the query sees: a query that overlaps its
        target only in part can score higher shifted along a corridor, so that more of it
        falls on the target's walls. On the ``campus``, coming down one corridor onto another it
        had driven before, the queries matched ± 3 keyframes 2.5 m off (the crossing corridor's
        width; 0.72 against 0.55 at the true pose) and every later closure inherited the shift.
        With ± 6 (the default), seeds 0-4 give 0.33, 0.46, 0.47, 5.64 and 0.45 m (± 3: 7.78,
        0.38, 7.60, 6.83, 0.34 m): not a cure, both hypotheses can still score alike. The
        Freiburg hospital's 32 perturbed runs (noise, dropped scans, both) all stay within the
        robustness bound (as with ± 3; without the global search's consistency test, ± 6 failed
        6 of 33), the 120-run simulated yardstick comes to a mean of 1.05 cm with 2 runs over 3
        cm (± 3: 1.11 cm, 5), and the shared logs within 1 %.
    loop_candidates : int
        Nearest candidates tried per keyframe. Chosen by where the keyframes stood instead
        of where they looked, a corridor driven back the other way (the ``offices`` world)
        closed once instead of 22 times (ATE 3.78 cm instead of 2.28; seeds 0-5, own frame
        and moved: 6 of 12 runs over 3 cm instead of none), and MIT CSAIL gave 0.0281 m
        instead of 0.0266 m.
    loop_skip_repeats : bool
        A candidate whose match scored under ``loop_min_score`` for the previous keyframe is
        not tried again for this one (it is the next time): the query shares two of its three
        keyframes with the previous one's. On MIT CSAIL 269 of the 585 failed searches
        repeated the previous keyframe's; skipping every other repeat changed no relation
        error by more than 1 % on the shared logs.
    loop_window : float
        Search window of a loop closure, ± metres (plus ``loop_growth`` of the distance
        travelled since the last closure, up to ``loop_max_window``)...
    loop_max_window : float
        See ``loop_window``.
    loop_window_deg : float
        ... and ± degrees.
    loop_min_score : float
        Smallest fine-grid score (mean likelihood of the query points, 0..1) accepted...
    loop_min_pairs : int
        ... with at least this many query points paired with a line by the refinement...
    loop_max_rms : float
        ... at an rms distance of at most this, metres.
    loop_kernel : float
        Cauchy kernel scale of loop edges (Mahalanobis units): a closure whose squared
        error is ``loop_kernel²`` gets half weight. At 3, one at the 95 % bound of a
        three-dimensional χ² (7.8) keeps more than half; at 1 even a correct closure one
        standard deviation off lost half its pull, and ACES's revisit after 70 minutes
        stayed 1.1-1.3 m apart (0.0465 m; 0.0346 m at 3, also with noise, dropped scans
        and last-bit noise).
    loop_max_chi2 : float
        After an optimisation, a loop edge whose squared Mahalanobis error exceeds this is
        switched off.
    loop_optimize_chi2 : float
        Closures that already agree with the estimate (each squared Mahalanobis error below
        this) are added without optimising: the optimisation would hardly move a pose, and
        the next one (at the latest in :meth:`GraphFastHoughSLAM.finish`) includes them.
        Optimisations on Intel at 0, 1 and 9 (0 optimises after every closure): 593, 239 and
        80, each time 0.0143 m; on MIT CSAIL at 1 and 9: 88 and 28, each time 0.0266 m
        (every shared log's relation error within 1 %, also under last-bit noise). 9 is
        about the 97 % bound of a three-dimensional χ².
    loop_confirm_distance : float
        A closure that would move its keyframe by more than this (metres)... With 0.3 m the
        pillared hall (``hall``, 1 mm of range noise, 10 % of the scans dropped) came back
        to its start with its estimate within 2 cm, and a single closure against the first
        keyframes, 11-24 cm off (scores about 0.56: at the start a target has no keyframes
        before it), moved it there unchecked for six of eight last-bit draws: ATE 6-12 cm
        instead of 0.9. With 0.1 m it waits, and no shared log's relation error changed by
        more than 1.5 %, also with range noise, dropped scans or last-bit noise.
    loop_confirm_deg : float
        ... or turn it by more than this (degrees) is held until an independent closure
        within ``loop_confirm_window`` keyframes agrees: its query shares no keyframe with
        this one's, nor its target's core with this one's (:meth:`GraphFastHoughSLAM.
        _independent`), and carried along the graph to the same keyframe, the two place it
        within ``loop_consistency`` metres and ``loop_consistency_deg`` degrees. A corridor
        lined with doors matches as well one door further, and so does the next keyframe's
        query, which shares two thirds of its points (MIT CSAIL: the relation error no longer
        turns on the last bit). Where a corridor ring comes back to its start, two queries
        apart matched the *same* start keyframes a corridor's width off, alike (scores 0.55
        and 0.72, 3.5 m off): a closure against the same target is no independent
        evidence.
    loop_unique_radius : float
        ... and a closure that would move it less is added at once only if its match is unique:
        nothing farther than this (metres, in x or y) from the match scores within
        ``global_max_ambiguity`` of it (:attr:`fhslam.scanmatch.MatchResult.runner_up`);
        otherwise it is held as above. 0 leaves the test out. ``smooth_clouds`` needs it (0.3,
        the default): the harsh pillared hall (``hall`` seed 0, 1 mm of range noise, 10 % of the
        scans dropped) comes back to its start, where its last keyframe matches the first ones
        along the pillar rows 11 cm, 78 cm and (without ``smooth_clouds``) 159 cm off, refined
        each to a residual under 1 cm. Without ``smooth_clouds`` the nearest of those moves the
        keyframe more than 0.1 m and waits; with it 11 cm off moves it less and, without this
        test, enters the graph unconfirmed and bends the run to an ATE of 5.77 cm (0.95 cm with
        it).
    loop_consistency : float
        See ``loop_confirm_deg``.
    loop_consistency_deg : float
        See ``loop_confirm_deg``.
    loop_confirm_window : int
        See ``loop_confirm_deg``.
    loop_repeat_confirm : float
        0 leaves this out. Above 0 (0.02, the default), a held closure whose
        match is unique (see ``loop_unique_radius``) and that moves its keyframe by at most
        three times ``loop_confirm_distance`` is also confirmed by another such closure from
        another keyframe's query, against the same target or not, when the two place the
        keyframe within this many metres and 0.5 degrees of each other
        (:meth:`GraphFastHoughSLAM._confirms`). On a single return to a place no
        independent closure comes, and the held ones lapse: the paper world, clean, seed 0,
        odometry perturbed in its last bit (seed 6), comes back to its first corridor with
        keyframes 126-127 matching 24-25 unique and 11.6 cm from its estimate, and with 0 ends
        at an ATE of 6.48 cm; with 0.02 the first two confirm each other (0.9 mm, 0.12 degrees
        apart) and it ends at 1.51 cm. Without the bound on the move, wrong matches that
        repeat as alike confirm each other: the ``ring``'s a corridor's width off (seeds
        0-3: 2.99-3.16 m instead of 0.10-0.12) and the ``campus``'s 2.5 m off (seed 2:
        0.47 -> 6.87 m).
    global_every : int
        Once the robot has travelled ``global_after`` metres since the last closure, every
        this many keyframes a *global* search runs (0: never): the last
        ``global_keyframes`` keyframes' clouds are matched (branch and bound over the
        coarse grid, then the fine grid) against the clouds of every keyframe at least
        ``global_after`` metres of travel older, within ``± loop_growth × distance``
        metres (at least ``loop_max_window``, at most ``global_max_window``) and
        ``± global_window_deg`` of a guess: the graph's estimate, once the local search's
        radius has reached ``loop_max_radius`` (110 m of travel by default; before that the
        local search looks there), and then, if ``global_from_odometry`` and nothing was
        found, where the odometry since the last closure puts the robot, if that lies more
        than half a window away. A match is taken only
        if it scores at least ``global_min_score``, is unique (nothing more than
        ``loop_window`` metres away scores over ``global_max_ambiguity`` of its coarse
        score) and refines point-to-line like a local closure; and then only as a
        hypothesis, until the match of a query that shares no keyframe with its own (from
        ``global_keyframes`` keyframes on, until ``global_every`` more have passed) agrees
        with it (``global_consistency``, ``global_consistency_deg``), scoring at least
        ``global_confirm_score``; both then enter the graph.
        The Freiburg hospital comes back to its start after 900 m without a closure, its
        estimate 17-39 m and 12-25 degrees off (85-146 m and 25-40 degrees with 1 mm of
        range noise or scans dropped): its global matches there score 0.6-0.7, and the
        relation error falls from 1.13 m to 0.127 m.
    global_after : float
        See ``global_every``: metres of travel without a closure before the global search
        starts (around the odometry's guess). Waiting until the local search's radius is at its
        largest (110 m) and looking around the estimate only, the hospital's return was found
        with its unperturbed ranges only.
    global_from_odometry : bool
        See ``global_every``.
    global_keyframes : int
        See ``global_every``.
    global_min_score : float
        See ``global_every``: the score a global match needs to be held as a hypothesis.
        The hospital's return scores 0.58-0.66 where it is found: with 0.6 and no
        ``global_confirm_score`` below it its dropped-scans runs failed in 4 of 14 (seeds 3, 11,
        12, 13), with 0.55 and 0.5 in 1.
    global_confirm_score : float
        See ``global_every``: the score the match that confirms a hypothesis needs (never
        more than ``global_min_score``; it must also be unique and agree with the hypothesis,
        which a chance match seldom does). Where the robot passes a place it comes back to only
        briefly, the queries after the one that found it see less of it: the hospital's
        dropped-scans seed 11 held a match scoring 0.741 whose 21 later queries scored
        0.34-0.56 at best (2.19 m unconfirmed; 0.124 m confirmed at 0.5).
    global_window_deg : float
        See ``global_every``: twice the local search's ``loop_window_deg``.
    global_max_window : float
        See ``global_every``: the search's cost grows with the window's area.
    global_max_ambiguity : float
        See ``global_every``. The hospital's accepted global matches have runners-up at
        0.63-0.77 of their score; in the simulated ``ring``, whose corridor repeats every
        10 m, a match one period off had one at 0.87-0.89.
    global_lookback : float
        After a global closure that ended ``L`` metres without a closure, the global search
        goes on as if still ``L`` metres from the last closure (its window, and the graph's
        estimate as a guess once ``L`` is beyond the local search's reach) for the next
        ``global_lookback × L`` metres; 0: not at all. A closure after a long blind stretch
        places the robot against one old place, but the old map around it may be bent
        (the hospital's: 9° at a spin between its start and the place its return meets
        first): the start, reached next, can lie 9-15 m off the corrected estimate, beyond
        the local search. Dropped-scans seed 2: 0.525 m without, 0.120 m with it.
    global_consistency : float
        See ``global_every``: how far (metres) the match that confirms a hypothesis may put
        its keyframe from where the hypothesis puts it (carried along the graph): twice the
        local closures' ``loop_consistency``. After a long blind stretch the two matches
        hit an old map that may be bent between the places they hit, with queries the
        tracker may have bent; the Freiburg hospital's right confirmations at its return
        after 900 m lie up to 0.22 m and 1.5 degrees apart, its other confirmations within
        0.06 m and 0.5 degrees, and a wrong match is metres away (the ``ring``'s period
        of 10 m, the ``campus``'s crossing of 2.5 m). With the local closures' 0.15 m and 2
        degrees, the hospital's dropped-scans seed 9 with ``smooth_clouds`` (0.159 m) and
        dropped scans and noise seed 0 likewise (0.186 m) missed their return.
    global_consistency_deg : float
        See ``global_consistency``: how far in heading, degrees.
    inner_closures_reset : bool
        Whether a local closure *within* the blind stretch ends it. A blind stretch is the
        travel since the last closure; the local search's radius and the global search
        count from where it began. A closure whose old keyframe lies ``global_after``
        metres or more into that same stretch ties the robot to a place as lost as itself:
        with False (the default) the stretch goes on, unless one of the keyframe's closures
        reaches further back. With True it ends it and with it the global search, and a
        hypothesis that search held is never confirmed: the Freiburg hospital's return with loop
        targets of ± 6 keyframes for turned candidates failed twice so: dropped-scans seed 1 (a
        closure of scans 6026/5955 between a hypothesis at scan 6005 and its confirmation) 3.73
        m, 0.130 m with the stretch going on; noise seed 13 0.98 m, 0.121 m. With the default
        targets no hospital run changes its outcome; MIT CSAIL and Freiburg 079 each make 2
        global closures with False (none with True).
    optimize_iterations : int
        Largest number of Gauss-Newton rounds after a keyframe that closed a loop...
    optimize_tol : float
        ... which stop once no pose moves more than this (metres, radians).
    """

    tracker: TrackerParams = field(default_factory=TrackerParams)
    lines: SlamParams = field(default_factory=SlamParams)
    keyframe_distance: float = 0.5
    keyframe_angle_deg: float = 20.0
    cloud_max_range: float = 20.0
    cloud_voxel: float = 0.02
    smooth_clouds: bool = True
    corner_deg: float = 0.0
    submap_keyframes: int = 5
    max_doubtful: int = 5
    edge_sigma: float = 0.03
    edge_points: float = 25.0
    odometry_sigma: tuple[float, float] = (0.1, 2.0)
    pair_edges: bool = False
    pair_share: bool = False
    loop_radius: float = 2.5
    loop_growth: float = 0.05
    loop_max_radius: float = 8.0
    loop_min_gap: int = 20
    loop_target_keyframes: int = 6
    loop_candidates: int = 2
    loop_skip_repeats: bool = True
    loop_window: float = 1.0
    loop_max_window: float = 3.0
    loop_window_deg: float = 15.0
    loop_min_score: float = 0.55
    loop_min_pairs: int = 50
    loop_max_rms: float = 0.03
    loop_kernel: float = 3.0
    loop_max_chi2: float = 25.0
    loop_optimize_chi2: float = 9.0
    loop_confirm_distance: float = 0.1
    loop_confirm_deg: float = 3.0
    loop_unique_radius: float = 0.3
    loop_consistency: float = 0.15
    loop_consistency_deg: float = 2.0
    loop_confirm_window: int = 10
    loop_repeat_confirm: float = 0.02
    global_every: int = 20
    global_after: float = 10.0
    global_from_odometry: bool = True
    global_keyframes: int = 9
    global_min_score: float = 0.55
    global_window_deg: float = 30.0
    global_max_window: float = 50.0
    global_max_ambiguity: float = 0.8
    global_confirm_score: float = 0.5
    global_lookback: float = 1.0
    global_consistency: float = 0.3
    global_consistency_deg: float = 3.0
    inner_closures_reset: bool = False
    optimize_iterations: int = 10
    optimize_tol: float = 1e-4

    RANGES: ClassVar[dict[str, Range]] = {
        "keyframe_distance": Range(0.0, 100.0, open_low=True, unit="m"),
        "keyframe_angle_deg": Range(0.0, 360.0, open_low=True, cap=False, unit="degrees"),
        "cloud_max_range": Range(0.0, 1000.0, open_low=True, unit="m"),
        "cloud_voxel": Range(0.0, 1.0, open_low=True, unit="m"),
        "corner_deg": Range(0.0, 90.0, cap=False, unit="degrees"),
        "submap_keyframes": Range(1, 1000, integer=True),
        "max_doubtful": Range(0, 1_000_000, integer=True),
        "edge_sigma": Range(0.0, 10.0, open_low=True, unit="m"),
        "edge_points": Range(0.0, 1e6, open_low=True),
        "odometry_sigma": Range(0.0, 1000.0, open_low=True, items=2),
        "loop_radius": Range(0.0, 1000.0, unit="m"),
        "loop_growth": Range(0.0, 10.0, open_low=True),
        "loop_max_radius": Range(0.0, 1000.0, unit="m"),
        "loop_min_gap": Range(1, 1_000_000, integer=True),
        "loop_target_keyframes": Range(0, 1000, integer=True),
        "loop_candidates": Range(0, 1000, integer=True),
        "loop_window": Range(0.0, 100.0, unit="m"),
        "loop_max_window": Range(0.0, 100.0, unit="m"),
        "loop_window_deg": Range(0.0, 180.0, cap=False, unit="degrees"),
        "loop_min_score": Range(0.0, 1.0, cap=False),
        "loop_min_pairs": Range(0, 1_000_000, integer=True),
        "loop_max_rms": Range(0.0, 10.0, unit="m"),
        "loop_kernel": Range(0.0, 1000.0, open_low=True),
        "loop_max_chi2": Range(0.0, 1e9),
        "loop_optimize_chi2": Range(0.0, 1e9),
        "loop_confirm_distance": Range(0.0, 100.0, open_low=True, unit="m"),
        "loop_confirm_deg": Range(0.0, 180.0, open_low=True, unit="degrees"),
        "loop_unique_radius": Range(0.0, 100.0, unit="m"),
        "loop_consistency": Range(0.0, 100.0, open_low=True, unit="m"),
        "loop_consistency_deg": Range(0.0, 180.0, open_low=True, unit="degrees"),
        "loop_confirm_window": Range(1, 1_000_000, integer=True),
        "loop_repeat_confirm": Range(0.0, 100.0, unit="m"),
        "global_every": Range(0, 1_000_000, integer=True),
        "global_after": Range(0.0, 1e6, unit="m"),
        "global_keyframes": Range(1, 1000, integer=True),
        "global_min_score": Range(0.0, 1.0, cap=False),
        "global_window_deg": Range(0.0, 180.0, open_low=True, cap=False, unit="degrees"),
        "global_max_window": Range(0.0, 500.0, open_low=True, unit="m"),
        "global_max_ambiguity": Range(0.0, 1.0, open_low=True, cap=False),
        "global_confirm_score": Range(0.0, 1.0, cap=False),
        "global_lookback": Range(0.0, 1000.0),
        "global_consistency": Range(0.0, 100.0, open_low=True, unit="m"),
        "global_consistency_deg": Range(0.0, 180.0, open_low=True, unit="degrees"),
        "optimize_iterations": Range(1, 1000, integer=True),
        "optimize_tol": Range(0.0, 1.0),
    }
    """The range of each number (:class:`fhslam.errors.Range`), checked when the parameters
    are made (``tracker`` and ``lines`` check their own). Upper bounds given as "at most"
    are limits of plausibility (a window or radius beyond them outgrows any map, a count
    any run), the others are limits of meaning (scores and shares from 0 to 1, angles)."""

    def __post_init__(self) -> None:
        for name, kind in (("tracker", TrackerParams), ("lines", SlamParams)):
            if not isinstance(getattr(self, name), kind):
                raise ParameterError(
                    "GraphSlamParams", name, getattr(self, name), f"a {kind.__name__}"
                )
        check_ranges(self, self.RANGES)
        if self.pair_share and not self.pair_edges:
            raise ValueError("pair_share shares the pair edges' information: set pair_edges too")


@dataclass(frozen=True, eq=False)
class LoopClosure:
    """An accepted loop closure: keyframe ``new`` seen from the older keyframe ``old``."""

    old: int
    new: int
    pose: NDArray[np.float64]
    score: float
    edge: int = -1
    """Its edge in :attr:`GraphFastHoughSLAM.graph`."""


class _HeldClosure(NamedTuple):
    """A local closure waiting for confirmation (``GraphFastHoughSLAM._confirms``): the
    closure of ``_verified``, whether its match was ambiguous (``loop_unique_radius``) and
    how far (metres) it moves keyframe ``i``."""

    j: int
    i: int
    z: NDArray
    information: NDArray
    score: float
    where: NDArray  # where it puts keyframe i
    ambiguous: bool
    shift: float


@dataclass(eq=False)
class _LoopTarget:
    """A loop candidate's target: the points and normals of its keyframes in its frame, and
    (built when first needed) their :class:`fhslam.scanmatch.PointMap`."""

    key: tuple
    points: NDArray[np.float64]
    normals: NDArray[np.float64]
    point_map: PointMap | None = None

    @property
    def nbytes(self) -> int:
        m = self.point_map
        extra = 0 if m is None else sum(a.nbytes for a in (m.points, m.normals, m.starts, m.order))
        return self.points.nbytes + self.normals.nbytes + extra


class LoopTargetCache:
    """Loop candidates' targets (:class:`_LoopTarget`) kept between keyframes, least
    recently used first out beyond ``max_bytes``.

    A target is found again only under the same key: its keyframes' range and the exact
    bytes of their poses in the graph, so a cached target is used only where building it
    again would give the same bits. Keyframes old enough to be candidates get no more
    points (scans attach to the newest keyframe), so their poses are all a target depends
    on. :meth:`drop_moved` forgets the targets whose keyframes an optimisation moved.
    """

    def __init__(self, max_bytes: int = 8 << 20):
        self.max_bytes = max_bytes
        self.nbytes = 0
        self.hits = self.misses = 0
        self._targets: OrderedDict[tuple, _LoopTarget] = OrderedDict()

    def __len__(self) -> int:
        return len(self._targets)

    @staticmethod
    def key(poses: NDArray[np.float64], members: range) -> tuple:
        return members.start, members.stop, poses[members.start : members.stop].tobytes()

    def get(self, poses: NDArray[np.float64], members: range, build) -> _LoopTarget:
        """The target of keyframes ``members`` at ``poses``: cached, else from ``build()``
        (its points and normals)."""
        key = self.key(poses, members)
        target = self._targets.get(key)
        if target is not None:
            self.hits += 1
            self._targets.move_to_end(key)
            return target
        self.misses += 1
        target = self._targets[key] = _LoopTarget(key, *build())
        self.nbytes += target.nbytes
        self._evict()
        return target

    def point_map(self, target: _LoopTarget) -> PointMap:
        """``target``'s point map, built once."""
        if target.point_map is None:
            before = target.nbytes
            target.point_map = PointMap.build(target.points, target.normals)
            if self._targets.get(target.key) is target:
                self.nbytes += target.nbytes - before
                self._evict()
        return target.point_map

    def drop_moved(self, poses: NDArray[np.float64]) -> None:
        """Forget the targets whose keyframes are no longer at their key's poses."""
        for key in [k for k in self._targets if self.key(poses, range(k[0], k[1])) != k]:
            self.nbytes -= self._targets.pop(key).nbytes

    def _evict(self) -> None:
        while self.nbytes > self.max_bytes and self._targets:
            self.nbytes -= self._targets.popitem(last=False)[1].nbytes


class _InOrder:
    """A thread that runs the calls given to it one after another, in the order given: the
    back end of :class:`GraphFastHoughSLAM` (why that changes no bit: the module docs, *Two
    threads*; a keyframe's cloud is complete before the back end reads it).

    A call that raises stops the rest; :meth:`wait` raises it. ``max_queued`` calls at most
    wait their turn (:meth:`submit` blocks beyond): the back end cannot fall far behind.
    The thread holds no reference to the calls it has run, and ends when :meth:`close` is
    called or this object is collected.
    """

    def __init__(self, max_queued: int = 256):
        self._queue: queue.Queue = queue.Queue(max_queued)
        self._failed: list[BaseException] = []
        thread = threading.Thread(
            target=_InOrder._serve, args=(self._queue, self._failed), daemon=True
        )
        thread.start()
        weakref.finalize(self, _InOrder._stop, self._queue)

    @staticmethod
    def _stop(jobs: queue.Queue) -> None:
        # Never blocks: at interpreter exit (Ctrl-C while the back end is behind) the queue
        # may be full, and the thread is a daemon then anyway.
        with contextlib.suppress(queue.Full):
            jobs.put_nowait(None)

    @staticmethod
    def _serve(jobs: queue.Queue, failed: list[BaseException]) -> None:
        while (job := jobs.get()) is not None:
            try:
                if not failed:
                    job[0](*job[1])
            except BaseException as e:  # re-raised by wait() in the caller's thread
                failed.append(e)
            finally:
                del job
                jobs.task_done()
        jobs.task_done()

    def submit(self, fn, *args) -> None:
        """Queue ``fn(*args)``; raises what an earlier call raised."""
        self._raise()
        self._queue.put((fn, args))

    def wait(self) -> None:
        """Block until every call given so far has run; raise what one raised."""
        self._queue.join()
        self._raise()

    def close(self) -> None:
        """Let the thread end once the calls given so far have run."""
        _InOrder._stop(self._queue)

    def _raise(self) -> None:
        if self._failed:
            raise self._failed[0]


def scan_cloud(
    points: NDArray[np.float64], params: GraphSlamParams
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A scan's points (laser frame, beam order) as they enter a keyframe's cloud, with
    their normals (NaN: none): smoothed (``smooth_clouds``), filled in between beams
    (:func:`fhslam.scanmatch.densify`, ``corner_deg``), the points with a normal first (so
    that thinning to one point per voxel keeps them)."""
    normals = scan_normals(points)
    if params.smooth_clouds:
        points = smooth_scan(points, normals)
    dense, dense_normals = densify(points, normals, corner_deg=params.corner_deg or None)
    first = np.argsort(np.isnan(dense_normals[:, 0]), kind="stable")
    return dense[first], dense_normals[first]


def _rotate_information(h: NDArray[np.float64], theta: float) -> NDArray[np.float64]:
    """A pose's information ``h`` (translation in the target frame) re-expressed for the
    pose-graph error, whose translation part is in the frame of the pose itself."""
    c, s = np.cos(theta), np.sin(theta)
    b = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return b.T @ h @ b


class GraphFastHoughSLAM:
    """Pose-graph SLAM with scan-to-map tracking, verified loop closures and a map of fast
    Hough lines (see the module docs).

    Parameters
    ----------
    params : GraphSlamParams, optional
    initial_pose : array-like, shape (3,), optional
        The pose of the first scan; default: the first odometry pose.
    background : bool
        Run the back end (the pose graph, loop closures, optimisation) on a thread of its
        own while the front end tracks the next scans (see :class:`_InOrder`): the same
        results, bit for bit, as ``False``, which runs it in turn.
    """

    def __init__(
        self,
        params: GraphSlamParams | None = None,
        initial_pose: ArrayLike | None = None,
        background: bool = True,
    ):
        self.params = params or GraphSlamParams()
        self.tracker = ScanTracker(self.params.tracker)
        self._graph = PoseGraph()
        self._loops: list[LoopClosure] = []
        self._background = background
        self._worker: _InOrder | None = None
        self._initial = None if initial_pose is None else as_pose(initial_pose, "initial_pose")
        self.origin: NDArray[np.float64] | None = None
        """The first scan's pose: the graph runs in its frame (see :meth:`step`)."""
        self._pose: NDArray[np.float64] | None = None
        self._last_odometry: NDArray[np.float64] | None = None
        self._kf_front: list[NDArray[np.float64]] = []  # keyframe poses, tracking frame
        # with pair_edges: keyframe n -> its sure tracker edge and that edge's scan part
        self._kf_edges: dict[int, tuple[int, NDArray[np.float64]]] = {}
        self._pair_map: tuple[int, PointMap] | None = None  # the last pair's later cloud
        self._kf_odometry: list[NDArray[np.float64]] = []  # the odometry at each keyframe
        self._clouds: list[NDArray[np.float64]] = []
        self._normals: list[NDArray[np.float64]] = []  # each cloud point's normal or NaN
        self._chunks: list[list[tuple[NDArray, NDArray]]] = []  # scans not yet thinned in
        self._kf_lines: list[list[Line]] = []
        self._views = np.zeros((0, 3))  # each complete keyframe's cloud mean (its frame), θ 0
        self._path: list[float] = []  # distance travelled at each keyframe
        self._last_loop_path = 0.0
        self._doubtful = 0  # doubtful scans in a row
        self._pending: list[_HeldClosure] = []
        self._failed: dict[int, int] = {}  # candidate -> the last keyframe it failed for
        self._hypothesis: tuple | None = None  # a global match waiting for another's support
        self._last_global = 0  # the keyframe of the last global search
        self._blind = (0.0, 0.0)  # (blind stretch a global closure ended, path it holds to)
        self._kf_doubt = False  # whether a scan since the last keyframe was doubtful
        self._kf_glitch = False  # whether the odometry glitched since the last keyframe
        self._edge_sure = False  # whether the last keyframe edge carried a sure track
        self._scan_kf: list[int] = []
        self._scan_rel: list[NDArray[np.float64]] = []
        self.loop_targets = LoopTargetCache()
        """Loop candidates' targets kept between keyframes (see :class:`LoopTargetCache`)."""

    @property
    def keyframe_steps(self) -> NDArray[np.intp]:
        """For each keyframe of :attr:`graph`, the index of the step (the scan) that started
        it, shape (K,)."""
        kf = np.asarray(self._scan_kf, dtype=np.intp)
        return np.flatnonzero(np.diff(kf, prepend=-1))

    # -- the per-scan step -----------------------------------------------------------------
    def step(self, scan: Scan | None, odometry: ArrayLike) -> StepResult:
        """Track one scan, start a keyframe when due, attach the scan to it; returns the
        tracked pose (the tracking frame; :meth:`finish` revises every pose)."""
        p = self.params
        odometry = as_pose(odometry, "odometry")
        pts = None if scan is None else scan.points(max_range=p.cloud_max_range)[0]
        track = None
        if self._pose is None:
            # Everything inside runs in the first pose's frame, so that where the world frame
            # lies changes nothing but the final composition (grids and voxels are aligned
            # with the axes of this frame).
            self.origin = odometry.copy() if self._initial is None else self._initial.copy()
            pose = np.zeros(3)
        else:
            step = relative(self._last_odometry, odometry)
            t = p.tracker
            self._kf_glitch = self._kf_glitch or bool(
                np.hypot(step[0], step[1]) > t.max_step or abs(np.degrees(step[2])) > t.max_turn_deg
            )
            predicted = compose(self._pose, step)
            pose = predicted
            if pts is not None and len(pts) >= 10:
                track = self.tracker.track(pts, predicted, self._pose)
                pose = track.pose
        self._last_odometry, self._pose = odometry, pose
        lines: list[Line] = []
        # A doubtful scan starts no keyframe and adds no points, unless doubt lasts.
        sure = track is None or track.sure
        self._doubtful = 0 if sure else self._doubtful + 1
        self._kf_doubt = self._kf_doubt or not sure
        new = not self._kf_front or (
            (sure or self._doubtful >= self.params.max_doubtful) and self._keyframe_due(pose)
        )
        if new:
            if scan is not None:
                fe = p.lines
                all_points = scan.points()[0]
                lines = (
                    fe.extractor(all_points)
                    if fe.extractor
                    else extract_lines(all_points, fe.extraction)
                )
            self._new_keyframe(pose, lines, track, odometry)
        k = len(self._kf_front) - 1
        rel = relative(self._kf_front[k], pose)
        self._scan_kf.append(k)
        self._scan_rel.append(rel)
        if pts is not None and len(pts) and (sure or new):
            c, s = np.cos(rel[2]), np.sin(rel[2])
            dense, dense_normals = scan_cloud(pts, p)
            # thinned to one point per voxel when the cloud is next read (see _cloud)
            self._chunks[k].append(
                (transform_points(rel, dense), dense_normals @ [[c, s], [-s, c]])
            )
        if new:
            self._update_local_map()
        matched = track is not None and track.matched
        return StepResult(compose(self.origin, pose), len(lines), 0, 0, matched, lines)

    def _keyframe_due(self, pose: NDArray[np.float64]) -> bool:
        rel = relative(self._kf_front[-1], pose)
        return bool(
            np.hypot(rel[0], rel[1]) >= self.params.keyframe_distance
            or abs(np.degrees(rel[2])) >= self.params.keyframe_angle_deg
        )

    def _update_local_map(self) -> None:
        k = len(self._kf_front) - 1
        members = range(max(0, k - self.params.submap_keyframes + 1), k + 1)
        self.tracker.set_map(*self._in_frame(self._kf_front, members))

    def _in_frame(self, poses, members, frame=None):
        """The clouds and normals of keyframes ``members`` placed at ``poses`` (in the frame
        of ``frame``, a pose in the same frame, if given)."""
        pts, nrm = [], []
        for m in members:
            x = poses[m] if frame is None else relative(frame, poses[m])
            c, s = np.cos(x[2]), np.sin(x[2])
            cloud, normals = self._cloud(m)
            pts.append(transform_points(x, cloud))
            nrm.append(normals @ [[c, s], [-s, c]])
        return np.vstack(pts), np.vstack(nrm)

    def _cloud(self, m: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Keyframe ``m``'s cloud and normals (its frame): the first point of each
        ``cloud_voxel`` cell, scans in order, within a scan points with a normal first. The
        scans added since the last read are merged here, once: the same points as thinning
        after every scan, without re-sorting the growing cloud each time."""
        if self._chunks[m]:
            cloud = np.vstack([self._clouds[m], *(c for c, _ in self._chunks[m])])
            normals = np.vstack([self._normals[m], *(n for _, n in self._chunks[m])])
            keep = voxel_index(cloud, self.params.cloud_voxel)
            self._clouds[m], self._normals[m] = cloud[keep], normals[keep]
            self._chunks[m] = []
        return self._clouds[m], self._normals[m]

    def _complete(self, m: int) -> None:
        """Keyframe ``m`` is complete: thin its cloud and note where it looked (the cloud's
        mean, its frame; its origin if it saw nothing)."""
        cloud = self._cloud(m)[0]
        view = [*cloud.mean(axis=0), 0.0] if len(cloud) else np.zeros(3)
        self._views = np.vstack([self._views, view])  # a new array: the back end reads it

    # -- keyframes and edges ---------------------------------------------------------------
    def _information(self, ref: Refinement | None, theta: float) -> NDArray[np.float64]:
        """The information of a refined match (see ``edge_sigma``), in the edge's frame."""
        p = self.params
        if ref is None or ref.n_matched < 10:
            return np.zeros((3, 3))
        h = ref.hessian * (p.edge_points / (ref.n_matched * p.edge_sigma**2))
        return _rotate_information(h, theta)

    def _new_keyframe(self, pose, lines: list[Line], track, odometry) -> None:
        """Start a keyframe at ``pose`` (tracking frame; ``odometry``: the odometry there) and
        give the graph its edge from the previous one."""
        p = self.params
        n = len(self._kf_front)
        if n == 0:
            self._path.append(0.0)
            self._in_turn(self._graph.add_node, pose)
        else:
            z = relative(self._kf_front[-1], pose)
            self._path.append(self._path[-1] + float(np.hypot(z[0], z[1])))
            s_xy, s_deg = p.odometry_sigma
            info = np.diag([1 / s_xy**2, 1 / s_xy**2, 1 / np.radians(s_deg) ** 2])
            sure = track is not None and track.sure and not self._kf_doubt
            scan_info = None
            if sure:
                scan_info = self._information(track.refinement, float(pose[2]))
                info = info + scan_info
            elif not self._kf_glitch:
                # The edge carries the odometry's information only: so its measurement is the
                # odometry's too. A doubtful track can be placed far off an odometry that
                # hardly turns (Freiburg hospital, among people: 7-15 degrees at one scan).
                z = relative(self._kf_odometry[-1], odometry)
            self._kf_doubt = self._kf_glitch = False
            # Keyframe n-1 is complete: its cloud is thinned now, so that from here on the
            # back end only reads it.
            self._complete(n - 1)
            self._in_turn(self._add_keyframe, n, z, info, scan_info)
            if p.pair_edges and sure and self._edge_sure and n >= 2:
                # keyframes n-2 and n-1 are both complete now, neither's scans doubtful
                guess = relative(self._kf_front[n - 2], self._kf_front[n - 1])
                self._in_turn(self._pair_edges, n - 2, n - 1, guess)
            self._edge_sure = sure
        self._kf_front.append(pose.copy())
        self._kf_odometry.append(odometry.copy())
        self._clouds.append(np.zeros((0, 2)))
        self._normals.append(np.zeros((0, 2)))
        self._chunks.append([])
        self._kf_lines.append(lines)

    # -- the back end: the graph, in turn (see _InOrder) ------------------------------------
    def _in_turn(self, fn, *args) -> None:
        """Run ``fn(*args)`` on the back end's thread after everything given before it (at
        once without a background thread)."""
        if not self._background:
            fn(*args)
            return
        if self._worker is None:
            self._worker = _InOrder()
        self._worker.submit(fn, *args)

    def sync(self) -> None:
        """Wait until the back end has done everything given to it so far (and raise what
        it raised)."""
        if self._worker is not None:
            self._worker.wait()

    def _add_keyframe(self, n: int, z, info, scan_info=None) -> None:
        """Keyframe ``n`` at ``z`` from keyframe ``n - 1`` with ``info`` (of which
        ``scan_info`` came from the scans); then look for loops of keyframe ``n - 1``, which
        is complete."""
        self._graph.add_node(compose(self._graph.pose(n - 1), z))
        e = self._graph.add_edge(n - 1, n, z, info)
        if self.params.pair_edges:
            self._kf_edges.pop(n - 2, None)  # its pair, if any, is made by now
            if scan_info is not None:
                self._kf_edges[n] = (e, scan_info)
        if n >= 2:
            self._close_loops(n - 1)

    def _pair_edges(self, a: int, b: int, guess: NDArray[np.float64]) -> None:
        """Join complete keyframes ``a`` and ``b`` (``guess``: ``b`` in ``a``'s frame, as
        tracked) by two edges, each cloud refined against the other's (see
        ``pair_edges``); a direction whose refinement pairs fewer than 10 points or moves
        farther than the tracker's window adds nothing. The edges carry no information
        about the heading: it comes from the same scans as the tracker's edge, which
        already holds it."""
        t = self.params.tracker
        maps = {a: self._pair_map[1]} if self._pair_map and self._pair_map[0] == a else {}
        for m in (a, b):
            if m not in maps:
                maps[m] = PointMap.build(*self._cloud(m))
        self._pair_map = (b, maps[b])  # the next pair's earlier keyframe
        made = []
        for target, query, x in ((a, b, guess), (b, a, inverse(guess))):
            q = voxel_downsample(self._cloud(query)[0], t.query_voxel)
            ref = refine(maps[target], q, x, t.refine_distance, t.refine_iterations)
            if ref.n_matched >= 10 and np.hypot(*(ref.pose[:2] - x[:2])) <= t.window:
                h = self._information(ref, float(ref.pose[2]))
                if not h[2, 2] > 0:
                    continue
                # where the other keyframe is, whatever its heading: the information about
                # the translation with the rotation left free (the Schur complement)
                info = np.zeros((3, 3))
                info[:2, :2] = h[:2, :2] - np.outer(h[:2, 2], h[2, :2]) / h[2, 2]
                made.append((target, query, ref.pose, info))
        share = 1.0
        edge, scan_info = self._kf_edges.pop(b, (-1, None))
        if self.params.pair_share and made and scan_info is not None:
            # the tracker's edge and the pairs, from the same scans, share their information
            # about the translation (its odometry prior and heading stay whole)
            share = 1.0 / (1 + len(made))
            s = np.diag([np.sqrt(share), np.sqrt(share), 1.0])
            info = self._graph.information(edge) - scan_info + s @ scan_info @ s
            self._graph.set_information(edge, info)
        for target, query, z, info in made:
            self._graph.add_edge(target, query, z, share * info, kind="pair")

    @property
    def graph(self) -> PoseGraph:
        """The pose graph of the keyframes (once the back end has caught up)."""
        self.sync()
        return self._graph

    @property
    def loops(self) -> list[LoopClosure]:
        """Every loop closure that entered the graph, in order (once the back end has caught
        up); see :attr:`accepted_loops`."""
        self.sync()
        return self._loops

    def _submap(self, frame: int, members, poses=None) -> tuple[NDArray, NDArray]:
        """Points and normals of keyframes ``members`` in keyframe ``frame``'s frame (at
        ``poses``, default the graph's)."""
        poses = self._graph.poses if poses is None else poses
        return self._in_frame(poses, members, poses[frame])

    def _close_loops(self, i: int) -> None:
        p = self.params
        if p.loop_candidates == 0 or i <= p.loop_min_gap:
            return
        poses = self._graph.poses
        n_old = i - p.loop_min_gap + 1  # keyframes old enough to be candidates
        drift = p.loop_growth * (self._path[i] - self._last_loop_path)
        radius = min(p.loop_max_radius, p.loop_radius + drift)
        if p.global_every and self._far(i) and self._search_globally(i, poses):
            return  # closed: the local search goes on from the next keyframe
        # Candidates: the keyframes that looked where this one's query looks (keyframes
        # i-2..i); where a keyframe looked is its cloud's mean, placed at its pose.
        views = self._looks(poses, i)
        d = np.hypot(*(views[:n_old] - views[max(0, i - 2) :].mean(axis=0)).T)
        cands = [
            int(j) for j in np.argsort(d, kind="stable")[: p.loop_candidates] if d[j] <= radius
        ]
        if not cands:
            return
        query = self._submap(i, range(max(0, i - 2), i + 1), poses)[0]
        if len(query) < 10:
            return
        # Right after a loop closure the pose is known well: search a small window only.
        tracking = bool(self._loops) and self._loops[-1].new == i - 1
        win = p.tracker.window if tracking else min(p.loop_max_window, p.loop_window + drift)
        win_deg = p.tracker.window_deg + 2 if tracking else p.loop_window_deg
        q_refine = voxel_downsample(query, 0.05)
        closed, held = [], []
        for j in cands[:1] if tracking else cands:
            if p.loop_skip_repeats and not tracking and self._failed.get(j) == i - 1:
                continue  # failed for the previous keyframe: tried again the next time
            members = self._target(j, i)
            cached = self.loop_targets.get(
                poses, members, lambda j=j, m=members: self._submap(j, m, poses)
            )
            target = cached.points
            if len(target) < 10:
                continue
            unique = p.loop_unique_radius > 0 and not tracking
            m = match_clouds(
                target, query, relative(poses[j], poses[i]), win, win_deg,
                exclude=(p.loop_unique_radius, p.global_max_ambiguity) if unique else None,
                exclude_min_score=p.loop_min_score,
            )  # fmt: skip
            if m.score < p.loop_min_score:
                self._failed[j] = i
                continue
            ref = refine(self.loop_targets.point_map(cached), q_refine, m.pose)
            c = self._verified(j, i, ref, m.pose, m.score, poses)
            if c is None:
                continue
            move = c[5] - poses[i]  # how far the closure moves keyframe i
            shift, ambiguous = float(np.hypot(move[0], move[1])), bool(m.runner_up > 0)
            if not tracking and (
                ambiguous  # not unique (loop_unique_radius)
                or shift > p.loop_confirm_distance
                or abs(np.degrees(np.angle(np.exp(1j * move[2])))) > p.loop_confirm_deg
            ):
                held.append(_HeldClosure(*c, ambiguous, shift))
                continue
            closed.append(self._add_loop(*c[:5]))
        if closed:
            self._pending = []  # the estimate is confirmed as it stands
        self._pending = [h for h in self._pending if i - h.i <= p.loop_confirm_window]
        for h in held:
            # an independent one that agrees (or, with loop_repeat_confirm, a repeat)
            support = [g for g in self._pending if self._confirms(g, h, poses)]
            if support:
                for g in [*support, h]:
                    closed.append(self._add_loop(*g[:5]))
                self._pending = [g for g in self._pending if not any(g is x for x in support)]
            else:
                self._pending.append(h)
        if closed:
            self._end_blind(i, [lc.old for lc in self._loops[-len(closed) :]])
            if self._graph.chi2(np.array(closed)).max() >= p.loop_optimize_chi2:
                self._optimize()

    def _far(self, i: int) -> bool:
        """Whether keyframe ``i`` lies ``global_after`` metres or more past the last
        closure, so that the global search runs."""
        return self._path[i] - self._last_loop_path >= self.params.global_after

    def _end_blind(self, i: int, olds) -> None:
        """Book keyframe ``i``'s local closures to keyframes ``olds``: they end the blind
        stretch unless every one of them lies ``global_after`` metres or more into it
        (``inner_closures_reset``)."""
        p = self.params
        inner = all(self._path[j] - self._last_loop_path >= p.global_after for j in olds)
        if p.inner_closures_reset or not inner:
            self._last_loop_path = self._path[i]

    def _looks(self, poses, i: int) -> NDArray[np.float64]:
        """Where keyframes ``0 .. i`` looked: their clouds' means placed at ``poses``."""
        return compose(poses[: i + 1], self._views[: i + 1])[:, :2]

    def _search_globally(self, i: int, poses) -> bool:
        """The global search (see ``global_every``): a match is held as a hypothesis until a
        match from a query that shares no keyframe with its own agrees with it; then both
        enter the graph, it is optimised, and True is returned."""
        p = self.params
        h = self._hypothesis
        if h is not None and i - h[1] > p.global_keyframes + p.global_every:
            h = self._hypothesis = None  # not confirmed in time
        if h is None and i - self._last_global < p.global_every:
            return False
        if h is not None and i - h[1] < p.global_keyframes:
            return False  # the next query must share no keyframe with the hypothesis's
        self._last_global = i
        # a hypothesis is confirmed by a match that agrees with it at the lower score
        low = p.global_min_score if h is None else min(p.global_min_score, p.global_confirm_score)
        g = self._global_match(i, poses, low)
        if g is None:
            return False
        tol = (p.global_consistency, p.global_consistency_deg)
        if h is None or not self._agree(h, g, poses, tol):
            if g[4] >= p.global_min_score:
                self._hypothesis = g
            return False
        self._hypothesis = None
        closed = [self._add_loop(*x[:5]) for x in (h, g)]
        blind = self._path[i] - self._last_loop_path
        if not (self._path[i] < self._blind[1] and self._blind[0] > blind):
            self._blind = (blind, self._path[i] + p.global_lookback * blind)
        self._last_loop_path = self._path[i]
        self._pending = []
        if self._graph.chi2(np.array(closed)).max() >= p.loop_optimize_chi2:
            self._optimize()
        return True

    def _travelled(self, i: int) -> float:
        """Metres the global search counts as travelled since the last closure at keyframe
        ``i`` (``global_lookback``: at least the blind stretch the last global closure ended,
        while its look-back lasts)."""
        d = self._path[i] - self._last_loop_path
        blind, until = self._blind
        return max(d, blind) if self._path[i] < until else d

    def _global_guesses(self, i: int, poses, win: float) -> list[NDArray[np.float64]]:
        """Where the global search looks for keyframe ``i`` (its pose in its own frame):
        the graph's estimate, once the local search no longer reaches far enough (its radius
        at ``loop_max_radius``), and where the odometry since the last closure puts it (the
        keyframe at the last closure moved by the odometry's motion since), unless that
        lies within half the window of the estimate."""
        p = self.params
        reach = (p.loop_max_radius - p.loop_radius) / p.loop_growth
        local = self._travelled(i) < reach  # the local search still grows
        guesses = [] if local else [np.zeros(3)]
        if p.global_from_odometry:
            a = int(np.searchsorted(self._path[: i + 1], self._last_loop_path))
            odo = compose(poses[a], relative(self._kf_odometry[a], self._kf_odometry[i]))
            g = relative(poses[i], odo)
            if np.hypot(g[0], g[1]) > win / 2 or abs(np.degrees(g[2])) > p.global_window_deg / 2:
                guesses.append(g)
        return guesses

    def _global_match(self, i: int, poses, min_score: float):
        """Match the last ``global_keyframes`` keyframes up to ``i`` against all keyframes
        ``global_after`` metres of travel older, around each guess in turn (see
        ``global_every``); returns a closure ``(j, i, z, information, score, where it puts
        keyframe i)`` or None."""
        p = self.params
        path = np.asarray(self._path[: i + 1])
        older = np.flatnonzero(path <= path[i] - p.global_after)
        travelled = self._travelled(i)
        win = min(p.global_max_window, max(p.loop_max_window, p.loop_growth * travelled))
        views = self._looks(poses, i)
        looks = [*views[max(0, i - 2) :].mean(axis=0), 0.0]  # where the query looks
        query = self._submap(i, range(max(0, i - p.global_keyframes + 1), i + 1), poses)[0]
        if len(query) < 10:
            return None
        for guess in self._global_guesses(i, poses, win):
            at = compose(compose(poses[i], guess), relative(poses[i], looks))[:2]
            old = older[np.hypot(*(views[older] - at).T) <= win + p.cloud_max_range]
            if not len(old):
                continue
            target = voxel_downsample(self._submap(i, old, poses)[0], 0.05)
            if len(target) < 10:
                continue
            m = match_clouds(
                target, query, guess, win, p.global_window_deg, prior=(0.0, 0.0),
                exclude=(p.loop_window, p.global_max_ambiguity), min_coarse=min_score,
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
        if near.min() > p.cloud_max_range:
            return None  # placed where no old keyframe looked
        pts, nrm = self._submap(j, old[near <= p.cloud_max_range], poses)
        guess = relative(poses[j], compose(poses[i], m.pose))
        ref = refine(PointMap.build(pts, nrm), voxel_downsample(query, 0.05), guess)
        return self._verified(j, i, ref, guess, m.score, poses)

    def _verified(self, j: int, i: int, ref: Refinement, matched, score: float, poses):
        """The closure ``(j, i, z, information, score, where it puts keyframe i)`` from a
        match of keyframe ``i``'s query against ``j``'s target at ``matched``, refined to
        ``ref``; None if the refinement pairs too few points or too loosely. The refined
        pose is taken unless it wandered more than 5 cm from the match."""
        p = self.params
        if ref.n_matched < p.loop_min_pairs or ref.rms > p.loop_max_rms:
            return None
        z = ref.pose if np.hypot(*(ref.pose[:2] - matched[:2])) <= 0.05 else matched
        return j, i, z, self._information(ref, float(z[2])), score, compose(poses[j], z)

    def _add_loop(self, j: int, i: int, z, info, score: float) -> int:
        e = self._graph.add_edge(j, i, z, info, self.params.loop_kernel, kind="loop")
        self._loops.append(LoopClosure(j, i, z, score, e))
        return e

    def _target(self, j: int, i: int, half: int | None = None) -> range:
        """The keyframes of candidate ``j``'s target for keyframe ``i``'s query: ``j`` and
        ``half`` (default ``loop_target_keyframes``) on either side, none within
        ``loop_min_gap`` of ``i``."""
        p = self.params
        k = p.loop_target_keyframes if half is None else half
        return range(max(0, j - k), min(j + k + 1, i - p.loop_min_gap + 1))

    def _independent(self, g, h) -> bool:
        """Whether held closures ``g`` and ``h`` share no keyframe in their queries
        (keyframes ``i - 2 .. i``) nor in the cores of their targets (:meth:`_target` with
        three keyframes on either side). Not the whole targets: with
        ``loop_target_keyframes`` 10, two queries ``loop_confirm_window`` keyframes apart
        could never confirm each other (the ``campus``'s closures were all held, none
        confirmed)."""
        a, b = self._target(g[0], g[1], 3), self._target(h[0], h[1], 3)
        return abs(g[1] - h[1]) >= 3 and max(a.start, b.start) >= min(a.stop, b.stop)

    def _confirms(self, g: _HeldClosure, h: _HeldClosure, poses) -> bool:
        """Whether held closure ``g`` confirms held closure ``h``: independent of it and
        agreeing within ``loop_consistency``; or, with ``loop_repeat_confirm``, both unique,
        neither moving its keyframe more than three times ``loop_confirm_distance``, from
        different queries, and agreeing within ``loop_repeat_confirm`` metres and 0.5
        degrees."""
        p = self.params
        if self._independent(g, h) and self._agree(g, h, poses):
            return True
        return (
            p.loop_repeat_confirm > 0
            and not (g.ambiguous or h.ambiguous)
            and max(g.shift, h.shift) <= 3 * p.loop_confirm_distance
            and g.i != h.i
            and self._agree(g, h, poses, (p.loop_repeat_confirm, 0.5))
        )

    def _agree(self, g, h, poses, tol=None) -> bool:
        """Whether held closures ``g`` and ``h`` place keyframe ``h``'s ``i`` alike (``g``'s
        placement carried along the graph): within ``tol`` (metres, degrees; default
        ``loop_consistency``, ``loop_consistency_deg``)."""
        p = self.params
        dist, deg = tol or (p.loop_consistency, p.loop_consistency_deg)
        carried = compose(g[5], relative(poses[g[1]], poses[h[1]]))
        d = carried - h[5]
        return bool(
            np.hypot(d[0], d[1]) <= dist and abs(np.degrees(np.angle(np.exp(1j * d[2])))) <= deg
        )

    def _optimize(self) -> None:
        """Optimise; switch off loop edges that stay inconsistent, optimise again."""
        p = self.params
        self._graph.optimize(p.optimize_iterations, p.optimize_tol)
        active = [lc for lc in self._loops if self._graph.is_active(lc.edge)]
        if active:
            chi2 = self._graph.chi2(np.array([lc.edge for lc in active]))
            bad = [lc for lc, c in zip(active, chi2, strict=True) if c > p.loop_max_chi2]
            if bad:
                for lc in bad:
                    self._graph.set_active(lc.edge, False)
                self._graph.optimize(p.optimize_iterations, p.optimize_tol)
        self.loop_targets.drop_moved(self._graph.poses)

    # -- results ---------------------------------------------------------------------------
    @property
    def accepted_loops(self) -> list[LoopClosure]:
        """The loop closures still in the graph (not switched off as inconsistent)."""
        self.sync()
        return [lc for lc in self._loops if self._graph.is_active(lc.edge)]

    @property
    def poses(self) -> NDArray[np.float64]:
        """Every scan's pose so far: its keyframe's graph pose ⊕ its pose relative to it."""
        if not self._scan_kf:
            return np.zeros((0, 3))
        self.sync()
        local = compose(self._graph.poses[np.array(self._scan_kf)], np.array(self._scan_rel))
        return compose(self.origin, local)

    def finish(self) -> FinalEstimate:
        """Close the last keyframe (look for loops), optimise, and build the map from the
        keyframes at their optimised poses; every scan's pose is revised."""
        self.sync()
        if self._worker is not None:
            self._worker.close()
            self._worker = None
        n = len(self._graph)
        if n >= 2:
            self._complete(n - 1)
            self._close_loops(n - 1)
            self._optimize()
        return FinalEstimate(self.build_map(), self.poses)

    def build_map(self) -> list[Line]:
        """The map of reference lines from the keyframes' lines at their optimised poses
        (:meth:`fhslam.reference_map.ReferenceMap.update`: the front end's policy, applied
        keyframe by keyframe)."""
        fe = self.params.lines
        if self.origin is None:
            return []
        self.sync()
        refs = ReferenceMap(
            fe.matching, fe.min_reference_length, fe.min_reference_points, fe.max_merge_residual
        )
        for x, lines in zip(compose(self.origin, self._graph.poses), self._kf_lines, strict=True):
            world = transform_lines(lines, x)
            refs.update(world, refs.associate(world, x))
        return refs.lines
