"""FH-SLAM on a pose graph: simulated worlds, real logs (Intel, held-out ACES), bad input."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from conftest import blind_turn

from fhslam.metrics import ate
from fhslam.pipeline import run_backend, run_slam
from fhslam.sim import OdometryNoise, degrade, load_world, perturb_odometry, simulate
from fhslam.slam import GraphFastHoughSLAM, GraphSlamParams
from fhslam.slam.graph import closure, search
from fhslam.slam.graph.params import GlobalSearchParams, LoopParams


@pytest.fixture(scope="module")
def three_laps():
    """A held-out world driven three times with 2-6 m of odometry drift."""
    return simulate(load_world("random:109"), seed=0, odometry=OdometryNoise.drifting(), laps=3)


def test_loops_are_closed_and_the_drift_removed(three_laps):
    log = three_laps
    slam = GraphFastHoughSLAM()
    r = run_backend(slam, log)
    assert len(slam.loops) >= 20  # measured 102
    assert all(lc.score >= slam.params.loops.min_score for lc in slam.loops)
    assert all(lc.new - lc.old >= slam.params.loops.min_gap for lc in slam.loops)
    odometry = ate(log.odometry, log.truth).rmse  # 2.3 m
    assert ate(r.poses, log.truth).rmse <= min(0.05, 0.05 * odometry)  # measured 0.42 cm
    assert len(r.poses) == len(log.timestamps) and len(r.map) > 0
    np.testing.assert_array_equal(r.timestamps, log.timestamps)


def test_closures_that_agree_are_added_without_optimising(three_laps, monkeypatch):
    """Optimising only after closures that disagree with the estimate (χ² >= 9) saves most
    optimisations and moves no pose by more than a few millimetres."""

    def run(params):
        slam = GraphFastHoughSLAM(params)
        count = []
        optimize = slam._optimize
        slam._optimize = lambda: count.append(1) or optimize()
        return run_backend(slam, three_laps).poses, len(count)

    lazy, n_lazy = run(GraphSlamParams())  # the default: LOOP_OPTIMIZE_CHI2 = 9
    monkeypatch.setattr(closure, "LOOP_OPTIMIZE_CHI2", 0.0)
    eager, n_eager = run(GraphSlamParams())
    assert n_eager >= 20 and n_lazy <= 0.5 * n_eager  # measured 1 of 102 (with finish)
    assert np.abs(lazy[:, :2] - eager[:, :2]).max() <= 0.01  # measured 2.1 mm
    truth = three_laps.truth
    assert ate(lazy, truth).rmse <= ate(eager, truth).rmse + 0.002  # measured 0.42 vs 0.49 cm


def test_a_closure_that_moves_its_keyframe_far_waits_for_an_independent_one():
    """Held closures agree when, carried along the graph to the same keyframe, they place
    it within 15 cm and 2° (``loops.consistency``, ``LOOP_CONSISTENCY_DEG``)."""
    from fhslam.geometry import compose

    slam = GraphFastHoughSLAM()
    poses = np.array([[0.0, 0.0, 0.0]] * 10 + [[5.0, 0.0, 0.0], [5.5, 0.0, 0.1]])
    moved = np.array([0.8, 0.1, 0.02])  # where the first held closure puts keyframe 10
    g = (0, 10, None, None, 0.6, compose(poses[10], moved))
    same = compose(compose(poses[10], moved), [0.5, 0.05, 0.1])  # keyframe 11 alike
    assert slam._agree(g, (1, 11, None, None, 0.6, same), poses)
    for off in ([0.16, 0.0, 0.0], [0.0, 0.0, np.radians(2.5)]):
        assert not slam._agree(g, (1, 11, None, None, 0.6, compose(same, off)), poses)


def test_closures_confirm_each_other_only_when_they_share_no_keyframe():
    """A target is candidate j and ``loops.target_keyframes`` (6) keyframes on either side,
    none within ``loops.min_gap`` (20) of the query. Independent: the queries (keyframes
    i-2..i) apart, and the targets' cores (j-3..j+3) too."""
    wide = GraphFastHoughSLAM()
    assert wide._target(50, 100) == range(44, 57) and wide._target(79, 100) == range(73, 81)
    assert wide._target(2, 100) == range(0, 9)
    slam = GraphFastHoughSLAM(GraphSlamParams(loops=LoopParams(target_keyframes=3)))
    assert slam._target(50, 100) == range(47, 54)
    assert slam._target(2, 100) == range(0, 6) and slam._target(79, 100) == range(76, 81)
    assert GraphFastHoughSLAM(GraphSlamParams(loops=LoopParams(target_keyframes=0)))._target(
        50, 100
    ) == (range(50, 51))
    for s in (slam, wide):  # the same cores whatever the targets' width
        assert s._independent((50, 97), (57, 100))
        assert not s._independent((50, 98), (57, 100))  # keyframe 98 in both queries
        assert not s._independent((51, 97), (57, 100))  # keyframe 54 in both cores
        assert not s._independent((0, 97), (0, 100)) and not s._independent((1, 97), (0, 100))


