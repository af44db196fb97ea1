"""The Kalman filter equals the closed-form posterior of linear-Gaussian problems."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.core import Gaussian, Measurement
from fusetrack.filters import ExtendedKalmanFilter, KalmanFilter, UnscentedKalmanFilter, run_filter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import PositionFix

FILTERS = [KalmanFilter, ExtendedKalmanFilter, UnscentedKalmanFilter]


def _random_spd(rng: np.random.Generator, d: int, scale: float = 1.0) -> np.ndarray:
    a = rng.standard_normal((d, d))
    return scale * (a @ a.T / d + 0.5 * np.eye(d))


@pytest.mark.parametrize("cls", FILTERS)
def test_static_state_equals_information_form(cls):
    """Several fixes of one static state: P^-1 = P0^-1 + sum H^T R^-1 H,
    x = P (P0^-1 x0 + sum H^T R^-1 (z - c))."""
    rng = np.random.default_rng(0)
    d = 4
    x0 = rng.standard_normal(d)
    p0 = _random_spd(rng, d, 2.0)
    sensors = [
        PositionFix("a", cov=_random_spd(rng, 2, 0.3)),
        PositionFix("b", cov=_random_spd(rng, 2, 0.1), bias=[0.5, -0.2]),
        PositionFix("c", cov=[[0.4]], position_index=(1,)),
    ]
    ms = [
        Measurement(0.0, "a", rng.standard_normal(2)),
        Measurement(0.0, "b", rng.standard_normal(2)),
        Measurement(0.0, "c", rng.standard_normal(1)),
        Measurement(0.0, "a", rng.standard_normal(2)),
    ]
    by_id = {s.sensor_id: s for s in sensors}
    info = np.linalg.inv(p0)
    vec = info @ x0
    for m in ms:
        s = by_id[m.sensor_id]
        h = s.jacobian(np.zeros(d))
        c = s.predict(np.zeros(d))
        r_inv = np.linalg.inv(s.noise_cov())
        info = info + h.T @ r_inv @ h
        vec = vec + h.T @ r_inv @ (m.value - c)
    p_exact = np.linalg.inv(info)
    x_exact = p_exact @ vec

    filt = cls(ConstantVelocity(), sensors)
    post = filt.update(Gaussian(x0, p0), ms)
    np.testing.assert_allclose(post.mean, x_exact, rtol=0, atol=1e-10)
    np.testing.assert_allclose(post.cov, p_exact, rtol=0, atol=1e-10)


def _joint_conditioning(x0, p0, fs, qs, h, c, r, zs):
    """Posterior of the last state by dense conditioning of the joint Gaussian.

    Everything is a linear map of the independent Gaussians u = (x0, w_1, v_1, ..., w_T, v_T):
    x_k = F_k x_{k-1} + w_k, z_k = H x_k + c + v_k.
    """
    d, m = x0.size, c.size
    n_t = len(fs)
    n_u = d + n_t * (d + m)
    cov_u = np.zeros((n_u, n_u))
    mean_u = np.zeros(n_u)
    mean_u[:d] = x0
    cov_u[:d, :d] = p0
    a_x = np.zeros((d, n_u))  # x_k = a_x @ u
    a_x[:, :d] = np.eye(d)
    a_z = []
    off = d
    for k in range(n_t):
        cov_u[off : off + d, off : off + d] = qs[k]
        cov_u[off + d : off + d + m, off + d : off + d + m] = r
        a_x = fs[k] @ a_x
        a_x[:, off : off + d] += np.eye(d)
        az = h @ a_x
        az[:, off + d : off + d + m] += np.eye(m)
        a_z.append(az)
        off += d + m
    a_z = np.vstack(a_z)
    mx, mz = a_x @ mean_u, a_z @ mean_u + np.tile(c, n_t)
    sxx = a_x @ cov_u @ a_x.T
    sxz = a_x @ cov_u @ a_z.T
    szz = a_z @ cov_u @ a_z.T
    gain = sxz @ np.linalg.inv(szz)
    return mx + gain @ (np.concatenate(zs) - mz), sxx - gain @ sxz.T


@pytest.mark.parametrize("cls", FILTERS)
@pytest.mark.parametrize("noise", ["continuous", "discrete"])
def test_two_step_cv_equals_joint_gaussian_conditioning(cls, noise):
    rng = np.random.default_rng(1)
    motion = ConstantVelocity(ndim=2, q=0.7, noise=noise)
    tag = PositionFix("tag", cov=[[0.3, 0.1], [0.1, 0.2]], bias=[0.1, 0.0])
    x0 = np.array([1.0, -2.0, 0.5, 0.3])
    p0 = np.diag([1.0, 2.0, 0.5, 0.4])
    dts = [0.7, 1.9]  # irregular
    zs = [
        rng.standard_normal(2) + np.array([1.5, -1.5]),
        rng.standard_normal(2) + np.array([2.0, -1.0]),
    ]
    fs = [motion.transition_matrix(dt) for dt in dts]
    qs = [motion.noise_cov(dt) for dt in dts]
    h = tag.jacobian(np.zeros(4))
    mean_exact, cov_exact = _joint_conditioning(
        x0, p0, fs, qs, h, tag.predict(np.zeros(4)), tag.noise_cov(), zs
    )

    filt = cls(motion, [tag])
    ms = [Measurement(0.7, "tag", zs[0]), Measurement(2.6, "tag", zs[1])]
    track = run_filter(filt, Gaussian(x0, p0), ms, t0=0.0)
    np.testing.assert_allclose(track.times, [0.7, 2.6])
    np.testing.assert_allclose(track.means[-1], mean_exact, rtol=0, atol=1e-10)
    np.testing.assert_allclose(track.covariances[-1], cov_exact, rtol=0, atol=1e-10)


def test_sequential_updates_equal_one_stacked_update():
    """Two independent sensors at one time, applied in sequence = one update with stacked H, R."""
    rng = np.random.default_rng(2)
    a = PositionFix("a", cov=[[0.2, 0.05], [0.05, 0.3]])
    b = PositionFix("b", cov=[[0.5]], position_index=(0,))
    prior = Gaussian(rng.standard_normal(4), _random_spd(rng, 4))
    za, zb = rng.standard_normal(2), rng.standard_normal(1)
    kf = KalmanFilter(ConstantVelocity(), [a, b])
    post = kf.update(prior, [Measurement(0.0, "a", za), Measurement(0.0, "b", zb)])

    h = np.vstack([a.jacobian(np.zeros(4)), b.jacobian(np.zeros(4))])
    r = np.zeros((3, 3))
    r[:2, :2], r[2:, 2:] = a.noise_cov(), b.noise_cov()
    s = h @ prior.cov @ h.T + r
    k = prior.cov @ h.T @ np.linalg.inv(s)
    innovation = np.r_[za, zb] - h @ prior.mean
    np.testing.assert_allclose(post.mean, prior.mean + k @ innovation, atol=1e-12)
    np.testing.assert_allclose(post.cov, prior.cov - k @ s @ k.T, atol=1e-12)


def test_measurement_covariance_overrides_sensor_noise():
    tag = PositionFix("tag", cov=np.eye(2))
    kf = KalmanFilter(ConstantVelocity(), [tag])
    prior = Gaussian(np.zeros(4), np.eye(4))
    z = np.array([1.0, 2.0])
    own = kf.update(prior, [Measurement(0.0, "tag", z, covariance=0.01 * np.eye(2))])
    tight = KalmanFilter(ConstantVelocity(), [PositionFix("tag", cov=0.01 * np.eye(2))])
    ref = tight.update(prior, [Measurement(0.0, "tag", z)])
    np.testing.assert_allclose(own.mean, ref.mean, atol=1e-14)
    np.testing.assert_allclose(own.cov, ref.cov, atol=1e-14)


def test_update_with_likelihood_is_the_predictive_density():
    rng = np.random.default_rng(3)
    tag = PositionFix("tag", cov=[[0.3, 0.1], [0.1, 0.2]])
    prior = Gaussian(rng.standard_normal(4), _random_spd(rng, 4))
    z = rng.standard_normal(2)
    kf = KalmanFilter(ConstantVelocity(), [tag])
    post, ll = kf.update_with_likelihood(prior, [Measurement(0.0, "tag", z)])
    h = tag.jacobian(np.zeros(4))
    pred = Gaussian(h @ prior.mean, h @ prior.cov @ h.T + tag.noise_cov())
    np.testing.assert_allclose(ll, pred.logpdf(z), atol=1e-12)
    np.testing.assert_allclose(post.mean, kf.update(prior, [Measurement(0.0, "tag", z)]).mean)


def test_kalman_filter_requires_linear_motion():
    from fusetrack.core import ConfigError
    from fusetrack.motion import CoordinatedTurnRate

    with pytest.raises(ConfigError, match="transition_matrix"):
        KalmanFilter(CoordinatedTurnRate(), [PositionFix("tag", cov=np.eye(2))])
    ExtendedKalmanFilter(CoordinatedTurnRate(), [PositionFix("tag", cov=np.eye(2))])
