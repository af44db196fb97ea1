"""Multi-target metrics: GOSPA, OSPA^(2), CLEAR MOT and SIAP on hand-computed cases, GOSPA and
OSPA against a brute-force search over assignments and against Stone Soup."""

from __future__ import annotations

import itertools
from datetime import datetime

import numpy as np
import pytest

from fusetrack.core import ConfigError, ShapeError, Track
from fusetrack.evaluation import (
    clear_mot,
    gospa,
    gospa_over_time,
    ospa,
    ospa2,
    ospa2_over_time,
    siap,
)

# --------------------------------------------------------------------------------------------
# GOSPA by hand


def test_gospa_one_matched_one_missed_one_false():
    truth = np.array([[0.0, 0.0], [10.0, 0.0]])
    est = np.array([[1.0, 0.0], [20.0, 20.0]])
    r = gospa(est, truth, c=2.0, p=2)
    # (0,0)-(1,0) at distance 1 < c is matched: localisation 1^2 = 1.
    # (10,0) is missed and (20,20) false, each costing c^p / alpha = 4 / 2 = 2.
    # GOSPA = sqrt(1 + 2 * (c^p / 2)) = sqrt(5).
    assert r.distance == pytest.approx(np.sqrt(5.0), abs=1e-12)
    assert (r.localisation, r.missed, r.false) == pytest.approx((1.0, 2.0, 2.0))
    assert (r.n_missed, r.n_false) == (1, 1)
    np.testing.assert_array_equal(r.assignment, [0, -1])
    # OSPA on the same sets spreads the cut-off pair over n = 2: sqrt((1 + 2^2) / 2)
    assert ospa(est, truth, c=2.0, p=2) == pytest.approx(np.sqrt(2.5))


def test_gospa_pair_beyond_cutoff_is_missed_plus_false_for_alpha_2():
    truth = np.array([[0.0, 0.0]])
    est = np.array([[3.0, 0.0], [50.0, 0.0]])
    # alpha = 2, p = 1, c = 2: nothing within c, so 1 missed + 2 false: (2 / 2) * 3 = 3
    r = gospa(est, truth, c=2.0, p=1)
    assert r.distance == pytest.approx(3.0)
    assert (r.localisation, r.missed, r.false) == pytest.approx((0.0, 1.0, 2.0))
    np.testing.assert_array_equal(r.assignment, [-1])
    # alpha = 1 (Definition 1): truth assigned to an estimate at cut-off cost min(3, 2) = 2,
    # plus c^p / alpha * (2 - 1) = 2 for the extra estimate: 4
    r1 = gospa(est, truth, c=2.0, p=1, alpha=1.0)
    assert r1.distance == pytest.approx(4.0)
    assert (r1.localisation, r1.missed, r1.false) == pytest.approx((2.0, 0.0, 2.0))
    assert r1.assignment[0] in (0, 1)


def test_gospa_empty_sets_and_nan_rows():
    truth = np.array([[0.0, 0.0], [5.0, 0.0], [0.0, 5.0]])
    # no estimates: 3 missed, sqrt(3 * c^2 / 2) = sqrt(6) with c = 2
    r = gospa(np.zeros((0, 2)), truth, c=2.0)
    assert r.distance == pytest.approx(np.sqrt(6.0))
    assert (r.missed, r.false, r.n_missed) == (6.0, 0.0, 3)
    np.testing.assert_array_equal(r.assignment, [-1, -1, -1])
    r = gospa(truth, [], c=2.0)
    assert (r.distance, r.false, r.n_false, r.assignment.size) == (np.sqrt(6.0), 6.0, 3, 0)
    assert gospa([], [], c=2.0).distance == 0.0
    # a NaN row is no estimate; the assignment names rows of the input
    r = gospa([[np.nan, np.nan], [0.5, 0.0]], truth[:1], c=2.0)
    np.testing.assert_array_equal(r.assignment, [1])
    assert r.distance == pytest.approx(0.5)


def test_gospa_over_time_and_over_the_run():
    truth = [np.array([[0.0, 0.0]]), np.array([[0.0, 0.0]])]
    est = [np.array([[1.0, 0.0]]), np.zeros((0, 2))]
    s = gospa_over_time(est, truth, c=2.0, p=2)
    # step 0: matched at 1 -> 1; step 1: one missed -> c^2 / 2 = 2
    np.testing.assert_allclose(s.distance, [1.0, np.sqrt(2.0)])
    np.testing.assert_allclose(s.localisation, [1.0, 0.0])
    np.testing.assert_allclose(s.missed, [0.0, 2.0])
    np.testing.assert_array_equal(s.n_missed, [0, 1])
    # over the run: sqrt(mean(1, 2)) = sqrt(1.5) = sqrt(mean loc + mean missed + mean false)
    assert s.run_distance == pytest.approx(np.sqrt(1.5))
    total = s.localisation.mean() + s.missed.mean() + s.false.mean()
    assert s.run_distance**2 == pytest.approx(total)