def _held(j, i, where, ambiguous=False, move=0.12):
    """A held closure as :meth:`GraphFastHoughSLAM._confirms` reads it."""
    return closure.HeldClosure(
        j, i, None, None, 0.7, np.asarray(where, dtype=float), ambiguous, move
    )


@pytest.mark.parametrize("repeat", [0.0, 0.02])
def test_a_repeated_unique_closure_confirms_itself_only_with_loop_repeat_confirm(
    repeat, monkeypatch
):
    """Two held closures of consecutive queries against the same target are not independent.
    With ``LOOP_REPEAT_CONFIRM`` they confirm each other if both are unique, move their
    keyframe by at most 3 × ``loops.confirm_distance`` (0.3 m), come from different queries
    and agree within it (metres) and 0.5 degrees (the default, 0.02); never when it is 0."""
    from fhslam.geometry import compose

    monkeypatch.setattr(closure, "LOOP_REPEAT_CONFIRM", repeat)
    slam = _straight_graph(GraphSlamParams(), n=130)
    poses = slam._graph.poses
    off = np.array([0.116, 0.0, 0.0])  # both put their keyframe 11.6 cm ahead
    mm, turn = np.array([0.001, 0.0, 0.0]), np.array([0.0, 0.0, np.radians(0.6)])
    g = _held(24, 126, compose(poses[126], off))
    h = _held(24, 127, compose(poses[127], off + mm))  # 1 mm apart
    assert not slam._independent(g, h)
    assert slam._confirms(g, h, poses) is (repeat > 0)
    # independent closures that agree within loops.consistency confirm each other either way
    assert slam._confirms(_held(60, 120, compose(poses[120], off)), h, poses)
    for other, why in (
        (_held(24, 127, compose(poses[127], off + 25 * mm)), "2.5 cm apart"),
        (_held(24, 127, compose(poses[127], off + turn)), "0.6 deg"),
        (_held(24, 127, compose(poses[127], off), ambiguous=True), "not unique"),
        (_held(24, 127, compose(poses[127], off), move=0.31), "moves it 31 cm"),
        (_held(25, 126, compose(poses[126], off)), "the same query"),
    ):
        assert not slam._confirms(g, other, poses), why


def test_the_paper_worlds_single_return_is_closed_by_a_repeated_closure():
    """The paper world, clean, seed 0, its odometry perturbed in the last bit (seed 6): on
    its one return to the first corridor keyframes 126-127 match keyframes 24-25, unique,
    11.6 cm from the estimate, and no independent closure comes to confirm them. With
    ``LOOP_REPEAT_CONFIRM`` 0 they lapse, and the draw ended at an ATE of 6.48 cm on one
    machine, decided by that threshold; with the default two of them confirm each other and
    the return is closed (24->126 and 24->127, 1.51 cm). How far the matches would move
    keyframe 127 turns on the CPU's last bits: on another machine it is under 10 cm, and
    24->127 enters at once, with or without ``LOOP_REPEAT_CONFIRM`` (1.24 cm). So this pins
    the return, however it is confirmed; the confirmation itself is pinned on canned closures
    (above)."""
    log = perturb_odometry(simulate(load_world("paper"), seed=0), 6)
    slam = GraphFastHoughSLAM()
    r = run_backend(slam, log)
    returns = [lc for lc in slam.accepted_loops if lc.old <= 30 and lc.new >= 120]
    assert len(returns) >= 1  # measured 24->126 and 24->127 on one machine, 24->127 on another
    assert ate(r.poses, log.truth).rmse <= 0.03  # the 3 cm limit; measured 1.51 / 1.24 cm


