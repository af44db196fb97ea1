"""The one tracking model: the ``Filter`` protocol, ``filter_step``, the log-likelihood that
``run_filter`` reports, and a user's own linear-Gaussian motion and sensor models."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from fusetrack.core import (
    ConfigError,
    Filter,
    Gaussian,
    LikelihoodFilter,
    Measurement,
    SteppingFilter,
    filter_step,
)
from fusetrack.filters import BootstrapFilter, KalmanFilter, run_filter
from fusetrack.motion import ConstantVelocity, LinearGaussianMotion
from fusetrack.sensors import LinearGaussianSensor, PositionFix


def _cv_matrices(dt: float, q: float) -> tuple[np.ndarray, np.ndarray]:
    F = np.array([[1.0, dt], [0.0, 1.0]])
    Q = q * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
    return F, Q


def test_user_linear_gaussian_models_equal_the_library_ones():
    cv = ConstantVelocity(ndim=1, q=0.3)
    mine = LinearGaussianMotion(
        F=lambda dt: _cv_matrices(dt, 0.3)[0], Q=lambda dt: _cv_matrices(dt, 0.3)[1]
    )
    kf_lib = KalmanFilter(cv, [PositionFix("p", cov=[[0.5]])])
    kf_own = KalmanFilter(mine, [LinearGaussianSensor("p", H=[[1.0, 0.0]], R=[[0.5]])])
    rng = np.random.default_rng(4)
    zs = [Measurement(0.7 * k, "p", [rng.normal(k, 1.0)]) for k in range(1, 12)]
    prior = Gaussian(np.zeros(2), np.eye(2))
    a = run_filter(kf_lib, prior, zs, t0=0.0, log_likelihood=True)
    b = run_filter(kf_own, prior, zs, t0=0.0, log_likelihood=True)
    np.testing.assert_allclose(b.means, a.means, rtol=0, atol=1e-12)
    np.testing.assert_allclose(b.covariances, a.covariances, rtol=0, atol=1e-12)
    assert b.info["log_likelihood"] == pytest.approx(a.info["log_likelihood"], abs=1e-10)


def test_kalman_log_likelihood_is_the_exact_joint_density():
    """On a linear-Gaussian model the summed increments equal log N(z_1:T; E z, Cov z) computed
    from the joint Gaussian of all measurements (no filtering involved)."""
    dt, q, r, T = 1.0, 0.2, 0.4, 6
    F, Q = _cv_matrices(dt, q)
    H = np.array([[1.0, 0.0]])
    m0, P0 = np.array([0.5, -0.2]), np.diag([2.0, 0.5])
    # x_k = F^k x_0 + sum_j F^(k-j) w_j; z_k = H x_k + v_k, k = 1..T
    A = [np.linalg.matrix_power(F, k) for k in range(T + 1)]
    mean = np.array([(H @ A[k] @ m0)[0] for k in range(1, T + 1)])
    cov = np.zeros((T, T))
    for i in range(1, T + 1):
        for j in range(1, T + 1):
            c = H @ A[i] @ P0 @ A[j].T @ H.T
            for s in range(1, min(i, j) + 1):
                c = c + H @ A[i - s] @ Q @ A[j - s].T @ H.T
            cov[i - 1, j - 1] = c[0, 0] + (r if i == j else 0.0)
    z = np.array([0.9, 0.4, 0.3, -0.6, -1.1, -2.0])
    exact = multivariate_normal(mean, cov).logpdf(z)
    kf = KalmanFilter(LinearGaussianMotion(F=F, Q=Q), [LinearGaussianSensor("s", H=H, R=[[r]])])
    track = run_filter(
        kf,
        Gaussian(m0, P0),
        [Measurement(k * dt, "s", [z[k - 1]]) for k in range(1, T + 1)],
        t0=0.0,
        log_likelihood=True,
    )
    assert float(track.info["log_likelihood"]) == pytest.approx(exact, abs=1e-9)


def test_protocols_are_real_types():
    kf = KalmanFilter(ConstantVelocity(ndim=1, q=0.1), [PositionFix("p", cov=[[1.0]])])
    assert isinstance(kf, Filter) and isinstance(kf, LikelihoodFilter)
    assert not isinstance(kf, SteppingFilter)
    assert not isinstance(object(), Filter)


def test_filter_step_is_predict_then_update():
    kf = KalmanFilter(ConstantVelocity(ndim=1, q=0.1), [PositionFix("p", cov=[[1.0]])])
    prior = Gaussian(np.zeros(2), np.eye(2))
    zs = [Measurement(1.0, "p", [0.7])]
    a = filter_step(kf, prior, 1.0, zs)
    b = kf.update(kf.predict(prior, 1.0), zs)
    np.testing.assert_array_equal(a.mean, b.mean)
    assert filter_step(kf, prior, 0.0, []) is prior


def test_log_likelihood_refused_for_a_filter_that_cannot_report_it():
    class NoLikelihood:
        def predict(self, belief, dt, rng=None):
            return belief

        def update(self, belief, measurements, rng=None):
            return belief

    with pytest.raises(ConfigError, match="log_likelihood"):
        run_filter(NoLikelihood(), Gaussian(np.zeros(2), np.eye(2)), [], log_likelihood=True)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"H": [[1.0, 0.0]], "R": [[-1.0]]}, "R"),
        ({"H": [[1.0, 0.0]], "R": [[1.0, 0.0]]}, "R"),
        ({"H": [1.0, 0.0], "R": [[1.0]]}, "H"),
    ],
)
def test_linear_gaussian_sensor_refuses_bad_matrices(kwargs, field):
    with pytest.raises(ConfigError, match=field):
        LinearGaussianSensor("s", **kwargs)


def test_linear_gaussian_motion_refuses_bad_matrices():
    with pytest.raises(ConfigError, match="Q"):
        LinearGaussianMotion(F=np.eye(2), Q=-np.eye(2))
    with pytest.raises(ConfigError, match="F"):
        LinearGaussianMotion(F=np.ones((2, 3)), Q=np.eye(2))


def test_bootstrap_filter_runs_on_user_models():
    motion = LinearGaussianMotion(F=_cv_matrices(1.0, 0.1)[0], Q=_cv_matrices(1.0, 0.1)[1])
    sensor = LinearGaussianSensor("s", H=[[1.0, 0.0]], R=[[0.25]])
    pf = BootstrapFilter(motion, [sensor], n_particles=4000)
    kf = KalmanFilter(motion, [sensor])
    zs = [Measurement(float(k), "s", [0.5 * k]) for k in range(1, 8)]
    prior = Gaussian(np.zeros(2), np.eye(2))
    a = run_filter(pf, prior, zs, t0=0.0, rng=np.random.default_rng(1))
    b = run_filter(kf, prior, zs, t0=0.0)
    np.testing.assert_allclose(a.means[-1], b.means[-1], atol=0.15)


def test_proposal_filter_reports_its_own_likelihood_with_the_same_draws():
    """A stepping filter's log-likelihood comes from its own step (same draws as without it),
    and with an EKF-bank proposal it estimates the exact linear-Gaussian value."""
    from fusetrack.filters import ProposalParticleFilter, SPPEKFProposal

    F, Q = _cv_matrices(1.0, 0.2)
    motion = LinearGaussianMotion(F=F, Q=Q)
    sensor = LinearGaussianSensor("s", H=[[1.0, 0.0]], R=[[0.3]])
    zs = [Measurement(float(k), "s", [0.4 * k + 0.3 * (-1) ** k]) for k in range(1, 15)]
    prior = Gaussian(np.zeros(2), np.eye(2))
    exact = run_filter(KalmanFilter(motion, [sensor]), prior, zs, t0=0.0, log_likelihood=True)
    pf = ProposalParticleFilter(motion, [sensor], SPPEKFProposal(), n_particles=2000)
    plain = run_filter(pf, prior, zs, t0=0.0, rng=np.random.default_rng(5))
    with_ll = run_filter(pf, prior, zs, t0=0.0, rng=np.random.default_rng(5), log_likelihood=True)
    np.testing.assert_array_equal(with_ll.means, plain.means)
    assert float(with_ll.info["log_likelihood"]) == pytest.approx(
        float(exact.info["log_likelihood"]), abs=0.2
    )
