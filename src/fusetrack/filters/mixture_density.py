"""Gaussian-mixture densities with one shared covariance, and a draw of the component.

``log sum_j exp(log w_j) N(x_i; m_j, cov)`` for every point ``x_i`` and a component index drawn
∝ ``w_j N(x_i; m_j, cov)``: the O(n m) hot loop of the grid proposals' ancestor completion and
Eq. 78 (Zhai 2007, Ch. 4-5), and of the marginal transition weight of Eq. 13 (spec 001, Sec. 2.1).
A Numba kernel does it in one pass per point without an ``(n, m)`` array; the NumPy reference
beside it is what the tests compare it with.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray
from scipy.special import logsumexp

Array = NDArray[np.float64]


def whitener(cov: Array) -> tuple[Array, float]:
    """``(L^-1, log N normaliser)`` for ``cov = L L^T``: ``log N(x; 0, cov) = c - |L^-1 x|^2 / 2``."""
    L = np.linalg.cholesky(cov)
    const = -0.5 * cov.shape[0] * np.log(2 * np.pi) - float(np.sum(np.log(np.diag(L))))
    return np.asarray(np.linalg.inv(L)), const


def gauss_logpdf(diff: Array, cov: Array) -> Array:
    """``log N(diff; 0, cov)`` over the last axis of ``diff``."""
    Linv, const = whitener(cov)
    u = diff @ Linv.T
    return np.asarray(const - 0.5 * np.sum(u * u, axis=-1))


@numba.njit(cache=True, nogil=True)
def _mixture_kernel(
    a: Array, b: Array, log_w: Array, u: Array
) -> tuple[Array, NDArray[np.intp]]:  # pragma: no cover - compiled
    n_a, n_b, k = a.shape[0], b.shape[0], a.shape[1]
    lse = np.empty(n_a)
    anc = np.zeros(n_a, dtype=np.intp)
    lp = np.empty(n_b)
    for i in range(n_a):
        top = -np.inf
        for j in range(n_b):
            s = 0.0
            for c in range(k):
                e = a[i, c] - b[j, c]
                s += e * e
            v = log_w[j] - 0.5 * s
            lp[j] = v
            if v > top:
                top = v
        if not np.isfinite(top):
            lse[i] = top
            continue
        tot = 0.0
        for j in range(n_b):
            d = lp[j] - top  # terms below e^-50 cannot change a sum that contains 1: skip exp
            lp[j] = math.exp(d) if d > -50.0 else 0.0
            tot += lp[j]
        lse[i] = top + math.log(tot)
        target, acc = u[i] * tot, 0.0
        for j in range(n_b):
            acc += lp[j]
            if acc >= target:
                anc[i] = j
                break
        else:
            anc[i] = n_b - 1
    return lse, anc


def gaussian_mixture_ancestors(
    x: Array, means: Array, cov: Array, log_w: Array, u: Array, engine: str = "numba"
) -> tuple[Array, NDArray[np.intp]]:
    """``log sum_j exp(log_w_j) N(x_i; means_j, cov)`` ``(n,)`` and an index ``j`` per ``x_i`` drawn
    ∝ ``exp(log_w_j) N(x_i; means_j, cov)`` by inverting the uniforms ``u (n,)``.

    The O(n m) hot loop of the ancestor completion and of Eq. 78. ``engine="numba"`` runs it in
    one compiled pass per point without an (n, m) array; ``"numpy"`` is the readable reference.
    """
    Linv, const = whitener(np.asarray(cov, float))
    a = np.ascontiguousarray(x @ Linv.T)
    b = np.ascontiguousarray(means @ Linv.T)
    lw = np.ascontiguousarray(np.broadcast_to(np.asarray(log_w, float), (len(b),)))
    if engine == "numba":
        lse, anc = _mixture_kernel(a, b, lw, np.ascontiguousarray(u, dtype=np.float64))
        return lse + const, anc
    d2 = np.sum((a[:, None, :] - b[None, :, :]) ** 2, axis=-1)
    lp = lw[None, :] - 0.5 * d2
    lse = logsumexp(lp, axis=1)
    cdf = np.cumsum(np.exp(lp - lp.max(axis=1, keepdims=True)), axis=1)
    anc = np.minimum((cdf < (u * cdf[:, -1])[:, None]).sum(axis=1), len(b) - 1)
    return np.asarray(lse + const), np.asarray(anc, dtype=np.intp)
