"""Gaussian-mixture messages of the smart-camera trackers (Kushwaha 2010, Ch. V, Eqs. 85-93).

* :func:`fit_kde_mixture` -- a weighted particle set's kernel density (Eq. 85) compressed to a
  mixture of order ``m <= m_max`` chosen by the Kullback-Leibler divergence (Eq. 86);
* :func:`mixture_product` -- the product of two mixtures, one component per pair (Eq. 88);
* :func:`reduce_mixture` -- the modified k-means that merges components by moment matching
  (Eqs. 89-93);
* :func:`mixture_mode` -- the highest mode by fixed-point search from the component means (Eq. 87).

Mixtures are :class:`fusetrack.core.GaussianMixture` values. Covariances are kept positive
definite (a floor on the eigenvalues), so a degenerate particle cloud gives a usable message.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import logsumexp

from ..core import ConfigError, GaussianMixture, invalid
from .mixture_kernels import (
    component_log_terms,
    em_fit,
    kde_log_density,
    log_sum_exp_rows,
)

Array = NDArray[np.float64]

MIN_VAR = 1e-8  # eigenvalue floor of every covariance (m^2 or px^2)


def floor_covariances(covs: ArrayLike, min_var: float = MIN_VAR) -> Array:
    """Symmetrise and lift the eigenvalues of ``(..., d, d)`` covariances to at least ``min_var``."""
    c = np.asarray(covs, float)
    c = 0.5 * (c + np.swapaxes(c, -1, -2))
    vals, vecs = np.linalg.eigh(c)
    vals = np.fmax(vals, min_var)  # NaN -> min_var
    return np.einsum("...ij,...j,...kj->...ik", vecs, vals, vecs)


def component_logpdf(x: ArrayLike, means: ArrayLike, covs: ArrayLike) -> Array:
    """``log N(x_n | mu_k, S_k)`` as ``(N, K)`` for points ``(N, d)`` and ``K`` components."""
    x = np.asarray(x, float)
    c = np.asarray(covs, float)
    prec = np.linalg.inv(c)
    logdet = np.linalg.slogdet(c)[1]
    return component_log_terms(x, np.asarray(means, float), prec, logdet, np.zeros(len(c)))


def mixture_logpdf(gm: GaussianMixture, x: ArrayLike) -> Array:
    """``log sum_k w_k N(x | mu_k, S_k)`` for points ``(N, d)``."""
    c = np.asarray(gm.covs, float)
    with np.errstate(divide="ignore"):
        log_w = np.log(gm.weights)
    terms = component_log_terms(
        np.asarray(x, float), gm.means, np.linalg.inv(c), np.linalg.slogdet(c)[1], log_w
    )
    return log_sum_exp_rows(terms)


def weighted_em(
    points: ArrayLike,
    weights: ArrayLike,
    k: int,
    rng: np.random.Generator,
    iterations: int = 20,
    extra_cov: ArrayLike | None = None,
) -> GaussianMixture:
    """EM for a ``k``-component mixture of weighted points; ``extra_cov`` (the kernel of a KDE)
    is added to every fitted covariance, which makes the mixture approximate the KDE itself."""
    x = np.asarray(points, float)
    w = np.asarray(weights, float)
    w = w / w.sum()
    n, d = x.shape
    extra = np.zeros((d, d)) if extra_cov is None else np.asarray(extra_cov, float)
    k = min(int(k), int(np.count_nonzero(w > 0)))
    # k-means++ seeding by weight: each new mean drawn with probability ~ w_i * (distance to the
    # nearest chosen mean)^2, so the seeds spread over the modes
    means = x[[rng.choice(n, p=w)]]
    for _ in range(1, k):
        d2 = np.min(np.sum((x[:, None, :] - means[None]) ** 2, axis=-1), axis=1) * w
        if d2.sum() <= 0:
            break
        means = np.vstack([means, x[rng.choice(n, p=d2 / d2.sum())]])
    k = len(means)
    spread = np.cov(x.T, aweights=w) if n > 1 else np.eye(d)
    covs = np.repeat(floor_covariances(np.atleast_2d(spread))[None], k, axis=0)
    mix, means, covs = em_fit(x, w, means, covs, iterations, min_var=1e-6)
    return GaussianMixture(mix, means, floor_covariances(covs + extra))


def kde_bandwidth(points: ArrayLike, weights: ArrayLike) -> float:
    """Silverman's rule on weighted points: ``h = sigma (4 / ((d + 2) n_eff))^(1 / (d + 4))``."""
    x = np.asarray(points, float)
    w = np.asarray(weights, float)
    w = w / w.sum()
    d = x.shape[1]
    n_eff = 1.0 / np.sum(w * w)
    sigma = np.sqrt(np.mean(np.diag(np.atleast_2d(np.cov(x.T, aweights=w))))) if len(x) > 1 else 0
    return float(max(sigma, 1e-6) * (4.0 / ((d + 2) * n_eff)) ** (1.0 / (d + 4)))


