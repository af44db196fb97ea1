"""JPDA: betas by hand on a 2-track 2-measurement scan, clustering, the belief-propagation
approximation, unassociated measurements, bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fusetrack.association import (
    JointProbabilisticDataAssociation,
    ScanLikelihoods,
    belief_propagation_marginals,
    exact_marginals,
    gate_clusters,
    joint_events,
    log_likelihood_ratios,
)
from fusetrack.core import ConfigError

NO = -np.inf
JPDA = JointProbabilisticDataAssociation()


def scan(ratios, missed, clutter):
    """Scores whose likelihood ratios exp(l_ij - log kappa_j) are ``ratios``."""
    ratios = np.asarray(ratios, float)
    clutter = np.asarray(clutter, float)
    with np.errstate(divide="ignore"):
        ll = np.log(ratios) + clutter
    t = ratios.shape[0]
    return ScanLikelihoods(tuple(range(1, t + 1)), ll, np.log(np.asarray(missed, float)), clutter)


def test_two_tracks_two_measurements_by_hand():
    # ratios a_ij = P_D g_ij / kappa_j, missed weights m_i = 1 - P_D P_G
    a = np.array([[4.0, 1.0], [2.0, 3.0]])
    m0 = m1 = 0.5
    # the seven joint events (track 1's choice, track 2's choice) and their weights
    events = {
        ("miss", "miss"): m0 * m1,  # 0.25
        ("z0", "miss"): a[0, 0] * m1,  # 2
        ("z1", "miss"): a[0, 1] * m1,  # 0.5
        ("miss", "z0"): m0 * a[1, 0],  # 1
        ("miss", "z1"): m0 * a[1, 1],  # 1.5
        ("z0", "z1"): a[0, 0] * a[1, 1],  # 12
        ("z1", "z0"): a[0, 1] * a[1, 0],  # 2
    }
    total = sum(events.values())
    assert total == 19.25

    def beta(track, choice):
        return sum(w for e, w in events.items() if e[track] == choice) / total

    result = JPDA.associate(scan(a, [m0, m1], clutter=[-1.0, -2.0]))
    got = {tid: {h.measurement: h.probability for h in hs} for tid, hs in result.hypotheses.items()}
    assert got[1] == pytest.approx({0: 14 / 19.25, 1: 2.5 / 19.25, None: 2.75 / 19.25})
    assert got[2] == pytest.approx({0: 3 / 19.25, 1: 13.5 / 19.25, None: 2.75 / 19.25})
    for track, tid in ((0, 1), (1, 2)):
        for choice, j in (("z0", 0), ("z1", 1), ("miss", None)):
            assert got[tid][j] == pytest.approx(beta(track, choice), rel=1e-12)
    assert result.unassociated == ()  # z0 from a track with 17/19.25, z1 with 16/19.25
    assert result.info["approximated"] == 0


def random_scores(rng, t, m, gated=0.5):
    ll = rng.normal(0, 2, (t, m))
    ll[rng.random((t, m)) > gated] = NO
    return ScanLikelihoods(
        tuple(range(t)), ll, np.log(rng.uniform(0.05, 0.9, t)), rng.normal(0, 1, m)
    )


def test_betas_of_each_track_sum_to_one_and_cover_only_gated_measurements():
    rng = np.random.default_rng(5)
    for _ in range(20):
        scores = random_scores(rng, rng.integers(1, 6), rng.integers(0, 6))
        result = JPDA.associate(scores)
        for i, tid in enumerate(scores.track_ids):
            hs = result.hypotheses[tid]
            assert sum(h.probability for h in hs) == pytest.approx(1.0, abs=1e-12)
            assert hs[-1].measurement is None
            for h in hs[:-1]:
                assert np.isfinite(scores.log_likelihood[i, h.measurement])


def test_cluster_splitting_gives_the_betas_of_the_full_enumeration():
    rng = np.random.default_rng(11)
    # two independent groups {tracks 0, 2} x {z1, z3} and {tracks 1, 3} x {z0, z2, z4}, and z5
    # in no gate
    ll = np.full((4, 6), NO)
    ll[np.ix_([0, 2], [1, 3])] = rng.normal(0, 1, (2, 2))
    ll[np.ix_([1, 3], [0, 2, 4])] = rng.normal(0, 1, (2, 3))
    scores = ScanLikelihoods((5, 6, 7, 8), ll, np.log([0.2, 0.3, 0.4, 0.1]), rng.normal(0, 1, 6))
    clusters = gate_clusters(np.isfinite(ll))
    assert [(a.tolist(), b.tolist()) for a, b in clusters] == [
        ([0, 2], [1, 3]),
        ([1, 3], [0, 2, 4]),
    ]
    full = exact_marginals(log_likelihood_ratios(scores))  # one enumeration, no clusters
    result = JPDA.associate(scores)
    np.testing.assert_allclose(result.info["beta"], full, atol=1e-14)
    assert 5 in result.unassociated


def test_joint_events_of_a_full_2x2_are_the_seven_by_hand():
    w = np.zeros((2, 3))
    assert sorted(joint_events(w)) == [(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1), (2, 2)]


def test_belief_propagation_is_exact_on_a_tree():
    # track 0 gates {z0, z1}, track 1 gates {z1, z2}: the association graph has no cycle
    w = np.array([[1.0, 2.0, NO, -1.0], [NO, 1.5, 0.5, -2.0]])
    np.testing.assert_allclose(belief_propagation_marginals(w), exact_marginals(w), atol=1e-12)


def test_belief_propagation_is_close_to_exact_on_random_small_clusters():
    # measured: mean max-error 0.017, worst 0.13 over these clusters; the per-track PDA that
    # ignores the other tracks is off by 0.40 on average
    rng = np.random.default_rng(1)
    errors = []
    for _ in range(100):
        t, m = rng.integers(2, 5), rng.integers(2, 5)
        w = np.concatenate([rng.normal(0, 2, (t, m)), rng.uniform(-3, -0.1, (t, 1))], axis=1)
        w[:, :-1][rng.random((t, m)) < 0.3] = NO
        approx = belief_propagation_marginals(w)
        np.testing.assert_allclose(approx.sum(axis=1), 1.0, atol=1e-12)
        errors.append(np.abs(approx - exact_marginals(w)).max())
    assert np.mean(errors) < 0.03
    assert np.max(errors) < 0.15


def test_large_clusters_switch_to_belief_propagation():
    rng = np.random.default_rng(2)
    scores = random_scores(rng, 4, 4, gated=1.0)  # 209 joint events in one cluster
    assert sum(1 for _ in joint_events(log_likelihood_ratios(scores))) == 209
    exact = JointProbabilisticDataAssociation(max_exact_events=209).associate(scores)
    approx = JointProbabilisticDataAssociation(max_exact_events=208).associate(scores)
    assert exact.info["approximated"] == 0 and approx.info["approximated"] == 1
    np.testing.assert_allclose(approx.info["beta"], exact.info["beta"], atol=0.15)
    assert not np.allclose(approx.info["beta"], exact.info["beta"], atol=1e-6)


def test_unassociated_are_measurements_more_likely_not_from_any_track():
    # one track, ratios 4 (z0) and 0.1 (z1), missed 0.5: beta = 4/4.6, 0.1/4.6, 0.5/4.6
    scores = scan([[4.0, 0.1]], [0.5], clutter=[0.0, 0.0])
    result = JPDA.associate(scores)
    np.testing.assert_allclose(result.info["beta"], [[4 / 4.6, 0.1 / 4.6, 0.5 / 4.6]])
    assert result.unassociated == (1,)
    strict = JointProbabilisticDataAssociation(unassociated_below=0.9).associate(scores)
    assert strict.unassociated == (0, 1)  # 4 / 4.6 = 0.87 < 0.9


def test_a_track_with_nothing_in_its_gate_is_missed():
    result = JPDA.associate(scan([[0.0, 0.0], [1.0, 0.0]], [0.3, 0.3], [0.0, 0.0]))  # 0: no gate
    assert [(h.measurement, h.probability) for h in result.hypotheses[1]] == [(None, 1.0)]
    assert result.unassociated == (1,)
    assert math.isclose(result.hypotheses[2][0].probability, 1 / 1.3)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"max_exact_events": -1}, "max_exact_events"),
        ({"max_exact_events": 2.5}, "max_exact_events"),
        ({"unassociated_below": 0.0}, "unassociated_below"),
        ({"unassociated_below": 1.5}, "unassociated_below"),
        ({"bp_iterations": 0}, "bp_iterations"),
        ({"bp_tolerance": 0.0}, "bp_tolerance"),
    ],
)
def test_bad_configuration(kwargs, field):
    with pytest.raises(ConfigError, match=field):
        JointProbabilisticDataAssociation(**kwargs)


def test_bad_scores():
    bad = ScanLikelihoods((1,), np.array([[np.nan]]), np.array([-1.0]), np.zeros(1))
    with pytest.raises(ConfigError, match="JointProbabilisticDataAssociation: log_likelihood="):
        JPDA.associate(bad)