def test_gospa_bad_arguments():
    X = np.zeros((2, 2))
    with pytest.raises(ConfigError, match="c="):
        gospa(X, X, c=0.0)
    with pytest.raises(ConfigError, match="p="):
        gospa(X, X, c=1.0, p=0.5)
    for alpha in (0.0, 2.5, -1.0):
        with pytest.raises(ConfigError, match="alpha="):
            gospa(X, X, c=1.0, alpha=alpha)
    with pytest.raises(ShapeError, match=r"estimates\.shape"):
        gospa(np.zeros((2, 3)), X, c=1.0)
    with pytest.raises(ShapeError, match=r"truth\.shape"):
        gospa(X, np.zeros((2, 2, 2)), c=1.0)
    with pytest.raises(ShapeError, match="len"):
        gospa_over_time([X], [X, X], c=1.0)


# --------------------------------------------------------------------------------------------
# GOSPA and OSPA against a brute-force search over every assignment


def _brute_gospa_alpha2(X, Y, c, p):
    """Proposition 1 of Rahmathullah et al. 2017: min over partial assignments gamma of
    sum_{gamma} d^p + c^p / 2 (|X| + |Y| - 2 |gamma|), pairs only when d < c."""
    D = np.linalg.norm(X[:, None] - Y[None], axis=-1) if len(X) and len(Y) else None
    best = c**p / 2 * (len(X) + len(Y))
    for k in range(1, min(len(X), len(Y)) + 1):
        for xs in itertools.combinations(range(len(X)), k):
            for ys in itertools.permutations(range(len(Y)), k):
                d = D[list(xs), list(ys)]
                if np.all(d < c):
                    best = min(best, np.sum(d**p) + c**p / 2 * (len(X) + len(Y) - 2 * k))
    return best ** (1 / p)


def _brute_definition(X, Y, c, p, alpha, normalise):
    """Definition 1 (GOSPA, normalise=False) / OSPA (normalise=True) by permutations."""
    if len(X) > len(Y):
        X, Y = Y, X
    m, n = len(X), len(Y)
    if n == 0:
        return 0.0
    D = np.minimum(np.linalg.norm(X[:, None] - Y[None], axis=-1), c) if m else np.zeros((0, n))
    best = min(np.sum(D[range(m), list(pi)] ** p) for pi in itertools.permutations(range(n), m))
    total = best + c**p / alpha * (n - m)
    return (total / n if normalise else total) ** (1 / p)


def test_gospa_and_ospa_equal_brute_force_on_random_sets():
    rng = np.random.default_rng(17)
    for _ in range(60):
        X = rng.uniform(0, 6, (rng.integers(0, 5), 2))
        Y = rng.uniform(0, 6, (rng.integers(0, 5), 2))
        c, p = rng.uniform(0.5, 4.0), rng.choice([1.0, 2.0, 3.0])
        alpha = rng.choice([0.5, 1.0, 2.0])
        r = gospa(X, Y, c=c, p=p)
        assert r.distance == pytest.approx(_brute_gospa_alpha2(X, Y, c, p), abs=1e-9)
        assert r.distance**p == pytest.approx(r.localisation + r.missed + r.false, abs=1e-9)
        ra = gospa(X, Y, c=c, p=p, alpha=alpha)
        assert ra.distance == pytest.approx(_brute_definition(X, Y, c, p, alpha, False), abs=1e-9)
        assert ospa(X, Y, c=c, p=p) == pytest.approx(_brute_definition(X, Y, c, p, 1, True))


# --------------------------------------------------------------------------------------------
# GOSPA and OSPA against Stone Soup (a bench extra: skipped when it is not installed)


def test_gospa_and_ospa_equal_stone_soup_on_random_sets():
    pytest.importorskip("stonesoup")
    from stonesoup.metricgenerator.ospametric import GOSPAMetric, OSPAMetric
    from stonesoup.types.state import State

    t0 = datetime(2017, 7, 10)
    rng = np.random.default_rng(2017)
    for _ in range(50):
        X = rng.uniform(0, 10, (rng.integers(1, 6), 2))  # Stone Soup needs a timestamp: no
        Y = rng.uniform(0, 10, (rng.integers(1, 6), 2))  # empty sets here
        c, p = rng.uniform(1.0, 6.0), rng.choice([1.0, 2.0])
        xs = [State(x.reshape(-1, 1), timestamp=t0) for x in X]
        ys = [State(y.reshape(-1, 1), timestamp=t0) for y in Y]
        ref = GOSPAMetric(c=c, p=p).compute_gospa_metric(xs, ys)[0].value
        r = gospa(X, Y, c=c, p=p)
        for name in ("distance", "localisation", "missed", "false"):
            assert getattr(r, name) == pytest.approx(float(ref[name]), abs=1e-9), name
        # Stone Soup's OSPA solves the assignment on d, not d^p: optimal for p = 1 only
        ref_ospa = OSPAMetric(c=c, p=1).compute_OSPA_distance(xs, ys).value
        assert ospa(X, Y, c=c, p=1) == pytest.approx(float(ref_ospa), abs=1e-9)