def fit_kde_mixture(
    points: ArrayLike,
    weights: ArrayLike,
    rng: np.random.Generator,
    m_max: int = 5,
    bandwidth: float | None = None,
    kl_samples: int = 1000,
    kl_tolerance: float = 0.05,
) -> tuple[GaussianMixture, list[float]]:
    """Compress the weighted KDE ``sum_i w_i N(x; x_i, h^2 I)`` (Eq. 85) to a mixture.

    Orders ``m = 1..m_max`` are fitted by EM; the KL divergence ``KL(kde || g_m)`` is estimated
    with ``kl_samples`` draws from the KDE (Eq. 86). The paper takes the argmin, which always
    favours the largest order (KL does not grow with m); here the smallest order whose KL is
    within ``kl_tolerance`` nats of the smallest KL is chosen (spec A-V-4), and the search stops
    at the first order that improves the KL by less than ``kl_tolerance``. Particles with a weight
    below ``1e-3`` of the largest are dropped first. Returns the mixture and the KLs computed.
    """
    x = np.asarray(points, float)
    w = np.asarray(weights, float)
    if x.ndim != 2 or w.shape != x.shape[:1] or not np.all(np.isfinite(w)) or w.sum() <= 0:
        raise ConfigError(invalid("weights", w.shape, "finite non-negative weights, not all zero"))
    w = w / w.sum()
    keep = w > 1e-3 * w.max()
    x, w = x[keep], w[keep] / w[keep].sum()
    d = x.shape[1]
    h = kde_bandwidth(x, w) if bandwidth is None else float(bandwidth)
    kernel = h * h * np.eye(d)
    idx = rng.choice(len(w), size=kl_samples, p=w)
    s = x[idx] + h * rng.standard_normal((kl_samples, d))
    log_kde = kde_log_density(s, x, w, h)
    fits, kls = [], []
    for m in range(1, max(1, m_max) + 1):
        gm = weighted_em(x, w, m, rng, extra_cov=kernel)
        fits.append(gm)
        kls.append(float(np.mean(log_kde - mixture_logpdf(gm, s))))
        if len(gm.weights) < m:  # fewer distinct points than components
            break
        if m > 1 and kls[-2] - kls[-1] < kl_tolerance:
            break
    best = min(kls)
    chosen = next(i for i, kl in enumerate(kls) if kl <= best + kl_tolerance)
    return fits[chosen], kls


def mixture_product(a: GaussianMixture, b: GaussianMixture) -> GaussianMixture:
    """Normalised product of two mixtures (Kushwaha 2010, Eq. 88): components
    ``S_ij = (V_i^-1 + W_j^-1)^-1``, ``xi_ij = S_ij (V_i^-1 mu_i + W_j^-1 lambda_j)`` and weights
    ``alpha_i beta_j N(mu_i | lambda_j, V_i + W_j)`` (the paper's ``gamma_ij`` written stably)."""
    vi = np.linalg.inv(a.covs)  # (I, d, d)
    wi = np.linalg.inv(b.covs)  # (J, d, d)
    prec = vi[:, None] + wi[None, :]
    cov = floor_covariances(np.linalg.inv(prec))
    rhs = np.einsum("iab,ib->ia", vi, a.means)[:, None] + np.einsum("jab,jb->ja", wi, b.means)[None]
    mean = np.einsum("ijab,ijb->ija", cov, rhs)
    s = a.covs[:, None] + b.covs[None, :]
    r = a.means[:, None] - b.means[None, :]
    L = np.linalg.cholesky(s)
    z = np.linalg.solve(L, r[..., None])[..., 0]
    d = a.dim
    logn = -0.5 * (
        np.sum(z * z, -1)
        + 2 * np.log(np.diagonal(L, axis1=-2, axis2=-1)).sum(-1)
        + d * np.log(2 * np.pi)
    )
    with np.errstate(divide="ignore"):
        logw = np.log(a.weights)[:, None] + np.log(b.weights)[None, :] + logn
    w = np.exp(logw - logsumexp(logw)).ravel()
    return GaussianMixture(w / w.sum(), mean.reshape(-1, d), cov.reshape(-1, d, d))


