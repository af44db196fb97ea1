import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.stats import multivariate_normal

from fusetrack.core import Gaussian, GaussianMixture, GridBelief, Particles, ShapeError


def test_gaussian_logpdf_matches_scipy():
    mean = np.array([1.0, -2.0])
    cov = np.array([[2.0, 0.3], [0.3, 0.5]])
    x = np.array([[0.0, 0.0], [1.5, -1.0]])
    np.testing.assert_allclose(
        Gaussian(mean, cov).logpdf(x), multivariate_normal(mean, cov).logpdf(x)
    )


def test_gaussian_sample_moments():
    cov = np.array([[2.0, 0.3], [0.3, 0.5]])
    s = Gaussian(np.array([1.0, -2.0]), cov).sample(np.random.default_rng(0), 200_000)
    np.testing.assert_allclose(s.mean(0), [1.0, -2.0], atol=0.01)
    np.testing.assert_allclose(np.cov(s.T), cov, atol=0.02)


def test_gaussian_rejects_mismatched_cov():
    with pytest.raises(ShapeError, match=r"cov\.shape"):
        Gaussian(np.zeros(3), np.eye(2))


def test_particles_moments_hand_computed():
    states = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 4.0]])
    w = np.array([0.5, 0.25, 0.25])
    p = Particles(states, np.log(w) + 7.0)  # unnormalised log-weights are fine
    np.testing.assert_allclose(p.weights, w)
    np.testing.assert_allclose(p.mean, [0.5, 1.0])
    r = states - [0.5, 1.0]
    np.testing.assert_allclose(p.cov, (w[:, None, None] * r[:, :, None] * r[:, None, :]).sum(0))
    np.testing.assert_allclose(p.ess, 1 / np.sum(w**2))


def test_particles_batched_axes_are_independent():
    rng = np.random.default_rng(1)
    states = rng.normal(size=(3, 50, 2))
    lw = rng.normal(size=(3, 50))
    p = Particles(states, lw)
    for r in range(3):
        q = Particles(states[r], lw[r])
        np.testing.assert_allclose(p.mean[r], q.mean)
        np.testing.assert_allclose(p.cov[r], q.cov)
        np.testing.assert_allclose(p.ess[r], q.ess)


def test_particles_resample_keeps_mean_in_expectation():
    rng = np.random.default_rng(2)
    states = rng.normal(size=(1000, 1))
    lw = -0.5 * (states[:, 0] - 1.0) ** 2
    p = Particles(states, lw)
    means = [p.resample(rng).mean[0] for _ in range(200)]
    assert abs(np.mean(means) - p.mean[0]) < 3 * np.std(means) / np.sqrt(200) + 1e-12
    r = p.resample(rng)
    np.testing.assert_allclose(r.weights, 1 / 1000)


@settings(max_examples=50, deadline=None)
@given(arrays(np.float64, st.integers(1, 40), elements=st.floats(-700, 700)))
def test_weights_normalised_and_ess_in_range(lw):
    p = Particles(np.zeros((lw.size, 1)), lw)
    assert np.isclose(p.weights.sum(), 1.0)
    assert 1.0 - 1e-9 <= p.ess <= lw.size + 1e-9
    assert np.isfinite(p.normalized().log_weights).all()


def test_grid_belief_moments():
    x = np.linspace(-5, 5, 201)
    y = np.linspace(-8, 12, 401)
    X, Y = np.meshgrid(x, y, indexing="ij")
    lp = -0.5 * ((X - 1) ** 2 / 0.5 + (Y - 2) ** 2 / 2.0)
    g = GridBelief((x, y), lp).normalized()
    np.testing.assert_allclose(g.mean, [1.0, 2.0], atol=1e-6)
    np.testing.assert_allclose(g.cov, np.diag([0.5, 2.0]), atol=2e-3)
    np.testing.assert_allclose(g.map_estimate, [1.0, 2.0])
    with pytest.raises(ShapeError, match="one entry per grid cell"):
        GridBelief((x, y), lp[:-1])


def test_gaussian_mixture_moment_matching():
    gm = GaussianMixture(
        np.array([0.3, 0.7]),
        np.array([[0.0, 0.0], [2.0, 1.0]]),
        np.stack([np.eye(2), 0.5 * np.eye(2)]),
    )
    s = gm.sample(np.random.default_rng(3), 300_000)
    np.testing.assert_allclose(gm.mean, [1.4, 0.7])
    np.testing.assert_allclose(s.mean(0), gm.mean, atol=0.01)
    np.testing.assert_allclose(np.cov(s.T), gm.cov, atol=0.02)
    x = np.array([0.5, 0.5])
    direct = np.log(
        0.3 * multivariate_normal([0, 0], np.eye(2)).pdf(x)
        + 0.7 * multivariate_normal([2, 1], 0.5 * np.eye(2)).pdf(x)
    )
    np.testing.assert_allclose(gm.logpdf(x), direct)
    with pytest.raises(ShapeError, match="summing to 1"):
        GaussianMixture(np.array([0.5, 0.6]), np.zeros((2, 1)), np.ones((2, 1, 1)))