# --------------------------------------------------------------------------------------------
# tracks for OSPA^(2), CLEAR MOT and SIAP


def _track(times, xy, track_id=None):
    xy = np.broadcast_to(np.asarray(xy, dtype=float), (len(times), 2))
    return Track(np.asarray(times, dtype=float), xy.copy(), id=track_id)


def _line(times, y, dy=0.0, track_id=None):
    """A target moving along x = t at height y (an estimate offset by dy)."""
    t = np.asarray(times, dtype=float)
    return _track(t, np.column_stack([t, np.full(t.size, y + dy)]), track_id)


def test_ospa2_identical_and_disjoint_track_sets():
    truth = [_line(range(5), 0.0, track_id=1), _line(range(2, 8), 10.0, track_id=2)]
    assert ospa2(truth, truth, c=5.0, p=2) == 0.0
    # far away at every time: each base distance is c, so OSPA^(2) = c
    far = [_line(range(5), 100.0), _line(range(2, 8), 200.0)]
    assert ospa2(far, truth, c=5.0) == pytest.approx(5.0)
    # disjoint in time: never both present, so every step of the union costs c
    later = [_line(range(10, 15), 0.0)]
    assert ospa2(later, truth, c=5.0, p=2) == pytest.approx(5.0)
    assert ospa2([], truth, c=5.0) == 5.0


def test_ospa2_time_averaged_base_distance_by_hand():
    truth = [_line(range(4), 0.0)]  # t = 0..3
    late = _line([1, 2, 3], 0.0, dy=1.0)  # starts one step late, 1 off
    # union of the two domains: 4 steps; t=0 only truth -> c = 5; t=1..3: 1 each.
    # base distance (5 + 1 + 1 + 1) / 4 = 2, and one track each: OSPA^(2) = 2
    assert ospa2([late], truth, c=5.0) == pytest.approx(2.0)
    # a spurious second track at base distance c: (1/2) (2^p + c^p (2 - 1))^(1/p)
    spurious = _line(range(4), 50.0)
    assert ospa2([late, spurious], truth, c=5.0, p=1) == pytest.approx((2 + 5) / 2)
    assert ospa2([late, spurious], truth, c=5.0, p=2) == pytest.approx(np.sqrt((4 + 25) / 2))
    # window of 2 steps: [0] only truth -> 5; [0,1] -> (5 + 1)/2 = 3; [1,2] -> 1; [2,3] -> 1
    times, values = ospa2_over_time([late], truth, c=5.0, window=2)
    np.testing.assert_allclose(times, [0, 1, 2, 3])
    np.testing.assert_allclose(values, [5.0, 3.0, 1.0, 1.0])


def _two_target_scene():
    """Truths A (y = 0) and B (y = 10), both along x = t for t = 0..4.

    Track 1 follows A throughout (0.1 off); track 2 follows B at t = 0, 1 (0.2 off); B has no
    estimate at t = 2 (a miss); track 3 picks B up at t = 3, 4 (0.3 off): an id switch after a
    fragmentation. Track 4 is a false alarm far away at t = 2.
    """
    T = range(5)
    truth = [_line(T, 0.0, track_id=10), _line(T, 10.0, track_id=20)]
    est = [
        _line(T, 0.0, dy=0.1, track_id=1),
        _line([0, 1], 10.0, dy=0.2, track_id=2),
        _line([3, 4], 10.0, dy=0.3, track_id=3),
        _track([2], [100.0, 100.0], track_id=4),
    ]
    return est, truth


def test_clear_mot_two_targets_one_switch_one_miss():
    est, truth = _two_target_scene()
    r = clear_mot(est, truth, threshold=1.0)
    # 10 true objects (2 targets x 5 steps); matches: A 5 + B 4 = 9
    assert (r.n_truth, r.matches) == (10, 9)
    assert (r.misses, r.false_positives, r.id_switches, r.fragmentations) == (1, 1, 1, 1)
    # MOTA = 1 - (1 miss + 1 false positive + 1 switch) / 10 = 0.7
    assert r.mota == pytest.approx(0.7)
    # MOTP = (5 * 0.1 + 2 * 0.2 + 2 * 0.3) / 9 = 1.5 / 9
    assert r.motp == pytest.approx(1.5 / 9)


