"""The array path of a scan (Kalman-family tracks stacked, associations as weight matrices)
gives what the per-track path gives: the stacked PDA mixture and IPDA existence, the stacked
scores and posteriors, the associators' weight matrices, JPDA's lone tracks and small
clusters, and a whole tracker run with a batched filter against the same filter run track by
track."""

from __future__ import annotations

import numpy as np
import pytest
from _tracking_scenarios import MOTION, POS, scenario, tracker

import fusetrack.association.clusters as clusters_module
from fusetrack.association import (
    GlobalNearestNeighbour,
    JointProbabilisticDataAssociation,
    PairPosteriors,
    ScanLikelihoods,
    exact_marginals,
    gate_clusters,
    hypothesis_weights,
    lone_track_marginals,
    scan_likelihoods,
    stack_gaussians,
)
from fusetrack.core import Gaussian, Measurement
from fusetrack.filters import KalmanFilter
from fusetrack.tracking import (
    MultiTargetTracker,
    combine_hypotheses,
    combine_stacked,
    update_existence,
    update_existences,
)

KF = KalmanFilter(MOTION, [POS])
NO = -np.inf


class PlainKF(KalmanFilter):
    """The same filter, seen as one the batch path does not trust (methods overridden)."""

    def predict(self, belief, dt, rng=None):
        return super().predict(belief, dt, rng)

    def update_with_likelihood(self, belief, measurements, rng=None):
        return super().update_with_likelihood(belief, measurements, rng)


def _beliefs(rng, n):
    out = []
    for _ in range(n):
        a = rng.standard_normal((4, 4))
        out.append(Gaussian(rng.normal(0, 3, 4), a @ a.T + np.eye(4)))
    return out