def test_a_corridor_ring_comes_back_to_its_start_without_a_false_closure():
    """The ``ring`` (150 m of corridor a lap, 8 m laser): back at its start the robot faces
    south where the first keyframes faced east. Two queries three keyframes apart matched the
    same start keyframes a corridor's width off (scores 0.55-0.72, 3.5 m off), agreed, and
    bent the whole run (ATE 3.22 m) when a closure against the same target counted as
    confirmation."""
    from fhslam.geometry import relative

    log = simulate(load_world("ring"), seed=1, laps=2)
    slam = GraphFastHoughSLAM()
    r = run_backend(slam, log)
    steps = slam.keyframe_steps
    assert len(slam.accepted_loops) >= 100  # measured 274 (81 before)
    for lc in slam.accepted_loops:
        true = relative(log.truth[steps[lc.old]], log.truth[steps[lc.new]])
        assert np.hypot(*(lc.pose[:2] - true[:2])) <= 0.3, (lc.old, lc.new)  # measured <= 0.03 m
    assert ate(r.poses, log.truth).rmse <= 0.2  # measured 0.116 m (odometry 14 m)


def test_a_corridor_driven_back_the_other_way_is_closed():
    """The ``offices`` route drives its corridor east, then back west: the 180-degree laser
    sees what the keyframes a few metres *ahead* saw on the way out. Loop candidates chosen
    by where the keyframes stood (they looked the other way) closed once on the way back
    (ATE 3.78 cm); chosen by where they looked, 20 times."""
    from fhslam.geometry import relative

    log = simulate(load_world("offices"), seed=0)
    slam = GraphFastHoughSLAM()
    r = run_backend(slam, log)
    steps = slam.keyframe_steps
    back = np.flatnonzero(log.truth[:, 0] > 18.9)[-1]  # the U-turn at the corridor's east end
    for lc in slam.accepted_loops:
        true = relative(log.truth[steps[lc.old]], log.truth[steps[lc.new]])
        assert np.hypot(*(lc.pose[:2] - true[:2])) <= 0.3, (lc.old, lc.new)  # measured <= 0.02
    assert sum(steps[lc.new] > back for lc in slam.accepted_loops) >= 10  # measured 20
    # the 3 cm limit for a simulated world; measured 1.14 cm (odometry 81 cm), 1.1-1.3 cm over
    # 7 last-bit draws
    assert ate(r.poses, log.truth).rmse <= 0.03


def _closure_errors(slam, log):
    """How far (metres) each accepted closure is from the true relative pose."""
    from fhslam.geometry import relative

    steps = slam.keyframe_steps
    errors = []
    for lc in slam.accepted_loops:
        true = relative(log.truth[steps[lc.old]], log.truth[steps[lc.new]])
        errors.append(float(np.hypot(*(lc.pose[:2] - true[:2]))))
    return np.array(errors)


def test_a_return_out_of_the_local_searchs_reach_is_closed_globally():
    """The ``offices`` floor driven twice, blind for 60 scans (4.6 m) shortly before the end
    of the first lap while the odometry turns 20 degrees too far: the estimate comes back
    20 degrees off, beyond the local search's ± 15 degrees, and nothing closes the lap. The
    global search (``search.every``) does, around the estimate: the odometry is what went
    wrong here, so its guess does not help. The lap (62 m) is shorter than the default reach
    of the local search (110 m of travel since the last closure), after which the global
    search looks around the estimate too, so that reach is cut to 10 m here
    (``loops.max_radius`` 3 m)."""
    log = blind_turn(simulate(load_world("offices"), seed=0, laps=2), 20, 8, 60, 30)
    local = run_slam(
        log,
        "graph",
        GraphSlamParams(search=GlobalSearchParams(every=0), loops=LoopParams(max_radius=3.0)),
    )
    assert ate(local.poses, log.truth).rmse >= 0.5  # measured 0.97 m
    default = run_slam(log, "graph")  # the odometry's guess alone: no closure
    assert ate(default.poses, log.truth).rmse >= 0.5  # measured 0.97 m
    slam = GraphFastHoughSLAM(GraphSlamParams(loops=LoopParams(max_radius=3.0)))
    r = run_backend(slam, log)
    errors = _closure_errors(slam, log)
    assert len(errors) >= 100 and errors.max() <= 0.3  # measured 146 closures, <= 0.06 m
    assert ate(r.poses, log.truth).rmse <= 0.03  # measured 2.5 cm


