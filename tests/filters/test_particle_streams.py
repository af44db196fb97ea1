"""The particle engine's fast paths of issues 2/3 equal their NumPy references: process noise
from fixed child streams drawn inside the fused loop, the atan2-free bearing residual, the
one-pass normalisation with the weighted mean, the division-free systematic merge."""

from __future__ import annotations

import numba
import numpy as np
import pytest

from fusetrack.core import Gaussian, Measurement
from fusetrack.core.resampling import inverse_cdf_reference, systematic_from_uniforms
from fusetrack.filters import BootstrapFilter, fused, kernels
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import Bearing, RangeBearing


@numba.njit
def _abs_angles(s, c, out):  # pragma: no cover - jit
    for i in range(s.shape[0]):
        out[i] = fused._abs_angle(s[i], c[i])


def test_abs_angle_is_abs_atan2_to_one_ulp():
    rng = np.random.default_rng(0)
    s = rng.standard_normal(200_000) * np.exp(rng.uniform(-40, 40, 200_000))
    c = rng.standard_normal(200_000) * np.exp(rng.uniform(-40, 40, 200_000))
    edges = [(0.0, 0.0), (0.0, -1.0), (0.0, 1.0), (1.0, 0.0), (-1.0, 0.0), (1e-300, -1.0)]
    edges += [(1.0, 1.0), (1.0, -1.0), (0.66, 1.0), (1.0, 0.66), (3.0, -1e-12), (-2.0, -2.0)]
    s = np.concatenate([s, [e[0] for e in edges]])
    c = np.concatenate([c, [e[1] for e in edges]])
    got = np.empty_like(s)
    _abs_angles(s, c, got)
    ref = np.abs(np.arctan2(s, c))
    assert np.all(np.abs(got - ref) <= np.spacing(np.maximum(ref, 1e-300)))
    assert got[-len(edges) :][:3].tolist() == [0.0, np.pi, 0.0]


def test_bearing_residual_across_the_cut_and_at_the_sensor():
    """``wrap(z - wrap(atan2 - h))`` near +-pi, with a heading, and a particle on the sensor."""
    b = Bearing("b", position=[1.0, -2.0], sigma=0.1, heading=2.9)
    rb = RangeBearing("rb", position=[1.0, -2.0], sigma_range=0.5, sigma_bearing=0.1, heading=-3)
    x = np.array([[1.0, -2.0, 0.0, 0.0], [-5.0, -2.0 + 1e-12, 0, 0], [-5.0, -2.0 - 1e-12, 0, 0]])
    x = np.concatenate([x, np.random.default_rng(1).normal(0, 5, (50, 4))])[None]
    for sensor, z in ((b, [np.pi - 1e-9]), (b, [-3.0]), (rb, [4.0, 3.1]), (rb, [0.5, -3.1])):
        kind, spec = (
            fused.KINDS[sensor.fused_likelihood()[0]],
            fused.sensor_params(*sensor.fused_likelihood()),
        )
        zz = np.zeros((1, 1, 2))
        zz[0, 0, : len(z)] = z
        got, _ = fused.log_likelihood_sum(
            x, np.zeros((1, x.shape[1])), np.array([kind]), spec[None], zz, np.ones((1, 1), bool)
        )
        np.testing.assert_allclose(got[0], sensor.log_likelihood(z, x[0]), rtol=1e-13, atol=1e-10)


@pytest.mark.parametrize("rows", [1, 3])
@pytest.mark.parametrize("gather", [False, True])
@pytest.mark.parametrize("n_streams", [1, 4])
def test_draw_inside_the_loop_equals_numpy_reference(rows, gather, n_streams):
    rng = np.random.default_rng(2)
    n = 1001
    cv = ConstantVelocity(ndim=2, q=0.4)
    F, G = cv.fused_transition(0.5)
    x = rng.normal(0, 30, (rows, n, 4))
    anc = np.sort(rng.integers(0, n, (rows, n)), axis=1) if gather else None

    def streams():
        return tuple(np.random.default_rng(10 + k) for k in range(n_streams))

    got = fused.linear_gaussian_draw(x, F, G, streams(), anc)
    src = x if anc is None else np.stack([x[r, anc[r]] for r in range(rows)])
    eps = fused.standard_normals(streams(), (rows, n, 4))
    np.testing.assert_allclose(got, src @ F.T + eps @ G.T, rtol=1e-13, atol=1e-12)
    if n_streams == 1:  # one stream: exactly what motion.sample draws
        np.testing.assert_array_equal(eps, np.random.default_rng(10).standard_normal((rows, n, 4)))