def prune_mixture(
    gm: GaussianMixture, max_components: int, min_weight: float = 1e-9
) -> GaussianMixture:
    """Keep the ``max_components`` heaviest components above ``min_weight`` (renormalised)."""
    order = np.argsort(-gm.weights)[:max_components]
    order = order[gm.weights[order] >= min_weight * gm.weights[order[0]]]
    w = gm.weights[order]
    return GaussianMixture(w / w.sum(), gm.means[order], gm.covs[order])


def reduce_mixture(
    gm: GaussianMixture,
    k: int,
    rng: np.random.Generator,
    tolerance: float = 1e-4,
    iterations: int = 50,
) -> GaussianMixture:
    """The modified k-means of Kushwaha 2010, Eqs. 89-93: ``k`` heads drawn from the components,
    distance ``(mu_i - lambda_j)^T (V_i^-1 + W_j^-1) (mu_i - lambda_j)``, moment-matched merge
    ``W_j = sum alpha_i (V_i + mu_i mu_i^T) / beta_j - lambda_j lambda_j^T`` (Eq. 93 prints the
    inner products ``mu_i^T mu_i``; the outer products are what preserves the covariance).
    Stops when ``sum_j |beta_j - beta_j^0| <= tolerance``; an empty cluster is re-seeded from the
    heaviest component. Total weight, mean and covariance are preserved."""
    n = len(gm.weights)
    if n <= k:
        return gm
    heads = rng.choice(n, size=k, replace=False, p=gm.weights)
    lam, W = gm.means[heads].copy(), gm.covs[heads].copy()
    vinv = np.linalg.inv(gm.covs)
    beta_old = np.zeros(k)
    assign = np.zeros(n, dtype=int)
    for _ in range(iterations):
        winv = np.linalg.inv(W)
        r = gm.means[:, None] - lam[None]  # (n, k, d)
        dist = np.einsum("nki,nkij,nkj->nk", r, vinv[:, None] + winv[None], r)
        assign = np.argmin(dist, axis=1)
        counts = np.bincount(assign, minlength=k)
        for j in np.flatnonzero(counts == 0):  # re-seed an empty cluster
            movable = np.flatnonzero(counts[assign] > 1)
            if movable.size == 0:
                break
            i = movable[np.argmax(gm.weights[movable])]
            counts[assign[i]] -= 1
            assign[i] = j
            counts[j] += 1
        onehot = np.eye(k)[assign] * gm.weights[:, None]  # (n, k)
        beta = onehot.sum(0)
        lam = (onehot.T @ gm.means) / beta[:, None]
        second = gm.covs + gm.means[:, :, None] * gm.means[:, None, :]
        W = floor_covariances(
            np.einsum("nk,nij->kij", onehot, second) / beta[:, None, None]
            - lam[:, :, None] * lam[:, None, :]
        )
        if np.sum(np.abs(beta - beta_old)) <= tolerance:
            break
        beta_old = beta
    keep = beta > 0
    return GaussianMixture(beta[keep] / beta[keep].sum(), lam[keep], W[keep])


def mixture_mode(gm: GaussianMixture, iterations: int = 50, max_starts: int = 20) -> Array:
    """``argmax_x sum_k w_k N(x | mu_k, S_k)`` (Eq. 87) by the fixed point
    ``x <- (sum_k r_k S_k^-1)^-1 sum_k r_k S_k^-1 mu_k`` from the heaviest component means."""
    prec = np.linalg.inv(gm.covs)
    pm = np.einsum("kij,kj->ki", prec, gm.means)
    starts = gm.means[np.argsort(-gm.weights)[:max_starts]]
    x = starts.copy()
    with np.errstate(divide="ignore"):
        logw = np.log(gm.weights)
    for _ in range(iterations):
        lr = component_logpdf(x, gm.means, gm.covs) + logw  # (S, K)
        r = np.exp(lr - lr.max(axis=1, keepdims=True))
        A = np.einsum("sk,kij->sij", r, prec)
        b = r @ pm
        x_new = np.linalg.solve(A, b[..., None])[..., 0]
        if np.max(np.abs(x_new - x)) < 1e-7:
            x = x_new
            break
        x = x_new
    return x[int(np.argmax(mixture_logpdf(gm, x)))]
