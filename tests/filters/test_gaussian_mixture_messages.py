"""Gaussian-mixture messages of the smart-camera trackers (Kushwaha 2010, Ch. V, Eqs. 85-93)."""

import numpy as np
from scipy.stats import multivariate_normal as mvn

from fusetrack.core import GaussianMixture
from fusetrack.filters.gaussian_mixtures import (
    component_logpdf,
    fit_kde_mixture,
    floor_covariances,
    mixture_mode,
    mixture_product,
    reduce_mixture,
)


def _gm(rng, k, d, spread=2.0):
    w = rng.uniform(0.2, 1.0, k)
    a = rng.normal(size=(k, d, d)) * 0.5
    return GaussianMixture(
        w / w.sum(), rng.normal(0, spread, (k, d)), a @ np.swapaxes(a, 1, 2) + 0.3 * np.eye(d)
    )


def test_component_logpdf_equals_scipy():
    rng = np.random.default_rng(0)
    g = _gm(rng, 3, 3)
    x = rng.normal(size=(50, 3))
    ref = np.stack([mvn(g.means[k], g.covs[k]).logpdf(x) for k in range(3)], 1)
    np.testing.assert_allclose(component_logpdf(x, g.means, g.covs), ref, atol=1e-10)


def test_product_equals_numerical_integration_on_a_grid():
    # Eq. 88: normalised product of two 2-D mixtures against the product of densities on a grid
    rng = np.random.default_rng(3)
    a, b = _gm(rng, 2, 2, 1.0), _gm(rng, 3, 2, 1.0)
    prod = mixture_product(a, b)
    assert len(prod.weights) == 6
    axis = np.linspace(-8, 8, 321)
    xx, yy = np.meshgrid(axis, axis, indexing="ij")
    pts = np.stack([xx.ravel(), yy.ravel()], 1)
    dens = np.exp(a.logpdf(pts) + b.logpdf(pts))
    cell = (axis[1] - axis[0]) ** 2
    dens /= dens.sum() * cell
    np.testing.assert_allclose(np.exp(prod.logpdf(pts)), dens, atol=2e-4 * dens.max())
    mean = (dens[:, None] * pts).sum(0) * cell
    np.testing.assert_allclose(prod.mean, mean, atol=1e-6)


def test_reduction_to_one_component_matches_moments_and_keeps_weight():
    rng = np.random.default_rng(4)
    g = _gm(rng, 7, 3)
    one = reduce_mixture(g, 1, rng)
    np.testing.assert_allclose(one.weights, [1.0])
    np.testing.assert_allclose(one.means[0], g.mean, atol=1e-12)
    np.testing.assert_allclose(one.covs[0], g.cov, atol=1e-10)
    four = reduce_mixture(g, 4, rng)
    assert len(four.weights) <= 4
    np.testing.assert_allclose(four.mean, g.mean, atol=1e-10)
    np.testing.assert_allclose(four.cov, g.cov, atol=1e-9)


def test_singular_covariances_are_floored_not_nan():
    c = np.zeros((2, 3, 3))
    c[0, 0, 0] = 1.0
    fixed = floor_covariances(c)
    assert np.all(np.linalg.eigvalsh(fixed) > 0)
    g = GaussianMixture(np.array([0.5, 0.5]), np.zeros((2, 3)), fixed)
    p = mixture_product(g, g)
    assert np.all(np.isfinite(p.means)) and np.all(np.isfinite(p.weights))
    assert np.all(np.isfinite(mixture_mode(p)))


def test_kde_fit_finds_two_clusters_and_one_for_one():
    rng = np.random.default_rng(5)
    x = np.vstack([rng.normal([0, 0, 0], 0.1, (400, 3)), rng.normal([2, 0, 0], 0.1, (400, 3))])
    gm, _ = fit_kde_mixture(x, np.ones(len(x)), rng)
    assert len(gm.weights) == 2
    np.testing.assert_allclose(np.sort(gm.means[:, 0]), [0, 2], atol=0.05)
    single, _ = fit_kde_mixture(x[:400], np.ones(400), rng)
    assert len(single.weights) == 1
    # all particles on one point: a degenerate cloud still gives a finite message
    same, _ = fit_kde_mixture(np.ones((50, 3)), np.ones(50), rng)
    assert np.all(np.isfinite(same.covs)) and np.allclose(same.means, 1.0)


def test_mode_of_a_two_component_mixture():
    g = GaussianMixture(
        np.array([0.3, 0.7]), np.array([[0.0, 0.0], [3.0, 1.0]]), np.stack([np.eye(2)] * 2) * 0.2
    )
    np.testing.assert_allclose(mixture_mode(g), [3.0, 1.0], atol=1e-3)
