"""Smoothers: RTS / extended / unscented RTS equal the exact posterior where it is known, the
particle backward simulation matches them within its Monte Carlo error, and run_filter(smooth=True)
rejects what it cannot smooth before any work."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.core import (
    ConfigError,
    DegenerateWeightsWarning,
    Gaussian,
    Measurement,
    Particles,
    ShapeError,
)
from fusetrack.filters import (
    AuxiliaryParticleFilter,
    BootstrapFilter,
    ExtendedKalmanFilter,
    KalmanFilter,
    RegularizedParticleFilter,
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
        Measurement(float(t), "gps", 0.6 * t + rng.standard_normal((runs, 1))) for t in range(steps)
    ]
    prior = Gaussian(np.zeros(2), np.diag([4.0, 1.0]))
    return motion, [sensor], prior, ms


def _z_scores(track, ref, n):
    """Errors of the particle means in units of the ideal Monte Carlo standard error
    ``sqrt(P^s_ii / n)`` of ``n`` independent draws from the exact smoothed marginal."""
    sd = np.sqrt(np.diagonal(ref.covariances, axis1=-2, axis2=-1))
    return (track.means - ref.means) / (sd / np.sqrt(n))


def _variance_ratio(track, ref):
    diag = np.diagonal(track.covariances, axis1=-2, axis2=-1)
    return float(np.mean(diag / np.diagonal(ref.covariances, axis1=-2, axis2=-1)))


# Tolerances, measured over seeds 0-29 (N = M = 500, lag None) and 0-19 (N = 300, lag 3) of
# these problems: the z-scores (errors in units of sqrt(P^s_ii / N), see _z_scores) have a spread
# of 2.0-2.35 (not 1: filter error and correlated trajectories), a per-seed max |z| of at most
# 8.1 over the 60 entries and a per-seed RMS of at most 3.1; the per-seed mean variance ratio
# stays in [0.91, 1.08]. The bounds leave a margin on every one; the filtered means (which a
# smoother that did nothing would return) sit 25-35 z-units away from the smoothed ones.
MAX_Z, RMS_Z, VAR_RATIO = 10.0, 4.0, (0.85, 1.15)


def _assert_matches(track, ref, n, filtered):
    z = _z_scores(track, ref, n)
    assert np.abs(z).max() < MAX_Z
    assert np.sqrt(np.mean(z**2)) < RMS_Z
    assert VAR_RATIO[0] < _variance_ratio(track, ref) < VAR_RATIO[1]
    assert np.abs(_z_scores(filtered, ref, n)).max() > 2 * MAX_Z  # the test can fail


def _lag_one_correlations(exact, motion, dt, samples=None):
    """Mean over steps and runs of corr(x_k,i, x_k+1,i | all data) per component i: exact,
    from the RTS cross covariance G_k P^s_k+1 (G_k = P_k F^T P^-_k+1^-1), or of the
    trajectories ``samples`` ``(T, ..., M, d)``."""
    if samples is not None:
        r = samples - samples.mean(axis=-2, keepdims=True)
        cross = np.einsum("k...mi,k...mj->k...ij", r[:-1], r[1:]) / samples.shape[-2]
        var = np.einsum("k...mi,k...mi->k...i", r, r) / samples.shape[-2]
    else:
        filt = exact.info["filtered"].covariances
        f, q = motion.transition_matrix(dt), motion.noise_cov(dt)
        gain = filt[:-1] @ f.T @ np.linalg.inv(f @ filt[:-1] @ f.T + q)
        cross = gain @ exact.covariances[1:]
        var = np.diagonal(exact.covariances, axis1=-2, axis2=-1)
    diag = np.diagonal(cross, axis1=-2, axis2=-1)
    return np.mean(diag / np.sqrt(var[:-1] * var[1:]), axis=(0, 1))


def test_backward_simulation_matches_rts_within_monte_carlo_error():
    motion, sensors, prior, ms = _particle_problem()
    n = 500
    exact = run_filter(KalmanFilter(motion, sensors), prior, ms, smooth=True)
    pf = BootstrapFilter(motion, sensors, n_particles=n)
    track = run_filter(pf, prior, ms, smooth=True, rng=np.random.default_rng(0))
    assert track.means.shape == (15, 2, 2)  # batched: two runs
    assert track.info["samples"].shape == (15, 2, n, 2)
    _assert_matches(track, exact, n, exact.info["filtered"])
    # the joint law: consecutive states correlate as the RTS cross covariance says (seeds 0-19:
    # spread 0.007 / 0.011 around the exact 0.75 / 0.21; a backward kernel with the transition
    # density tempered by 1/2, i.e. Q doubled, lands 0.065 / 0.13 away)
    rho = _lag_one_correlations(exact, motion, 1.0)
    got = _lag_one_correlations(exact, motion, 1.0, track.info["samples"])
    np.testing.assert_allclose(got, rho, rtol=0, atol=0.05)


def test_smoothed_run_keeps_the_filtered_track_and_lag_t_minus_1_is_the_fixed_interval_pass():
    motion, sensors, prior, ms = _particle_problem()
    pf = BootstrapFilter(motion, sensors, n_particles=50)
    track = run_filter(pf, prior, ms, smooth=True, rng=np.random.default_rng(0))
    plain = run_filter(pf, prior, ms, rng=np.random.default_rng(0))  # draw for draw
    np.testing.assert_array_equal(track.info["filtered"].means, plain.means)
    np.testing.assert_array_equal(track.info["filtered"].covariances, plain.covariances)
    lagged = run_filter(pf, prior, ms, smooth=True, lag=14, rng=np.random.default_rng(0))
    np.testing.assert_array_equal(lagged.means, track.means)  # one backward pass: same draws
    assert track.info["smoother"] == "backward simulation"


def test_fixed_lag_backward_simulation_matches_the_fixed_lag_kalman_smoother():
    motion, sensors, prior, ms = _particle_problem()
    n, lag = 300, 3
    kf = KalmanFilter(motion, sensors)
    exact = run_filter(kf, prior, ms, smooth=True, lag=lag)
    pf = BootstrapFilter(motion, sensors, n_particles=n)
    track = run_filter(pf, prior, ms, smooth=True, lag=lag, rng=np.random.default_rng(1))
    _assert_matches(track, exact, n, exact.info["filtered"])
    assert track.info["lag"] == lag


@pytest.mark.parametrize("cls", [AuxiliaryParticleFilter, RegularizedParticleFilter])
def test_every_particle_filter_of_the_family_is_smoothed(cls):
    """The auxiliary and regularised filters' particle sets are weighted filtering
    approximations too: with 200 particles the smoothed means land 4-6x closer to the RTS
    means than the filtered ones (ratio 0.16-0.27 over seeds 0-4 for the three filters)."""
    motion, sensors, prior, ms = _particle_problem()
    exact = run_filter(KalmanFilter(motion, sensors), prior, ms, smooth=True)
    pf = cls(motion, sensors, n_particles=200)
    track = run_filter(pf, prior, ms, smooth=True, rng=np.random.default_rng(0))
    smoothed_gap = np.abs(track.means - exact.means).mean()
    filtered_gap = np.abs(track.info["filtered"].means - exact.means).mean()
    assert smoothed_gap < 0.4 * filtered_gap


def test_backward_simulation_draws_whole_trajectories_from_the_filter_particles():
    """Every drawn state is one of that step's particles, and each step's draws follow the
    backward weights: a particle with zero filter weight is never drawn."""
    motion, sensors, prior, ms = _particle_problem(runs=1, steps=4)
    pf = BootstrapFilter(motion, sensors, n_particles=50)
    rng = np.random.default_rng(2)
    beliefs = [pf.initialize(prior, rng, batch_shape=(1,))]
    for m in ms[1:]:
        beliefs.append(pf.update(pf.predict(beliefs[-1], 1.0, rng), [m]))
    lw = beliefs[1].log_weights.copy()
    lw[..., :25] = -np.inf  # half the particles of step 1 impossible
    beliefs[1] = type(beliefs[1])(beliefs[1].states, lw)
    draws = backward_simulation(motion, beliefs, np.ones(3), rng, n_trajectories=200)
    assert draws.shape == (4, 1, 200, 2)
    for k, b in enumerate(beliefs):
        hit = np.all(draws[k][:, :, None, :] == b.states[:, None, :, :], axis=-1)
        assert np.all(hit.sum(axis=-1) >= 1)  # each draw is a particle of step k
    hit1 = np.all(draws[1][:, :, None, :] == beliefs[1].states[:, None, :, :], axis=-1)
    assert not hit1[..., :25].any()


class _CVThroughLogDensity(ConstantVelocity):
    """The same model with ``mean`` overridden: no ``fused_transition``, so the backward
    step goes through ``log_density`` instead of the whitened matrix product."""

    def mean(self, x, dt):
        return super().mean(x, dt)


def test_whitened_fast_path_draws_what_log_density_draws():
    motion, sensors, prior, ms = _particle_problem(runs=2, steps=6)
    slow = _CVThroughLogDensity(ndim=1, q=0.5)
    assert motion.fused_transition(1.0) is not None and slow.fused_transition(1.0) is None
    pf = BootstrapFilter(motion, sensors, n_particles=200)
    rng = np.random.default_rng(3)
    beliefs = [pf.update(pf.initialize(prior, rng, batch_shape=(2,)), [ms[0]])]
    for m in ms[1:]:
        beliefs.append(pf.update(pf.predict(beliefs[-1], 1.0, rng), [m]))
    fast = backward_simulation(motion, beliefs, np.ones(5), np.random.default_rng(4))
    ref = backward_simulation(slow, beliefs, np.ones(5), np.random.default_rng(4))
    np.testing.assert_array_equal(fast, ref)


def test_unreachable_successors_fall_back_to_the_filter_weights_with_a_warning():
    """Discrete (rank-1) process noise: the transition density is -inf off a line, so no
    particle of step 0 reaches the drawn state of step 1."""
    motion = ConstantVelocity(ndim=1, q=0.5, noise="discrete")
    rng = np.random.default_rng(5)
    beliefs = [Particles.uniform(rng.standard_normal((30, 2))) for _ in range(2)]
    with pytest.warns(DegenerateWeightsWarning, match="backward simulation"):
        draws = backward_simulation(motion, beliefs, [1.0], rng, n_trajectories=40)
    assert np.all(np.isfinite(draws))
    hit = np.all(draws[0][:, None, :] == beliefs[0].states[None, :, :], axis=-1)
    assert np.all(hit.sum(axis=-1) == 1)


# -- bad input --------------------------------------------------------------------------------


class _Identity:
    """A filter run_filter can run but nobody can smooth (no known backward kernel)."""

    calls = 0

    def predict(self, belief, dt, rng=None):
        _Identity.calls += 1
        return belief

    def update(self, belief, measurements, rng=None):
        _Identity.calls += 1
        return belief


def test_smoothing_an_unsupported_filter_fails_before_any_step():
    _, _, prior, ms = _particle_problem(runs=1, steps=3)
    _Identity.calls = 0
    with pytest.raises(ConfigError, match=r"smooth=True is invalid.*_Identity"):
        run_filter(_Identity(), prior, ms, smooth=True)
    assert _Identity.calls == 0
    run_filter(_Identity(), prior, ms)  # unsmoothed it runs
    assert _Identity.calls > 0


@pytest.mark.parametrize(
    ("kwargs", "text"),
    [
        ({"smooth": True, "lag": -1}, "lag=-1 is invalid"),
        ({"smooth": True, "lag": 1.5}, "lag=1.5 is invalid"),
        ({"smooth": False, "lag": 2}, "lag=2 is invalid: expected None unless smooth=True"),
        ({"smooth": "rts"}, "smooth='rts' is invalid"),
    ],
)
def test_bad_smoothing_options_raise_config_errors(kwargs, text):
    motion, sensors, prior, ms = _particle_problem(runs=1, steps=3)
    with pytest.raises(ConfigError, match=text):
        run_filter(KalmanFilter(motion, sensors), prior, ms, **kwargs)


def test_particle_smoothing_needs_one_generator():
    motion, sensors, prior, ms = _particle_problem(runs=2, steps=3)
    pf = BootstrapFilter(motion, sensors, n_particles=10)
    gens = [np.random.default_rng(i) for i in range(2)]
    with pytest.raises(ConfigError, match=r"rng=.*one numpy Generator"):
        run_filter(pf, prior, ms, smooth=True, rng=gens)  # type: ignore[arg-type]


def test_smoother_functions_check_their_inputs():
    motion, sensors, _, _ = _particle_problem()
    kf = KalmanFilter(motion, sensors)
    means, covs = np.zeros((3, 2)), np.tile(np.eye(2), (3, 1, 1))
    with pytest.raises(ShapeError, match=r"dts.shape"):
        rts_smoother(kf, means, covs, [1.0])
    with pytest.raises(ConfigError, match="dts="):
        rts_smoother(kf, means, covs, [1.0, -1.0])
    with pytest.raises(ShapeError, match=r"means.shape, covs.shape"):
        rts_smoother(kf, means, covs[:, :1], [1.0, 1.0])
    with pytest.raises(ConfigError, match="filt="):
        rts_smoother(_Identity(), means, covs, [1.0, 1.0])  # type: ignore[arg-type]
    pf = BootstrapFilter(motion, sensors, n_particles=5)
    rng = np.random.default_rng(0)
    parts = [pf.initialize(Gaussian(np.zeros(2), np.eye(2)), rng) for _ in range(3)]
    with pytest.raises(ConfigError, match="n_trajectories=0"):
        backward_simulation(motion, parts, [1.0, 1.0], rng, n_trajectories=0)
    with pytest.raises(ConfigError, match=r"dts=.*> 0"):
        backward_simulation(motion, parts, [1.0, 0.0], rng)
    with pytest.raises(ConfigError, match="lag=-2"):
        backward_simulation(motion, parts, [1.0, 1.0], rng, lag=-2)
    with pytest.raises(ConfigError, match="particles="):
        backward_simulation(motion, [Gaussian(means, covs)], [], rng)  # type: ignore[list-item]
