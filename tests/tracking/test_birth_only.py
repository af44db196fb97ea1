"""Birth-only sensors: their measurements only start tracks, never touch an existing one, and
start nothing inside a live track's gate (a hand-worked scan)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from fusetrack.association import (
    GlobalNearestNeighbour,
    JointProbabilisticDataAssociation,
    TrackOrientedMHT,
)
from fusetrack.core import ConfigError, Gaussian, Measurement
from fusetrack.filters import KalmanFilter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import PositionFix
from fusetrack.tracking import (
    InverseMeasurementPrior,
    MissedCountDeleter,
    MultiTargetTracker,
    SinglePointInitiator,
)

POS = PositionFix("pos", cov=0.25 * np.eye(2))  # updates tracks, starts none
SEED = PositionFix("seed", cov=np.eye(2))  # starts tracks, updates none
KF = KalmanFilter(ConstantVelocity(ndim=2, q=0.1), [POS, SEED])
WIDE = Gaussian(np.zeros(4), np.diag([0.0, 0.0, 4.0, 4.0]))
P_S = 0.9


def _tracker(associator=None, **kw):
    return MultiTargetTracker(
        KF,
        [POS, SEED],
        associator or GlobalNearestNeighbour(),
        SinglePointInitiator(InverseMeasurementPrior([SEED], WIDE), existence=0.6),
        MissedCountDeleter(3),
        p_detect={"pos": 0.9},  # none needed for the birth-only sensor
        clutter_density={"pos": 1e-3},
        gate_probability=0.99,
        survival_probability=P_S,
        **{"birth_only_sensors": ["seed"], **kw},
    )


@pytest.mark.parametrize(
    "associator", [GlobalNearestNeighbour(), JointProbabilisticDataAssociation()]
)
def test_a_birth_only_sensor_starts_tracks_outside_the_gates_and_touches_none(associator):
    tracker = _tracker(associator)
    rng = np.random.default_rng(0)
    seed = [Measurement(0.0, "seed", [0.0, 0.0])]
    s0 = tracker.step(tracker.initial_state(), 0.0, seed, rng, scanned=["seed"])
    assert [tr.id for tr in s0.tracks] == [0] and s0.tracks[0].confirmed
    born = s0.tracks[0]
    assert born.existence == 0.6
    # scan 1: the track predicted one second; its gate on a seed report (R = I) by hand:
    # S = P^-_pos + I, d^2 = y^T S^-1 y, inside when d^2 <= chi2.ppf(0.99, 2) = 9.21
    pred = KF.predict(born.belief, 1.0)
    s_pos = pred.cov[:2, :2] + np.eye(2)
    edge = np.sqrt(chi2.ppf(0.99, 2) * s_pos[0, 0])  # the gate's extent along x (S diagonal)
    assert s_pos[0, 1] == 0.0
    inside, outside = [0.9 * edge, 0.0], [1.1 * edge, 0.0]
    seeds = [Measurement(1.0, "seed", inside), Measurement(1.0, "seed", outside)]
    s1 = tracker.step(s0, 1.0, seeds, rng, scanned=["seed"])  # the position sensor did not look
    assert [tr.id for tr in s1.tracks] == [0, 1]  # only the report outside the gate started one
    np.testing.assert_allclose(s1.tracks[1].belief.mean, [1.1 * edge, 0.0, 0.0, 0.0])
    old = s1.tracks[0]
    # untouched: the prediction itself, existence only predicted (P_S r), no hit, no miss
    np.testing.assert_array_equal(old.belief.mean, pred.mean)
    np.testing.assert_array_equal(old.belief.cov, pred.cov)
    assert old.existence == pytest.approx(P_S * 0.6, rel=1e-15)
    assert (old.scans, old.hits, old.misses, old.measurements) == (1, 1, 0, ())
    assert s1.stats.births == 2
    # scan 2: the position sensor looks and misses both tracks: each counts a miss; its
    # report far from both starts nothing (the initiator starts tracks from seeds only)
    s2 = tracker.step(s1, 2.0, [Measurement(2.0, "pos", [500.0, 500.0])], rng)
    assert [(tr.id, tr.misses) for tr in s2.tracks] == [(0, 1), (1, 1)]


def test_a_seed_beside_a_track_starts_nothing_while_a_position_report_updates_it():
    tracker = _tracker()
    rng = np.random.default_rng(0)
    s0 = tracker.step(tracker.initial_state(), 0.0, [Measurement(0.0, "seed", [0.0, 0.0])], rng)
    # the position report comes first and updates the track; the seed beside it is gated out
    scan = [Measurement(1.0, "pos", [0.2, 0.1]), Measurement(1.0, "seed", [0.3, 0.0])]
    s1 = tracker.step(s0, 1.0, scan, rng)
    assert [(tr.id, tr.hits, tr.measurements) for tr in s1.tracks] == [(0, 2, (0,))]


def test_birth_only_configuration_errors():
    with pytest.raises(ConfigError, match="birth_only_sensors"):
        _tracker(birth_only_sensors=["radar"])
    with pytest.raises(ConfigError, match="birth_only_sensors"):
        MultiTargetTracker(
            KF, [POS, SEED], GlobalNearestNeighbour(),
            SinglePointInitiator(InverseMeasurementPrior([SEED], WIDE)), MissedCountDeleter(3),
            0.9, 1e-3, birth_only_sensors="seed",
        )  # fmt: skip
    with pytest.raises(ConfigError, match="p_detect"):  # the other sensors still need theirs
        MultiTargetTracker(
            KF, [POS, SEED], GlobalNearestNeighbour(),
            SinglePointInitiator(InverseMeasurementPrior([SEED], WIDE)), MissedCountDeleter(3),
            {"seed": 0.9}, 1e-3, birth_only_sensors=["seed"],
        )  # fmt: skip
    with pytest.raises(ConfigError, match="birth_only_sensors"):
        MultiTargetTracker(
            KF, [POS, SEED], TrackOrientedMHT(),
            SinglePointInitiator(InverseMeasurementPrior([SEED], WIDE)), MissedCountDeleter(3),
            0.9, 1e-3, birth_only_sensors=["seed"],
        )  # fmt: skip
