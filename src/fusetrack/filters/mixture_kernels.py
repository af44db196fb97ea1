"""Numba kernels for the Gaussian-mixture messages' inner loops (Kushwaha 2010, Ch. V, Eqs. 85-86).

The smart-camera trackers compress a weighted particle set to a mixture by EM and score each
order by a Monte Carlo KL divergence against the particles' kernel density
(:func:`fusetrack.filters.gaussian_mixtures.fit_kde_mixture`). Profiling setups A and B put half
of a run's time in those loops, which NumPy did as several passes over ``(N, K)`` and
``(S, N)`` temporaries. Each kernel here is one pass over points and components, with the
straightforward NumPy reference it must match beside it (the tests compare them, to rounding):

* :func:`component_log_terms` -- ``log N(x_n | mu_k, S_k) + c_k`` as ``(N, K)`` from the
  components' precision matrices and log-determinants (``(x - mu)^T S^-1 (x - mu)`` directly);
* :func:`log_sum_exp_rows` -- ``log sum_k exp(a_nk)`` per row, shifted by the row's maximum;
* :func:`em_responsibilities` -- the E-step: the weighted log-likelihood ``sum_n w_n log p(x_n)``
  and the weighted responsibilities ``w_n r_nk`` (Bishop 2006, Eqs. 9.23 and 9.28);
* :func:`weighted_scatter` -- ``sum_n r_nk (x_n - mu_k)(x_n - mu_k)^T`` (Bishop 2006, Eq. 9.25);
* :func:`em_fit` -- the whole EM loop (E-step, M-step, covariance floor) in one call;
* :func:`kde_log_density` -- ``log sum_j w_j N(s_i | x_j, h^2 I)`` of a weighted isotropic
  kernel density (Eq. 85) at sample points, without the ``(S, N)`` distance matrix.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

LOG_2PI = math.log(2.0 * math.pi)


@numba.njit(cache=True, nogil=True)
def _component_log_terms(x, means, prec, logdet, offset, out):  # pragma: no cover - jit
    n, d = x.shape
    k = means.shape[0]
    diff = np.empty(d)
    for j in range(k):
        const = logdet[j] + d * LOG_2PI
        for i in range(n):
            for a in range(d):
                diff[a] = x[i, a] - means[j, a]
            maha = 0.0
            for a in range(d):
                t = 0.0
                for b in range(d):
                    t += prec[j, a, b] * diff[b]
                maha += diff[a] * t
            out[i, j] = -0.5 * (max(maha, 0.0) + const) + offset[j]


def component_log_terms(x: Array, means: Array, prec: Array, logdet: Array, offset: Array) -> Array:
    """``log N(x_n | mu_k, S_k) + offset_k`` ``(N, K)`` for points ``(N, d)``, means ``(K, d)``,
    precisions ``S_k^-1`` ``(K, d, d)`` and ``log det S_k`` ``(K,)``."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    out = np.empty((x.shape[0], len(means)))
    _component_log_terms(
        x,
        np.ascontiguousarray(means, dtype=np.float64),
        np.ascontiguousarray(prec, dtype=np.float64),
        np.ascontiguousarray(logdet, dtype=np.float64),
        np.ascontiguousarray(offset, dtype=np.float64),
        out,
    )
    return out


def component_log_terms_reference(
    x: Array, means: Array, prec: Array, logdet: Array, offset: Array
) -> Array:
    """Readable NumPy version of :func:`component_log_terms`."""
    diff = x[:, None, :] - means[None]
    maha = np.einsum("nki,kij,nkj->nk", diff, prec, diff)
    d = x.shape[1]
    return -0.5 * (np.maximum(maha, 0.0) + logdet + d * LOG_2PI) + offset


@numba.njit(cache=True, nogil=True)
def _lse_row(a, i):  # pragma: no cover - jit
    k = a.shape[1]
    m = -np.inf
    for j in range(k):
        if a[i, j] > m:
            m = a[i, j]
    if not math.isfinite(m):
        m = 0.0
    s = 0.0
    for j in range(k):
        s += math.exp(a[i, j] - m)
    return np.log(s) + m


@numba.njit(cache=True, nogil=True)
def _log_sum_exp_rows(a, out):  # pragma: no cover - jit
    for i in range(a.shape[0]):
        out[i] = _lse_row(a, i)


def log_sum_exp_rows(a: Array) -> Array:
    """``log sum_k exp(a_nk)`` ``(N,)`` of ``(N, K)``, shifted by each row's finite maximum
    (a row of ``-inf`` gives ``-inf``)."""
    a = np.ascontiguousarray(a, dtype=np.float64)
    out = np.empty(a.shape[0])
    _log_sum_exp_rows(a, out)
    return out


def log_sum_exp_rows_reference(a: Array) -> Array:
    """Readable NumPy version of :func:`log_sum_exp_rows`."""
    m = np.max(a, axis=1, keepdims=True)
    m = np.where(np.isfinite(m), m, 0.0)
    with np.errstate(divide="ignore"):
        return np.log(np.sum(np.exp(a - m), axis=1)) + m[:, 0]


