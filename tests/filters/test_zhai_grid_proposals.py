"""Galerkin and discretisation proposals (Zhai 2007, Algorithms 5-6)."""

import numpy as np
import pytest

from fusetrack.core import Gaussian, Measurement
from fusetrack.filters import KalmanFilter, run_filter
from fusetrack.filters.grid_proposals import (
    DiscretisationProposal,
    GalerkinProposal,
    galerkin_predict,
)
from fusetrack.filters.sis import ProposalParticleFilter
from fusetrack.motion import ConstantVelocity
from fusetrack.sensors import PositionFix


def test_galerkin_prediction_equals_direct_integration_1d():
    """Fourier-basis prediction == Δ Σ_n k(x_m - x_n) p(x_n) on the periodic grid (Eq. 74 corrected)."""
    n, a, b = 64, -8.0, 8.0
    dx = (b - a) / n
    x = a + dx * np.arange(n)
    p = np.exp(-0.5 * (x - 1.0) ** 2 / 0.7) + 0.5 * np.exp(-0.5 * (x + 3.0) ** 2 / 0.3)
    p /= p.sum() * dx
    offsets = (np.arange(n) - n // 2) * dx
    kern = lambda u: np.exp(-0.5 * (u - 0.4) ** 2 / 0.5) / np.sqrt(2 * np.pi * 0.5)  # noqa: E731
    direct = np.array(
        [
            dx
            * sum(
                kern(((x[m] - x[j] + (b - a) / 2) % (b - a)) - (b - a) / 2) * p[j] for j in range(n)
            )
            for m in range(n)
        ]
    )
    np.testing.assert_allclose(galerkin_predict(p, kern(offsets), dx), direct, atol=1e-12)
    # mass is preserved and, away from the border, it is the continuous Chapman-Kolmogorov result
    assert galerkin_predict(p, kern(offsets), dx).sum() * dx == pytest.approx(1.0, abs=1e-9)


def test_galerkin_prediction_2d_matches_a_shifted_gaussian():
    g, h = 64, 10.0
    d = 2 * h / g
    ax = -h + d * np.arange(g)
    X, Y = np.meshgrid(ax, ax, indexing="ij")
    p = np.exp(-0.5 * (X**2 + Y**2) / 1.0) / (2 * np.pi)
    off = (np.arange(g) - g // 2) * d
    OX, OY = np.meshgrid(off, off, indexing="ij")
    k = np.exp(-0.5 * ((OX - 1.0) ** 2 + OY**2) / 0.5) / (2 * np.pi * 0.5)
    out = galerkin_predict(p, k, d * d)
    want = np.exp(-0.5 * ((X - 1.0) ** 2 + Y**2) / 1.5) / (2 * np.pi * 1.5)
    assert np.max(np.abs(out - want)) < 1e-6


@pytest.mark.parametrize(
    "proposal",
    [
        GalerkinProposal(n_grid=60),
        GalerkinProposal(n_grid=16, prediction="mixture"),
        DiscretisationProposal(),
    ],
    ids=["galerkin", "mixture", "cells"],
)
def test_grid_proposals_keep_the_kalman_mean(proposal):
    """Linear-Gaussian CV + position fix: mean over 20 runs within 4 s.e. of the KF's after 6 steps."""
    motion = ConstantVelocity(q=0.5)
    sensor = PositionFix("p", cov=np.eye(2) * 2.0)
    prior = Gaussian(np.array([0.0, 0.0, 1.0, 0.5]), np.diag([4.0, 4.0, 1.0, 1.0]))
    zs = [[np.array([1.2 + k, 0.4 * k])] for k in range(6)]
    kf, b = KalmanFilter(motion, [sensor]), prior
    for k, (z,) in enumerate(zs):
        b = kf.update(kf.predict(b, 1.0), [Measurement(float(k), "p", z)])
    ests = []
    for r in range(20):
        f = ProposalParticleFilter(motion, [sensor], proposal, 200)
        ms = [Measurement(k + 1.0, "p", z) for k, (z,) in enumerate(zs)]
        ests.append(run_filter(f, prior, ms, rng=np.random.default_rng(r), t0=0.0).means[-1])
    ests = np.array(ests)
    se = ests.std(axis=0) / np.sqrt(len(ests))
    assert np.all(np.abs(ests.mean(axis=0) - b.mean) < 4 * se + 0.02), (ests.mean(axis=0), b.mean)


def test_a_grid_too_small_is_counted():
    """A measurement far outside the predicted window puts the posterior mass on the border."""
    motion = ConstantVelocity(q=0.01)
    sensor = PositionFix("p", cov=np.eye(2) * 0.01)
    f = ProposalParticleFilter(motion, [sensor], GalerkinProposal(n_grid=20, span=2.0), 100)
    rng = np.random.default_rng(0)
    s = f.initialize(Gaussian(np.zeros(4), np.eye(4) * 0.1), rng)
    s = f.step(s, 1.0, [Measurement(1.0, "p", [30.0, 0.0])], rng)
    assert f.stats.grid_too_small == 1
    assert np.all(np.isfinite(s.estimate))


def test_grid_proposals_refuse_batches():
    f = ProposalParticleFilter(
        ConstantVelocity(), [PositionFix("p", cov=np.eye(2))], GalerkinProposal(), 10
    )
    with pytest.raises(ValueError, match=r"particles\.shape"):
        f.initialize(Gaussian(np.zeros(4), np.eye(4)), np.random.default_rng(0), batch_shape=(3,))


def test_mixture_kernel_matches_numpy_reference() -> None:
    from fusetrack.filters.mixture_density import gaussian_mixture_ancestors

    rng = np.random.default_rng(7)
    x, means = rng.normal(size=(300, 2)) * 3, rng.normal(size=(250, 2)) * 3
    cov = np.array([[2.0, 0.3], [0.3, 0.5]])
    log_w = np.log(rng.dirichlet(np.ones(250)))
    u = rng.random(300)
    lse_n, anc_n = gaussian_mixture_ancestors(x, means, cov, log_w, u, engine="numba")
    lse_r, anc_r = gaussian_mixture_ancestors(x, means, cov, log_w, u, engine="numpy")
    np.testing.assert_allclose(lse_n, lse_r, rtol=1e-12)
    assert np.mean(anc_n == anc_r) > 0.99  # ties at the CDF boundary may differ by rounding
    # the mixture density by hand at one point
    from scipy.stats import multivariate_normal

    direct = np.log(
        sum(np.exp(lw) * multivariate_normal(m, cov).pdf(x[0]) for lw, m in zip(log_w, means))
    )
    assert lse_n[0] == pytest.approx(direct, rel=1e-10)
    # the ancestors follow the mixture responsibilities: chi-square on one point repeated
    xs = np.repeat(x[:1], 20000, axis=0)
    _, anc = gaussian_mixture_ancestors(xs, means[:5], cov, np.zeros(5), rng.random(20000))
    resp = np.array([multivariate_normal(m, cov).pdf(x[0]) for m in means[:5]])
    resp /= resp.sum()
    counts = np.bincount(anc, minlength=5)
    keep = resp > 1e-3
    chi2 = np.sum((counts[keep] - 20000 * resp[keep]) ** 2 / (20000 * resp[keep]))
    assert chi2 < 25.0
