"""The Numba Joseph-form kernel (filters.kalman_kernels) against the NumPy path of the Kalman
update it replaces for large batches, and its fall-backs."""

from __future__ import annotations

import numpy as np
import pytest

import fusetrack.filters.kalman as kalman
from fusetrack.core import Gaussian, Measurement
from fusetrack.filters import ExtendedKalmanFilter, KalmanFilter, UnscentedKalmanFilter
from fusetrack.filters.kalman_kernels import joseph_update
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import PositionFix, RangeBearing

N = 64


def _batch(rng: np.random.Generator, n: int = N) -> Gaussian:
    a = rng.normal(size=(n, 4, 4))
    cov = a @ np.swapaxes(a, -1, -2) + np.eye(4)
    mean = np.c_[rng.uniform(-80, 80, (n, 2)), rng.normal(size=(n, 2))]
    return Gaussian(mean, cov)


def _both(filt, belief, meas, monkeypatch):
    monkeypatch.setattr(kalman, "KERNEL_MIN_BATCH", 1)
    fast = filt.update_with_likelihood(belief, meas)
    monkeypatch.setattr(kalman, "KERNEL_MIN_BATCH", 10**9)
    slow = filt.update_with_likelihood(belief, meas)
    return fast, slow


def _assert_same(fast, slow):
    (g1, l1), (g2, l2) = fast, slow
    np.testing.assert_allclose(g1.mean, g2.mean, rtol=1e-12, atol=1e-10)
    np.testing.assert_allclose(g1.cov, g2.cov, rtol=1e-12, atol=1e-10)
    np.testing.assert_allclose(l1, l2, rtol=1e-12, atol=1e-9)
    np.testing.assert_array_equal(g1.cov, np.swapaxes(g1.cov, -1, -2))


def test_ekf_range_bearing_kernel_equals_numpy_path(monkeypatch):
    rng = np.random.default_rng(3)
    radar = RangeBearing("radar", position=[0.0, 0.0], sigma_range=0.5, sigma_bearing=0.01)
    ekf = ExtendedKalmanFilter(ConstantVelocity(ndim=2, q=0.1), [radar])
    z = np.c_[rng.uniform(50, 100, N), rng.uniform(-np.pi, np.pi, N)]  # bearings across the cut
    _assert_same(*_both(ekf, _batch(rng), [Measurement(1.0, "radar", z)], monkeypatch))


def test_linear_kalman_kernel_equals_numpy_path_with_per_row_covariances(monkeypatch):
    rng = np.random.default_rng(4)
    kf = KalmanFilter(ConstantVelocity(ndim=2, q=0.1), [PositionFix("tag", cov=0.25 * np.eye(2))])
    a = rng.normal(size=(N, 2, 2))
    r = a @ np.swapaxes(a, -1, -2) + 0.1 * np.eye(2)
    meas = [
        Measurement(1.0, "tag", rng.normal(size=(N, 2)) * 30, covariance=r),
        Measurement(1.0, "tag", rng.normal(size=(N, 2)) * 30),  # sequential: the sensor's R
    ]
    _assert_same(*_both(kf, _batch(rng), meas, monkeypatch))


def test_kernel_hand_computed_scalar_case():
    # d = 1, m = 1: P = 4, R = 1, H = 1, y = 2 -> S = 5, K = 0.8, x+ = 1.6, P+ = 0.8
    mean, cov, ll = joseph_update(
        np.zeros((1, 1)), np.full((1, 1, 1), 4.0), np.ones((1, 1, 1)), np.ones((1, 1, 1)),
        np.full((1, 1), 2.0), True,
    )  # fmt: skip
    assert mean[0, 0] == pytest.approx(1.6)
    assert cov[0, 0, 0] == pytest.approx(0.2**2 * 4 + 0.8**2 * 1)  # (1-K)^2 P + K^2 R = 0.8
    assert cov[0, 0, 0] == pytest.approx(0.8)
    assert ll[0] == pytest.approx(-0.5 * (4 / 5 + np.log(5) + np.log(2 * np.pi)))


def test_kernel_flags_a_singular_innovation_covariance_and_filter_falls_back(monkeypatch):
    h = np.ones((1, 1, 1))
    assert joseph_update(np.zeros((2, 1)), np.zeros((2, 1, 1)), h, np.zeros((1, 1, 1)),
                         np.zeros((2, 1)), False) is None  # fmt: skip
    # the filter then takes the NumPy path (pseudo-inverse) and counts the degenerate step
    monkeypatch.setattr(kalman, "KERNEL_MIN_BATCH", 1)
    kf = KalmanFilter(ConstantVelocity(ndim=2, q=0.1), [PositionFix("tag", cov=0.25 * np.eye(2))])
    prior = Gaussian(np.zeros((3, 4)), np.zeros((3, 4, 4)))
    post = kf.update(prior, [Measurement(0.0, "tag", np.ones((3, 2)), covariance=np.zeros((2, 2)))])
    assert np.all(np.isfinite(post.mean))
    assert kf.stats.degenerate_steps == 1


def test_ukf_and_partial_rows_keep_the_numpy_path(monkeypatch):
    monkeypatch.setattr(kalman, "KERNEL_MIN_BATCH", 1)
    calls = []
    monkeypatch.setattr(kalman, "joseph_update", lambda *a: calls.append(1))
    rng = np.random.default_rng(5)
    radar = RangeBearing("radar", position=[0.0, 0.0], sigma_range=0.5, sigma_bearing=0.01)
    ukf = UnscentedKalmanFilter(ConstantVelocity(ndim=2, q=0.1), [radar])
    z = np.c_[rng.uniform(50, 100, N), rng.uniform(-3, 3, N)]
    ukf.update(_batch(rng), [Measurement(1.0, "radar", z)])
    ekf = ExtendedKalmanFilter(ConstantVelocity(ndim=2, q=0.1), [radar])
    z[0] = np.nan  # one unusable row: the whole call takes the NumPy path
    post = ekf.update(_batch(rng), [Measurement(1.0, "radar", z)])
    assert calls == []
    assert np.all(np.isfinite(post.mean))
