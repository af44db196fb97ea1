"""Coordinated turn with known and estimated turn rate, including the omega -> 0 limit."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _motion_helpers import assert_moments, numerical_jacobian
from scipy.stats import multivariate_normal

from fusetrack.core import ConfigError, MotionModel, ShapeError
from fusetrack.motion import ConstantVelocity, CoordinatedTurn, CoordinatedTurnRate
from fusetrack.motion.turn import turn_factor_derivatives, turn_factors


def _ct_matrix_direct(omega: float, dt: float) -> np.ndarray:
    """Li & Jilkov's CT matrix written out with the plain divisions (omega != 0)."""
    s, c = math.sin(omega * dt), math.cos(omega * dt)
    return np.array(
        [
            [1, 0, s / omega, -(1 - c) / omega],
            [0, 1, (1 - c) / omega, s / omega],
            [0, 0, c, -s],
            [0, 0, s, c],
        ]
    )


def test_ct_transition_matrix_hand_computed():
    ct = CoordinatedTurn(omega=0.3, q=1.0)
    np.testing.assert_allclose(ct.transition_matrix(2.0), _ct_matrix_direct(0.3, 2.0), rtol=1e-14)
    # one number by hand: sin(0.6)/0.3 = 0.5646425/0.3 = 1.8821416
    assert ct.transition_matrix(2.0)[0, 2] == pytest.approx(1.8821416, abs=1e-7)


def test_ct_turns_anticlockwise_and_keeps_speed():
    ct = CoordinatedTurn(omega=math.pi / 2)  # a quarter turn per second
    x = np.array([0.0, 0.0, 1.0, 0.0])
    x1 = ct.mean(x, 1.0)
    np.testing.assert_allclose(x1[2:], [0.0, 1.0], atol=1e-15)  # heading +x -> +y
    r = 1.0 / (math.pi / 2)  # radius v / omega
    np.testing.assert_allclose(x1[:2], [r, r], atol=1e-15)
    x4 = ct.mean(x, 4.0)  # full circle: back where it started
    np.testing.assert_allclose(x4, x, atol=1e-14)


def test_ct_noise_is_the_cv_noise():
    np.testing.assert_allclose(
        CoordinatedTurn(0.2, q=0.7).noise_cov(1.5), ConstantVelocity(2, 0.7).noise_cov(1.5)
    )
    q = CoordinatedTurnRate(q=0.7, q_omega=0.04).noise_cov(1.5)
    np.testing.assert_allclose(q[:4, :4], ConstantVelocity(2, 0.7).noise_cov(1.5))
    assert q[4, 4] == pytest.approx(0.06) and not np.any(q[4, :4]) and not np.any(q[:4, 4])


@pytest.mark.parametrize("omega", [0.0, 1e-12, -1e-9, 1e-6])
def test_ct_at_and_near_zero_turn_rate_is_cv(omega):
    cv = ConstantVelocity(2)
    x = np.random.default_rng(0).normal(size=(8, 4)) * 10
    ct = CoordinatedTurn(omega)
    tol = abs(omega) * 1.7**2 * 50 + 1e-12  # first-order effect of the turn (|v| < 50)
    np.testing.assert_allclose(ct.mean(x, 1.7), cv.mean(x, 1.7), rtol=0, atol=tol)
    xr = np.concatenate([x, np.full((8, 1), omega)], axis=1)
    np.testing.assert_allclose(
        CoordinatedTurnRate().mean(xr, 1.7)[:, :4], cv.mean(x, 1.7), rtol=0, atol=tol
    )
    assert np.all(np.isfinite(CoordinatedTurnRate().jacobian(xr, 1.7)))


def test_ct_exactly_zero_equals_cv_bit_for_bit():
    x = np.array([1.0, -2.0, 3.0, 0.5])
    np.testing.assert_array_equal(
        CoordinatedTurn(0.0).transition_matrix(0.4), ConstantVelocity(2).transition_matrix(0.4)
    )
    xr = np.append(x, 0.0)
    np.testing.assert_array_equal(
        CoordinatedTurnRate().mean(xr, 0.4)[:4], ConstantVelocity(2).mean(x, 0.4)
    )


def test_ct_rate_mean_matches_known_rate_model_row_by_row():
    rng = np.random.default_rng(1)
    x = rng.normal(size=(6, 5))
    got = CoordinatedTurnRate().mean(x, 0.9)
    for i in range(6):
        np.testing.assert_allclose(
            got[i, :4], CoordinatedTurn(x[i, 4]).mean(x[i, :4], 0.9), rtol=1e-13
        )
        assert got[i, 4] == x[i, 4]


def test_turn_factors_series_and_closed_form_agree():
    a = np.array([-0.3, -0.12, -0.1, -0.0999999, -0.05, 0.05, 0.0999999, 0.1, 0.1000001, 0.3, 2.0])
    d1, d2 = turn_factor_derivatives(a)
    d1_exact = (a * np.cos(a) - np.sin(a)) / a**2
    d2_exact = (a * np.sin(a) - 1 + np.cos(a)) / a**2
    np.testing.assert_allclose(d1, d1_exact, rtol=1e-9, atol=1e-13)
    np.testing.assert_allclose(d2, d2_exact, rtol=1e-9)
    f1, f2 = turn_factors(a)
    np.testing.assert_allclose(f1, np.sin(a) / a, rtol=1e-14)
    np.testing.assert_allclose(f2, (1 - np.cos(a)) / a, rtol=1e-9)
    d1z, d2z = turn_factor_derivatives(0.0)
    assert d1z == 0.0 and d2z == 0.5
    f1z, f2z = turn_factors(0.0)
    assert f1z == 1.0 and f2z == 0.0


