"""Particle filter measurement handling: subsets, sequences, bad values, degenerate steps."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from fusetrack.core import (
    ConfigError,
    DegenerateWeightsWarning,
    Gaussian,
    Measurement,
    MeasurementError,
    UnknownSensorError,
)
from fusetrack.filters import AuxiliaryParticleFilter, BootstrapFilter, RegularizedParticleFilter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import Bearing, PositionFix

MOTION = ConstantVelocity(ndim=2, q=0.1)
TAG = PositionFix("tag", cov=0.01 * np.eye(2))
DOA = Bearing("doa", position=[-10.0, 0.0], sigma=0.05)
PRIOR = Gaussian(np.zeros(4), np.diag([1.0, 1.0, 0.1, 0.1]))
FILTERS = [BootstrapFilter, AuxiliaryParticleFilter, RegularizedParticleFilter]


def _start(cls=BootstrapFilter, n=500, seed=0, **kw):
    pf = cls(MOTION, [TAG, DOA], n_particles=n, **kw)
    rng = np.random.default_rng(seed)
    return pf, pf.predict(pf.initialize(PRIOR, rng), 1.0, rng), rng


def test_sequence_in_one_update_equals_successive_updates():
    pf, p, _ = _start()
    m1, m2 = Measurement(1.0, "tag", [0.1, -0.2]), Measurement(1.0, "doa", [0.02])
    both = pf.update(p, [m1, m2])
    one_by_one = pf.update(pf.update(p, [m1]), m2)
    np.testing.assert_allclose(both.log_weights, one_by_one.log_weights, rtol=1e-12, atol=1e-10)
    only_doa = pf.update(p, [m2])  # any subset of the sensors
    assert not np.allclose(only_doa.log_weights, both.log_weights)


def test_update_weights_are_prior_times_likelihood():
    pf, p, _ = _start()
    z = np.array([0.3, -0.1])
    q = pf.update(p, [Measurement(1.0, "tag", z)])
    lw = p.log_weights + TAG.log_likelihood(z, p.states)  # log domain: some weights are ~e^-700
    lw -= np.logaddexp.reduce(lw)
    np.testing.assert_allclose(q.log_weights, lw, rtol=1e-12, atol=1e-11)
    np.testing.assert_allclose(q.weights.sum(), 1.0)
    np.testing.assert_allclose(pf.effective_sample_size(q), 1 / np.sum(q.weights**2), rtol=1e-10)


def test_measurement_covariance_overrides_the_sensor_noise():
    pf, p, _ = _start()
    cov = np.array([[0.5, 0.1], [0.1, 0.3]])
    got = pf.update(p, [Measurement(1.0, "tag", [0.2, 0.1], covariance=cov)])
    pf2 = BootstrapFilter(MOTION, [PositionFix("tag", cov=cov)], n_particles=500)
    want = pf2.update(p, [Measurement(1.0, "tag", [0.2, 0.1])])
    np.testing.assert_allclose(got.log_weights, want.log_weights, rtol=1e-10, atol=1e-10)


def test_batched_measurement_covariances():
    pf = BootstrapFilter(MOTION, [TAG], n_particles=200)
    rng = np.random.default_rng(1)
    p = pf.initialize(PRIOR, rng, batch_shape=(2,))
    covs = np.stack([np.eye(2) * 0.2, np.eye(2) * 0.7])
    z = np.array([[0.1, 0.2], [-0.3, 0.0]])
    got = pf.update(p, [Measurement(0.0, "tag", z, covariance=covs)])
    for r in range(2):
        ref = BootstrapFilter(MOTION, [PositionFix("tag", cov=covs[r])], n_particles=200)
        want = ref.update(p, [Measurement(0.0, "tag", z)])  # z (2, 2) broadcasts per run
        np.testing.assert_allclose(got.log_weights[r], want.log_weights[r], rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize("cls", FILTERS)
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_values_are_skipped_and_counted(cls, bad):
    pf, p, rng = _start(cls)
    q = pf.update(p, [Measurement(1.0, "tag", [bad, 0.0]), Measurement(1.0, "doa", [bad])], rng)
    assert pf.stats.skipped_measurements == 2
    np.testing.assert_array_equal(q.log_weights, p.log_weights)
    np.testing.assert_array_equal(q.states, p.states)


@pytest.mark.parametrize("cls", FILTERS)
def test_partly_bad_batch_skips_only_those_runs(cls):
    pf = cls(MOTION, [TAG, DOA], n_particles=300)
    rng = np.random.default_rng(2)
    p = pf.predict(pf.initialize(PRIOR, rng, batch_shape=(3,)), 1.0, rng)
    z = np.array([[0.1, 0.0], [np.nan, 0.0], [0.0, 0.1]])
    q = pf.update(p, [Measurement(1.0, "tag", z)], rng)
    assert pf.stats.skipped_measurements == 1
    assert not np.any(np.isnan(q.log_weights)) and not np.any(np.isnan(q.states))
    if cls is not AuxiliaryParticleFilter:  # the APF redraws every run's children
        np.testing.assert_array_equal(q.log_weights[1], p.log_weights[1])
    est = pf.estimate(q).mean
    assert np.all(np.isfinite(est))


def test_unknown_sensor_and_wrong_size():
    pf, p, _ = _start()
    with pytest.raises(UnknownSensorError, match=r"'nope'.*doa.*tag"):
        pf.update(p, [Measurement(1.0, "nope", [0.0])])
    with pytest.raises(MeasurementError, match="m=2"):
        pf.update(p, [Measurement(1.0, "tag", [0.0])])
    with pytest.raises(MeasurementError, match="batch axes"):
        pf.update(p, [Measurement(1.0, "tag", np.zeros((3, 2)))])  # 3 runs, particles have none


def test_configuration_errors_name_the_field():
    with pytest.raises(ConfigError, match="n_particles"):
        BootstrapFilter(MOTION, [TAG], n_particles=0)
    with pytest.raises(ConfigError, match="engine"):
        BootstrapFilter(MOTION, [TAG], engine="cuda")
    with pytest.raises(ConfigError, match="ess_threshold"):
        BootstrapFilter(MOTION, [TAG], ess_threshold=1.5)
    with pytest.raises(ConfigError, match="resampler"):
        BootstrapFilter(MOTION, [TAG], resampler="best")
    with pytest.raises(ConfigError, match="degenerate"):
        BootstrapFilter(MOTION, [TAG], degenerate="panic")
    with pytest.raises(ConfigError, match="temper_factor"):
        BootstrapFilter(MOTION, [TAG], temper_factor=1.0)


@pytest.mark.parametrize("cls", FILTERS)
def test_far_outlier_is_recovered_counted_and_warned_once(cls):
    pf, p, rng = _start(cls)
    far = Measurement(1.0, "tag", [1e4, -1e4])  # ~1e5 sigma outside the particle cloud
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        q = pf.update(p, [far], rng)
        q2 = pf.update(q, [far], rng)
    assert pf.stats.degenerate_steps == 2
    assert sum(issubclass(w.category, DegenerateWeightsWarning) for w in caught) == 1
    for r in (q, q2):
        assert np.all(np.isfinite(r.log_weights)) and np.all(np.isfinite(r.states))
        assert np.all(np.isfinite(pf.estimate(r).mean))
    if cls is BootstrapFilter:  # 'keep': the outlier is ignored
        np.testing.assert_array_equal(q.log_weights, p.log_weights)


def test_degenerate_measurement_among_good_ones_is_the_only_one_ignored():
    pf, p, _ = _start()
    good = Measurement(1.0, "doa", [0.01])
    with pytest.warns(DegenerateWeightsWarning):
        q = pf.update(p, [Measurement(1.0, "tag", [1e4, 1e4]), good])
    np.testing.assert_allclose(q.log_weights, pf.update(p, [good]).log_weights, rtol=1e-12)
    assert pf.stats.degenerate_steps == 1


def test_degenerate_run_in_a_batch_leaves_the_others_alone():
    pf = BootstrapFilter(MOTION, [TAG], n_particles=300)
    rng = np.random.default_rng(4)
    p = pf.initialize(PRIOR, rng, batch_shape=(3,))
    z = np.array([[0.1, 0.0], [1e4, 0.0], [0.0, 0.1]])
    with pytest.warns(DegenerateWeightsWarning):
        q = pf.update(p, [Measurement(0.0, "tag", z)])
    assert pf.stats.degenerate_steps == 1  # one step, however many runs
    np.testing.assert_array_equal(q.log_weights[1], p.log_weights[1])
    assert not np.allclose(q.log_weights[0], p.log_weights[0])


def test_inflate_policy_tempers_towards_the_outlier():
    pf, p, _ = _start(degenerate="inflate")
    with pytest.warns(DegenerateWeightsWarning, match="inflate"):
        q = pf.update(p, [Measurement(1.0, "tag", [60.0, 0.0])])
    assert pf.stats.degenerate_steps == 1
    assert np.all(np.isfinite(q.log_weights))
    assert pf.estimate(q).mean[0] > pf.estimate(p).mean[0] + 0.5  # pulled towards x = 60
    assert 1.0 <= float(pf.effective_sample_size(q)) < 500


class _Blind:
    """A sensor whose likelihood is zero everywhere (e.g. a target outside every particle's view)."""

    sensor_id = "blind"
    dim = 1
    angular = (False,)

    def log_likelihood(self, z, x):
        return np.full(np.broadcast_shapes(np.shape(z)[:-1], np.shape(x)[:-1]), -np.inf)


@pytest.mark.parametrize("policy", ["keep", "inflate"])
def test_all_minus_inf_likelihoods_keep_the_prior_weights(policy):
    pf = BootstrapFilter(MOTION, [_Blind()], n_particles=100, degenerate=policy)
    p = pf.initialize(PRIOR, np.random.default_rng(0))
    with pytest.warns(DegenerateWeightsWarning):
        q = pf.update(p, [Measurement(0.0, "blind", [1.0])])
    np.testing.assert_array_equal(q.log_weights, p.log_weights)
    assert pf.stats.degenerate_steps == 1


def test_resampling_follows_the_ess_threshold():
    pf, p, rng = _start(ess_threshold=0.0)
    q = pf.update(p, [Measurement(1.0, "tag", [0.5, 0.5])])
    pf.predict(q, 1.0, rng)
    assert pf.stats.resample_count == 0
    pf2, p2, rng2 = _start(ess_threshold=1.0)
    q2 = pf2.update(p2, [Measurement(1.0, "tag", [0.5, 0.5])])
    assert pf2.stats.resample_count == 0  # uniform weights (ESS = N) are never resampled
    r2 = pf2.predict(q2, 1.0, rng2)
    assert pf2.stats.resample_count == 1
    np.testing.assert_allclose(r2.log_weights, -np.log(500))
    pf2.predict(r2, 1.0, rng2)
    assert pf2.stats.resample_count == 1


def test_apf_without_resampling_equals_bootstrap():
    """With ess_threshold=0 the APF keeps its predicted children and its weights reduce to
    w p(z | x): the bootstrap filter's."""
    ms = [Measurement(1.0, "tag", [0.2, -0.1]), Measurement(1.0, "doa", [0.03])]
    out = []
    for cls in (BootstrapFilter, AuxiliaryParticleFilter):
        pf = cls(MOTION, [TAG, DOA], n_particles=400, ess_threshold=0.0)
        rng = np.random.default_rng(8)
        p = pf.initialize(PRIOR, rng)
        for _ in range(3):
            p = pf.update(pf.predict(p, 1.0, rng), ms, rng)
        out.append(p)
    np.testing.assert_array_equal(out[0].states, out[1].states)
    np.testing.assert_allclose(out[0].log_weights, out[1].log_weights, rtol=1e-9, atol=1e-9)


def test_regularized_jitter_has_the_optimal_bandwidth():
    """After resampling, the copies spread by h_opt^2 times the weighted covariance."""
    pf = RegularizedParticleFilter(
        ConstantVelocity(ndim=1, q=0.0),
        [PositionFix("x", cov=[[1.0]], position_index=(0,))],
        n_particles=20000,
    )
    n, d = 20000, 2
    assert pf.bandwidth(n, d) == pytest.approx((4 / (n * (d + 2))) ** (1 / (d + 4)))
    rng = np.random.default_rng(5)
    p = pf.initialize(Gaussian(np.zeros(2), np.diag([4.0, 1.0])), rng)
    q = pf.update(p, [Measurement(0.0, "x", [1.0])])
    before = pf.estimate(q).cov
    r = pf.predict(q, 0.0, rng)  # dt = 0: no motion, so only resampling + jitter act
    h2 = pf.bandwidth(n, d) ** 2
    after = np.cov(r.states.T)
    np.testing.assert_allclose(after, before * (1 + h2), rtol=0.05, atol=0.01)
    plain = BootstrapFilter(pf.motion, pf.sensors, n_particles=n).predict(q, 0.0, rng)
    assert len(np.unique(plain.states[:, 0])) < 0.7 * n  # resampling alone leaves duplicates
    assert len(np.unique(r.states[:, 0])) == n  # the jitter removes them