def test_a_global_match_that_is_not_unique_is_not_taken(monkeypatch):
    """The ``ring``'s corridor repeats every 10 m. Blind for 200 scans (16 m) 30 m before
    the end of its first lap while the odometry turns 20 degrees too far, the estimate comes
    back to the start about 9 m off, outside the global search's window (5 % of the 150 m
    travelled): the best match inside it is one period off (coarse score 0.97). Its runner-up
    more than 1 m away scores 0.92-0.99 of it, so it is refused
    (``GLOBAL_MAX_AMBIGUITY`` 0.8); taken, it closes the lap 10 m off."""
    log = blind_turn(simulate(load_world("ring"), seed=0, laps=2), 20, 30, 200, 30)
    wrong = GraphFastHoughSLAM()
    with monkeypatch.context() as m:  # any runner-up allowed
        m.setattr(closure, "GLOBAL_MAX_AMBIGUITY", 1.0)
        m.setattr(search, "GLOBAL_MAX_AMBIGUITY", 1.0)
        run_backend(wrong, log)
    assert _closure_errors(wrong, log).max() >= 5.0  # measured 10.0 m: one period
    slam = GraphFastHoughSLAM()
    run_backend(slam, log)
    assert _closure_errors(slam, log).max(initial=0.0) <= 0.3  # measured: no closure


def _straight_graph(params, n=80, spacing=0.5):
    """A graph back end with ``n`` keyframes ``spacing`` metres apart on a straight line
    (odometry edges only), for the global search's bookkeeping; ``slam._global_match`` is
    to be replaced by canned matches."""
    slam = GraphFastHoughSLAM(params, background=False)
    for k in range(n):
        slam._graph.add_node([k * spacing, 0.0, 0.0])
        if k:
            slam._graph.add_edge(k - 1, k, np.array([spacing, 0.0, 0.0]), np.eye(3) * 100)
    slam._path = [k * spacing for k in range(n)]
    return slam


def _canned(slam, scores, offset=0.0):
    """Make ``slam``'s global search return, for keyframe ``i`` in ``scores``, a match
    against keyframe 0 that scores ``scores[i]`` (if that reaches the search's floor) and
    puts keyframe ``i`` ``offset`` metres ahead of where the graph has it."""
    from fhslam.geometry import compose, relative

    asked = []

    def match(i, poses, min_score):
        asked.append((i, min_score))
        score = scores.get(i, 0.0)
        if score < min_score:
            return None
        placed = compose(poses[i], [offset, 0.0, 0.0])
        return 0, i, relative(poses[0], placed), np.eye(3) * 100, score, placed

    slam._global_match = match
    return asked


def test_a_held_global_match_is_confirmed_at_the_lower_score():
    """``search.min_score`` finds a hypothesis, ``search.confirm_score`` confirms it: a
    match at 0.52 is neither held nor refused as a confirmation; a hypothesis at 0.58 (over
    0.55) is held, not closed, and the agreeing match nine keyframes on at 0.52 closes both."""
    slam = _straight_graph(GraphSlamParams())
    poses = slam._graph.poses
    asked = _canned(slam, {20: 0.52, 40: 0.58, 49: 0.52})
    assert not slam._search_globally(20, poses) and slam._hypothesis is None
    assert not slam._search_globally(40, poses) and slam._hypothesis[1] == 40
    assert not slam._search_globally(48, poses)  # queries may not share a keyframe
    assert slam._search_globally(49, poses)
    assert [(lc.old, lc.new) for lc in slam.loops] == [(0, 40), (0, 49)]
    assert asked == [(20, 0.55), (40, 0.55), (49, 0.5)]
    # with the confirmation as strict as the finding, the same match confirms nothing
    strict = _straight_graph(GraphSlamParams(search=GlobalSearchParams(confirm_score=0.55)))
    _canned(strict, {40: 0.58, 49: 0.52})
    assert not strict._search_globally(40, poses) and not strict._search_globally(49, poses)
    assert strict.loops == [] and strict._hypothesis[1] == 40


def test_a_weak_match_that_disagrees_leaves_the_hypothesis_held():
    """A match under ``search.min_score`` that places the robot elsewhere (1 m off) neither
    confirms the held hypothesis nor replaces it; one over it replaces it."""
    slam = _straight_graph(GraphSlamParams())
    poses = slam._graph.poses
    _canned(slam, {40: 0.58})
    slam._search_globally(40, poses)
    _canned(slam, {49: 0.52, 50: 0.57}, offset=1.0)
    assert not slam._search_globally(49, poses) and slam._hypothesis[1] == 40
    assert not slam._search_globally(50, poses) and slam._hypothesis[1] == 50
    assert slam.loops == []


