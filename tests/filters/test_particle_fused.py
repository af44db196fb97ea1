"""The fused fast paths of the particle filters equal their NumPy references (issue 3)."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.core import Gaussian, Measurement
from fusetrack.filters import BootstrapFilter, fused
from fusetrack.motion import ConstantAcceleration, ConstantVelocity
from fusetrack.motion._common import psd_factor
from fusetrack.sensors import Bearing, PositionFix, Range, RangeBearing

SENSORS = [
    Bearing("b0", position=[0.0, 0.0], sigma=0.02),
    Bearing("b1", position=[40.0, 0.0], sigma=0.05, heading=2.5),
    Range("r2", position=[10.0, 30.0], sigma=0.7),
    RangeBearing("rb", position=[-5.0, 5.0], sigma_range=0.4, sigma_bearing=0.03, heading=-1.0),
    PositionFix("tag", cov=[[2.0, 0.6], [0.6, 1.0]], bias=[0.5, -0.25]),
    PositionFix("x_only", cov=[[0.3]], position_index=(0,)),
]


def _spec(sensor):
    s = sensor.fused_likelihood()
    return fused.KINDS[s[0]], fused.sensor_params(*s)


@pytest.mark.parametrize("n", [1000, fused.PARALLEL_MIN + 7])
@pytest.mark.parametrize("gather", [False, True])
def test_linear_gaussian_step_equals_numpy(n, gather):
    rng = np.random.default_rng(1)
    cv = ConstantVelocity(ndim=2, q=0.3)
    F, G = cv.fused_transition(0.7)
    np.testing.assert_array_equal(F, cv.transition_matrix(0.7))
    np.testing.assert_allclose(G @ G.T, cv.noise_cov(0.7), atol=1e-15)
    x = rng.normal(0, 50, (2, n, 4))
    eps = rng.standard_normal((2, n, 4))
    anc = np.sort(rng.integers(0, n, (2, n)), axis=1) if gather else None
    got = fused.linear_gaussian_step(x, F, G, eps, anc)
    src = x if anc is None else np.stack([x[r, anc[r]] for r in range(2)])
    np.testing.assert_allclose(got, src @ F.T + eps @ G.T, rtol=1e-13, atol=1e-12)


def test_fused_transition_matches_sample_draws():
    ca = ConstantAcceleration(ndim=3, q=0.1)
    F, G = ca.fused_transition(0.5)
    np.testing.assert_array_equal(G, psd_factor(ca.noise_cov(0.5)))
    x = np.random.default_rng(2).normal(size=(100, 9))
    ref = ca.sample(x, 0.5, np.random.default_rng(3))
    eps = np.random.default_rng(3).standard_normal((1, 100, 9))
    np.testing.assert_allclose(fused.linear_gaussian_step(x[None], F, G, eps)[0], ref, atol=1e-12)


def test_models_that_change_the_maths_have_no_fused_form():
    class Shifted(ConstantVelocity):
        def mean(self, x, dt):
            return super().mean(x, dt) + 1.0

    class Biased(Bearing):
        def predict(self, x):
            return super().predict(x) + 0.1

    assert Shifted().fused_transition(1.0) is None
    assert Biased("b", position=[0.0, 0.0], sigma=0.1).fused_likelihood() is None

    class Shifted2(PositionFix):
        def predict(self, x):
            return super().predict(x) + 1.0

    assert Shifted2("gps", cov=[[1.0, 0.2], [0.2, 1.0]]).fused_likelihood() is None
    assert all(s.fused_likelihood() is not None for s in SENSORS)


@pytest.mark.parametrize("n", [777, fused.PARALLEL_MIN + 3])
def test_log_likelihood_sum_equals_sensor_log_likelihoods(n):
    rng = np.random.default_rng(4)
    rows = 2
    x = np.concatenate([rng.normal(0, 40, (rows, n, 2)), rng.normal(0, 1, (rows, n, 2))], -1)
    x[0, :5, :2] = [[-30.0, 1e-9], [-30.0, -1e-9], [-5.0, 5.0], [0.0, 0.0], [40.0, 0.0]]
    # bearings near +-pi for b0 (the branch cut), one run's values, one run's own values
    z = np.zeros((rows, len(SENSORS), 2))
    z[:, 0, 0] = [np.pi - 1e-3, -np.pi + 1e-3]
    z[:, 1, 0] = [0.3, -2.0]
    z[:, 2, 0] = [25.0, 31.0]
    z[:, 3, :] = [[12.0, 3.1], [20.0, -3.1]]
    z[:, 4, :] = [[3.0, -4.0], [10.0, 2.0]]
    z[:, 5, 0] = [1.0, -20.0]
    usable = np.array([[True] * 6, [True, False, True, True, False, True]])
    lw = np.log(rng.dirichlet(np.ones(n), size=rows))
    specs = [_spec(s) for s in SENSORS]
    kinds = np.array([k for k, _ in specs])
    params = np.stack([p for _, p in specs])
    got, maxima = fused.log_likelihood_sum(x, lw, kinds, params, z, usable)
    acc = lw.copy()
    for k, s in enumerate(SENSORS):
        for r in range(rows):
            if usable[r, k]:
                acc[r] += s.log_likelihood(z[r, k, : s.dim], x[r])
        np.testing.assert_allclose(maxima[:, k], acc.max(axis=1), rtol=1e-12)
    np.testing.assert_allclose(got, acc, rtol=1e-11, atol=1e-9)


def _scenario_run(engine, rngs, batch=(), n=500, steps=8, **kw):
    sensors = SENSORS[:3]
    filt = BootstrapFilter(ConstantVelocity(q=0.2), sensors, n_particles=n, engine=engine, **kw)
    prior = Gaussian(np.array([10.0, 12.0, 1.0, -0.5]), np.diag([4.0, 4.0, 0.2, 0.2]))
    p = filt.initialize(prior, rngs, batch_shape=batch)
    truth = np.array([10.0, 12.0, 1.0, -0.5])
    meas_rng = np.random.default_rng(99)
    means = []
    for k in range(steps):
        truth = truth + np.array([truth[2], truth[3], 0.0, 0.0])
        ms = [Measurement(k, s.sensor_id, s.simulate(truth, meas_rng)) for s in sensors]
        p = filt.update(filt.predict(p, 1.0, rngs), ms, rngs)
        means.append(filt.mean(p))
    return np.array(means), p, filt


def test_bootstrap_fused_engine_equals_numpy_engine():
    a, pa, fa = _scenario_run("numba", np.random.default_rng(5))
    b, pb, fb = _scenario_run("numpy", np.random.default_rng(5))
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-9)
    np.testing.assert_allclose(pa.states, pb.states, rtol=0, atol=1e-9)
    np.testing.assert_allclose(pa.log_weights, pb.log_weights, rtol=0, atol=1e-8)
    assert fa.stats.resample_count == fb.stats.resample_count == 7  # not before step 1


def test_bootstrap_fused_partial_resampling_equals_numpy_engine():
    a, pa, _ = _scenario_run("numba", np.random.default_rng(6), ess_threshold=0.5)
    b, pb, _ = _scenario_run("numpy", np.random.default_rng(6), ess_threshold=0.5)
    np.testing.assert_allclose(pa.states, pb.states, rtol=0, atol=1e-9)
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-9)


def test_batched_runs_bit_identical_to_separate_runs_on_the_fused_path():
    runs, n = 3, fused.PARALLEL_MIN // 2  # the batch takes the threaded loops, a run alone not
    seeds = [11, 12, 13]
    batch_means, pb, _ = _scenario_run(
        "numba", [np.random.default_rng(s) for s in seeds], batch=(runs,), n=n, steps=4
    )
    for r, s in enumerate(seeds):
        m, p, _ = _scenario_run("numba", [np.random.default_rng(s)], batch=(1,), n=n, steps=4)
        np.testing.assert_array_equal(batch_means[:, r], m[:, 0])
        np.testing.assert_array_equal(pb.states[r], p.states[0])
        np.testing.assert_array_equal(pb.log_weights[r], p.log_weights[0])


def test_measurement_covariance_takes_the_generic_path():
    sensors = SENSORS[:1]
    prior = Gaussian(np.array([10.0, 12.0, 1.0, -0.5]), np.diag([4.0, 4.0, 0.2, 0.2]))
    out = []
    for engine in ("numba", "numpy"):
        f = BootstrapFilter(ConstantVelocity(q=0.2), sensors, n_particles=300, engine=engine)
        rng = np.random.default_rng(7)
        p = f.initialize(prior, rng)
        p = f.predict(p, 1.0, rng)
        p = f.update(p, [Measurement(1.0, "b0", [0.9], covariance=[[0.01]])])
        out.append(p.log_weights)
    np.testing.assert_allclose(out[0], out[1], atol=1e-10)


def test_degenerate_measurement_falls_back_to_the_exact_update():
    f = BootstrapFilter(ConstantVelocity(q=0.01), [Range("r", position=[0.0, 0.0], sigma=0.01)])
    rng = np.random.default_rng(8)
    p = f.initialize(Gaussian(np.array([10.0, 0.0, 0.0, 0.0]), np.eye(4) * 0.01), rng)
    p = f.predict(p, 1.0, rng)
    with pytest.warns(Warning):
        q = f.update(p, [Measurement(1.0, "r", [1000.0])])
    assert f.stats.degenerate_steps == 1
    np.testing.assert_array_equal(q.log_weights, p.log_weights)
