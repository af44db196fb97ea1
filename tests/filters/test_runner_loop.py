"""run_filter: irregular steps, grouping, ordering policies, output times, particle priors."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.core import ConfigError, Gaussian, Measurement, MeasurementError, Particles
from fusetrack.filters import FilterStats, KalmanFilter, UnscentedKalmanFilter, run_filter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import Bearing, PositionFix


def _kf():
    return KalmanFilter(
        ConstantVelocity(q=0.2),
        [
            PositionFix("tag", cov=0.3 * np.eye(2)),
            PositionFix("x", cov=[[0.1]], position_index=(0,)),
        ],
    )


PRIOR = Gaussian(np.array([0.0, 0.0, 1.0, 0.5]), np.eye(4))


def _measurements():
    rng = np.random.default_rng(30)
    return [
        Measurement(0.0, "tag", rng.standard_normal(2)),
        Measurement(0.3, "tag", rng.standard_normal(2)),
        Measurement(0.3, "x", rng.standard_normal(1)),  # same time: one step, two updates
        Measurement(1.7, "tag", rng.standard_normal(2)),
        Measurement(4.0, "x", rng.standard_normal(1)),
    ]


def test_irregular_steps_equal_a_hand_written_loop():
    kf = _kf()
    ms = _measurements()
    track = run_filter(kf, PRIOR, ms)
    np.testing.assert_array_equal(track.times, [0.0, 0.3, 1.7, 4.0])
    assert track.means.shape == (4, 4) and track.covariances.shape == (4, 4, 4)

    b = kf.update(PRIOR, ms[:1])  # the prior holds at the first time: no prediction
    expected = [b]
    b = kf.update(kf.predict(b, 0.3), ms[1:3])
    expected.append(b)
    b = kf.update(kf.predict(b, 1.4), ms[3:4])
    expected.append(b)
    b = kf.update(kf.predict(b, 2.3), ms[4:5])
    expected.append(b)
    for k, e in enumerate(expected):
        np.testing.assert_allclose(track.means[k], e.mean, atol=1e-12)
        np.testing.assert_allclose(track.covariances[k], e.cov, atol=1e-12)
    assert track.label == "KalmanFilter"


def test_t0_predicts_to_the_first_measurement():
    kf = _kf()
    ms = _measurements()
    track = run_filter(kf, PRIOR, ms, t0=-0.5)
    first = kf.update(kf.predict(PRIOR, 0.5), ms[:1])
    np.testing.assert_allclose(track.means[0], first.mean, atol=1e-12)
    with pytest.raises(MeasurementError, match="t0"):
        run_filter(kf, PRIOR, ms, t0=1.0)


def test_out_of_order_times_reject_or_reorder():
    kf = _kf()
    ms = _measurements()
    shuffled = [ms[3], ms[0], ms[4], ms[1], ms[2]]
    with pytest.raises(MeasurementError, match="reorder"):
        run_filter(kf, PRIOR, shuffled)
    with pytest.raises(MeasurementError):
        run_filter(kf, PRIOR, shuffled, order="reject")
    got = run_filter(kf, PRIOR, shuffled, order="reorder")
    ref = run_filter(kf, PRIOR, ms)
    np.testing.assert_array_equal(got.times, ref.times)
    np.testing.assert_allclose(got.means, ref.means, atol=1e-12)
    with pytest.raises(ConfigError, match="order"):
        run_filter(kf, PRIOR, ms, order="sort")


def test_output_times_add_predict_only_steps():
    kf = _kf()
    ms = _measurements()
    track = run_filter(kf, PRIOR, ms, times=[1.0, 0.3, 5.0, 1.0 + 1e-12, -1.0])
    np.testing.assert_allclose(track.times, [-1.0, 0.0, 0.3, 1.0, 1.7, 4.0, 5.0])
    ref = run_filter(kf, PRIOR, ms, t0=-1.0)
    # t=-1 is the prior itself; t=0 then predicts by 1 s before its update
    np.testing.assert_allclose(track.means[0], PRIOR.mean)
    after_03 = track.means[2], track.covariances[2]
    pred = kf.predict(Gaussian(*after_03), 0.7)
    np.testing.assert_allclose(track.means[3], pred.mean, atol=1e-12)
    np.testing.assert_allclose(track.covariances[3], pred.cov, atol=1e-12)
    # the predict-only step does not change later estimates (prediction composes: 0.7 + 0.7 = 1.4)
    np.testing.assert_allclose(track.means[4], ref.means[2], atol=1e-10)
    np.testing.assert_allclose(
        track.means[6], kf.predict(Gaussian(ref.means[3], ref.covariances[3]), 1.0).mean, atol=1e-12
    )


def test_predict_only_run_and_empty_run():
    kf = _kf()
    track = run_filter(kf, PRIOR, [], times=[0.0, 1.0, 2.5], t0=0.0)
    np.testing.assert_allclose(track.means[2], kf.predict(PRIOR, 2.5).mean, atol=1e-12)
    empty = run_filter(kf, PRIOR, [])
    assert len(empty) == 0 and empty.means.shape == (0, 4)


def test_tuples_are_accepted_and_skipped_measurements_reported():
    kf = _kf()
    track = run_filter(
        kf, PRIOR, [(0.0, "tag", [0.1, 0.2]), (1.0, "tag", [np.nan, 0.0]), (2.0, "x", [2.0])]
    )
    assert len(track) == 3
    assert track.info["stats"]["skipped_measurements"] == 1
    # the NaN step is a pure prediction
    pred = kf.predict(Gaussian(track.means[0], track.covariances[0]), 1.0)
    np.testing.assert_allclose(track.means[1], pred.mean, atol=1e-12)
    # counters are per run even when the filter object is reused
    again = run_filter(kf, PRIOR, [(0.0, "tag", [np.nan, 0.0])])
    assert again.info["stats"]["skipped_measurements"] == 1
    assert kf.stats.skipped_measurements == 2


def test_batched_measurements_give_a_batched_track():
    rng = np.random.default_rng(31)
    ukf = UnscentedKalmanFilter(
        ConstantVelocity(q=0.1),
        [Bearing("m0", position=[0.0, 0.0], sigma=0.02), Bearing("m1", [10.0, 0.0], sigma=0.02)],
    )
    prior = Gaussian(np.array([5.0, 5.0, 0.0, 0.0]), np.eye(4))
    runs = 5
    ms = []
    for k in range(6):
        ms.append(Measurement(0.5 * k, "m0", rng.uniform(0.6, 0.9, (runs, 1))))
        ms.append(Measurement(0.5 * k, "m1", rng.uniform(2.2, 2.5, (runs, 1))))
    track = run_filter(ukf, prior, ms, times=[4.0])
    assert track.means.shape == (7, runs, 4)
    assert track.covariances.shape == (7, runs, 4, 4)
    for r in (0, 3):
        ms_r = [Measurement(m.time, m.sensor_id, m.value[r]) for m in ms]
        one = run_filter(ukf, prior, ms_r, times=[4.0])
        np.testing.assert_allclose(track.means[:, r], one.means, atol=1e-11)
        np.testing.assert_allclose(track.covariances[:, r], one.covariances, atol=1e-11)


class _ToyParticleFilter:
    """A minimal particle filter (random-walk proposal, Gaussian fix) to check run_filter's
    handling of sampled beliefs; the library's particle filters are tested on their own."""

    def __init__(self, n=4000):
        self.n = n
        self.stats = FilterStats()
        self.init_calls = []

    def initialize(self, prior, rng, batch_shape=()):
        self.init_calls.append(tuple(batch_shape))
        p = prior
        if batch_shape:
            d = prior.dim
            p = Gaussian(
                np.broadcast_to(prior.mean, (*batch_shape, d)),
                np.broadcast_to(prior.cov, (*batch_shape, d, d)),
            )
        return Particles.from_gaussian(p, self.n, rng)

    def predict(self, particles, dt, rng):
        x = particles.states + np.sqrt(dt) * rng.standard_normal(particles.states.shape)
        return Particles(x, particles.log_weights)

    def update(self, particles, measurements, rng):
        lw = particles.log_weights
        for m in measurements:
            z = np.asarray(m.value)[..., None, :]
            lw = lw - 0.5 * np.sum((particles.states - z) ** 2, axis=-1)
        p = Particles(particles.states, lw).normalized()
        self.stats.resample_count += 1
        return p.resample(rng)