@pytest.mark.parametrize(
    ("tolerance", "off", "closes"), [(0.3, 0.25, True), (0.3, 0.35, False), (0.15, 0.25, False)]
)
def test_a_confirmation_agrees_within_global_consistency(tolerance, off, closes, monkeypatch):
    """``GLOBAL_CONSISTENCY``: a hypothesis held at keyframe 40 is confirmed at keyframe 49
    by a match that puts the keyframe 0.25 m from where the hypothesis puts it (the Freiburg
    hospital's right confirmations after its 900 m without a closure lie up to 0.22 m apart),
    not by one 0.35 m off; with the local closures' 0.15 m by neither. A
    match that does not confirm is held instead."""
    monkeypatch.setattr(search, "GLOBAL_CONSISTENCY", tolerance)
    slam = _straight_graph(GraphSlamParams())
    poses = slam._graph.poses
    _canned(slam, {40: 0.58})
    assert not slam._search_globally(40, poses) and slam._hypothesis[1] == 40
    _canned(slam, {49: 0.58}, offset=off)
    assert slam._search_globally(49, poses) is closes
    assert len(slam.loops) == (2 if closes else 0)
    assert slam._hypothesis is None if closes else slam._hypothesis[1] == 49


@pytest.mark.parametrize("lookback", [0.0, 1.0])
def test_after_a_long_blind_stretch_the_global_search_stays_wide(lookback, monkeypatch):
    """``GLOBAL_LOOKBACK``: a global closure that ended 34.5 m without a closure (keyframes
    0.5 m apart, closed at keyframe 69) keeps the distance the global search counts (its
    window; from 110 m also the estimate's guess) at 34.5 m for the next ``lookback × 34.5``
    metres, and a global closure after a shorter stretch within them does not cut that
    short. Without it the distance counts from each closure."""
    monkeypatch.setattr(search, "GLOBAL_LOOKBACK", lookback)
    slam = _straight_graph(GraphSlamParams(), n=200)
    poses = slam._graph.poses
    _canned(slam, {60: 0.6, 69: 0.6, 100: 0.6, 109: 0.6})
    slam._search_globally(60, poses)
    assert slam._search_globally(69, poses)
    assert slam._travelled(69) == (34.5 if lookback else 0.0)  # at the closure itself
    assert slam._travelled(100) == (34.5 if lookback else 15.5)
    slam._search_globally(100, poses)
    assert slam._search_globally(109, poses)  # 20 m after the first closure
    assert slam._travelled(120) == (34.5 if lookback else 5.5)
    assert slam._travelled(137) == (34.5 if lookback else 14.0)  # 68.5 m: still within
    assert slam._travelled(138) == 14.5  # at 69 m (34.5 + 34.5): counted from 54.5 m


def test_a_closure_within_the_blind_stretch_does_not_end_it():
    """30 m without a closure (keyframes 0.5 m apart, the last
    closure at keyframe 0), a global hypothesis held at keyframe 50; a local closure of
    keyframe 54 to keyframe 30 (15 m into the stretch, ``search.after`` 10 m) leaves the
    stretch going on, and the hypothesis is confirmed at keyframe 59. Only a closure that
    reaches back further (keyframe 10, 5 m in) ends it."""
    slam = _straight_graph(GraphSlamParams())
    poses = slam._graph.poses
    _canned(slam, {50: 0.6, 59: 0.6})
    assert not slam._search_globally(50, poses) and slam._hypothesis[1] == 50
    slam._end_blind(54, [30])
    assert slam._travelled(59) == 29.5
    assert slam._far(59)  # _close_loops searches globally again
    assert slam._search_globally(59, poses) and slam._last_loop_path == 29.5
    slam._last_loop_path = 0.0
    slam._end_blind(62, [30, 10])  # one of them reaches back: the stretch ends
    assert slam._last_loop_path == 31.0
    slam._last_loop_path = 0.0
    slam._end_blind(62, [19, 20])  # 9.5 m in: not as lost as the global search's start
    assert slam._last_loop_path == 31.0


