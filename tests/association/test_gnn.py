"""Global nearest neighbour: hand-computed cases where greedy assignment is wrong, missed and
clutter options, agreement with brute-force enumeration, bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fusetrack.association import (
    GlobalNearestNeighbour,
    ScanLikelihoods,
    joint_events,
    log_likelihood_ratios,
)
from fusetrack.core import ConfigError, ShapeError

NO = -np.inf


def scan(ll, missed, clutter=None, ids=None):
    ll = np.asarray(ll, float)
    t, m = ll.shape
    clutter = np.zeros(m) if clutter is None else np.asarray(clutter, float)
    ids = tuple(range(10, 10 + t)) if ids is None else ids
    return ScanLikelihoods(ids, ll, np.broadcast_to(np.asarray(missed, float), (t,)), clutter)


def chosen(association):
    return {tid: tuple(h.measurement for h in hs) for tid, hs in association.hypotheses.items()}


def test_2x2_optimal_differs_from_greedy():
    # greedy takes the best pair (10, track 10 -> z0) and leaves track 11 with z1 (1): total 11;
    # the optimum swaps them: 9 + 9 = 18
    result = GlobalNearestNeighbour().associate(scan([[10, 9], [9, 1]], missed=-100.0))
    assert chosen(result) == {10: (1,), 11: (0,)}
    assert result.unassociated == ()
    assert result.info["log_ratio"] == pytest.approx(18.0)
    assert all(h.probability == 1.0 for hs in result.hypotheses.values() for h in hs)


def test_3x2_optimal_misses_the_track_greedy_would_keep():
    # events: (z0, miss, z1) = 5 - 2 + 3 = 6 (greedy), (z1, z0, miss) = 4 + 4.5 - 2 = 6.5 (best),
    # (miss, z0, z1) = -2 + 4.5 + 3 = 5.5
    ll = [[5, 4], [4.5, NO], [NO, 3]]
    result = GlobalNearestNeighbour().associate(scan(ll, missed=-2.0))
    assert chosen(result) == {10: (1,), 11: (0,), 12: (None,)}
    assert result.info["log_ratio"] == pytest.approx(6.5)


def test_clutter_density_enters_as_a_per_measurement_offset():
    # the same likelihoods, but z1 is in a dense-clutter region: its ratios drop by 3
    # events: (z0, z1) = 5 + (3 - 3) = 5 vs (z0, miss) = 5 - 1 = 4 -> still assigned;
    # with ratios dropping by 5: (z0, z1) = 3 < 4 -> missed, z1 is clutter
    ll = [[5, NO], [NO, 3]]
    kept = GlobalNearestNeighbour().associate(scan(ll, -1.0, clutter=[0.0, 3.0]))
    assert chosen(kept) == {10: (0,), 11: (1,)}
    lost = GlobalNearestNeighbour().associate(scan(ll, -1.0, clutter=[0.0, 5.0]))
    assert chosen(lost) == {10: (0,), 11: (None,)}
    assert lost.unassociated == (1,)


@pytest.mark.parametrize(("ll", "assigned"), [(-10.0, False), (0.0, True)])
def test_missed_and_clutter_chosen_when_the_likelihood_is_poor(ll, assigned):
    # ratio ll - 0 against missed log(0.1) = -2.30
    result = GlobalNearestNeighbour().associate(scan([[ll]], missed=math.log(0.1)))
    assert chosen(result) == {10: (0 if assigned else None,)}
    assert result.unassociated == (() if assigned else (0,))


def test_impossible_miss_with_nothing_in_the_gate_is_reported_missed():
    # log_missed = -inf (P_D P_G = 1) and no gated measurement: the only event has probability 0
    result = GlobalNearestNeighbour().associate(scan([[NO, 2.0], [NO, 1.0]], missed=NO))
    assert chosen(result) == {10: (1,), 11: (None,)}  # the better ratio keeps z1
    assert result.unassociated == (0,)
    assert result.info["log_ratio"] == -np.inf


def test_empty_scans():
    none = GlobalNearestNeighbour().associate(scan(np.zeros((2, 0)), missed=-1.0))
    assert chosen(none) == {10: (None,), 11: (None,)}
    no_tracks = GlobalNearestNeighbour().associate(scan(np.zeros((0, 3)), missed=-1.0))
    assert dict(no_tracks.hypotheses) == {} and no_tracks.unassociated == (0, 1, 2)


def test_gnn_is_the_most_likely_enumerated_event():
    rng = np.random.default_rng(3)
    for _ in range(40):
        t, m = rng.integers(1, 5), rng.integers(0, 5)
        ll = rng.normal(0, 3, (t, m))
        ll[rng.random((t, m)) < 0.3] = NO
        scores = scan(ll, rng.uniform(-4, -0.1, t), rng.normal(0, 1, m))
        w = log_likelihood_ratios(scores)
        best = max(sum(w[i, j] for i, j in enumerate(e)) for e in joint_events(w))
        result = GlobalNearestNeighbour().associate(scores)
        assert result.info["log_ratio"] == pytest.approx(best, abs=1e-9)


@pytest.mark.parametrize(
    ("scores", "field"),
    [
        (
            ScanLikelihoods((1,), np.zeros((1, 2)), np.array([-1.0]), np.zeros(3)),
            "log_likelihood.shape",
        ),
        (
            ScanLikelihoods((1, 2), np.zeros((2, 2)), np.array([-1.0]), np.zeros(2)),
            "log_missed.shape",
        ),
        (ScanLikelihoods((1, 1), np.zeros((2, 2)), np.array([-1.0, -1]), np.zeros(2)), "track_ids"),
    ],
)
def test_inconsistent_shapes_are_shape_errors(scores, field):
    with pytest.raises(ShapeError, match=field):
        GlobalNearestNeighbour().associate(scores)


@pytest.mark.parametrize(
    ("scores", "field"),
    [
        (scan([[np.nan, 1.0]], -1.0), "log_likelihood="),
        (scan([[np.inf, 1.0]], -1.0), "log_likelihood="),
        (scan([[1.0]], 0.5), "log_missed="),
        (scan([[1.0]], -1.0, clutter=[np.nan]), "log_clutter="),
        (ScanLikelihoods((1,), np.array([["a"]]), np.array([-1.0]), np.zeros(1)), "numeric"),
        ("not scores", "ScanLikelihoods"),
    ],
)
def test_bad_values_are_config_errors(scores, field):
    with pytest.raises(ConfigError, match=field):
        GlobalNearestNeighbour().associate(scores)
