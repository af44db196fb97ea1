"""Jacobians against central finite differences, Fisher information, singular points."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fusetrack.sensors import AzimuthPolar, Bearing, PositionFix, Range, RangeBearing, SensorBase

# (sensor, state dimension d)
CASES: list[tuple[SensorBase, int]] = [
    (Bearing("bearing", [1.0, 2.0], 0.1), 2),
    (Bearing("bearing_cv", [1.0, 2.0], 0.1, heading=2.5), 4),
    (Bearing("bearing_idx", [-1.0, 0.5], 0.1, position_index=(3, 1)), 5),
    (AzimuthPolar("azpol_cv3", [0.5, -1.0, 2.0], 0.1, 0.2, heading=-1.0), 6),
    (AzimuthPolar("azpol_idx", [0.0, 0.0, 0.0], 0.1, 0.2, position_index=(2, 4, 0)), 6),
    (Range("range2", [1.0, 2.0], 0.3), 4),
    (Range("range3", [1.0, 2.0, -1.0], 0.3), 6),
    (RangeBearing("rb_cv", [3.0, -2.0], 0.3, 0.05, heading=0.7), 4),
    (RangeBearing("rb_idx", [0.0, 0.0], 0.3, 0.05, position_index=(2, 3)), 4),
    (PositionFix("tag", [[0.2, 0.05], [0.05, 0.1]], bias=[0.3, -0.1]), 4),
    (PositionFix("tag3", np.diag([0.1, 0.2, 0.3])), 6),
    (PositionFix("tag_idx", np.eye(2), position_index=(3, 0)), 5),
]


def numerical_jacobian(sensor: SensorBase, x: np.ndarray, eps: float = 1e-6) -> np.ndarray:
    """Central differences, using the wrapped residual so angle jumps do not matter."""
    d = x.shape[-1]
    cols = []
    for j in range(d):
        e = np.zeros(d)
        e[j] = eps
        cols.append(sensor.residual(sensor.predict(x + e), sensor.predict(x - e)) / (2 * eps))
    return np.stack(cols, axis=-1)


@pytest.mark.parametrize(("sensor", "d"), CASES, ids=[c[0].sensor_id for c in CASES])
def test_jacobian_matches_central_differences(sensor: SensorBase, d: int) -> None:
    rng = np.random.default_rng(1)
    x = rng.uniform(-5.0, 5.0, size=(40, d))
    J = sensor.jacobian(x)
    assert J.shape == (40, sensor.dim, d)
    np.testing.assert_allclose(J, numerical_jacobian(sensor, x), rtol=1e-5, atol=1e-6)
    # only the position columns are nonzero
    other = [j for j in range(d) if j not in sensor.position_index]
    assert np.all(J[..., other] == 0.0)


@pytest.mark.parametrize(("sensor", "d"), CASES, ids=[c[0].sensor_id for c in CASES])
def test_fisher_information_is_ht_rinv_h(sensor: SensorBase, d: int) -> None:
    rng = np.random.default_rng(2)
    x = rng.uniform(-5.0, 5.0, size=(2, 3, d))
    F = sensor.fisher_information(x)
    H = sensor.jacobian(x)
    R_inv = np.linalg.inv(sensor.noise_cov())
    expected = np.einsum("...ji,jk,...kl->...il", H, R_inv, H)
    np.testing.assert_allclose(F, expected, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(F, np.swapaxes(F, -1, -2), atol=1e-12)


def test_bearing_fisher_information_closed_form() -> None:
    # bearing information is (1 / (sigma r)^2) along the tangential direction
    s = Bearing("b", [0.0, 0.0], 0.1)
    F = s.fisher_information([3.0, 4.0])
    t = np.array([-4.0, 3.0]) / 5.0
    np.testing.assert_allclose(F, np.outer(t, t) / (0.1 * 5.0) ** 2)


def test_jacobian_is_finite_at_the_sensor_position() -> None:
    for s, x in [
        (Bearing("b", [1.0, 2.0], 0.1), [1.0, 2.0]),
        (RangeBearing("rb", [1.0, 2.0], 0.1, 0.1), [1.0, 2.0]),
        (Range("r", [1.0, 2.0, 3.0], 0.1), [1.0, 2.0, 3.0]),
        (AzimuthPolar("ap", [1.0, 2.0, 3.0], 0.1, 0.1), [1.0, 2.0, 3.0]),
        (AzimuthPolar("ap_axis", [1.0, 2.0, 3.0], 0.1, 0.1), [1.0, 2.0, 7.0]),  # vertical axis
    ]:
        J = s.jacobian(np.array(x))
        assert np.all(np.isfinite(J)), s.sensor_id
        assert np.all(np.isfinite(s.fisher_information(np.array(x)))), s.sensor_id


def test_azimuth_polar_near_the_vertical_axis_stays_accurate() -> None:
    s = AzimuthPolar("ap", [0.0, 0.0, 0.0], 0.1, 0.1)
    x = np.array([[1e-3, 2e-3, 1.0]])
    np.testing.assert_allclose(s.jacobian(x), numerical_jacobian(s, x, 1e-8), rtol=1e-4)


def test_jacobian_at_known_point() -> None:
    s = RangeBearing("rb", [1.0, 2.0], 0.1, 0.1)
    J = s.jacobian([4.0, 6.0, 0.0, 0.0])
    expected = [[0.6, 0.8, 0.0, 0.0], [-4.0 / 25.0, 3.0 / 25.0, 0.0, 0.0]]
    np.testing.assert_allclose(J, expected)
    assert math.isclose(float(Range("r", [1.0, 2.0], 1.0).jacobian([4.0, 6.0])[0, 1]), 0.8)