def test_a_candidate_that_failed_for_the_previous_keyframe_waits_a_keyframe(
    three_laps, monkeypatch
):
    """A wide search does not try again, for keyframe i, the candidate whose match failed
    for keyframe i - 1 (it does for i + 1): the query shares two of its three keyframes with
    the previous one's. On this log some searches fail, none is such a repeat, and the run
    closes its loops to the usual ATE."""
    import inspect

    match = closure.match_clouds
    searches = []  # (keyframe, candidate, tracking, passed)

    def spy(*args, **kwargs):
        m = match(*args, **kwargs)
        f = inspect.currentframe().f_back.f_locals
        min_score = f["p"].loops.min_score
        searches.append((f["i"], f["j"], f["win"] == f["p"].tracker.window, m.score >= min_score))
        return m

    monkeypatch.setattr(closure, "match_clouds", spy)
    slam = GraphFastHoughSLAM(background=False)
    r = run_backend(slam, three_laps)
    failed = {(i, j) for i, j, _, ok in searches if not ok}
    repeats = [(i, j) for i, j, track, _ in searches if not track and (i - 1, j) in failed]
    assert len(failed) >= 3, failed  # the rule has something to skip
    assert repeats == [], repeats
    assert ate(r.poses, three_laps.truth).rmse <= 0.02  # measured 0.42 cm


@pytest.mark.parametrize("glitch", [False, True])
def test_an_edge_across_doubtful_scans_carries_the_odometrys_motion(
    three_laps, monkeypatch, glitch
):
    """An edge across a doubtful scan has the odometry's information only, so its
    measurement is the odometry's motion between the two keyframes, not the doubtful track's
    (here scans 60-66 are made doubtful, each turned 8 degrees off its prediction). After an
    odometry glitch on the way (a 1 m jump at scan 63) the odometry's motion is wrong: that
    edge keeps the track's."""
    from dataclasses import replace

    from fhslam.geometry import relative
    from fhslam.slam.graph.tracker import ScanTracker, Track

    doubtful = range(60, 67)
    log = three_laps
    if glitch:
        odometry = log.odometry.copy()
        odometry[63:, 0] += 1.0
        log = replace(log, odometry=odometry)
    step, track = GraphFastHoughSLAM.step, ScanTracker.track
    at = [-1]

    def counted(self, scan, odometry):
        at[0] += 1
        return step(self, scan, odometry)

    def off(self, points, predicted, previous):
        t = track(self, points, predicted, previous)
        if at[0] in doubtful:
            turned = predicted + np.array([0, 0, np.radians(8)])
            return Track(turned, 0.5, True, False, False, None)
        return t

    monkeypatch.setattr(GraphFastHoughSLAM, "step", counted)
    monkeypatch.setattr(ScanTracker, "track", off)
    slam = GraphFastHoughSLAM(GraphSlamParams(loops=LoopParams(candidates=0)), background=False)
    run_backend(slam, log)
    first, second, z, _ = slam.graph.edges
    kf = slam.keyframe_steps
    across = [
        e
        for e in range(len(z))
        if second[e] == first[e] + 1 and kf[first[e]] < doubtful[-1] and kf[second[e]] > 60
    ]
    assert across  # the doubt spans one or two keyframe edges
    differ = []
    for e in across:
        a, b = first[e], second[e]
        odometry = relative(log.odometry[kf[a]], log.odometry[kf[b]])
        tracked = relative(slam._kf_front[a], slam._kf_front[b])
        glitched = glitch and kf[a] < 63 <= kf[b]
        expected, other = (tracked, odometry) if glitched else (odometry, tracked)
        np.testing.assert_allclose(z[e], expected, atol=1e-9)
        differ.append(np.abs(z[e] - other).max())
    assert max(differ) > 0.1  # and the two differ: the turns of 8 degrees, the 1 m jump


def test_same_log_same_numbers(three_laps):
    a = run_slam(three_laps, "graph").poses
    b = run_slam(three_laps, "graph").poses
    np.testing.assert_array_equal(a, b)