def test_stacked_scores_and_posteriors_equal_the_per_track_ones():
    rng = np.random.default_rng(3)
    beliefs = _beliefs(rng, 5)
    zs = [Measurement(1.0, "pos", rng.normal(0, 3, 2)) for _ in range(7)]
    kw = {"sensors": [POS], "p_detect": 0.8, "clutter_density": 1e-3, "keep_posteriors": True}
    plain = PlainKF(MOTION, [POS])
    ref, ref_post = scan_likelihoods(range(5), beliefs, zs, filt=plain, **kw)
    got, post = scan_likelihoods(range(5), stack_gaussians(beliefs), zs, filt=KF, **kw)
    assert isinstance(post, PairPosteriors) and not isinstance(ref_post, PairPosteriors)
    assert np.isfinite(ref.log_likelihood).sum() >= 3  # several pairs gated: a real test
    np.testing.assert_allclose(got.log_likelihood, ref.log_likelihood, rtol=1e-12)
    assert set(post) == set(ref_post)
    for pair, belief in ref_post.items():
        np.testing.assert_allclose(post[pair].mean, belief.mean, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(post[pair].cov, belief.cov, rtol=1e-12, atol=1e-12)
    # a sub-block keeps its pairs, renumbered
    rows, cols = [1, 3, 4], [0, 2, 5, 6]
    sub = post.restrict(rows, cols, got.shape)
    expected = {(rows.index(r), cols.index(c)) for r, c in ref_post if r in rows and c in cols}
    assert set(sub) == expected
    for r, c in expected:
        np.testing.assert_array_equal(sub[(r, c)].mean, post[(rows[r], cols[c])].mean)


def test_stacked_mixture_equals_the_per_track_combination():
    rng = np.random.default_rng(4)
    prior = _beliefs(rng, 3)
    posts = _beliefs(rng, 4)  # pairs (0, 0), (0, 2), (1, 1), (2, 2)
    rows, cols = np.array([0, 0, 1, 2]), np.array([0, 2, 1, 2])
    pairs = PairPosteriors(rows, cols, stack_gaussians(posts))
    weights = np.array(
        [
            [0.5, 0.0, 0.3, 0.2],  # two measurements and missed (JPDA)
            [0.0, 1.0, 0.0, 0.0],  # one sure measurement (GNN)
            [0.0, 0.0, 0.0, 1.0],  # missed
        ]
    )
    got = combine_stacked(stack_gaussians(prior), pairs, weights).unstack()
    ref0 = combine_hypotheses([posts[0], posts[1], prior[0]], [0.5, 0.3, 0.2])
    np.testing.assert_allclose(got[0].mean, ref0.mean, rtol=1e-13)
    np.testing.assert_allclose(got[0].cov, ref0.cov, rtol=1e-12, atol=1e-13)
    # one hypothesis of weight 1: that belief exactly, as combine_hypotheses returns it
    np.testing.assert_array_equal(got[1].mean, posts[2].mean)
    np.testing.assert_array_equal(got[1].cov, posts[2].cov)
    np.testing.assert_array_equal(got[2].mean, prior[2].mean)
    np.testing.assert_array_equal(got[2].cov, prior[2].cov)


@pytest.mark.parametrize(
    ("r", "gate", "ratios"),
    [(0.5, 0.891, []), (0.5, 0.891, [np.log(10.0)]), (0.3, 0.9, [np.log(0.9)]),
     (1.0, 1.0, []), (0.9, 0.5, [50.0]), (0.4, 0.7, [0.3, -1.0])],
)  # fmt: skip
def test_existence_of_many_tracks_equals_one_by_one(r, gate, ratios):
    total = float(np.exp(ratios).sum()) if ratios else 0.0
    got = update_existences(np.array([r, r]), gate, np.array([total, total]))
    assert got.tolist() == [update_existence(r, gate, ratios)] * 2


def _random_scan(rng, t, m, density):
    ll = np.where(rng.random((t, m)) < density, rng.normal(0, 2, (t, m)), NO)
    return ScanLikelihoods(
        tuple(range(10, 10 + t)), ll, np.log(rng.uniform(0.05, 0.5, t)), rng.normal(0, 1, m)
    )


@pytest.mark.parametrize(
    "associator", [GlobalNearestNeighbour(), JointProbabilisticDataAssociation()]
)
def test_weight_matrix_is_the_association(associator):
    rng = np.random.default_rng(8)
    for _ in range(30):
        scores = _random_scan(rng, int(rng.integers(1, 7)), int(rng.integers(0, 7)), 0.4)
        answer = associator.association_weights(scores)
        association = associator.associate(scores)
        np.testing.assert_array_equal(
            answer.weights, hypothesis_weights(association, scores.track_ids, scores.shape[1])
        )
        assert answer.unassociated == association.unassociated
        np.testing.assert_allclose(answer.weights.sum(axis=1), 1.0, rtol=1e-12)


def test_lone_tracks_in_one_pass_equal_their_enumeration():
    w = np.array([[1.0, NO, NO, -0.5], [NO, 2.0, -1.0, -2.0], [NO, NO, NO, -0.1], [NO, NO, NO, NO]])
    got = lone_track_marginals(w)
    for i in range(3):
        np.testing.assert_allclose(got[i], exact_marginals(w[i : i + 1])[0], rtol=1e-14)
    assert got[3].tolist() == [0.0, 0.0, 0.0, 1.0]  # every event impossible: missed
    # hand: track 0 takes z0 with e^1 / (e^1 + e^-0.5)
    assert got[0, 0] == pytest.approx(np.e / (np.e + np.exp(-0.5)), rel=1e-14)


def test_small_clusters_equal_the_sparse_graph_components(monkeypatch):
    rng = np.random.default_rng(2)
    for _ in range(200):
        t, m = int(rng.integers(1, 20)), int(rng.integers(0, 20))
        gated = rng.random((t, m)) < rng.uniform(0.0, 0.25)
        dense = gate_clusters(gated)
        with monkeypatch.context() as patch:
            patch.setattr(clusters_module, "_DENSE_TRACKS", 0)
            sparse = gate_clusters(gated)
        assert [(a.tolist(), b.tolist()) for a, b in dense] == [
            (a.tolist(), b.tolist()) for a, b in sparse
        ]
    # by hand: tracks 0 and 2 share z1, track 1 is alone with z0, track 3 gates nothing
    gated = np.array([[0, 1, 0], [1, 0, 0], [0, 1, 1], [0, 0, 0]], bool)
    got = [(a.tolist(), b.tolist()) for a, b in gate_clusters(gated)]
    assert got == [([0, 2], [1, 2]), ([1], [0]), ([3], [])]


@pytest.mark.parametrize(
    "associator", [GlobalNearestNeighbour(), JointProbabilisticDataAssociation()]
)
def test_a_batched_tracker_run_equals_the_per_track_run(associator):
    measurements, _, _ = scenario(6, n_scans=30, clutter=4.0)
    runs = []
    for filt in (KF, PlainKF(MOTION, [POS])):
        base = tracker(filt=filt)
        t = MultiTargetTracker(
            base.filter, [POS], associator, base.initiator, base.deleter,
            p_detect=0.9, clutter_density=base.clutter_density["pos"], gate_probability=0.999,
        )  # fmt: skip
        runs.append(t.run_with_state(measurements, np.random.default_rng(0)))
    (batched, state_b), (plain, state_p) = runs
    assert len(batched) >= 2 and state_b.stats == state_p.stats
    assert [tr.id for tr in batched] == [tr.id for tr in plain]
    for a, b in zip(batched, plain, strict=True):
        np.testing.assert_allclose(a.means, b.means, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(a.covariances, b.covariances, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(a.info["existence"], b.info["existence"], rtol=1e-9)
        assert a.info["measurements"] == b.info["measurements"]
