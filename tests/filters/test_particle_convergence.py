"""On a linear-Gaussian problem the particle filters converge to the Kalman filter's posterior mean."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.core import Gaussian, Measurement
from fusetrack.filters import (
    AuxiliaryParticleFilter,
    BootstrapFilter,
    KalmanFilter,
    RegularizedParticleFilter,
)
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import PositionFix

STEPS = 6
RUNS = 8  # independent batched runs per N
MOTION = ConstantVelocity(ndim=2, q=0.5)
SENSORS = [
    PositionFix("tag", cov=np.diag([1.0, 2.0])),
    PositionFix("x", cov=[[0.5]], position_index=(0,)),
]
PRIOR = Gaussian(np.array([0.0, 0.0, 1.0, -0.5]), np.diag([4.0, 4.0, 1.0, 1.0]))


def _scenario(seed: int = 7) -> list[list[Measurement]]:
    rng = np.random.default_rng(seed)
    x = PRIOR.sample(rng)
    out = []
    for k in range(1, STEPS + 1):
        x = MOTION.sample(x, 1.0, rng)
        out.append([Measurement(float(k), s.sensor_id, s.simulate(x, rng)) for s in SENSORS])
    return out


def _kalman(scenario) -> tuple[np.ndarray, np.ndarray]:
    kf = KalmanFilter(MOTION, SENSORS)
    g = PRIOR
    means, sds = [], []
    for ms in scenario:
        g = kf.update(kf.predict(g, 1.0), ms)
        means.append(g.mean)
        sds.append(np.sqrt(np.diag(g.cov)))
    return np.array(means), np.array(sds)


def _standardised_error(cls, n: int, seed: int, scenario, kf_means, kf_sds, **kw) -> float:
    """RMS over runs, steps and state components of (PF mean - KF mean) / KF posterior sd."""
    pf = cls(MOTION, SENSORS, n_particles=n, **kw)
    rng = np.random.default_rng(seed)
    p = pf.initialize(PRIOR, rng, batch_shape=(RUNS,))
    errs = []
    for k, ms in enumerate(scenario):
        p = pf.update(pf.predict(p, 1.0, rng), ms, rng)
        errs.append((pf.estimate(p).mean - kf_means[k]) / kf_sds[k])
    assert pf.stats.degenerate_steps == 0
    return float(np.sqrt(np.mean(np.square(errs))))


NS = np.array([250, 1000, 4000, 16000])


def test_bootstrap_error_to_kalman_mean_shrinks_as_one_over_root_n():
    scenario = _scenario()
    kf_means, kf_sds = _kalman(scenario)
    errs = np.array(
        [
            _standardised_error(BootstrapFilter, int(n), 100 + i, scenario, kf_means, kf_sds)
            for i, n in enumerate(NS)
        ]
    )
    slope = np.polyfit(np.log(NS), np.log(errs), 1)[0]
    assert -0.8 < slope < -0.3, (slope, errs)
    assert errs[-1] < 0.05


@pytest.mark.parametrize(
    ("cls", "kw", "tol"),
    [
        (AuxiliaryParticleFilter, {}, 0.05),
        (RegularizedParticleFilter, {}, 0.08),  # the kernel jitter adds a bias of order h^2
        (BootstrapFilter, {"resampler": "residual", "ess_threshold": 0.5}, 0.05),
        (BootstrapFilter, {"resampler": "stratified", "engine": "numpy"}, 0.05),
    ],
)
def test_other_filters_converge_to_kalman_mean(cls, kw, tol):
    scenario = _scenario()
    kf_means, kf_sds = _kalman(scenario)
    small = _standardised_error(cls, 500, 1, scenario, kf_means, kf_sds, **kw)
    large = _standardised_error(cls, 16000, 2, scenario, kf_means, kf_sds, **kw)
    assert large < tol, (small, large)
    assert large < 0.5 * small, (small, large)


def test_particle_covariance_matches_kalman():
    scenario = _scenario()
    kf = KalmanFilter(MOTION, SENSORS)
    g = PRIOR
    pf = BootstrapFilter(MOTION, SENSORS, n_particles=40000)
    rng = np.random.default_rng(3)
    p = pf.initialize(PRIOR, rng)
    for ms in scenario:
        g = kf.update(kf.predict(g, 1.0), ms)
        p = pf.update(pf.predict(p, 1.0, rng), ms)
    est = pf.estimate(p)
    np.testing.assert_allclose(est.cov, g.cov, rtol=0.1, atol=0.02 * np.max(np.diag(g.cov)))
    # the estimate equals the core Particles moments
    np.testing.assert_allclose(est.mean, p.mean, rtol=1e-10)
    # mean() after update is the one-pass mean cached by the fused update (sum of e x / sum e,
    # e the unnormalised weights): the same mean to rounding, not bit for bit
    np.testing.assert_allclose(pf.mean(p), est.mean, rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(est.cov, p.cov, rtol=1e-8, atol=1e-12)