def test_the_papers_parameters_shape_the_map_and_move_no_pose(paper_log_small):
    """``lines`` (the paper's Loops 1 and 2) are not parameters of the estimate: another
    extraction or merging leaves every pose bit-equal; a longer shortest reference line
    drops the map's one shorter line."""
    from dataclasses import replace

    from fhslam.slam import SlamParams

    paper = SlamParams()
    a = run_backend(GraphFastHoughSLAM(), paper_log_small)
    b = run_backend(GraphFastHoughSLAM(lines=replace(paper, min_reference_length=1.0)),
                    paper_log_small)  # fmt: skip
    c = run_backend(GraphFastHoughSLAM(lines=replace(paper, extraction=replace(
        paper.extraction, cluster_gap=0.05))), paper_log_small)  # fmt: skip
    np.testing.assert_array_equal(a.poses, b.poses)
    np.testing.assert_array_equal(a.poses, c.poses)
    lengths = sorted(line.length for line in a.map)  # measured 0.89, 1.78, 2.19, 4.5, 4.77 m
    assert lengths[0] < 1.0 and lengths[1] > 1.0
    assert sorted(line.length for line in b.map) == lengths[1:]


def test_the_back_ends_thread_changes_no_bit(three_laps):
    """The back end on its own thread (the default) gets the same calls in the same order as
    in turn: the same poses, closures and graph, bit for bit."""
    runs = []
    for background in (True, False):
        slam = GraphFastHoughSLAM(background=background)
        runs.append((run_backend(slam, three_laps).poses, slam))
    (a, sa), (b, sb) = runs
    np.testing.assert_array_equal(a, b)
    assert [(lc.old, lc.new, lc.score) for lc in sa.loops] == [
        (lc.old, lc.new, lc.score) for lc in sb.loops
    ]
    np.testing.assert_array_equal(sa.graph.poses, sb.graph.poses)
    assert sa._worker is None  # finish() let the thread end


def test_the_back_end_raises_in_the_callers_thread(three_laps):
    """An error on the back end's thread surfaces at the next keyframe or read, not lost."""
    slam = GraphFastHoughSLAM()

    def broken(i):
        raise RuntimeError(f"no loops at keyframe {i}")

    slam._close_loops = broken
    with pytest.raises(RuntimeError, match="no loops at keyframe 1"):
        run_backend(slam, three_laps)


def test_a_dropped_slam_leaves_no_thread_behind(three_laps):
    import gc
    import threading
    import weakref

    from fhslam.experiments.bench import log_head

    before = threading.active_count()
    slam = GraphFastHoughSLAM()
    for k in range(40):  # some keyframes, no finish(): the thread is still there
        slam.step(three_laps.scan(k), three_laps.odometry[k])
    assert slam._worker is not None and threading.active_count() == before + 1
    slam.sync()  # the calls still queued hold the object
    gone = weakref.ref(slam)
    del slam
    gc.collect()
    assert gone() is None
    for _ in range(100):  # the thread ends once it sees the object collected
        if threading.active_count() == before:
            break
        threading.Event().wait(0.01)
    assert threading.active_count() == before
    assert len(run_slam(log_head(three_laps, 40), "graph").poses) == 40


@functools.cache
def _harsh_hall():
    """The pillared hall with 1 mm of range noise and 10 % of its scans dropped."""
    return degrade(
        simulate(load_world("hall"), seed=0), drop_fraction=0.1, range_noise=0.001, seed=0
    )


@pytest.mark.parametrize("last_bit", [None, 1, 3, 6])
def test_a_near_closure_at_the_start_waits_for_confirmation(last_bit):
    """The harsh hall comes back to its start with its estimate within 2 cm; closures against
    the first keyframes (whose targets have no keyframes before them) are 11-165 cm off
    there. When a wrong one moved its keyframe by less than 0.3 m it entered the graph
    unconfirmed: ATE 8.8, 6.0 and 11.7 cm for last-bit draws 1, 3 and 6 (0.93 cm unperturbed).
    Measured now (``loops.confirm_distance`` 0.1 m): 0.95, 0.83, 0.87, 0.89 cm."""
    log = _harsh_hall() if last_bit is None else perturb_odometry(_harsh_hall(), last_bit)
    assert len(log) == 299
    r = ate(run_slam(log).poses, log.truth)
    assert r.rmse <= 0.02, f"last bit {last_bit}: ATE {100 * r.rmse:.2f} cm"


@pytest.mark.parametrize("last_bit", [None, 1])
def test_a_near_closure_that_is_not_unique_waits_for_confirmation(last_bit):
    """The same return: the last keyframe matches the first ones 11 cm (score 0.62) and 81
    cm (0.68) off along the pillar rows, both refined to a residual under 1 cm; the nearer
    moves the keyframe less than ``loops.confirm_distance``, but it is not unique
    (``LOOP_UNIQUE_RADIUS``) and waits. Measured: 0.95 and 0.83 cm (last-bit draws none and
    1); 5.50 cm when such a match entered unconfirmed."""
    log = _harsh_hall() if last_bit is None else perturb_odometry(_harsh_hall(), last_bit)
    r = ate(run_slam(log).poses, log.truth)
    assert r.rmse <= 0.02, f"last bit {last_bit}: ATE {100 * r.rmse:.2f} cm"