def test_particle_filters_get_particles_from_a_gaussian_prior():
    pf = _ToyParticleFilter()
    prior = Gaussian(np.zeros(2), np.eye(2))
    ms = [Measurement(t, "any", [t, -t]) for t in (0.0, 1.0, 2.0)]
    with pytest.raises(ConfigError, match="rng"):
        run_filter(pf, prior, ms)
    track = run_filter(pf, prior, ms, rng=np.random.default_rng(0))
    assert pf.init_calls == [()]
    assert track.means.shape == (3, 2) and track.info["stats"]["resample_count"] == 3
    # equals the Kalman answer for this linear-Gaussian toy (variances 0.5, 0.6, 8/13 after
    # each update; final mean 0.6 + (1.6 / 2.6) * 1.4), up to Monte Carlo error
    kalman = 0.6 + 1.6 / 2.6 * 1.4
    assert np.all(np.abs(track.means[-1] - [kalman, -kalman]) < 0.05)
    np.testing.assert_allclose(np.diag(track.covariances[-1]), 1.6 / 2.6, rtol=0.1)
    again = run_filter(pf, prior, ms, rng=np.random.default_rng(0))
    np.testing.assert_array_equal(again.means, track.means)  # a seed reproduces a run

    batched = [Measurement(m.time, m.sensor_id, np.tile(m.value, (3, 1))) for m in ms]
    bt = run_filter(pf, prior, batched, rng=np.random.default_rng(1))
    assert pf.init_calls[-1] == (3,) and bt.means.shape == (3, 3, 2)

    # a particle prior is used as is
    start = Particles.from_gaussian(prior, 100, np.random.default_rng(2))
    pt = run_filter(pf, start, ms, rng=np.random.default_rng(3))
    assert len(pf.init_calls) == 3 and pt.means.shape == (3, 2)


def test_bad_times_raise():
    with pytest.raises(ConfigError, match="times"):
        run_filter(_kf(), PRIOR, _measurements(), times=[0.0, np.nan])
