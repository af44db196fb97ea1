"""Batched runs, per-run generators and engines: what must be identical is identical."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.core import ConfigError, Gaussian, Measurement, Particles
from fusetrack.filters import AuxiliaryParticleFilter, BootstrapFilter, RegularizedParticleFilter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import Bearing, PositionFix

MOTION = ConstantVelocity(ndim=2, q=0.05)
BEARINGS = [
    Bearing(f"s{i}", position=p, sigma=0.02) for i, p in enumerate([[0, 0], [400, 0], [200, 350]])
]
PRIOR = Gaussian(np.array([150.0, 100.0, 1.5, 1.0]), np.diag([400.0, 400.0, 1.0, 1.0]))
FILTERS = [BootstrapFilter, AuxiliaryParticleFilter, RegularizedParticleFilter]
SEEDS = (11, 22, 33)


def _measurements(runs: int, steps: int, seed: int = 5) -> list[list[Measurement]]:
    """``steps`` lists of bearing measurements with values ``(runs, 1)`` (one truth per run)."""
    rng = np.random.default_rng(seed)
    x = np.broadcast_to(PRIOR.mean, (runs, 4)).copy()
    out = []
    for k in range(1, steps + 1):
        x = MOTION.sample(x, 1.0, rng)
        ms = [Measurement(float(k), s.sensor_id, s.simulate(x, rng)) for s in BEARINGS]
        out.append(ms[: 1 + k % 3])  # a different subset of sensors at each step
    return out


def _row(ms: list[Measurement], r: int) -> list[Measurement]:
    return [Measurement(m.time, m.sensor_id, m.value[r]) for m in ms]


def _run(pf, rng, steps, batch_shape=()):
    p = pf.initialize(PRIOR, rng, batch_shape=batch_shape)
    for ms in steps:
        p = pf.update(pf.predict(p, 1.0, rng), ms, rng)
    return p


@pytest.mark.parametrize("engine", ["numba", "numpy"])
@pytest.mark.parametrize("cls", FILTERS)
def test_batch_with_one_generator_per_run_is_bit_identical_to_separate_runs(cls, engine):
    steps = _measurements(len(SEEDS), 5)
    kw = {"n_particles": 300, "engine": engine, "ess_threshold": 0.7}
    batch_pf = cls(MOTION, BEARINGS, **kw)
    gens = [np.random.default_rng(s) for s in SEEDS]
    batch = _run(batch_pf, gens, steps, batch_shape=(len(SEEDS),))
    est = batch_pf.estimate(batch)
    for r, seed in enumerate(SEEDS):
        pf = cls(MOTION, BEARINGS, **kw)
        single = _run(pf, np.random.default_rng(seed), [_row(ms, r) for ms in steps])
        np.testing.assert_array_equal(batch.states[r], single.states)
        np.testing.assert_array_equal(batch.log_weights[r], single.log_weights)
        np.testing.assert_array_equal(est.mean[r], pf.estimate(single).mean)
        np.testing.assert_array_equal(est.cov[r], pf.estimate(single).cov)


@pytest.mark.parametrize("cls", FILTERS)
def test_engines_agree(cls):
    steps = _measurements(1, 8)
    steps = [_row(ms, 0) for ms in steps]
    out = {}
    for engine in ("numba", "numpy"):
        pf = cls(MOTION, BEARINGS, n_particles=2000, engine=engine, ess_threshold=0.5)
        p = _run(pf, np.random.default_rng(9), steps)
        out[engine] = (p, pf.estimate(p), pf.stats.as_dict())
    (pa, ea, sa), (pb, eb, sb) = out["numba"], out["numpy"]
    assert sa == sb
    np.testing.assert_allclose(pa.states, pb.states, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(pa.log_weights, pb.log_weights, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(ea.mean, eb.mean, rtol=1e-12)
    np.testing.assert_allclose(ea.cov, eb.cov, rtol=1e-10)


def test_one_generator_batch_agrees_statistically_with_separate_runs():
    """With a single generator the batch draws differ from separate runs, but each run is a
    correct filter: the spread of the batch estimates matches that of separate runs."""
    steps = _measurements(1, 4)
    steps = [_row(ms, 0) for ms in steps]
    runs = 40
    pf = BootstrapFilter(MOTION, BEARINGS, n_particles=400)
    batch = pf.estimate(_run(pf, np.random.default_rng(0), steps, batch_shape=(runs,))).mean
    singles = np.array(
        [pf.estimate(_run(pf, np.random.default_rng(1000 + r), steps)).mean for r in range(runs)]
    )
    assert batch.shape == singles.shape == (runs, 4)
    se = np.sqrt(batch.var(axis=0) / runs + singles.var(axis=0) / runs)
    assert np.all(np.abs(batch.mean(axis=0) - singles.mean(axis=0)) < 4 * se)
    ratio = batch.std(axis=0) / singles.std(axis=0)
    assert np.all((ratio > 0.5) & (ratio < 2.0)), ratio


def test_batched_prior_and_multi_axis_batch():
    prior = Gaussian(np.stack([PRIOR.mean, PRIOR.mean + 10.0]), np.stack([PRIOR.cov, PRIOR.cov]))
    pf = BootstrapFilter(MOTION, BEARINGS, n_particles=50)
    p = pf.initialize(prior, np.random.default_rng(0))
    assert p.states.shape == (2, 50, 4)
    p = pf.initialize(PRIOR, np.random.default_rng(0), batch_shape=(2, 3))
    assert p.states.shape == (2, 3, 50, 4)
    z = np.full((2, 3, 1), 0.6)
    z[1, 2] = np.nan
    p2 = pf.update(pf.predict(p, 1.0, np.random.default_rng(1)), [Measurement(1.0, "s0", z)])
    assert pf.stats.skipped_measurements == 1
    assert p2.log_weights.shape == (2, 3, 50)
    np.testing.assert_allclose(
        p2.log_weights[1, 2], -np.log(50)
    )  # the skipped run kept its weights
    assert pf.estimate(p2).mean.shape == (2, 3, 4)
    assert pf.effective_sample_size(p2).shape == (2, 3)


def test_rng_is_required_and_checked():
    pf = BootstrapFilter(MOTION, BEARINGS, n_particles=10)
    p = pf.initialize(PRIOR, np.random.default_rng(0), batch_shape=(2,))
    with pytest.raises(ConfigError, match="rng"):
        pf.predict(p, 1.0, None)
    with pytest.raises(ConfigError, match="2 of them"):
        pf.predict(p, 1.0, [np.random.default_rng(0)])
    with pytest.raises(ConfigError, match="rng"):
        pf.predict(p, 1.0, 42)


def test_uncached_particles_are_normalised_first():
    """Particles built by hand (unnormalised log-weights, no cache) work like the filter's own."""
    pf = BootstrapFilter(MOTION, [PositionFix("tag", cov=np.eye(2))], n_particles=4)
    states = np.array([[0.0, 0, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0], [5, 5, 0, 0]])
    p = Particles(states, np.log([1.0, 2.0, 3.0, 4.0]) + 100.0)
    np.testing.assert_allclose(pf.weights(p), [0.1, 0.2, 0.3, 0.4])
    q = pf.update(p, [Measurement(0.0, "tag", [0.0, 0.0])])
    ll = -0.5 * np.sum(states[:, :2] ** 2, axis=1)
    w = np.array([0.1, 0.2, 0.3, 0.4]) * np.exp(ll)
    np.testing.assert_allclose(q.weights, w / w.sum(), rtol=1e-12)
    np.testing.assert_allclose(pf.weights(q), q.weights, rtol=1e-12)