def test_clear_mot_keeps_a_valid_previous_correspondence():
    truth = [_track([0, 1], [0.0, 0.0], track_id=7)]
    old = _track([0, 1], [0.5, 0.0], track_id=1)
    closer = _track([1], [0.1, 0.0], track_id=2)
    r = clear_mot([old, closer], truth, threshold=1.0)
    # at t = 1 the match (7, 1) is still within 1, so it is kept although track 2 is nearer:
    # no switch, and track 2 is a false positive. MOTA = 1 - 1/2.
    assert (r.id_switches, r.false_positives, r.matches) == (0, 1, 2)
    assert r.mota == pytest.approx(0.5)
    assert r.motp == pytest.approx(0.5)
    # once the old track drifts past the threshold the nearer one takes over: one switch
    drifted = _track([0, 1], [[0.5, 0.0], [3.0, 0.0]], track_id=1)
    assert clear_mot([drifted, closer], truth, threshold=1.0).id_switches == 1


def test_clear_mot_no_truth_and_bad_arguments():
    est, truth = _two_target_scene()
    r = clear_mot(est, [], threshold=1.0)
    assert np.isnan(r.mota) and np.isnan(r.motp) and r.false_positives == 10
    with pytest.raises(ConfigError, match="threshold="):
        clear_mot(est, truth, threshold=0.0)
    with pytest.raises(ConfigError, match="ids"):
        clear_mot([est[0], est[0]], truth, threshold=1.0)
    with pytest.raises(ConfigError, match="Track"):
        clear_mot([np.zeros((3, 2))], truth, threshold=1.0)
    with pytest.raises(ConfigError, match="sequence"):
        clear_mot(est[0], truth, threshold=1.0)
    batched = Track(np.arange(3.0), np.zeros((3, 4, 2)), id=1)
    with pytest.raises(ShapeError, match=r"means\.shape"):
        clear_mot([batched], truth, threshold=1.0)
    with pytest.raises(ShapeError, match="position size"):
        clear_mot(est, truth, threshold=1.0, truth_index=[0])
    with pytest.raises(ConfigError, match="time_tol="):
        clear_mot(est, truth, threshold=1.0, time_tol=-1.0)


def test_siap_hand_made_case():
    est, truth = _two_target_scene()
    est = [
        *est[:3],
        _line([2], 0.0, dy=0.4, track_id=4),  # a second track on A at t = 2: ambiguity
        _track([0, 1], [100.0, 100.0], track_id=5),  # spurious at t = 0, 1
    ]
    r = siap(est, truth, threshold=1.0)
    # step: J (truths), JT (tracked truths), N (tracks), NA (tracks on a truth)
    # t0: 2, 2, 3, 2 | t1: 2, 2, 3, 2 | t2: 2, 1, 2, 2 | t3: 2, 2, 2, 2 | t4: 2, 2, 2, 2
    # sums: J 10, JT 9, N 12, NA 10
    assert r.completeness == pytest.approx(9 / 10)
    assert r.ambiguity == pytest.approx(10 / 9)
    assert r.spuriousness == pytest.approx(2 / 12)
    # errors: track 1 5 x 0.1, track 2 2 x 0.2, track 3 2 x 0.3, track 4 1 x 0.4 -> 1.9 / 10
    assert r.position_accuracy == pytest.approx(0.19)
    # A: one track covers it (NU 1), tracked 4 s, longest segment 4 s, lifetime 4 s.
    # B: tracks 2 then 3 (NU 2), tracked 1 + 1 = 2 s, longest 1 s, lifetime 4 s.
    # R = ((1 - 1) + (2 - 1)) / (4 + 2) = 1/6; LS = (4 + 1) / (4 + 4) = 5/8
    assert r.rate_of_track_number_change == pytest.approx(1 / 6)
    assert r.longest_track_segment == pytest.approx(5 / 8)


def test_siap_without_tracks_and_merged_times():
    _, truth = _two_target_scene()
    r = siap([], truth, threshold=1.0)
    assert r.completeness == 0.0
    assert np.isnan(r.ambiguity) and np.isnan(r.spuriousness) and np.isnan(r.position_accuracy)
    assert r.longest_track_segment == 0.0
    # times that differ by float noise are one step (time_tol)
    shifted = [_line(np.arange(5) + 1e-12, 0.0, dy=0.1, track_id=1)]
    assert siap(shifted, truth[:1], threshold=1.0).completeness == 1.0
    assert clear_mot(shifted, truth[:1], threshold=1.0).mota == 1.0
