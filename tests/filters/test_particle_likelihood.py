"""The particle filter's log-likelihood increment ``log p(z_k | z_1:k-1)``: on a linear-Gaussian
model its sum matches the Kalman filter's exact one, and it ranks parameter values as the exact
likelihood does."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.core import Gaussian, LikelihoodFilter, Measurement, Particles
from fusetrack.filters import (
    AuxiliaryParticleFilter,
    BootstrapFilter,
    KalmanFilter,
    run_filter,
)
from fusetrack.motion import LinearGaussianMotion
from fusetrack.sensors import LinearGaussianSensor

F = np.array([[1.0, 1.0], [0.0, 1.0]])
H = np.array([[1.0, 0.0]])
PRIOR = Gaussian(np.array([0.0, 1.0]), np.diag([4.0, 1.0]))


def _model(q: float) -> LinearGaussianMotion:
    return LinearGaussianMotion(F=F, Q=q * np.array([[1 / 3, 1 / 2], [1 / 2, 1.0]]))


def _sensors() -> list[LinearGaussianSensor]:
    return [
        LinearGaussianSensor("a", H=H, R=[[0.5]]),
        LinearGaussianSensor("b", H=[[1.0, 1.0]], R=[[2.0]]),
    ]


def _simulate(q: float, steps: int, runs: int, seed: int) -> list[Measurement]:
    """Two sensors per step; values ``(runs, 1)`` (one trajectory per run)."""
    rng = np.random.default_rng(seed)
    motion = _model(q)
    x = PRIOR.mean + rng.standard_normal((runs, 2)) @ np.linalg.cholesky(PRIOR.cov).T
    out = []
    for k in range(1, steps + 1):
        x = motion.sample(x, 1.0, rng)
        for s in _sensors():
            out.append(Measurement(float(k), s.sensor_id, s.simulate(x, rng)))
    return out


def _loglik(filt, zs, rng=None) -> np.ndarray:
    track = run_filter(filt, PRIOR, zs, rng=rng, t0=0.0, log_likelihood=True)
    return np.asarray(track.info["log_likelihood"], dtype=float)


@pytest.mark.parametrize("engine", ["numba", "numpy"])
def test_bootstrap_log_likelihood_matches_the_kalman_filter(engine):
    """Per run the PF estimate of log p(z_1:T) is within a few hundredths of the exact value.
    Forgetting the prior weights adds log N per measurement; ignoring them (a plain mean of the
    likelihoods when the weights are not uniform, ess_threshold=0.5) is off by whole units."""
    zs = _simulate(q=0.3, steps=15, runs=4, seed=1)
    exact = _loglik(KalmanFilter(_model(0.3), _sensors()), zs)
    pf = BootstrapFilter(_model(0.3), _sensors(), 20_000, ess_threshold=0.5, engine=engine)
    assert isinstance(pf, LikelihoodFilter)
    est = _loglik(pf, zs, np.random.default_rng(2))
    assert est.shape == exact.shape == (4,)
    np.testing.assert_allclose(est, exact, atol=0.15)
    assert abs(float(np.mean(est - exact))) < 0.08


def test_auxiliary_log_likelihood_matches_the_kalman_filter():
    """Both stages' normalisers: dropping either is off by several units per step (the APF
    estimate is noisier than the bootstrap one here, hence the wider tolerance)."""
    zs = _simulate(q=0.3, steps=15, runs=4, seed=3)
    exact = _loglik(KalmanFilter(_model(0.3), _sensors()), zs)
    apf = AuxiliaryParticleFilter(_model(0.3), _sensors(), 20_000, ess_threshold=0.5)
    np.testing.assert_allclose(_loglik(apf, zs, np.random.default_rng(4)), exact, atol=0.5)


def test_update_with_likelihood_is_update_plus_the_increment():
    """Same particles as update (same draws) and, for one measurement, the increment is
    log sum_i w_i p(z | x_i) with the normalised prior weights."""
    pf = BootstrapFilter(_model(0.3), _sensors(), 500, ess_threshold=0.0)
    rng = np.random.default_rng(5)
    p = pf.initialize(PRIOR, rng)
    p = pf.update(p, [Measurement(0.0, "a", [0.4])])  # non-uniform weights from here on
    p = pf.predict(p, 1.0, rng)
    z = [Measurement(1.0, "a", [1.3])]
    plain = pf.update(p, z)
    with_ll, ll = pf.update_with_likelihood(p, z)
    np.testing.assert_array_equal(with_ll.log_weights, plain.log_weights)
    w = pf.weights(p)
    lik = np.exp(_sensors()[0].log_likelihood(np.array([[1.3]]), p.states))
    assert float(ll) == pytest.approx(np.log(np.sum(w * lik)), rel=1e-12)
    assert float(pf.update_with_likelihood(p, [])[1]) == 0.0
    shifted = Particles(p.states, p.log_weights + 5.0)  # unnormalised: normalised first
    assert float(pf.update_with_likelihood(shifted, z)[1]) == pytest.approx(float(ll), rel=1e-12)


def test_grid_search_over_q_peaks_at_the_true_value():
    """The summed PF log-likelihood over 20 runs of 40 steps is highest at the q that made the
    data, as the exact (Kalman) likelihood is."""
    q_true = 0.5
    zs = _simulate(q=q_true, steps=40, runs=20, seed=7)
    grid = [0.125, 0.25, 0.5, 1.0, 2.0]
    pf_ll = [
        float(
            np.sum(
                _loglik(BootstrapFilter(_model(q), _sensors(), 2000), zs, np.random.default_rng(8))
            )
        )
        for q in grid
    ]
    kf_ll = [float(np.sum(_loglik(KalmanFilter(_model(q), _sensors()), zs))) for q in grid]
    assert grid[int(np.argmax(kf_ll))] == q_true
    assert grid[int(np.argmax(pf_ll))] == q_true
    assert pf_ll[2] == pytest.approx(kf_ll[2], abs=3.0)  # 800 steps; far from q_true PF is worse
