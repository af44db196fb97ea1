"""MCMCDA with per-observation covariances (elongated triangulation ellipses) instead of one
isotropic obs_std: the same chain when the covariances are obs_std² I, the gate and the track
score follow each observation's covariance, and the tracker passes Measurement.covariance."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.association import MCMCDA, MCMCDAConfig
from fusetrack.association.mcmcda import HypothesisSampler
from fusetrack.core import ConfigError, Measurement
from fusetrack.sensors import PositionFix
from fusetrack.tracking import MCMCDATracker

CONFIG = MCMCDAConfig(n_mc=200, obs_std=0.5, max_speed=4.0, dt=0.25)


def _scans(seed: int = 0, steps: int = 10) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    out = []
    for k in range(steps):
        pts = [np.array([2.0 + 3.0 * 0.25 * k, 5.0]), np.array([30.0 - 3.0 * 0.25 * k, 12.0])]
        pts = [p + rng.normal(0, 0.5, 2) for p in pts]
        if k % 3 == 0:
            pts.append(rng.uniform([0, 0], [35, 20]))
        out.append(np.array(pts))
    return out


def _run(scans, covs=None):
    tracker = MCMCDA(CONFIG)
    state = tracker.initial_state()
    rng = np.random.default_rng(7)
    for k, y in enumerate(scans):
        state = tracker.step(state, y, rng, None if covs is None else covs[k])
    return state


def test_isotropic_covariances_give_the_same_chain_as_obs_std():
    scans = _scans()
    iso = [np.broadcast_to(0.25 * np.eye(2), (len(y), 2, 2)) for y in scans]
    a, b = _run(scans), _run(scans, iso)
    assert a.best == b.best and a.ids == b.ids


def test_gate_follows_the_observations_covariance():
    # two observations 3 m apart in x, one step (0.25 s) apart: max_speed * dt = 1 m
    obs = [np.array([[0.0, 0.0]]), np.array([[3.0, 0.0]])]
    narrow = HypothesisSampler(CONFIG, obs, np.random.default_rng(0))
    assert not narrow.gate((0, 0), (1, 0))  # reach 1 + 2 * 0.5 = 2 m < 3 m
    wide = [np.diag([1.0, 0.01])[None], np.diag([0.01, 0.01])[None]]  # sd 1 m along x
    sampler = HypothesisSampler(CONFIG, obs, np.random.default_rng(0), covariances=wide)
    assert sampler.gate((0, 0), (1, 0))  # reach 1 + 2 * 1 = 3 m


def test_track_score_uses_each_observations_covariance():
    r0, r1 = np.diag([2.0, 0.5]), np.array([[1.0, 0.3], [0.3, 0.8]])
    obs = [np.array([[0.0, 0.0]]), np.array([[0.4, -0.2]])]
    sampler = HypothesisSampler(
        CONFIG, obs, np.random.default_rng(0), covariances=[r0[None], r1[None]]
    )
    ll, _ = sampler.kalman(((0, 0), (1, 0)))
    # by hand: prior position cov r0, velocity var init_speed_std²; predicted position cov
    # r0 + dt² v² I + Q_pos; innovation y1 - y0 with S = that + r1
    dt, v, a = CONFIG.dt, CONFIG.init_speed_std, CONFIG.accel_std
    s = r0 + (dt * v) ** 2 * np.eye(2) + a**2 * (dt**2 / 2) ** 2 * np.eye(2) + r1
    y = obs[1][0] - obs[0][0]
    expect = -0.5 * y @ np.linalg.solve(s, y) - np.log(2 * np.pi) - 0.5 * np.log(np.linalg.det(s))
    assert ll == pytest.approx(expect, rel=1e-12)


def test_bad_covariance_shape_is_a_clear_error():
    tracker = MCMCDA(CONFIG)
    with pytest.raises(ConfigError, match=r"covariances.shape"):
        tracker.step(tracker.initial_state(), np.zeros((2, 2)), np.random.default_rng(0), np.eye(2))


def test_tracker_passes_measurement_covariances():
    tag = PositionFix("tag", cov=0.25 * np.eye(2))
    # 3 m steps along x at dt = 0.25 (12 m/s > max_speed 4): only elongated covariances link them
    zs = [
        Measurement(0.25 * k, "tag", np.array([3.0 * k, 5.0]), covariance=np.diag([4.0, 0.01]))
        for k in range(6)
    ]
    plain = [Measurement(m.time, m.sensor_id, m.value) for m in zs]
    rng = np.random.default_rng(0)
    assert len(MCMCDATracker([tag], CONFIG).run(zs, rng)) == 1
    assert len(MCMCDATracker([tag], CONFIG).run(plain, rng)) == 0