@numba.njit(cache=True, nogil=True)
def _em_responsibilities(logr, w, r):  # pragma: no cover - jit
    n, k = logr.shape
    loglik = 0.0
    for i in range(n):
        norm = _lse_row(logr, i)
        loglik += w[i] * norm
        for j in range(k):
            r[i, j] = math.exp(logr[i, j] - norm) * w[i]
    return loglik


def em_responsibilities(logr: Array, w: Array) -> tuple[float, Array]:
    """E-step from ``logr = log(pi_k N(x_n | mu_k, S_k))`` ``(N, K)`` and point weights ``w``:
    ``(sum_n w_n log sum_k exp(logr_nk), w_n r_nk)`` (Bishop 2006, Eqs. 9.23, 9.28)."""
    logr = np.ascontiguousarray(logr, dtype=np.float64)
    r = np.empty_like(logr)
    loglik = _em_responsibilities(logr, np.ascontiguousarray(w, dtype=np.float64), r)
    return float(loglik), r


def em_responsibilities_reference(logr: Array, w: Array) -> tuple[float, Array]:
    """Readable NumPy version of :func:`em_responsibilities`."""
    norm = log_sum_exp_rows_reference(logr)
    return float(w @ norm), np.exp(logr - norm[:, None]) * w[:, None]


@numba.njit(cache=True, nogil=True)
def _weighted_scatter(r, x, means, out):  # pragma: no cover - jit
    n, d = x.shape
    k = means.shape[0]
    diff = np.empty(d)
    for j in range(k):
        for i in range(n):
            rij = r[i, j]
            for a in range(d):
                diff[a] = x[i, a] - means[j, a]
            for a in range(d):
                ra = rij * diff[a]
                for b in range(d):
                    out[j, a, b] += ra * diff[b]


def weighted_scatter(r: Array, x: Array, means: Array) -> Array:
    """``sum_n r_nk (x_n - mu_k)(x_n - mu_k)^T`` ``(K, d, d)`` (Bishop 2006, Eq. 9.25 before
    the division by ``N_k``)."""
    means = np.ascontiguousarray(means, dtype=np.float64)
    out = np.zeros((means.shape[0], means.shape[1], means.shape[1]))
    _weighted_scatter(
        np.ascontiguousarray(r, dtype=np.float64),
        np.ascontiguousarray(x, dtype=np.float64),
        means,
        out,
    )
    return out


def weighted_scatter_reference(r: Array, x: Array, means: Array) -> Array:
    """Readable NumPy version of :func:`weighted_scatter`."""
    diff = x[None, :, :] - means[:, None, :]
    return np.einsum("nk,kni,knj->kij", r, diff, diff)


@numba.njit(cache=True, nogil=True)
def _floor_symmetric(c, min_var, out):  # pragma: no cover - jit
    """``out[j]`` = ``c[j]`` symmetrised, eigenvalues lifted to ``min_var`` (NaN -> ``min_var``)."""
    d = c.shape[1]
    for j in range(c.shape[0]):
        vals, vecs = np.linalg.eigh(0.5 * (c[j] + c[j].T))
        for a in range(d):
            if not vals[a] >= min_var:
                vals[a] = min_var
        for a in range(d):
            for b in range(d):
                t = 0.0
                for e in range(d):
                    t += vecs[a, e] * vals[e] * vecs[b, e]
                out[j, a, b] = t


@numba.njit(cache=True, nogil=True)
def _em_fit(x, w, means, covs, iterations, min_var):  # pragma: no cover - jit
    n, d = x.shape
    k = means.shape[0]
    mix = np.full(k, 1.0 / k)
    last = -np.inf
    for _ in range(iterations):
        prec = np.empty((k, d, d))
        logdet = np.empty(k)
        for j in range(k):
            prec[j] = np.linalg.inv(covs[j])
            logdet[j] = np.linalg.slogdet(covs[j])[1]
        logr = np.empty((n, k))
        _component_log_terms(x, means, prec, logdet, np.log(mix), logr)
        r = np.empty((n, k))
        loglik = _em_responsibilities(logr, w, r)
        if loglik - last < 1e-4:
            break
        last = loglik
        nk = r.sum(axis=0)
        keep = np.flatnonzero(nk > 1e-12)
        k = len(keep)
        r = np.ascontiguousarray(r[:, keep])
        nk = nk[keep]
        mix = nk / nk.sum()
        means = np.empty((k, d))
        for j in range(k):
            for a in range(d):
                t = 0.0
                for i in range(n):
                    t += r[i, j] * x[i, a]
                means[j, a] = t / nk[j]
        scatter = np.zeros((k, d, d))
        _weighted_scatter(r, x, means, scatter)
        for j in range(k):
            scatter[j] /= nk[j]
        covs = np.empty((k, d, d))
        _floor_symmetric(scatter, min_var, covs)
    return mix, means, covs


