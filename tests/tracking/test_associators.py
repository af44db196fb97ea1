"""The real associators inside the trackers, on a hand-worked ambiguous crossing.

Two targets start one metre apart and cross: A from (0, 0) with velocity (1, 1), B from (1, 0)
with velocity (-1, 1). Their tracks start at scan 0 with an unknown velocity (std 3 m/s), so
at scan 1 both predictions stay at the birth points with position variance S ~ 9 m^2 per axis.
Scan 1's reports are A(1) = (1, 1) and B(1) = (0, 1) (exact, R = 0.01 I):

    track 0 (at (0, 0)):  d^2 to A(1) = 2/S,  to B(1) = 1/S
    track 1 (at (1, 0)):  d^2 to A(1) = 1/S,  to B(1) = 2/S

so the swapped joint event has total d^2 = 2/S against 4/S for the true one: it is exp(1/S)
~ 1.12 times likelier. Scan 2 (A(2) = (2, 2), B(2) = (-1, 2)) decides: a track that took the
wrong report at scan 1 flies at velocity (0, 1) and is 1 m off the straight continuations,
with a position std of 0.1 m.

* GNN commits to the swap at scan 1 and, its velocities now wrong, keeps it: track 0 ends on B.
* JPDA shares scan 1 between the two events (track 0's x is the mixture of 0 and 1 weighted by
  the event probabilities) and recovers: track 0 ends on A.
* MHT also prefers the swap at scan 1, but keeps the other hypothesis; at scan 2 the straight
  histories win by far and track 0 ends on A (its scan-1 estimate was the swap).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fusetrack.association import (
    GlobalNearestNeighbour,
    JointProbabilisticDataAssociation,
    TrackOrientedMHT,
)
from fusetrack.core import ConfigError, Gaussian, Measurement
from fusetrack.filters import KalmanFilter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import LinearGaussianSensor
from fusetrack.tracking import (
    InverseMeasurementPrior,
    MHTTracker,
    MHTTrackerState,
    MissedCountDeleter,
    MultiTargetTracker,
    SinglePointInitiator,
)

H = np.hstack([np.eye(2), np.zeros((2, 2))])
POS = LinearGaussianSensor("pos", H=H, R=0.01 * np.eye(2))
MOTION = ConstantVelocity(ndim=2, q=0.001)
WIDE = Gaussian(np.zeros(4), np.diag([0.0, 0.0, 9.0, 9.0]))


def A(k):
    return np.array([k, k], float)


def B(k):
    return np.array([1.0 - k, k])


SCANS = [z for k in range(5) for z in (Measurement(k, "pos", A(k)), Measurement(k, "pos", B(k)))]


def make(associator, kind=MultiTargetTracker):
    return kind(
        KalmanFilter(MOTION, [POS]),
        [POS],
        associator,
        SinglePointInitiator(InverseMeasurementPrior([POS], WIDE)),
        MissedCountDeleter(3),
        p_detect=0.95,
        clutter_density=1e-3,
        gate_probability=0.9999,
    )


def test_gnn_commits_to_the_likelier_swap_and_keeps_it():
    tracks = make(GlobalNearestNeighbour()).run(SCANS)
    assert [t.id for t in tracks] == [0, 1]
    zero = tracks[0]
    # scan 0 its birth report A(0) (index 0), then B's every scan: 3, 5, 7, 9
    assert zero.info["measurements"] == ((0,), (3,), (5,), (7,), (9,))
    assert np.linalg.norm(zero.means[-1, :2] - B(4)) < 0.2


def test_jpda_shares_the_ambiguous_scan_in_the_event_ratio_and_recovers():
    tr = make(JointProbabilisticDataAssociation())
    tracks = tr.run(SCANS)
    zero = tracks[0]
    # scan 1: both reports, A(1) (index 2) and B(1) (index 3)
    assert zero.info["measurements"][1] == (2, 3)
    p_a, p_b = zero.info["probabilities"][1]
    predicted = tr.filter.predict(InverseMeasurementPrior([POS], WIDE)(SCANS[0]), 1.0)
    s = predicted.cov[0, 0] + 0.01  # S per axis (diagonal)
    # P(swap) / P(true) = exp(1 / S); the missed events (weight 0.05 against ~17) shift it < 1%
    assert p_b / p_a == pytest.approx(math.exp(1.0 / s), rel=1e-2)
    assert p_a + p_b == pytest.approx(1.0, abs=1e-2)
    # track 0's x after scan 1: the updates on A(1) (x ~ 1) and on B(1) (x ~ 0) mixed
    assert zero.means[1, 0] == pytest.approx(p_a * (s - 0.01) / s, abs=1e-2)
    # and it recovers: on A from scan 3 on
    assert np.linalg.norm(zero.means[-1, :2] - A(4)) < 0.2
    assert np.linalg.norm(tracks[1].means[-1, :2] - B(4)) < 0.2


def test_mht_prefers_the_swap_at_the_ambiguous_scan_then_revises_it():
    tr = make(TrackOrientedMHT(n_scan=2), MHTTracker)
    state = tr.initial_state()
    assert isinstance(state, MHTTrackerState)
    per_scan = []
    for k in range(5):
        state = tr.step(state, float(k), SCANS[2 * k : 2 * k + 2])
        per_scan.append({t.id: t.belief.mean[:2].copy() for t in state.tracks})
        # every leaf has a belief, and only the leaves do
        assert set(state.leaf_beliefs) == {leaf.id for leaf in state.hypotheses.leaves}
    # scan 1: the best global hypothesis is the swap, as for GNN
    np.testing.assert_allclose(per_scan[1][0], B(1), atol=0.02)
    # scan 2: the straight histories win; from then on track 0 is on A
    for k in (2, 3, 4):
        np.testing.assert_allclose(per_scan[k][0], A(k), atol=0.05)
        np.testing.assert_allclose(per_scan[k][1], B(k), atol=0.05)
    # the winning leaf of track 0 took A's report at every scan (scan indices 0..4)
    (best,) = [
        leaf
        for leaf in state.hypotheses.leaves
        if leaf.family == 0 and np.allclose(state.leaf_beliefs[leaf.id].mean[:2], per_scan[4][0])
    ]
    assert best.choices[-3:] == (0, 0, 0)  # A's report is column 0 of each scan
    # at most max_hypotheses leaves per family
    assert len(state.hypotheses.leaves) <= 2 * 20


def test_mht_run_gives_the_tracks_with_ids():
    tracks, state = make(TrackOrientedMHT(n_scan=2), MHTTracker).run_with_state(SCANS)
    assert [t.id for t in tracks] == [0, 1]
    assert tracks[0].info["measurements"][2:] == ((4,), (6,), (8,))
    assert np.linalg.norm(tracks[0].means[-1, :2] - A(4)) < 0.1
    assert state.stats.births == 2 and state.stats.scans == 5


def test_a_multi_target_tracker_with_the_mht_is_the_mht_tracker():
    tr = make(TrackOrientedMHT(n_scan=2))
    assert type(tr) is MHTTracker and isinstance(tr, MultiTargetTracker)
    assert isinstance(tr.initial_state(), MHTTrackerState)
    again = MultiTargetTracker(
        tr.filter, [POS], associator=TrackOrientedMHT(), initiator=tr.initiator,
        deleter=tr.deleter, p_detect=0.9, clutter_density=1e-3,
    )  # fmt: skip
    assert type(again) is MHTTracker
    assert type(make(GlobalNearestNeighbour())) is MultiTargetTracker
    with pytest.raises(ConfigError, match="TrackOrientedMHT"):
        make(GlobalNearestNeighbour(), MHTTracker)


def _every_tracker():
    from fusetrack.association import MCMCDAConfig
    from fusetrack.tracking import MCMCDATracker

    mcmcda = MCMCDAConfig(dt=1.0, max_speed=3.0, obs_std=0.1, area=100.0, n_mc=200, window=5)
    return {
        "gnn": make(GlobalNearestNeighbour()),
        "jpda": make(JointProbabilisticDataAssociation()),
        "mht": make(TrackOrientedMHT(n_scan=2), MHTTracker),
        "mcmcda": MCMCDATracker([POS], mcmcda),
    }


@pytest.mark.parametrize("name", ["gnn", "jpda", "mht", "mcmcda"])
def test_every_tracker_has_the_same_interface(name):
    """initial_state / step(state, time, measurements, rng) / run(measurements, rng): live
    tracks with ids and beliefs, core.Track values with ids and the measurements they used.
    All but GNN end with track 0 on A (MCMCDA: the window's best partition is the two straight
    lines)."""
    tr = _every_tracker()[name]
    rng = np.random.default_rng(0)
    state = tr.initial_state()
    for k in range(5):
        state = tr.step(state, float(k), SCANS[2 * k : 2 * k + 2], rng)
        assert state.time == float(k) and state.stats.scans == k + 1
    assert [t.id for t in state.tracks] == [0, 1]
    on = A(4) if name != "gnn" else B(4)
    np.testing.assert_allclose(state.tracks[0].belief.mean[:2], on, atol=0.2)
    # indices into the scan's list: A's report is 0, B's 1
    assert state.tracks[0].measurements == ((0,) if name != "gnn" else (1,))
    tracks = tr.run(SCANS, np.random.default_rng(0))
    assert [t.id for t in tracks] == [0, 1]
    assert all(len(t) == 5 and len(t.info["measurements"]) == 5 for t in tracks)
    np.testing.assert_allclose(tracks[0].means[-1, :2], on, atol=0.2)
