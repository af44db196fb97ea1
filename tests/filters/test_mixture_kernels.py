"""Numba kernels of the Gaussian-mixture messages against their NumPy references and hand values."""

import numpy as np
from scipy.special import logsumexp
from scipy.stats import multivariate_normal as mvn

from fusetrack.filters.mixture_kernels import (
    component_log_terms,
    component_log_terms_reference,
    em_fit,
    em_fit_reference,
    em_responsibilities,
    em_responsibilities_reference,
    kde_log_density,
    kde_log_density_reference,
    log_sum_exp_rows,
    log_sum_exp_rows_reference,
    weighted_scatter,
    weighted_scatter_reference,
)


def _components(rng, k=3, d=3):
    a = rng.normal(size=(k, d, d)) * 0.5
    covs = a @ np.swapaxes(a, 1, 2) + 0.3 * np.eye(d)
    return rng.normal(0, 2, (k, d)), covs


def test_component_log_terms_equal_scipy_and_reference():
    rng = np.random.default_rng(0)
    means, covs = _components(rng)
    x = rng.normal(size=(40, 3))
    prec, logdet = np.linalg.inv(covs), np.linalg.slogdet(covs)[1]
    offset = np.log([0.2, 0.3, 0.5])
    got = component_log_terms(x, means, prec, logdet, offset)
    scipy_ref = np.stack([mvn(means[k], covs[k]).logpdf(x) for k in range(3)], 1) + offset
    np.testing.assert_allclose(got, scipy_ref, rtol=1e-12, atol=1e-10)
    np.testing.assert_allclose(
        got, component_log_terms_reference(x, means, prec, logdet, offset), rtol=1e-13
    )


def test_log_sum_exp_rows_hand_values_and_minus_infinity():
    a = np.array([[0.0, np.log(3.0)], [-np.inf, -np.inf], [1000.0, 1000.0], [-np.inf, 2.0]])
    got = log_sum_exp_rows(a)
    np.testing.assert_allclose(got[[0, 2, 3]], [np.log(4.0), 1000.0 + np.log(2.0), 2.0])
    assert got[1] == -np.inf
    np.testing.assert_array_equal(got, log_sum_exp_rows_reference(a))
    b = np.random.default_rng(1).normal(size=(20, 5)) * 30
    np.testing.assert_allclose(log_sum_exp_rows(b), logsumexp(b, axis=1), rtol=1e-14)


def test_em_responsibilities_sum_to_the_point_weights():
    rng = np.random.default_rng(2)
    logr = rng.normal(size=(30, 4)) * 5
    w = rng.uniform(size=30)
    w /= w.sum()
    loglik, r = em_responsibilities(logr, w)
    np.testing.assert_allclose(r.sum(1), w, rtol=1e-13)
    ref_ll, ref_r = em_responsibilities_reference(logr, w)
    np.testing.assert_allclose(loglik, ref_ll, rtol=1e-13)
    np.testing.assert_allclose(r, ref_r, rtol=1e-13)
    np.testing.assert_allclose(loglik, w @ logsumexp(logr, axis=1), rtol=1e-13)


def test_weighted_scatter_of_hand_points():
    # two points at +-1 on x with responsibilities 1 and 3 around mean 0: sum r x x^T = 4 e_x e_x^T
    x = np.array([[1.0, 0.0], [-1.0, 0.0]])
    r = np.array([[1.0], [3.0]])
    got = weighted_scatter(r, x, np.zeros((1, 2)))
    np.testing.assert_allclose(got, [[[4.0, 0.0], [0.0, 0.0]]])
    rng = np.random.default_rng(3)
    x, r, mu = rng.normal(size=(25, 3)), rng.uniform(size=(25, 2)), rng.normal(size=(2, 3))
    np.testing.assert_allclose(
        weighted_scatter(r, x, mu), weighted_scatter_reference(r, x, mu), rtol=1e-12
    )


def test_kde_log_density_of_one_point_is_a_gaussian():
    s = np.array([[0.5, -0.2, 1.0], [3.0, 0.0, 0.0]])
    got = kde_log_density(s, np.zeros((1, 3)), np.ones(1), 0.7)
    np.testing.assert_allclose(got, mvn(np.zeros(3), 0.49 * np.eye(3)).logpdf(s), rtol=1e-13)
    rng = np.random.default_rng(4)
    x, w = rng.normal(size=(60, 3)), rng.uniform(size=60)
    w[5] = 0.0  # a zero weight contributes nothing
    w /= w.sum()
    s = rng.normal(size=(30, 3)) * 2
    np.testing.assert_allclose(
        kde_log_density(s, x, w, 0.3), kde_log_density_reference(s, x, w, 0.3), rtol=1e-12
    )


def test_em_fit_matches_reference_and_separates_two_clusters():
    rng = np.random.default_rng(5)
    x = np.vstack([rng.normal(-3, 0.5, (80, 2)), rng.normal(3, 1.0, (120, 2))])
    w = np.full(200, 1 / 200)
    means = np.array([[-1.0, 0.0], [1.0, 0.0]])
    covs = np.repeat(np.eye(2)[None] * 4, 2, axis=0)
    mix, mu, cov = em_fit(x, w, means, covs, 50)
    rmix, rmu, rcov = em_fit_reference(x, w, means, covs, 50)
    np.testing.assert_allclose(mix, rmix, rtol=1e-10)
    np.testing.assert_allclose(mu, rmu, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(cov, rcov, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(mix, [0.4, 0.6], atol=1e-6)  # the clusters' shares of the points
    np.testing.assert_allclose(mu[0], x[:80].mean(0), atol=1e-6)
    np.testing.assert_allclose(mu[1], x[80:].mean(0), atol=1e-6)


def test_em_fit_drops_a_component_without_responsibility_and_floors_covariances():
    x = np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]])  # a degenerate cloud
    w = np.full(3, 1 / 3)
    means = np.array([[0.0, 0.0], [1e3, 1e3]])
    covs = np.repeat(np.eye(2)[None], 2, axis=0)
    mix, mu, cov = em_fit(x, w, means, covs, 20, min_var=1e-6)
    np.testing.assert_allclose(mix, [1.0])
    np.testing.assert_allclose(mu, [[0.0, 0.0]])
    np.testing.assert_allclose(cov, [1e-6 * np.eye(2)])
    *_, rcov = em_fit_reference(x, w, means, covs, 20, min_var=1e-6)
    np.testing.assert_allclose(cov, rcov)
