"""PMMH: the chain's law is the exact posterior (Andrieu, Doucet & Holenstein 2010, Thm. 4),
checked against the posterior computed on a grid with the Kalman filter's exact likelihood."""

from __future__ import annotations

import numpy as np
import pytest
from _estimation_models import THETA, kalman_model, log_prior, particle_model, simulate

from fusetrack.core import ConfigError
from fusetrack.estimation import LogLikelihood, pmmh, prepare_series, proposal_covariance

SERIES = prepare_series(simulate(100, seed=11))


def _grid_posterior() -> tuple[np.ndarray, np.ndarray]:
    """Mean ``(2,)`` and covariance ``(2, 2)`` of ``p(theta | y)`` on a 30 x 45 grid (``log r``
    has a long left tail: small ``r`` is hard to tell from none)."""
    ev = LogLikelihood(SERIES)
    a = np.linspace(-1.5, 1.5, 30)  # log q
    b = np.linspace(-8.0, 1.5, 45)  # log r
    pts = np.array([(x, y) for x in a for y in b])
    lp = np.array([ev(*kalman_model(th)) + log_prior(th) for th in pts])
    w = np.exp(lp - lp.max())
    w /= w.sum()
    grid = w.reshape(a.size, b.size)
    assert max(grid[[0, -1]].max(), grid[:, [0, -1]].max()) < 1e-5  # the grid holds the mass
    mean = w @ pts
    d = pts - mean
    return mean, (w[:, None] * d).T @ d


EXACT_MEAN, EXACT_COV = _grid_posterior()


def _batch_means_se(x: np.ndarray, batches: int = 20) -> np.ndarray:
    """Monte Carlo standard error of the mean of a correlated chain ``(K, p)`` (batch means)."""
    k = x.shape[0] // batches
    means = x[: k * batches].reshape(batches, k, -1).mean(axis=1)
    return means.std(axis=0, ddof=1) / np.sqrt(batches)


def test_pmmh_recovers_the_exact_posterior():
    out = pmmh(
        particle_model(200), log_prior, [0.0, 0.0], SERIES, n_iterations=3000, burn_in=500,
        scale=0.25, rng=np.random.default_rng(1),
    )  # fmt: skip
    draws = out.posterior
    lo, hi = np.quantile(draws, [0.025, 0.975], axis=0)
    assert np.all((lo < THETA) & (THETA < hi)), (lo, hi)
    se = _batch_means_se(draws)
    assert np.all(np.abs(draws.mean(axis=0) - EXACT_MEAN) < 4 * se), (draws.mean(0), EXACT_MEAN, se)
    sd = draws.std(axis=0)
    assert np.allclose(sd, np.sqrt(np.diag(EXACT_COV)), rtol=0.3), (sd, np.sqrt(np.diag(EXACT_COV)))
    assert 0.05 < out.acceptance_rate < 0.6
    assert out.chain.shape == (3001, 1, 2) and out.accepted.shape == (3000, 1)


def test_adaptation_learns_the_posterior_scale():
    """Haario et al. 2001: after burn-in the proposal is about 2.38^2 / 2 times the posterior
    covariance (the burn-in chain's, so within a factor of 2 of the exact one)."""
    out = pmmh(
        kalman_model, log_prior, [[0.0, 0.0], [0.5, -1.0]], SERIES, n_iterations=700,
        burn_in=600, scale=1.0, adapt=True, rng=np.random.default_rng(2),
    )  # fmt: skip
    ratio = np.diag(out.proposal_cov) / (2.38**2 / 2 * np.diag(EXACT_COV))
    assert np.all((0.5 < ratio) & (ratio < 2.0)), ratio


def test_kalman_model_is_exact_metropolis_hastings():
    """With the exact likelihood the chain's log-likelihoods are the Kalman values of its states."""
    out = pmmh(
        kalman_model, log_prior, [0.0, 0.0], SERIES, n_iterations=50, scale=0.2,
        rng=np.random.default_rng(3),
    )  # fmt: skip
    ev = LogLikelihood(SERIES)
    for it in (0, 17, 50):
        th = out.chain[it, 0]
        assert out.log_likelihoods[it, 0] == pytest.approx(ev(*kalman_model(th)), abs=1e-9)
        assert out.log_priors[it, 0] == log_prior(th)


def test_rejected_proposals_outside_the_prior_build_no_model():
    built = []

    def model(theta):
        built.append(theta.copy())
        return kalman_model(theta)

    def half_prior(theta):
        return log_prior(theta) if theta[0] <= 0.0 else -np.inf

    out = pmmh(model, half_prior, [-0.1, -0.5], SERIES, n_iterations=200, scale=0.3,
               rng=np.random.default_rng(4))  # fmt: skip
    assert np.all(out.chain[:, 0, 0] <= 0.0)
    assert all(th[0] <= 0.0 for th in built)
    assert len(built) < 201  # some proposals fell outside and were never built


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"scale": -0.1}, "scale"),
        ({"scale": [0.1, 0.2, 0.3]}, "scale"),
        ({"burn_in": 100}, "burn_in"),
        ({"n_iterations": 0}, "n_iterations"),
        ({"theta0": [np.nan, 0.0]}, "theta0"),
        ({"theta0": [9.0, 9.0], "log_prior": lambda th: -np.inf}, "theta0"),
        ({"rng": 3}, "rng"),
        ({"log_prior": lambda th: np.nan}, "log_prior"),
    ],
)
def test_bad_input_names_the_field(kwargs, field):
    args = {
        "model": kalman_model, "log_prior": log_prior, "theta0": [0.0, 0.0],
        "measurements": SERIES, "n_iterations": 100, "rng": np.random.default_rng(0),
    }  # fmt: skip
    args.update(kwargs)
    with pytest.raises(ConfigError, match=field):
        pmmh(**args)


def test_proposal_covariance_forms():
    assert np.array_equal(proposal_covariance(0.5, 2), 0.25 * np.eye(2))
    assert np.allclose(proposal_covariance([0.1, 2.0], 2), np.diag([0.01, 4.0]), rtol=1e-15)
    cov = np.array([[1.0, 0.3], [0.3, 0.5]])
    assert np.array_equal(proposal_covariance(cov, 2), cov)
    with pytest.raises(ConfigError, match="scale"):
        proposal_covariance([[1.0, 2.0], [2.0, 1.0]], 2)  # not positive definite