def test_dropped_scans_and_clutter(three_laps):
    """10% of the scans dropped, 5% clutter returns: every scan still gets a pose."""
    log = degrade(three_laps, drop_fraction=0.1, clutter_fraction=0.05, seed=1)
    r = run_slam(log, "graph")
    assert np.isfinite(r.poses).all() and len(r.poses) == len(log.timestamps)
    assert ate(r.poses, log.truth).rmse <= 0.10  # measured 0.55 cm


def test_a_keyframe_that_saw_nothing_looks_where_it_stands(three_laps):
    """Scans 300-339 dropped (a blind stretch of 2.4 m): the keyframes started there have
    no points, and where they looked (for the loop search) is their own position; no empty
    mean, no NaN, and the run closes its loops as before."""
    import dataclasses
    import warnings

    ranges = three_laps.ranges.copy()
    ranges[300:340] = np.nan
    log = dataclasses.replace(three_laps, ranges=ranges)
    slam = GraphFastHoughSLAM()
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # numpy's "Mean of empty slice"
        r = run_backend(slam, log)
    steps = slam.keyframe_steps
    blind = np.flatnonzero((steps > 300) & (steps < 339))
    assert len(blind) >= 3  # measured 6
    np.testing.assert_array_equal(slam._views[blind], 0.0)
    assert np.isfinite(slam._views).all() and len(slam._views) == len(slam.graph)
    assert len(slam.loops) >= 20  # measured 97
    assert ate(r.poses, log.truth).rmse <= 0.05  # measured 0.60 cm


def test_without_loop_closures_no_loop_edges(three_laps):
    slam = GraphFastHoughSLAM(GraphSlamParams(loops=LoopParams(candidates=0)))
    run_backend(slam, three_laps)
    assert slam.loops == [] and set(slam.graph.edges[3]) == {"odometry"}


@pytest.mark.parametrize(
    ("group", "field", "value", "message"),
    [
        ("keyframes", "distance", 0.0, "KeyframeParams.distance must be > 0"),
        ("keyframes", "voxel", -1.0, "KeyframeParams.voxel must be > 0"),
        ("keyframes", "submap", 0, "KeyframeParams.submap must be >= 1"),
        ("loops", "min_score", 1.5, r"LoopParams.min_score must be in \[0, 1\]"),
        ("loops", "target_keyframes", -1, "LoopParams.target_keyframes must be >= 0"),
        ("loops", "consistency", 0.0, "LoopParams.consistency must be > 0"),
        ("search", "every", -1, "GlobalSearchParams.every must be >= 0"),
        ("search", "after", -1.0, "GlobalSearchParams.after must be >= 0"),
        ("search", "after", float("nan"), "GlobalSearchParams.after must be >= 0"),
        ("search", "min_score", 1.5, r"GlobalSearchParams.min_score must be in \[0, 1\]"),
        ("search", "window_deg", 0.0, r"GlobalSearchParams.window_deg must be in \(0, 180\]"),
        ("search", "confirm_score", 1.5, r"confirm_score must be in \[0, 1\]"),
        ("edges", "odometry_sigma", (0.1, 0.0), "EdgeParams.odometry_sigma must be"),
        ("optimiser", "iterations", 0, "OptimiserParams.iterations must be >= 1"),
    ],
)
def test_bad_parameters_are_named(group, field, value, message):
    import dataclasses

    kind = type(getattr(GraphSlamParams(), group))
    with pytest.raises(ValueError, match=message):
        kind(**{field: value})
    with pytest.raises(ValueError, match=f"GraphSlamParams.{group} must be a {kind.__name__}"):
        GraphSlamParams(**{group: dataclasses.asdict(kind())})


def test_the_default_method_has_at_most_40_parameters():
    """The default method's parameters (its groups opened) are at most 40, and every one
    has a range."""
    from dataclasses import fields

    from fhslam.slam.graph import count_parameters

    params = GraphSlamParams()
    assert count_parameters(params) == 37
    for f in fields(params):
        group = getattr(params, f.name)
        assert set(group.RANGES) == {g.name for g in fields(group)}, f.name
