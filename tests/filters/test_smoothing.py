"""Smoothers: RTS / extended / unscented RTS equal the exact posterior where it is known, the
particle backward simulation matches them within its Monte Carlo error, and run_filter(smooth=True)
rejects what it cannot smooth before any work."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.core import ConfigError, Gaussian, Measurement, ShapeError
from fusetrack.filters import (
    BootstrapFilter,
    ExtendedKalmanFilter,
    KalmanFilter,
    UnscentedKalmanFilter,
    backward_simulation,
    rts_smoother,
    run_filter,
)
from fusetrack.motion import ConstantVelocity, CoordinatedTurnRate
from fusetrack.sensors import PositionFix

GAUSSIAN_FILTERS = [KalmanFilter, ExtendedKalmanFilter, UnscentedKalmanFilter]


def _linear_problem(runs: int = 3, seed: int = 0):
    """A 2-D constant-velocity target, two position sensors (one biased, one on x only),
    irregular steps, an output time without measurements; ``runs`` batched measurement sets."""
    rng = np.random.default_rng(seed)
    motion = ConstantVelocity(ndim=2, q=0.3)
    sensors = [
        PositionFix("a", cov=[[0.5, 0.1], [0.1, 0.3]]),
        PositionFix("b", cov=[[0.2]], position_index=(0,), bias=[0.4]),
    ]
    times = np.cumsum([0.0, 0.5, 1.0, 0.3, 0.7, 1.2, 0.4, 0.9, 0.6, 1.1])
    ms = []
    for k, t in enumerate(times):
        if k == 4:
            continue  # predict-only step (an extra output time)
        ms.append(Measurement(float(t), "a", rng.standard_normal((runs, 2)) + t))
        if k % 3 == 1:
            ms.append(Measurement(float(t), "b", rng.standard_normal((runs, 1)) + t + 0.4))
    prior = Gaussian(np.array([0.0, 0.0, 1.0, 1.0]), np.diag([2.0, 2.0, 1.0, 1.0]))
    return motion, sensors, prior, ms, times


def _batch_posterior(motion, sensors, prior, ms, times, run):
    """The exact smoothed posterior of every state by one stacked least-squares (information
    form) solve over the whole trajectory x_0..x_{T-1}:
    Lambda = blkdiag(P0^-1, 0..) + sum A_k^T Q_k^-1 A_k + sum H^T R^-1 H, mean = Lambda^-1 eta,
    covariances = diagonal blocks of Lambda^-1 (x_0 ~ prior: the prior is at the first time)."""
    d, n_t = prior.dim, len(times)
    lam = np.zeros((n_t * d, n_t * d))
    eta = np.zeros(n_t * d)
    p0_inv = np.linalg.inv(prior.cov)
    lam[:d, :d] += p0_inv
    eta[:d] += p0_inv @ prior.mean
    for k in range(n_t - 1):
        dt = times[k + 1] - times[k]
        a = np.zeros((d, n_t * d))  # x_{k+1} - F x_k ~ N(0, Q)
        a[:, k * d : (k + 1) * d] = -motion.transition_matrix(dt)
        a[:, (k + 1) * d : (k + 2) * d] = np.eye(d)
        lam += a.T @ np.linalg.inv(motion.noise_cov(dt)) @ a
    by_id = {s.sensor_id: s for s in sensors}
    for m in ms:
        k = int(np.argmin(np.abs(times - m.time)))
        s = by_id[m.sensor_id]
        h = np.zeros((s.dim, n_t * d))
        h[:, k * d : (k + 1) * d] = s.jacobian(np.zeros(d))
        r_inv = np.linalg.inv(s.noise_cov())
        lam += h.T @ r_inv @ h
        eta += h.T @ r_inv @ (m.value[run] - s.predict(np.zeros(d)))
    cov = np.linalg.inv(lam)
    mean = cov @ eta
    blocks = np.stack([cov[k * d : (k + 1) * d, k * d : (k + 1) * d] for k in range(n_t)])
    return mean.reshape(n_t, d), blocks


def _filtered_and_smoothed(cls, problem, **kwargs):
    motion, sensors, prior, ms, times = problem
    track = run_filter(cls(motion, sensors), prior, ms, times=times, smooth=True, **kwargs)
    return track.info["filtered"], track


# -- Kalman family ----------------------------------------------------------------------------


def test_rts_equals_the_batch_least_squares_posterior():
    problem = _linear_problem(runs=3)
    _, smoothed = _filtered_and_smoothed(KalmanFilter, problem)
    assert smoothed.means.shape == (10, 3, 4)
    for run in range(3):
        mean, cov = _batch_posterior(*problem, run)
        np.testing.assert_allclose(smoothed.means[:, run], mean, rtol=0, atol=1e-9)
        np.testing.assert_allclose(smoothed.covariances[:, run], cov, rtol=0, atol=1e-9)


@pytest.mark.parametrize("cls", GAUSSIAN_FILTERS)
def test_last_step_is_the_filtered_one_and_smoothing_only_shrinks_the_covariance(cls):
    filtered, smoothed = _filtered_and_smoothed(cls, _linear_problem())
    np.testing.assert_array_equal(smoothed.means[-1], filtered.means[-1])
    np.testing.assert_array_equal(smoothed.covariances[-1], filtered.covariances[-1])
    gap = np.linalg.eigvalsh(filtered.covariances - smoothed.covariances)  # P_f - P_s >= 0
    assert gap.min() > -1e-12
    assert np.all(gap[:-1].max(axis=-1) > 1e-3)  # and strictly smaller before the last step
    assert smoothed.info["filter"] == cls.__name__
    assert smoothed.info["lag"] is None


@pytest.mark.parametrize("cls", [ExtendedKalmanFilter, UnscentedKalmanFilter])
def test_extended_and_unscented_smoothers_equal_rts_on_a_linear_model(cls):
    problem = _linear_problem()
    _, exact = _filtered_and_smoothed(KalmanFilter, problem)
    _, smoothed = _filtered_and_smoothed(cls, problem)
    np.testing.assert_allclose(smoothed.means, exact.means, rtol=0, atol=1e-9)
    np.testing.assert_allclose(smoothed.covariances, exact.covariances, rtol=0, atol=1e-9)


def test_fixed_lag_rts_is_the_smoother_of_the_data_up_to_k_plus_lag():
    problem = _linear_problem(runs=2)
    motion, sensors, prior, ms, times = problem
    kf = KalmanFilter(motion, sensors)
    lag = 2
    track = run_filter(kf, prior, ms, times=times, smooth=True, lag=lag)
    for k in range(len(times)):
        end = min(k + lag, len(times) - 1)
        cut = times[: end + 1]
        upto = [m for m in ms if m.time <= cut[-1] + 1e-9]
        ref = run_filter(kf, prior, upto, times=cut, smooth=True)
        np.testing.assert_allclose(track.means[k], ref.means[k], rtol=0, atol=1e-12)
        np.testing.assert_allclose(track.covariances[k], ref.covariances[k], rtol=0, atol=1e-12)
    filtered = run_filter(kf, prior, ms, times=times)
    zero = run_filter(kf, prior, ms, times=times, smooth=True, lag=0)
    np.testing.assert_array_equal(zero.means, filtered.means)
    full = run_filter(kf, prior, ms, times=times, smooth=True)
    long = run_filter(kf, prior, ms, times=times, smooth=True, lag=len(times) - 1)
    np.testing.assert_array_equal(long.means, full.means)


def test_extended_smoother_gain_uses_the_jacobian_at_the_filtered_mean():
    """Two steps by hand: m0^s = m0 + G (m1 - f(m0)), G = P0 J^T (J P0 J^T + Q)^-1,
    P0^s = P0 + G (P1 - P1^-) G^T with J = df/dx at m0 (Särkkä 2013, Alg. 9.1)."""
    motion = CoordinatedTurnRate(q=0.2, q_omega=0.05)
    ekf = ExtendedKalmanFilter(motion, [PositionFix("p", cov=0.3 * np.eye(2))])
    m = np.array([[1.0, 2.0, 3.0, -1.0, 0.4], [1.5, 2.2, 2.0, 0.5, -0.3]])
    rng = np.random.default_rng(3)
    a = rng.standard_normal((2, 5, 5))
    p = a @ np.swapaxes(a, -1, -2) / 5 + 0.2 * np.eye(5)
    dt = 0.7
    sm, sp = rts_smoother(ekf, m, p, [dt])
    j = motion.jacobian(m[0], dt)
    p_pred = j @ p[0] @ j.T + motion.noise_cov(dt)
    g = p[0] @ j.T @ np.linalg.inv(p_pred)
    np.testing.assert_allclose(sm[0], m[0] + g @ (m[1] - motion.mean(m[0], dt)), atol=1e-12)
    np.testing.assert_allclose(sp[0], p[0] + g @ (p[1] - p_pred) @ g.T, atol=1e-12)


def test_unscented_and_extended_smoothers_agree_when_the_spread_is_small():
    """For a small covariance the unscented cross covariance is P J^T + O(|P|^2): the two
    smoothers of a nonlinear (coordinated-turn) model agree to second order."""
    motion = CoordinatedTurnRate(q=0.2, q_omega=0.05)
    sensors = [PositionFix("p", cov=0.3 * np.eye(2))]
    rng = np.random.default_rng(4)
    t = 6
    m = np.array([1.0, 2.0, 3.0, -1.0, 0.4]) + 0.1 * rng.standard_normal((t, 5))
    a = rng.standard_normal((t, 5, 5))
    p = a @ np.swapaxes(a, -1, -2) / 5 + 0.2 * np.eye(5)
    gaps = []
    for scale in (1e-2, 1e-3):
        e = rts_smoother(ExtendedKalmanFilter(motion, sensors), m, scale * p, np.full(t - 1, 0.5))
        u = rts_smoother(UnscentedKalmanFilter(motion, sensors), m, scale * p, np.full(t - 1, 0.5))
        gaps.append(np.abs(e[0] - u[0]).max())
    assert gaps[1] < 1e-4
    assert gaps[1] < gaps[0] / 20  # shrinks at least ~quadratically with the spread


def test_gaussian_smoothers_reduce_the_error_on_a_nonlinear_model():
    """100 simulated coordinated turns: the smoothed position error is well below the filtered
    one (smoothing uses the later fixes too) for both nonlinear smoothers."""
    motion = CoordinatedTurnRate(q=0.5, q_omega=0.02)
    sensor = PositionFix("p", cov=1.0 * np.eye(2))
    rng = np.random.default_rng(5)
    runs, steps, dt = 100, 25, 0.5
    x = np.tile(np.array([0.0, 0.0, 4.0, 0.0, 0.3]), (runs, 1))
    truth, ms = [], []
    for k in range(steps):
        if k:
            x = motion.sample(x, dt, rng)
        truth.append(x)
        ms.append(Measurement(k * dt, "p", sensor.simulate(x, rng)))
    truth_a = np.stack(truth)
    prior = Gaussian(np.array([0.0, 0.0, 4.0, 0.0, 0.3]), np.diag([1.0, 1.0, 1.0, 1.0, 0.05]))
    for cls in (ExtendedKalmanFilter, UnscentedKalmanFilter):
        track = run_filter(cls(motion, [sensor]), prior, ms, smooth=True)
        filt = track.info["filtered"]

        def rmse(means):
            return np.sqrt(np.mean((means[:-1, :, :2] - truth_a[:-1, :, :2]) ** 2))

        assert rmse(track.means) < 0.8 * rmse(filt.means), cls.__name__


# -- particle smoothing -----------------------------------------------------------------------


def _particle_problem(runs: int = 2, steps: int = 15, seed: int = 7):
    rng = np.random.default_rng(seed)
    motion = ConstantVelocity(ndim=1, q=0.5)
    sensor = PositionFix("gps", cov=[[1.0]], position_index=(0,))
    ms = [
        Measurement(float(t), "gps", 0.6 * t + rng.standard_normal((runs, 1)))
        for t in range(steps)
    ]
    prior = Gaussian(np.zeros(2), np.diag([4.0, 1.0]))
    return motion, [sensor], prior, ms