def test_noise_streams_do_not_depend_on_the_threads():
    cv = ConstantVelocity(ndim=2, q=0.4)
    F, G = cv.fused_transition(1.0)
    x = np.random.default_rng(3).normal(0, 30, (1, 5000, 4))
    before = numba.get_num_threads()
    outs = []
    try:
        for threads in (1, before):
            numba.set_num_threads(threads)
            ss = tuple(np.random.default_rng(7).spawn(fused.NOISE_STREAMS))
            outs.append(fused.linear_gaussian_draw(x, F, G, ss))
    finally:
        numba.set_num_threads(before)
    np.testing.assert_array_equal(outs[0], outs[1])


SENSORS = [
    Bearing("b0", position=[0.0, 0.0], sigma=0.05),
    Bearing("b1", position=[60.0, 0.0], sigma=0.05, heading=1.0),
]
PRIOR = Gaussian(np.array([20.0, 30.0, 1.0, 0.5]), np.diag([9.0, 9.0, 0.1, 0.1]))


def _run(engine, rng, n, steps=3, batch=()):
    f = BootstrapFilter(ConstantVelocity(q=0.1), SENSORS, n_particles=n, engine=engine)
    p = f.initialize(PRIOR, rng, batch_shape=batch)
    truth = PRIOR.mean.copy()
    meas_rng = np.random.default_rng(99)
    means = []
    for k in range(steps):
        truth = truth + np.array([truth[2], truth[3], 0.0, 0.0])
        ms = [Measurement(k, s.sensor_id, s.simulate(truth, meas_rng)) for s in SENSORS]
        p = f.update(f.predict(p, 1.0, rng), ms, rng)
        means.append(f.mean(p))
    return np.array(means), p


def test_split_noise_engines_agree_and_seeds_repeat():
    n = fused.SPLIT_MIN  # the noise comes from the child streams on both engines
    a, pa = _run("numba", np.random.default_rng(5), n)
    b, pb = _run("numpy", np.random.default_rng(5), n)
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-9)
    np.testing.assert_allclose(pa.states, pb.states, rtol=0, atol=1e-8)
    c, pc = _run("numba", np.random.default_rng(5), n)  # a fresh filter, the same seed
    np.testing.assert_array_equal(a, c)
    np.testing.assert_array_equal(pa.states, pc.states)


def test_split_noise_batch_is_bit_identical_to_separate_runs():
    n = fused.SPLIT_MIN
    seeds = [21, 22]
    batch, pb = _run("numba", [np.random.default_rng(s) for s in seeds], n, steps=2, batch=(2,))
    for r, s in enumerate(seeds):
        alone, p = _run("numba", np.random.default_rng(s), n, steps=2)
        np.testing.assert_array_equal(batch[:, r], alone)
        np.testing.assert_array_equal(pb.states[r], p.states)


def test_cached_mean_equals_weighted_mean():
    means, p = _run("numba", np.random.default_rng(8), 3000)
    f = BootstrapFilter(ConstantVelocity(q=0.1), SENSORS, n_particles=3000)
    fresh = kernels.weighted_mean_reference(p.states, f.weights(p))
    np.testing.assert_allclose(means[-1], fresh, rtol=1e-13, atol=1e-12)


