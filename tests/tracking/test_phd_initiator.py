"""The PHD-driven initiator: a hand-worked birth, then two targets in clutter started from
consistent detection pairs only."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fusetrack.association import GlobalNearestNeighbour
from fusetrack.core import ConfigError, Gaussian, Measurement
from fusetrack.filters import GMPHDFilter, KalmanFilter, PhdIntensity
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import LinearGaussianSensor
from fusetrack.tracking import MissedCountDeleter, MultiTargetTracker, PHDInitiator

H = np.hstack([np.eye(2), np.zeros((2, 2))])
R = 0.25 * np.eye(2)
POS = LinearGaussianSensor("pos", H=H, R=R)
MOTION = ConstantVelocity(ndim=2, q=0.05)
SIDE, CLUTTER_RATE = 200.0, 2.0
KAPPA = CLUTTER_RATE / SIDE**2
BIRTH_COV = np.diag([100.0**2, 100.0**2, 9.0, 9.0])
BIRTH = PhdIntensity([0.05], [[100.0, 100.0, 0.0, 0.0]], [BIRTH_COV])


def phd():
    return GMPHDFilter(
        MOTION, [POS], BIRTH, survival_probability=0.99, detection_probability=0.9,
        clutter_intensity=KAPPA, merge_threshold=0.0,
    )  # fmt: skip


def test_one_detection_is_a_light_component_two_consistent_ones_a_track():
    init = PHDInitiator(phd(), threshold=0.5, m=2, n=3)
    z0 = Measurement(0.0, "pos", [150.0, 60.0])
    state, started = init.births(init.initial_state(), 0.0, "pos", [z0])
    assert started == []
    # Vo & Ma Eq. 30 with one prior component (the birth): w = p_D w_b q / (kappa + p_D w_b q)
    s = H @ BIRTH_COV @ H.T + R
    y = z0.value - 100.0
    q = math.exp(-0.5 * y @ np.linalg.solve(s, y)) / (2 * math.pi * math.sqrt(np.linalg.det(s)))
    w = 0.9 * 0.05 * q / (KAPPA + 0.9 * 0.05 * q)
    kf = KalmanFilter(MOTION, [POS])
    first = kf.update(Gaussian(BIRTH.means[0], BIRTH_COV), [z0])
    k = int(np.argmin(np.linalg.norm(state.intensity.means[:, :2] - z0.value, axis=1)))
    assert state.intensity.weights[k] == pytest.approx(w, rel=1e-9)
    assert w < 0.05  # a false alarm alone starts nothing
    # one second later a detection where that component predicts the target
    z1 = Measurement(1.0, "pos", [150.5, 60.5])
    after, started = init.births(state, 1.0, "pos", [Measurement(1.0, "pos", [10.0, 10.0]), z1])
    ((belief, credited),) = started
    assert credited == 1  # z1, not the far report
    expected = kf.update(kf.predict(first, 1.0), [z1])
    np.testing.assert_allclose(belief.mean, expected.mean, rtol=1e-9)
    np.testing.assert_allclose(belief.cov, expected.cov, rtol=1e-9)
    # the heavy component left the intensity (it is a track now); only light ones stay there
    near = np.linalg.norm(after.intensity.means[:, :2] - z1.value, axis=1) < 1.0
    assert 0 < after.intensity.weights[near].sum() < 0.05
    # a sensor the PHD does not know starts nothing and leaves the state alone
    assert init.births(after, 2.0, "radar", [z1]) == (after, [])
    with pytest.raises(ConfigError, match="GMPHDFilter"):
        PHDInitiator(object())  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="threshold"):
        PHDInitiator(phd(), threshold=0.0)


def scenario(seed, n_scans=40):
    """Two constant-velocity targets, P_D = 0.9, two false alarms per scan on average."""
    rng = np.random.default_rng(seed)
    x = np.array([[20.0, 20.0, 2.0, 1.0], [180.0, 180.0, -1.0, -1.5]])
    zs, source = [], []
    for k in range(n_scans):
        if k:
            x = MOTION.sample(x, 1.0, rng)
        for i in range(2):
            if rng.random() < 0.9:
                zs.append(Measurement(k, "pos", x[i, :2] + 0.5 * rng.standard_normal(2)))
                source.append(i)
        for _ in range(rng.poisson(CLUTTER_RATE)):
            zs.append(Measurement(k, "pos", rng.uniform(0.0, SIDE, 2)))
            source.append(-1)
    return zs, np.array(source)


@pytest.mark.parametrize("seed", [0, 3, 7])
def test_two_targets_in_clutter_are_started_by_the_phd_and_nothing_else(seed):
    """Each target becomes one track within a few scans (two detections that fit its motion),
    and no false alarm starts even a tentative track (the per-measurement M-of-N starts ~80 on
    these runs)."""
    zs, source = scenario(seed)
    tracker = MultiTargetTracker(
        KalmanFilter(MOTION, [POS]), [POS], GlobalNearestNeighbour(),
        PHDInitiator(phd(), threshold=0.5, m=2, n=3), MissedCountDeleter(3),
        p_detect=0.9, clutter_density=KAPPA, gate_probability=0.999,
    )  # fmt: skip
    tracks, state = tracker.run_with_state(zs, np.random.default_rng(0))
    assert [t.id for t in tracks] == [0, 1]
    assert state.stats.births == 2 and state.stats.dropped == 0
    owners = set()
    for t in tracks:
        used = np.concatenate([np.array(u, dtype=int) for u in t.info["measurements"]])
        (owner,) = set(source[used].tolist())
        owners.add(owner)
        assert t.times[0] <= 5 and t.times[-1] == 39 and t.info["deleted"] is None
    assert owners == {0, 1}
