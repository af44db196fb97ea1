"""Batched runs, skipped measurements and the errors of bad measurements."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.core import Gaussian, Measurement, MeasurementError, UnknownSensorError
from fusetrack.filters import (
    ExtendedKalmanFilter,
    FilterStats,
    KalmanFilter,
    UnscentedKalmanFilter,
    as_sensor_map,
    validate_measurement,
)
from fusetrack.motion import ConstantVelocity, CoordinatedTurnRate
from fusetrack.sensors import Bearing, PositionFix, RangeBearing

R_RUNS = 6


def _batch_prior(rng, d=4):
    mean = rng.standard_normal((R_RUNS, d)) * 3 + np.r_[8.0, 6.0, np.zeros(d - 2)]
    a = rng.standard_normal((R_RUNS, d, d))
    cov = a @ np.swapaxes(a, -1, -2) / d + 0.3 * np.eye(d)
    return Gaussian(mean, cov)


def _sensors():
    return [
        RangeBearing("radar", position=[0.0, 0.0], sigma_range=0.4, sigma_bearing=0.03),
        Bearing("mic", position=[12.0, -3.0], sigma=0.05, heading=1.0),
        PositionFix("tag", cov=[[0.5, 0.2], [0.2, 0.4]]),
    ]


@pytest.mark.parametrize("cls", [KalmanFilter, ExtendedKalmanFilter, UnscentedKalmanFilter])
def test_batched_step_equals_per_run_steps(cls):
    rng = np.random.default_rng(10)
    filt = cls(ConstantVelocity(q=0.2), _sensors())
    prior = _batch_prior(rng)
    ms = [
        Measurement(1.0, "radar", np.c_[rng.uniform(8, 12, R_RUNS), rng.uniform(0.4, 0.9, R_RUNS)]),
        Measurement(1.0, "mic", rng.uniform(0.5, 1.5, (R_RUNS, 1))),
        Measurement(
            1.0,
            "tag",
            rng.standard_normal((R_RUNS, 2)) + np.array([8.0, 6.0]),
            covariance=np.stack([np.eye(2) * (0.1 + r) for r in range(R_RUNS)]),
        ),
        Measurement(1.0, "tag", [8.0, 6.5]),  # one value shared by every run
    ]
    batched = filt.update(filt.predict(prior, 0.8), ms)
    _, ll_batched = filt.update_with_likelihood(filt.predict(prior, 0.8), ms)
    assert batched.mean.shape == (R_RUNS, 4) and batched.cov.shape == (R_RUNS, 4, 4)
    for r in range(R_RUNS):
        one = Gaussian(prior.mean[r], prior.cov[r])
        ms_r = [
            Measurement(
                m.time,
                m.sensor_id,
                m.value[r] if m.value.ndim == 2 else m.value,
                None if m.covariance is None else m.covariance[r],
            )
            for m in ms
        ]
        post, ll = filt.update_with_likelihood(filt.predict(one, 0.8), ms_r)
        np.testing.assert_allclose(batched.mean[r], post.mean, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(batched.cov[r], post.cov, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(ll_batched[r], ll, rtol=1e-12)


def test_batched_nonlinear_motion():
    rng = np.random.default_rng(11)
    motion = CoordinatedTurnRate(q=0.1, q_omega=0.01)
    mean = np.c_[
        rng.uniform(5, 10, (R_RUNS, 2)),
        rng.standard_normal((R_RUNS, 2)),
        rng.uniform(-0.3, 0.3, R_RUNS),
    ]
    prior = Gaussian(mean, np.broadcast_to(np.diag([0.5, 0.5, 0.1, 0.1, 0.01]), (R_RUNS, 5, 5)))
    for cls in (ExtendedKalmanFilter, UnscentedKalmanFilter):
        filt = cls(motion, [])
        batched = filt.predict(prior, 1.3)
        for r in range(R_RUNS):
            one = filt.predict(Gaussian(prior.mean[r], prior.cov[r]), 1.3)
            np.testing.assert_allclose(batched.mean[r], one.mean, atol=1e-12)
            np.testing.assert_allclose(batched.cov[r], one.cov, atol=1e-12)


def test_unbatched_prior_broadcasts_against_batched_values():
    kf = KalmanFilter(ConstantVelocity(), [PositionFix("tag", cov=np.eye(2))])
    prior = Gaussian(np.zeros(4), np.eye(4))
    z = np.array([[1.0, 0.0], [0.0, 1.0], [2.0, 2.0]])
    post = kf.update(prior, [Measurement(0.0, "tag", z)])
    assert post.mean.shape == (3, 4) and post.cov.shape == (3, 4, 4)
    np.testing.assert_allclose(post.mean[2, :2], [1.0, 1.0])


@pytest.mark.parametrize("cls", [KalmanFilter, ExtendedKalmanFilter, UnscentedKalmanFilter])
def test_nan_measurement_is_skipped_and_counted(cls):
    filt = cls(ConstantVelocity(), _sensors())
    prior = Gaussian(np.array([5.0, 5.0, 0.0, 0.0]), np.eye(4))
    post = filt.update(
        prior, [Measurement(0.0, "radar", [np.nan, 0.3]), Measurement(0.0, "mic", [np.inf])]
    )
    np.testing.assert_array_equal(post.mean, prior.mean)
    np.testing.assert_array_equal(post.cov, prior.cov)
    assert filt.stats.skipped_measurements == 2
    assert filt.stats.degenerate_steps == 0


@pytest.mark.parametrize("cls", [KalmanFilter, UnscentedKalmanFilter])
def test_nan_rows_in_a_batch_leave_only_those_runs_unchanged(cls):
    rng = np.random.default_rng(12)
    filt = cls(ConstantVelocity(), _sensors())
    prior = _batch_prior(rng)
    z = np.c_[rng.uniform(8, 12, R_RUNS), rng.uniform(0.4, 0.9, R_RUNS)]
    bad = np.array([1, 4])
    z_nan = z.copy()
    z_nan[bad, 1] = np.nan
    post, ll = filt.update_with_likelihood(prior, [Measurement(0.0, "radar", z_nan)])
    full = filt.update(prior, [Measurement(0.0, "radar", z)])
    good = np.setdiff1d(np.arange(R_RUNS), bad)
    np.testing.assert_array_equal(post.mean[bad], prior.mean[bad])
    np.testing.assert_array_equal(post.cov[bad], prior.cov[bad])
    np.testing.assert_allclose(post.mean[good], full.mean[good], atol=1e-13)
    np.testing.assert_allclose(post.cov[good], full.cov[good], atol=1e-13)
    assert np.all(ll[bad] == 0) and np.all(np.isfinite(ll))
    assert filt.stats.skipped_measurements == 2


def test_unknown_sensor_raises_with_the_id_and_the_known_ids():
    kf = KalmanFilter(ConstantVelocity(), _sensors())
    prior = Gaussian(np.zeros(4), np.eye(4))
    with pytest.raises(UnknownSensorError) as err:
        kf.update(prior, [Measurement(3.0, "camera7", [1.0])])
    msg = str(err.value)
    assert "camera7" in msg
    for known in ("mic", "radar", "tag"):
        assert known in msg


def test_wrong_measurement_size_raises_naming_m():
    kf = KalmanFilter(ConstantVelocity(), _sensors())
    with pytest.raises(MeasurementError, match="m=2"):
        kf.update(Gaussian(np.zeros(4), np.eye(4)), [Measurement(0.0, "radar", [1.0, 2.0, 3.0])])


def test_validate_measurement_and_sensor_map():
    sensors = as_sensor_map(_sensors())
    assert sorted(sensors) == ["mic", "radar", "tag"]
    stats = FilterStats()
    v = validate_measurement(
        Measurement(0.0, "tag", [[1.0, 2.0], [np.nan, 0.0], [0.0, 0.0]]), sensors, stats
    )
    np.testing.assert_array_equal(v.usable, [True, False, True])
    assert v.sensor is sensors["tag"] and stats.skipped_measurements == 1
    assert stats.as_dict() == {
        "skipped_measurements": 1,
        "degenerate_steps": 0,
        "resample_count": 0,
    }
    stats.reset()
    assert stats.skipped_measurements == 0
    from fusetrack.core import ConfigError

    with pytest.raises(ConfigError, match="unique"):
        as_sensor_map([PositionFix("a", cov=np.eye(2)), PositionFix("a", cov=np.eye(2))])
    assert list(as_sensor_map({"alias": sensors["mic"]})) == ["alias"]


def test_singular_innovation_covariance_is_counted_not_fatal():
    """A noiseless fix of a perfectly known position: S = 0 (pseudo-inverse, counted)."""
    kf = KalmanFilter(ConstantVelocity(), [PositionFix("tag", cov=np.eye(2))])
    prior = Gaussian(np.zeros(4), np.diag([0.0, 0.0, 1.0, 1.0]))
    post = kf.update(prior, [Measurement(0.0, "tag", [0.0, 0.0], covariance=np.zeros((2, 2)))])
    assert np.all(np.isfinite(post.mean)) and np.all(np.isfinite(post.cov))
    assert kf.stats.degenerate_steps == 1


def test_mismatched_batch_axes_raise_a_shape_error():
    from fusetrack.core import ShapeError

    kf = KalmanFilter(ConstantVelocity(), [PositionFix("tag", cov=np.eye(2))])
    prior = Gaussian(np.zeros((5, 4)), np.broadcast_to(np.eye(4), (5, 4, 4)))
    with pytest.raises(ShapeError, match=r"\(5,\)"):
        kf.update(prior, [Measurement(0.0, "tag", np.zeros((3, 2)))])
