"""ekf_bearing_steps: the one-loop steps equal the filter's own predict/update per reading, and
decline (None) whatever they do not cover."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.core import Gaussian, Measurement
from fusetrack.filters import (
    ExtendedKalmanFilter,
    KalmanFilter,
    UnscentedKalmanFilter,
    ekf_bearing_steps,
)
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import Bearing, Range

PRIOR = Gaussian(np.array([10.0, 5.0, 1.0, -0.5]), np.diag([4.0, 9.0, 1.0, 1.0]))


def mics(n=6):
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return [
        Bearing(f"m{i}", position=[10 + 30 * np.cos(t), 5 + 30 * np.sin(t)], sigma=0.02 + 0.01 * i,
                heading=0.3 * i)
        for i, t in enumerate(a)
    ]  # fmt: skip


def readings(sensors, n=40, seed=1):
    rng = np.random.default_rng(seed)
    times = 0.1 + np.cumsum(rng.uniform(0.001, 0.05, n))
    times[7] = times[6] + 1e-12  # within the tolerance: an update without a predict
    return [
        Measurement(float(t), sensors[i % len(sensors)].sensor_id, [rng.uniform(-3.1, 3.1)])
        for i, t in enumerate(times)
    ]


def by_hand(filt, belief, time, ms, tol=1e-9):
    for m in ms:
        if m.time - time > tol:
            belief, time = filt.predict(belief, m.time - time), m.time
        belief = filt.update(belief, [m])
    return belief, time


@pytest.mark.parametrize("cls", [ExtendedKalmanFilter, KalmanFilter])
def test_the_loop_equals_one_predict_and_update_per_reading(cls):
    sensors = mics()
    filt = cls(ConstantVelocity(q=0.5), sensors)
    ms = readings(sensors)
    (got, t), (want, t_want) = (
        ekf_bearing_steps(filt, PRIOR, 0.0, ms, 1e-9),
        by_hand(filt, PRIOR, 0.0, ms),
    )
    assert t == t_want == ms[-1].time
    np.testing.assert_allclose(got.mean, want.mean, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(got.cov, want.cov, rtol=1e-10, atol=1e-12)
    assert np.array_equal(got.cov, got.cov.T)


def test_it_declines_what_it_does_not_cover():
    sensors = mics(3)
    ms = readings(sensors, n=10)
    ekf = ExtendedKalmanFilter(
        ConstantVelocity(q=0.5), [*sensors, Range("r", position=[0, 0], sigma=1.0)]
    )
    ukf = UnscentedKalmanFilter(ConstantVelocity(q=0.5), sensors)
    assert ekf_bearing_steps(ukf, PRIOR, 0.0, ms, 1e-9) is None  # another filter
    with_range = [*ms, Measurement(ms[-1].time + 0.1, "r", [12.0])]
    assert ekf_bearing_steps(ekf, PRIOR, 0.0, with_range, 1e-9) is None  # another sensor
    own = [*ms[:-1], Measurement(ms[-1].time, ms[-1].sensor_id, ms[-1].value, covariance=[[1.0]])]
    assert ekf_bearing_steps(ekf, PRIOR, 0.0, own, 1e-9) is None  # its own covariance
    nan = [*ms[:-1], Measurement(ms[-1].time, ms[-1].sensor_id, [np.nan])]
    assert ekf_bearing_steps(ekf, PRIOR, 0.0, nan, 1e-9) is None  # skipped and counted there
    batch = Gaussian(np.tile(PRIOR.mean, (2, 1)), np.tile(PRIOR.cov, (2, 1, 1)))
    assert ekf_bearing_steps(ekf, batch, 0.0, ms, 1e-9) is None  # a batch of beliefs