def test_turn_factor_derivatives_equal_finite_differences():
    a = np.array([0.0, 1e-5, 0.05, 0.0999, 0.1001, 0.5, -1.3])
    h = 1e-6
    p1, p2 = turn_factors(a + h)
    m1, m2 = turn_factors(a - h)
    d1, d2 = turn_factor_derivatives(a)
    np.testing.assert_allclose(d1, (p1 - m1) / (2 * h), atol=1e-9)
    np.testing.assert_allclose(d2, (p2 - m2) / (2 * h), atol=1e-9)


@pytest.mark.parametrize("omega", [0.3, -0.3, 1e-4, 0.0, -2e-3, 0.1 / 0.8, 1.7])
@pytest.mark.parametrize("dt", [0.8, 2.5])
def test_ct_rate_jacobian_equals_finite_differences(omega, dt):
    rng = np.random.default_rng(2)
    x = rng.normal(size=(5, 5)) * [3, 3, 2, 2, 0]
    x[:, 4] = omega
    model = CoordinatedTurnRate()
    j = model.jacobian(x, dt)
    assert j.shape == (5, 5, 5)
    num = numerical_jacobian(lambda y: model.mean(y, dt), x, h=1e-6)
    np.testing.assert_allclose(j, num, atol=2e-8 * max(1.0, dt**2))


@pytest.mark.parametrize("omega", [0.3, 0.0, 1e-7])
def test_ct_known_rate_jacobian_equals_finite_differences(omega):
    model = CoordinatedTurn(omega)
    x = np.random.default_rng(3).normal(size=(4, 4))
    num = numerical_jacobian(lambda y: model.mean(y, 1.2), x)
    np.testing.assert_allclose(model.jacobian(x, 1.2), num, atol=1e-8)


@pytest.mark.parametrize("model", [CoordinatedTurn(0.3, q=0.8), CoordinatedTurnRate(0.8, 0.05)])
def test_ct_sample_moments(model):
    rng = np.random.default_rng(4)
    x0 = np.array([1.0, 2.0, 3.0, -1.0, 0.3])[: model.dim]
    s = model.sample(np.broadcast_to(x0, (100_000, model.dim)), 1.4, rng)
    assert_moments(s, model.mean(x0, 1.4), model.noise_cov(1.4))


@pytest.mark.parametrize("model", [CoordinatedTurn(0.3, q=0.8), CoordinatedTurnRate(0.8, 0.05)])
def test_ct_log_density_equals_scipy(model):
    rng = np.random.default_rng(5)
    x = rng.normal(size=(6, model.dim))
    xn = model.sample(x, 0.7, rng) + 0.2 * rng.normal(size=x.shape)
    m, cov = model.mean(x, 0.7), model.noise_cov(0.7)
    expected = [multivariate_normal(m[i], cov).logpdf(xn[i]) for i in range(6)]
    np.testing.assert_allclose(model.log_density(xn, x, 0.7), expected, rtol=1e-10)


def test_ct_rate_zero_q_omega_keeps_the_turn_rate():
    model = CoordinatedTurnRate(q=1.0, q_omega=0.0)
    rng = np.random.default_rng(6)
    x = np.array([[0.0, 0.0, 1.0, 1.0, 0.2]])
    xn = model.sample(x, 1.0, rng)
    assert xn[0, 4] == 0.2
    assert np.isfinite(model.log_density(xn, x, 1.0)).all()
    bumped = xn.copy()
    bumped[0, 4] += 0.01
    assert model.log_density(bumped, x, 1.0)[0] == -np.inf


def test_ct_dt_zero():
    model = CoordinatedTurnRate()
    x = np.array([1.0, 2.0, 3.0, 4.0, 0.5])
    np.testing.assert_array_equal(model.mean(x, 0.0), x)
    np.testing.assert_array_equal(model.jacobian(x, 0.0), np.eye(5))
    with pytest.raises(ConfigError, match=r"dt=0\.0"):
        model.log_density(x, x, 0.0)


def test_ct_attributes_and_protocol():
    for m in (CoordinatedTurn(0.1), CoordinatedTurnRate()):
        assert isinstance(m, MotionModel)
        assert m.position_index == (0, 1) and m.velocity_index == (2, 3)
    assert CoordinatedTurn(0.1).dim == 4 and CoordinatedTurnRate().dim == 5
    assert CoordinatedTurnRate().state_names[-1] == "omega"


def test_ct_errors():
    with pytest.raises(ConfigError, match="omega=nan"):
        CoordinatedTurn(float("nan"))
    with pytest.raises(ConfigError, match="omega="):
        CoordinatedTurn("fast")
    with pytest.raises(ConfigError, match="q=-1"):
        CoordinatedTurn(0.1, q=-1)
    with pytest.raises(ConfigError, match=r"q_omega=-0\.1"):
        CoordinatedTurnRate(q_omega=-0.1)
    with pytest.raises(ShapeError, match=r"d=5, \[x, y, vx, vy, omega\]"):
        CoordinatedTurnRate().mean(np.zeros((3, 4)), 1.0)
    with pytest.raises(ShapeError, match="d=4"):
        CoordinatedTurn(0.1).mean(np.zeros((3, 5)), 1.0)
    with pytest.raises(ConfigError, match="dt="):
        CoordinatedTurnRate().jacobian(np.zeros(5), -1.0)
