"""Zhai 2007's models: manoeuvre turn (Eqs. 42-43, corrected Jacobian 55-63), scalar benchmark, power sensor."""

import numpy as np
import pytest

from fusetrack.motion.benchmark import ScalarBenchmark
from fusetrack.motion.maneuver import ManeuverTurn
from fusetrack.sensors.power import Power


def _fd(fun, x, eps=1e-6):
    return np.stack([(fun(x + eps * e) - fun(x - eps * e)) / (2 * eps) for e in np.eye(len(x))], -1)


@pytest.mark.parametrize("direction", [1, -1])
@pytest.mark.parametrize(
    "state", [[1.0, 2.0, 0.7, -0.4], [0.0, 0.0, -3.0, 0.01], [5.0, 1.0, 0.2, 0.1]]
)
def test_maneuver_turn_jacobian_matches_finite_differences(direction, state):
    m = ManeuverTurn(a_m=0.5, direction=direction)
    x = np.array(state)
    np.testing.assert_allclose(m.jacobian(x, 1.3), _fd(lambda v: m.mean(v, 1.3), x), atol=2e-6)


def test_the_thesis_jacobian_typos_would_fail():
    """The printed g1 sign (Eq. 56) differs from the derivative: our version is not the printed one."""
    m = ManeuverTurn(a_m=0.5)
    x, dt = np.array([0.0, 0.0, 0.7, -0.4]), 1.0
    om = float(m.turn_rate(x))
    a = om * dt
    vx, vy = x[2], x[3]
    g1_printed = (
        dt * np.cos(a) * vx / om
        - np.sin(a) * vx / om**2
        - dt * np.sin(a) * vy / om
        + (-1 + np.cos(a)) * vy / om**2
    )
    g1_right = (
        dt * np.cos(a) * vx / om
        - np.sin(a) * vx / om**2
        - dt * np.sin(a) * vy / om
        + (1 - np.cos(a)) * vy / om**2
    )
    num = (m.mean(x, dt)[0] - ManeuverTurn(a_m=0.5 * (1 - 1e-7)).mean(x, dt)[0]) / (om * 1e-7)
    assert abs(num - g1_right) < 1e-5 and abs(num - g1_printed) > 1e-2


def test_turn_keeps_speed_and_turns_the_right_way():
    ccw, cw = ManeuverTurn(a_m=0.2, direction=1), ManeuverTurn(a_m=0.2, direction=-1)
    x = np.array([0.0, 0.0, 1.0, 0.0])
    a, b = ccw.mean(x, 1.0), cw.mean(x, 1.0)
    assert a[3] > 0 > b[3]
    assert np.hypot(*a[2:]) == pytest.approx(1.0) and np.hypot(*b[2:]) == pytest.approx(1.0)
    assert np.linalg.matrix_rank(ManeuverTurn(0.2, noise="discrete").noise_cov(1.0)) == 2
    assert np.linalg.matrix_rank(ccw.noise_cov(1.0)) == 4


def test_scalar_benchmark_and_power_sensor_by_hand():
    m = ScalarBenchmark()
    x = np.array([0.5])
    assert m.mean(x)[0] == pytest.approx(1.7 * np.exp(-0.5) + 5 * np.sin(0.5))
    assert m.jacobian(x)[0, 0] == pytest.approx(-6.8 * 0.5 * np.exp(-0.5) + 5 * np.cos(0.5))
    c = ScalarBenchmark(trig="cos", q=8.0)
    assert c.mean(x)[0] == pytest.approx(1.7 * np.exp(-0.5) + 5 * np.cos(0.5))
    assert c.noise_cov()[0, 0] == 8.0
    s = Power("y", exponent=2, sigma=2.0, scale=0.05)
    assert s.predict(np.array([3.0]))[0] == pytest.approx(0.45)
    assert s.jacobian(np.array([3.0]))[0, 0] == pytest.approx(0.3)
    assert s.log_likelihood(np.array([0.45]), np.array([3.0])) == pytest.approx(
        -np.log(2.0) - 0.5 * np.log(2 * np.pi)
    )
    with pytest.raises(ValueError, match="exponent"):
        Power("y", exponent=0)
    with pytest.raises(ValueError, match="trig"):
        ScalarBenchmark(trig="tan")  # type: ignore[arg-type]


def test_standing_target_falls_back_to_constant_velocity():
    m = ManeuverTurn(a_m=0.5)
    x = np.array([1.0, 2.0, 0.0, 0.0])
    np.testing.assert_array_equal(m.mean(x, 1.0), x)
    assert np.all(np.isfinite(m.jacobian(x, 1.0)))
