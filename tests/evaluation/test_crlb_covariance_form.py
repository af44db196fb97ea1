"""The PCRB's covariance form: equal to Prop. 1 with full-rank Q, to the Kalman filter with a
singular Q, and still refused for nonlinear motion with a singular Q."""

import numpy as np
import pytest

from fusetrack.core import ConfigError, Gaussian, Measurement
from fusetrack.evaluation.crlb import posterior_crlb, posterior_information
from fusetrack.filters import KalmanFilter, run_filter
from fusetrack.motion import ConstantVelocity, CoordinatedTurnRate
from fusetrack.sensors import Bearing, PositionFix

TAG = PositionFix("tag", cov=[[0.5, 0.1], [0.1, 0.3]])
MICS = [
    Bearing("m1", position=[0.0, 0.0], sigma=0.02),
    Bearing("m2", position=[30.0, 5.0], sigma=0.05),
]
P0 = np.diag([4.0, 4.0, 1.0, 1.0])


def truths(motion, R, T, dt, seed=0):
    rng = np.random.default_rng(seed)
    x = np.empty((R, T, motion.dim))
    x[:, 0] = rng.multivariate_normal([5.0, 10.0, 1.0, 0.2], P0, size=R)
    for k in range(T - 1):
        x[:, k + 1] = motion.sample(x[:, k], dt, rng)
    return x


@pytest.mark.parametrize("average", [True, False])
def test_both_forms_agree_with_full_rank_noise(average):
    """Nonlinear sensors averaged over trajectories, linear motion: the matrix inversion lemma."""
    cv = ConstantVelocity(ndim=2, q=0.3)
    x = truths(cv, 6, 25, 0.5)
    mask = np.random.default_rng(1).random((25, 2)) < 0.7
    args = (cv, MICS, x, 0.5, P0)
    Ji = posterior_information(*args, mask=mask, average=average, form="information")
    Jc = posterior_information(*args, mask=mask, average=average, form="covariance")
    np.testing.assert_allclose(Jc, Ji, rtol=1e-10, atol=1e-10 * np.abs(Ji).max())
    # "auto" with an invertible Q is the information form, bit for bit
    np.testing.assert_array_equal(posterior_information(*args, mask=mask, average=average), Ji)


def test_singular_noise_equals_the_kalman_filter():
    """Wiener-sequence (rank-2) noise: the bound is fusetrack's KalmanFilter covariance."""
    cv = ConstantVelocity(ndim=2, q=0.3, noise="discrete")
    assert np.linalg.matrix_rank(cv.noise_cov(0.5)) == 2
    T, dt = 30, 0.5
    rng = np.random.default_rng(4)
    reported = rng.random(T) < 0.6
    reported[8:15] = False  # a gap: the covariance grows along the noise's two directions only
    times = dt * np.arange(T)
    ms = [Measurement(float(t), "tag", rng.normal(size=2)) for t, r in zip(times, reported) if r]
    kf = KalmanFilter(cv, {"tag": TAG})
    track = run_filter(kf, Gaussian(np.zeros(4), P0), ms, times=times, t0=0.0)
    B = posterior_crlb(cv, [TAG], truths(cv, 3, T, dt), dt, P0, mask=reported[:, None])
    assert track.covariances is not None and track.covariances.shape == B.shape
    np.testing.assert_allclose(B, track.covariances, rtol=1e-9, atol=1e-12)


def test_singular_noise_with_the_information_form_is_refused():
    cv = ConstantVelocity(ndim=2, q=0.3, noise="discrete")
    with pytest.raises(ConfigError, match=r"noise_cov\(dt=0.5\)"):
        posterior_crlb(cv, [TAG], truths(cv, 2, 4, 0.5), 0.5, P0, form="information")


def test_nonlinear_motion_with_singular_noise_is_refused():
    """A coordinated turn with a constant turn rate (q_omega = 0): Q is singular and the
    Jacobian differs between trajectories, so neither form applies to the average."""
    ct = CoordinatedTurnRate(q=0.3, q_omega=0.0)
    rng = np.random.default_rng(2)
    x = np.empty((4, 5, 5))
    start = rng.normal(size=(4, 4)) + np.array([5.0, 10.0, 1.0, 0.0])
    x[:, 0] = np.column_stack([start, rng.normal(0, 0.1, 4)])
    for k in range(4):
        x[:, k + 1] = ct.sample(x[:, k], 1.0, rng)
    p0 = np.diag([4.0, 4.0, 1.0, 1.0, 0.01])
    with pytest.raises(ConfigError, match=r"noise_cov\(dt=1.0\).*jacobian differs"):
        posterior_crlb(ct, MICS, x, 1.0, p0)
    # one trajectory at a time the Jacobian is known, and the covariance form applies
    B = posterior_crlb(ct, MICS, x, 1.0, p0, average=False)
    assert B.shape == (4, 5, 5, 5) and np.all(np.linalg.eigvalsh(B) > 0)
    # with a full-rank Q, asking for the covariance form of the average is refused
    with pytest.raises(ConfigError, match="form"):
        posterior_crlb(CoordinatedTurnRate(q=0.3), MICS, x, 1.0, p0, form="covariance")
    with pytest.raises(ConfigError, match="form"):
        posterior_crlb(ct, MICS, x, 1.0, p0, form="fast")