def em_fit(
    x: Array, w: Array, means: Array, covs: Array, iterations: int, min_var: float = 1e-6
) -> tuple[Array, Array, Array]:
    """EM for a mixture of weighted points ``x`` ``(N, d)`` (weights ``w`` summing to 1) from
    initial ``means`` ``(K, d)``, ``covs`` ``(K, d, d)`` and equal mixing weights, until the
    weighted log-likelihood gains less than ``1e-4`` or after ``iterations`` (Bishop 2006,
    Sec. 9.2.2). Components whose responsibility vanishes are dropped; the fitted covariances'
    eigenvalues are floored at ``min_var``. Returns ``(mix, means, covs)``."""
    mix, mu, cov = _em_fit(
        np.ascontiguousarray(x, dtype=np.float64),
        np.ascontiguousarray(w, dtype=np.float64),
        np.ascontiguousarray(means, dtype=np.float64),
        np.ascontiguousarray(covs, dtype=np.float64),
        int(iterations),
        float(min_var),
    )
    return mix, mu, cov


def _floor_reference(c: Array, min_var: float) -> Array:
    vals, vecs = np.linalg.eigh(0.5 * (c + np.swapaxes(c, -1, -2)))
    return np.einsum("...ij,...j,...kj->...ik", vecs, np.fmax(vals, min_var), vecs)


def em_fit_reference(
    x: Array, w: Array, means: Array, covs: Array, iterations: int, min_var: float = 1e-6
) -> tuple[Array, Array, Array]:
    """Readable NumPy version of :func:`em_fit`."""
    mix = np.full(len(means), 1.0 / len(means))
    last = -np.inf
    for _ in range(iterations):
        prec = np.asarray(np.linalg.inv(covs), dtype=np.float64)
        logdet = np.linalg.slogdet(covs)[1]
        terms = component_log_terms_reference(x, means, prec, logdet, np.log(mix))
        loglik, r = em_responsibilities_reference(terms, w)
        if loglik - last < 1e-4:
            break
        last = loglik
        nk = r.sum(0)
        keep = nk > 1e-12
        r, nk = r[:, keep], nk[keep]
        mix = nk / nk.sum()
        means = (r.T @ x) / nk[:, None]
        covs = _floor_reference(
            weighted_scatter_reference(r, x, means) / nk[:, None, None], min_var
        )
    return mix, means, covs


@numba.njit(cache=True, nogil=True)
def _kde_log_density(s, x, log_w, h, out):  # pragma: no cover - jit
    m_s, d = s.shape
    n = x.shape[0]
    inv2h2 = 0.5 / (h * h)
    const = 0.5 * d * math.log(2.0 * math.pi * h * h)
    terms = np.empty(n)
    for i in range(m_s):
        top = -np.inf
        for j in range(n):
            sq = 0.0
            for a in range(d):
                t = s[i, a] - x[j, a]
                sq += t * t
            v = log_w[j] - sq * inv2h2
            terms[j] = v
            if v > top:
                top = v
        if not math.isfinite(top):
            top = 0.0
        acc = 0.0
        for j in range(n):
            acc += math.exp(terms[j] - top)
        out[i] = np.log(acc) + top - const


def kde_log_density(s: Array, x: Array, w: Array, h: float) -> Array:
    """``log sum_j w_j N(s_i | x_j, h^2 I)`` ``(S,)`` at samples ``(S, d)`` of the kernel density
    of weighted points ``(N, d)`` with bandwidth ``h`` (Kushwaha 2010, Eq. 85)."""
    out = np.empty(len(s))
    with np.errstate(divide="ignore"):
        log_w = np.log(np.asarray(w, dtype=np.float64))
    _kde_log_density(
        np.ascontiguousarray(s, dtype=np.float64),
        np.ascontiguousarray(x, dtype=np.float64),
        np.ascontiguousarray(log_w),
        float(h),
        out,
    )
    return out


def kde_log_density_reference(s: Array, x: Array, w: Array, h: float) -> Array:
    """Readable NumPy version of :func:`kde_log_density`."""
    sq = np.sum((s[:, None, :] - x[None, :, :]) ** 2, axis=-1)
    d = x.shape[1]
    with np.errstate(divide="ignore"):
        a = -0.5 * sq / (h * h) + np.log(w)
    return log_sum_exp_rows_reference(a) - 0.5 * d * np.log(2 * np.pi * h * h)


__all__ = [
    "component_log_terms",
    "component_log_terms_reference",
    "em_fit",
    "em_fit_reference",
    "em_responsibilities",
    "em_responsibilities_reference",
    "kde_log_density",
    "kde_log_density_reference",
    "log_sum_exp_rows",
    "log_sum_exp_rows_reference",
    "weighted_scatter",
    "weighted_scatter_reference",
]