@pytest.mark.parametrize("shape", [(1, 5), (3, 1000)])
def test_normalize_with_mean_equals_references(shape):
    rng = np.random.default_rng(9)
    v = rng.normal(-50, 30, shape)
    v[0, 0] = -np.inf
    x = rng.normal(0, 10, (*shape, 3))
    lw, w, lse, ess, mean = kernels.normalize_with_mean(v.copy(), v.max(axis=-1), x)
    r_lw, r_w, r_lse, r_ess = kernels.normalize_log_weights_reference(v)
    np.testing.assert_allclose(lw, r_lw, rtol=1e-14, atol=1e-12)
    np.testing.assert_allclose(w, r_w, rtol=1e-13, atol=1e-300)
    np.testing.assert_allclose(lse, r_lse, rtol=1e-14)
    np.testing.assert_allclose(ess, r_ess, rtol=1e-12)
    np.testing.assert_allclose(mean, kernels.weighted_mean_reference(x, r_w), rtol=1e-12)


def test_division_free_systematic_merge():
    rng = np.random.default_rng(10)
    w = rng.random((5, 777)) ** 4
    w[:, -30:] = 0.0  # trailing zero weights are never chosen, even for u0 just below 1
    u0 = np.array([0.0, 0.25, 0.5, 0.999, np.nextafter(1.0, 0.0)])
    idx = systematic_from_uniforms(w, u0)
    ref = inverse_cdf_reference(w, (np.arange(777) + u0[:, None]) / 777)
    np.testing.assert_array_equal(idx[:4], ref[:4])
    # the last u of the last row rounds to 1.0 in the reference, which then picks particle 776
    np.testing.assert_array_equal(idx[4, :-1], ref[4, :-1])
    assert idx.max() == 746 and np.all(w[np.arange(5)[:, None], idx] > 0)


def test_three_d_position_fix_and_range_in_the_fused_loop():
    from fusetrack.sensors import PositionFix, Range

    cov = np.array([[2.0, 0.3, 0.1], [0.3, 1.0, -0.2], [0.1, -0.2, 0.5]])
    sensors = [
        PositionFix("tag", cov=cov, bias=[0.1, 0.2, -0.3], position_index=(0, 1, 2)),
        Range("r", position=[1.0, 2.0, 3.0], sigma=0.4, position_index=(0, 1, 2)),
    ]
    rng = np.random.default_rng(11)
    x = rng.normal(0, 5, (2, 300, 6))
    z = np.array([[[1.0, 2.0, 0.5], [6.0, 0, 0]], [[-3.0, 0.0, 1.0], [2.5, 0, 0]]])
    specs = [s.fused_likelihood() for s in sensors]
    kinds = np.array([fused.KINDS[s[0]] for s in specs])
    params = np.stack([fused.sensor_params(*s) for s in specs])
    got, maxima = fused.log_likelihood_sum(
        x, np.zeros((2, 300)), kinds, params, z, np.ones((2, 2), bool)
    )
    ref = np.stack(
        [
            sum(s.log_likelihood(z[r, k, : s.dim], x[r]) for k, s in enumerate(sensors))
            for r in range(2)
        ]
    )
    np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(maxima[:, -1], ref.max(axis=1), rtol=1e-12)


def test_position_fix_takes_the_fused_path_and_matches_the_numpy_engine():
    from fusetrack.sensors import PositionFix

    sensors = [SENSORS[0], PositionFix("tag", cov=[[4.0, 1.0], [1.0, 2.0]], bias=[0.3, 0.0])]
    out = []
    for engine in ("numba", "numpy"):
        f = BootstrapFilter(ConstantVelocity(q=0.1), sensors, n_particles=2000, engine=engine)
        rng = np.random.default_rng(12)
        p = f.initialize(PRIOR, rng)
        for k in range(3):
            p = f.predict(p, 1.0, rng)
            ms = [Measurement(k, "b0", [0.98 + 0.01 * k]), Measurement(k, "tag", [21.0 + k, 31.0])]
            if engine == "numba":
                assert (
                    f._reweight_fused(p.states, f._weights(p), f._check_measurements(ms, ()))
                    is not None
                )
            p = f.update(p, ms, rng)
        out.append((f.mean(p), p.log_weights))
    np.testing.assert_allclose(out[0][0], out[1][0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(out[0][1], out[1][1], rtol=0, atol=1e-8)
