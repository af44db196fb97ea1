"""simulate: noise statistics, detection, NaN rows outside the field of view or range."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fusetrack.sensors import AzimuthPolar, Bearing, PositionFix, Range, RangeBearing, SensorBase

CASES: list[tuple[SensorBase, np.ndarray]] = [
    (Bearing("bearing", [1.0, 2.0], 0.05, heading=1.0), np.array([4.0, 6.0, 1.0, 1.0])),
    # target almost behind: simulated bearings straddle +-pi and must still average right
    (Bearing("bearing_pi", [0.0, 0.0], 0.05), np.array([-5.0, 0.01])),
    (AzimuthPolar("azpol", [0.0, 0.0, 0.0], 0.03, 0.04), np.array([1.0, 2.0, 1.5, 0, 0, 0])),
    (Range("range3", [1.0, 2.0, -1.0], 0.3), np.array([4.0, 6.0, 2.0])),
    (RangeBearing("rb", [3.0, -2.0], 0.3, 0.05), np.array([-1.0, 4.0, 0.0, 0.0])),
    (PositionFix("tag", [[0.2, 0.08], [0.08, 0.1]], bias=[0.3, -0.1]), np.array([1.0, 2.0])),
]
N = 40_000


@pytest.mark.parametrize(("sensor", "x"), CASES, ids=[c[0].sensor_id for c in CASES])
def test_residuals_have_zero_mean_and_covariance_r(sensor: SensorBase, x: np.ndarray) -> None:
    rng = np.random.default_rng(5)
    xs = np.broadcast_to(x, (N, x.size))
    z = sensor.simulate(xs, rng)
    assert z.shape == (N, sensor.dim)
    assert np.all(np.isfinite(z))
    r = sensor.residual(z, sensor.predict(x))
    R = sensor.noise_cov()
    se = np.sqrt(np.diag(R) / N)
    assert np.all(np.abs(r.mean(axis=0)) < 4.5 * se)
    C = np.cov(r.T).reshape(R.shape)
    # sample covariance entries: sd of C_ij is about sqrt((R_ii R_jj + R_ij^2) / N)
    tol = 4.5 * np.sqrt((np.outer(np.diag(R), np.diag(R)) + R**2) / N)
    assert np.all(np.abs(C - R) < tol)
    for k, is_angle in enumerate(sensor.angular):
        if is_angle:
            assert np.all(z[:, k] >= -math.pi) and np.all(z[:, k] < math.pi)


def test_position_fix_measures_position_plus_bias() -> None:
    tag = PositionFix("tag", np.diag([0.01, 0.04]), bias=[1.0, -2.0])
    z = tag.simulate(np.broadcast_to([3.0, 4.0, 0.0, 0.0], (N, 4)), np.random.default_rng(6))
    np.testing.assert_allclose(z.mean(axis=0), [4.0, 2.0], atol=5e-3)


def test_detection_fraction_matches_detection_prob() -> None:
    s = Range("r", [0.0, 0.0], 0.1, detection_prob=0.7)
    z = s.simulate(np.ones((N, 2)), np.random.default_rng(7))
    frac = np.mean(np.isfinite(z[:, 0]))
    assert abs(frac - 0.7) < 4.5 * math.sqrt(0.7 * 0.3 / N)
    assert np.array_equal(np.isnan(z[:, 0]), np.isnan(z).any(axis=1))


def test_nan_outside_fov_and_beyond_max_range() -> None:
    s = RangeBearing("rb", [0.0, 0.0], 0.1, 0.01, heading=0.0, fov=math.pi / 2, max_range=10.0)
    x = np.array([[5.0, 0.0], [5.0, 4.0], [0.0, 5.0], [-5.0, 0.0], [20.0, 0.0], [9.0, 1.0]])
    z = s.simulate(x, np.random.default_rng(8))
    seen = [True, True, False, False, False, True]
    assert np.isfinite(z).all(axis=1).tolist() == seen
    assert np.isnan(z[~np.array(seen)]).all()


def test_zero_detection_probability_gives_all_nan() -> None:
    s = Bearing("b", [0.0, 0.0], 0.1, detection_prob=0.0)
    assert np.isnan(s.simulate(np.ones((100, 2)), np.random.default_rng(0))).all()


def test_simulate_is_reproducible_and_batched() -> None:
    s = AzimuthPolar("ap", [0.0, 0.0, 0.0], 0.1, 0.1, detection_prob=0.5)
    x = np.random.default_rng(1).normal(size=(4, 6, 3))
    z1 = s.simulate(x, np.random.default_rng(42))
    z2 = s.simulate(x, np.random.default_rng(42))
    assert z1.shape == (4, 6, 2)
    np.testing.assert_array_equal(z1, z2)
    z3 = s.simulate(x[0, 0], np.random.default_rng(42))  # a single state
    assert z3.shape == (2,)
