"""maximum_likelihood: the fit recovers the noise parameters within the standard errors of the
observed Fisher information, and those standard errors match the spread of the estimate over
simulated series (a parametric bootstrap)."""

from __future__ import annotations

import numpy as np
import pytest
from _estimation_models import THETA, kalman_model, particle_model, simulate

from fusetrack.core import ConfigError
from fusetrack.estimation import maximum_likelihood, observed_information, prepare_series


def test_fit_recovers_q_and_r_on_a_long_series():
    fit = maximum_likelihood(kalman_model, [0.5, 0.5], simulate(2000, seed=5))
    assert fit.exact and fit.result.success
    z = (fit.theta - THETA) / fit.standard_errors
    assert np.all(np.abs(z) < 3.0), z
    assert np.allclose(fit.covariance @ fit.information, np.eye(2), atol=1e-8)


def test_standard_errors_match_the_spread_over_series():
    """30 series of T = 300 from the true model: the standard deviation of the estimates agrees
    with the standard error from the information (the sd of 30 draws is within ~13 %)."""
    fits = [maximum_likelihood(kalman_model, THETA, simulate(300, seed=100 + s)) for s in range(30)]
    est = np.array([f.theta for f in fits])
    se = np.array([f.standard_errors for f in fits]).mean(axis=0)
    ratio = est.std(axis=0, ddof=1) / se
    assert np.all((0.6 < ratio) & (ratio < 1.5)), ratio
    assert np.all(np.abs(est.mean(axis=0) - THETA) < 3 * est.std(axis=0, ddof=1) / np.sqrt(30))


def test_observed_information_of_a_quadratic():
    A = np.array([[2.0, 0.5], [0.5, 1.0]])
    info = observed_information(
        lambda th: -0.5 * th @ A @ th + th.sum(), np.array([0.3, -1.0]), 1e-2
    )
    assert np.allclose(info, A, atol=1e-8)


def test_particle_fit_uses_common_random_numbers():
    """Each evaluation draws the same numbers, so the objective is a function of theta and the
    fit lands near the exact fit (within its standard errors)."""
    series = prepare_series(simulate(300, seed=9))
    exact = maximum_likelihood(kalman_model, [0.0, 0.0], series)
    fit = maximum_likelihood(particle_model(500), [0.0, 0.0], series, seed=3)
    assert not fit.exact
    again = maximum_likelihood(particle_model(500), [0.0, 0.0], series, seed=3)
    assert np.array_equal(fit.theta, again.theta)
    assert np.all(np.abs(fit.theta - exact.theta) < exact.standard_errors), (fit.theta, exact.theta)


def test_bad_start_is_reported():
    with pytest.raises(ConfigError, match="theta0"):
        maximum_likelihood(kalman_model, [[0.0, 0.0]], simulate(10, seed=0))
