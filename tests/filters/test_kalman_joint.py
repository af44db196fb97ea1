"""Joint (stacked) Kalman updates: equal to the sequential ones for linear models, and for
nonlinear ones to the textbook stacked EKF update computed by hand here."""

from __future__ import annotations

import numpy as np
import pytest

from fusetrack.core import Gaussian, Measurement
from fusetrack.filters import ExtendedKalmanFilter, KalmanFilter, UnscentedKalmanFilter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import Bearing, PositionFix

PRIOR = Gaussian(np.array([10.0, 5.0, 1.0, -0.5]), np.diag([4.0, 9.0, 1.0, 1.0]))


def _mics(n):
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return [
        Bearing(f"m{i}", position=[10 + 30 * np.cos(t), 5 + 30 * np.sin(t)], sigma=0.02 + 0.01 * i)
        for i, t in enumerate(a)
    ]


def test_joint_equals_sequential_for_linear_models():
    tags = [PositionFix(f"t{i}", cov=np.diag([0.5 + i, 1.0])) for i in range(5)]
    ms = [Measurement(0.0, f"t{i}", [10.3 + 0.1 * i, 4.6]) for i in range(5)]
    seq = KalmanFilter(ConstantVelocity(q=0.1), tags).update(PRIOR, ms)
    joint = KalmanFilter(ConstantVelocity(q=0.1), tags, joint=True).update(PRIOR, ms)
    np.testing.assert_allclose(joint.mean, seq.mean, atol=1e-12)
    np.testing.assert_allclose(joint.cov, seq.cov, atol=1e-12)


@pytest.mark.parametrize("n", [2, 50])  # 50 > d: the d x d (Woodbury) gain
def test_joint_ekf_is_the_stacked_update(n):
    mics = _mics(n)
    truth = np.array([12.0, 3.0])
    z = [np.arctan2(truth[1] - m.position[1], truth[0] - m.position[0]) for m in mics]
    ms = [Measurement(0.0, m.sensor_id, [zi + 0.01]) for m, zi in zip(mics, z)]
    got = ExtendedKalmanFilter(ConstantVelocity(q=0.1), mics, joint=True).update(PRIOR, ms)
    # by hand: one H, one S, one K, linearised at the prior mean
    x, p = PRIOR.mean, PRIOR.cov
    h = np.vstack([m.jacobian(x) for m in mics])
    zp = np.concatenate([m.predict(x) for m in mics])
    r = np.diag([m.sigma**2 for m in mics])
    s = h @ p @ h.T + r
    k = p @ h.T @ np.linalg.inv(s)
    y = (np.array(z) + 0.01 - zp + np.pi) % (2 * np.pi) - np.pi
    np.testing.assert_allclose(got.mean, x + k @ y, atol=1e-10)
    np.testing.assert_allclose(got.cov, p - k @ s @ k.T, atol=1e-10)
    # the m x m path (taken when the likelihood is wanted, or a reading has its own
    # covariance) gives the same posterior as the O(d^2 m) one
    ekf = ExtendedKalmanFilter(ConstantVelocity(q=0.1), mics, joint=True)
    with_ll, _ = ekf.update_with_likelihood(PRIOR, ms)
    np.testing.assert_allclose(with_ll.mean, got.mean, atol=1e-10)
    np.testing.assert_allclose(with_ll.cov, got.cov, atol=1e-10)
    own = [Measurement(0.0, m.sensor_id, m.value, covariance=[[mics[i].sigma ** 2]])
           for i, m in enumerate(ms)]  # fmt: skip
    np.testing.assert_allclose(ekf.update(PRIOR, own).mean, got.mean, atol=1e-10)
    # and it is not the sequential EKF (relinearised after each reading)
    seq = ExtendedKalmanFilter(ConstantVelocity(q=0.1), mics).update(PRIOR, ms)
    assert np.abs(seq.mean - got.mean).max() > 1e-9


def test_joint_ukf_and_given_covariance_and_unusable_rows():
    mics = _mics(3)
    ms = [Measurement(0.0, m.sensor_id, [0.1 * i]) for i, m in enumerate(mics)]
    ms[1] = Measurement(0.0, "m1", [0.1], covariance=[[0.5]])
    ukf = UnscentedKalmanFilter(ConstantVelocity(q=0.1), mics, joint=True)
    got = ukf.update(PRIOR, ms)
    assert np.all(np.isfinite(got.cov)) and np.trace(got.cov) < np.trace(PRIOR.cov)
    # the given covariance is used: a huge one makes m1 irrelevant
    big = [ms[0], Measurement(0.0, "m1", [0.1], covariance=[[1e12]]), ms[2]]
    without = ukf.update(PRIOR, [ms[0], ms[2]])
    np.testing.assert_allclose(ukf.update(PRIOR, big).mean, without.mean, atol=1e-6)
    # a NaN reading is skipped and counted, the rest fused jointly
    ekf = ExtendedKalmanFilter(ConstantVelocity(q=0.1), mics, joint=True)
    nan = [ms[0], Measurement(0.0, "m1", [np.nan]), ms[2]]
    np.testing.assert_allclose(
        ekf.update(PRIOR, nan).mean, ekf.update(PRIOR, [ms[0], ms[2]]).mean, atol=1e-12
    )
    assert ekf.stats.skipped_measurements == 1
