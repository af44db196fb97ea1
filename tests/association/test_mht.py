"""Track-oriented MHT: a deferred decision revised by the next scan, N-scan pruning, the global
hypothesis against brute force, n_scan = 0 is GNN, hypothesis caps, bad input."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from fusetrack.association import (
    GlobalNearestNeighbour,
    MHTState,
    ScanLikelihoods,
    TrackHypothesis,
    TrackOrientedMHT,
    best_global_hypothesis,
)
from fusetrack.core import ConfigError, ShapeError

NO = -np.inf


def scan(ids, ratios, missed):
    ratios = np.asarray(ratios, float)
    t, m = ratios.shape
    return ScanLikelihoods(tuple(ids), ratios, np.full(t, float(missed)), np.zeros(m))


def test_the_next_scan_revises_a_deferred_decision():
    mht = TrackOrientedMHT(n_scan=1)
    # scan 0, track 5: z0 (ratio 3) looks better than z1 (2.5); GNN would commit to z0
    first = mht.associate(scan([5], [[3.0, 2.5]], missed=-2.0))
    assert first.info["children"] == {(5, 0): 6, (5, 1): 7, (5, None): 8}
    assert first.info["best"] == {5: 6}
    state = first.info["state"]
    assert {leaf.id: leaf.choices for leaf in state.leaves} == {6: (0,), 7: (1,), 8: (None,)}
    # scan 1, one row per leaf (each leaf's own belief): y0 fits the z1 history best
    # totals: 6 -> (3 - 5, 3 - 2), 7 -> (2.5 + 5, 2.5 - 2), 8 -> (-2 + 1, -2 - 2)
    second = mht.associate(scan([6, 7, 8], [[-5.0], [5.0], [1.0]], missed=-2.0), state=state)
    best = second.info["best"][5]
    new_state = second.info["state"]
    leaf = {h.id: h for h in new_state.leaves}[best]
    assert leaf.choices == (1, 0) and leaf.log_score == pytest.approx(7.5)
    # N-scan pruning fixed scan 0 to z1: only leaf 7's children survive
    assert {h.choices for h in new_state.leaves} == {(1, 0), (1, None)}
    assert set(second.info["dead"]) == {6, 8}
    p = 1 / (1 + math.exp(0.5 - 7.5))
    assert [h.measurement for h in second.hypotheses[7]] == [0, None]
    assert [h.probability for h in second.hypotheses[7]] == pytest.approx([p, 1 - p])
    assert second.unassociated == ()


def brute_force(leaves):
    """(families given a leaf, best total score) over every consistent choice."""
    families = sorted({leaf.family for leaf in leaves})
    options = [[None] + [h for h in leaves if h.family == f] for f in families]
    best = (-1, -math.inf)
    for combo in itertools.product(*options):
        chosen = [h for h in combo if h is not None]
        used = [key for h in chosen for key in h.used()]
        if len(used) != len(set(used)):
            continue
        best = max(best, (len(chosen), sum(h.log_score for h in chosen)))
    return best


def test_global_hypothesis_matches_brute_force():
    rng = np.random.default_rng(4)
    for _ in range(60):
        leaves = []
        for family in range(rng.integers(1, 4)):
            for _ in range(rng.integers(1, 5)):
                choices = tuple(
                    None if rng.random() < 0.3 else int(rng.integers(0, 3)) for _ in range(2)
                )
                leaves.append(
                    TrackHypothesis(len(leaves), family, 0, choices, float(rng.normal(0, 3)))
                )
        best = best_global_hypothesis(leaves)
        used = [key for h in best.values() for key in h.used()]
        assert len(used) == len(set(used))
        assert all(h.family == f for f, h in best.items())
        n, total = brute_force(leaves)
        assert len(best) == n
        assert sum(h.log_score for h in best.values()) == pytest.approx(total, abs=1e-9)


def test_conflicting_families_share_a_measurement_only_once():
    # two tracks want z0 (ratios 4 and 3); missed costs -1: best = 4 + (-1) with track 2 missed
    result = TrackOrientedMHT(n_scan=0).associate(scan([1, 2], [[4.0], [3.0]], missed=-1.0))
    state = result.info["state"]
    chosen = {leaf.family: leaf.choices for leaf in state.leaves}
    assert chosen == {1: (0,), 2: (None,)}


def test_n_scan_zero_is_global_nearest_neighbour_scan_after_scan():
    rng = np.random.default_rng(8)
    mht = TrackOrientedMHT(n_scan=0)
    for _ in range(20):
        ids = [10, 11, 12]
        state = None
        for _ in range(3):
            ll = rng.normal(0, 3, (3, 4))
            ll[rng.random((3, 4)) < 0.4] = NO
            scores = scan(ids, ll, -1.5)
            result = mht.associate(scores, state=state)
            gnn = GlobalNearestNeighbour().associate(scores)
            state = result.info["state"]
            assert len(state.leaves) == 3  # one leaf per family
            for row_id, hs in result.hypotheses.items():
                assert [h.measurement for h in hs] == [gnn.hypotheses[row_id][0].measurement]
            assert result.unassociated == gnn.unassociated
            ids = [
                result.info["children"][(r, hs[0].measurement)]
                for r, hs in result.hypotheses.items()
            ]


def test_at_most_max_hypotheses_per_family_and_the_best_is_kept():
    rng = np.random.default_rng(9)
    mht = TrackOrientedMHT(n_scan=5, max_hypotheses=3)
    state = MHTState.for_tracks([1, 2])
    for _ in range(4):
        rows = [leaf.id for leaf in state.leaves]
        result = mht.associate(scan(rows, rng.normal(0, 2, (len(rows), 3)), -1.0), state=state)
        state = result.info["state"]
        for family in (1, 2):
            leaves = [leaf for leaf in state.leaves if leaf.family == family]
            assert 1 <= len(leaves) <= 3
            assert result.info["best"][family] in {leaf.id for leaf in leaves}
        for hs in result.hypotheses.values():
            assert sum(h.probability for h in hs) == pytest.approx(1.0)


def test_add_track_starts_a_family_at_the_next_scan():
    first = TrackOrientedMHT(n_scan=1).associate(scan([1], [[2.0, NO]], missed=-1.0))
    state, root = first.info["state"].add_track(7)
    assert first.unassociated == (1,)
    rows = [leaf.id for leaf in state.leaves]
    assert root == max(rows) and root not in (1, 2, 3)
    second = TrackOrientedMHT(n_scan=1).associate(
        scan(rows, np.full((len(rows), 1), 1.0), missed=-1.0), state=state
    )
    assert 7 in second.info["best"]
    with pytest.raises(ConfigError, match="family"):
        state.add_track(7)
    assert {leaf.family for leaf in second.info["state"].remove_track(1).leaves} == {7}


def test_bad_input():
    with pytest.raises(ConfigError, match="n_scan"):
        TrackOrientedMHT(n_scan=-1)
    with pytest.raises(ConfigError, match="max_hypotheses"):
        TrackOrientedMHT(max_hypotheses=0)
    state = MHTState.for_tracks([1, 2])
    with pytest.raises(ShapeError, match="leaf ids"):
        TrackOrientedMHT().associate(scan([1, 3], np.zeros((2, 1)), -1.0), state=state)
    bad = ScanLikelihoods((1,), np.array([[np.nan]]), np.array([-1.0]), np.zeros(1))
    with pytest.raises(ConfigError, match="TrackOrientedMHT: log_likelihood="):
        TrackOrientedMHT().associate(bad)


def test_add_tracks_is_add_track_for_several_families():
    state = MHTState.for_tracks([0, 1])
    one, a = state.add_track(5)
    both, b = one.add_track(6)
    batch, roots = state.add_tracks([5, 6])
    assert roots == (a, b) and batch.next_id == both.next_id
    assert batch.leaves == both.leaves
    with pytest.raises(ConfigError, match="family=6"):
        state.add_tracks([6, 6])
    with pytest.raises(ConfigError, match="family=1"):
        state.add_tracks([4, 1])
