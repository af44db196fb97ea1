"""Numba kernels for the particle filters' hot loops, each beside the NumPy reference it must match.

Every kernel works on weight rows ``(..., N)`` (leading axes: independent runs) and, where it
draws on states, on ``(..., N, d)``. Sums run in two levels, over chunks of :data:`CHUNK`
particles and then over the chunks' partial sums, which keeps the rounding error of a sum of a
million terms near that of NumPy's pairwise sums; the NumPy references compute the same
quantities with array operations and agree to rounding (about 1e-15 relative), not bit for bit.

* :func:`log_weight_update` -- ``log w += log p(z | x)`` then normalise by log-sum-exp, returning
  the new log-weights, the weights (each ``exp`` computed once), the log-evidence
  ``log sum_i w_i p(z | x_i)`` and the effective sample size.
* :func:`normalize_log_weights` -- the same with no likelihood (normalise only).
* :func:`weighted_mean_cov` -- weighted mean and covariance (two passes: the mean, then the
  centred second moment, which is stable however far the cloud is from the origin).
* :func:`effective_sample_size` -- ``(sum w)^2 / sum w^2`` from weights (normalised first, so
  that the squares of tiny weights do not underflow).

A row whose largest log-weight after the update is not finite (every particle's likelihood is
``-inf``, or something returned ``+inf``) is left for the caller to recover: its new log-weights
are the raw sums ``log w + log p`` (NaN read as ``-inf``), its weights and ESS are 0 and its
log-evidence is that largest value (``-inf`` or ``+inf``).

The kernels are serial (``parallel=False``). Threaded twins were measured on the 2-core
machines this project runs on and were slower than the serial loops at N = 1e5 and no faster
at 1e6: the passes are memory-bound, and Monte Carlo studies already keep every core busy with
one run per worker (threads inside a kernel would only oversubscribe them).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]

CHUNK = 4096  # particles per partial sum

__all__ = [
    "CHUNK",
    "effective_sample_size",
    "effective_sample_size_reference",
    "log_weight_update",
    "log_weight_update_reference",
    "normalize_log_weights",
    "normalize_log_weights_reference",
    "weighted_mean_cov",
    "weighted_mean_cov_reference",
]


# ---------------------------------------------------------------------------------------------
# log-weight update:  log w_i <- log w_i + l_i - logsumexp_j(log w_j + l_j)
# ---------------------------------------------------------------------------------------------


@numba.njit(cache=True, fastmath=False, nogil=True)
def _update_rows(lw, ll, has_ll, out_lw, out_w, lse, ess):  # pragma: no cover - jit
    rows, n = out_lw.shape
    for r in range(rows):
        # pass 1: v = log w + log p (NaN -> -inf), and its maximum
        m = -np.inf
        for i in range(n):
            v = lw[r, i] + ll[r, i] if has_ll else lw[r, i]
            if v != v:
                v = -np.inf
            out_lw[r, i] = v
            if v > m:
                m = v
        if not math.isfinite(m):  # degenerate row: the caller recovers
            for i in range(n):
                out_w[r, i] = 0.0
            lse[r] = m
            ess[r] = 0.0
            continue
        # pass 2: e_i = exp(v_i - m), the only exp of the step, and their sum
        s = 0.0
        for lo in range(0, n, CHUNK):
            part = 0.0
            for i in range(lo, min(n, lo + CHUNK)):
                e = math.exp(out_lw[r, i] - m)
                out_w[r, i] = e
                part += e
            s += part
        total = m + math.log(s)
        # pass 3: log w_i = v_i - logsumexp, w_i = e_i / s, and sum w_i^2
        q = 0.0
        for lo in range(0, n, CHUNK):
            part = 0.0
            for i in range(lo, min(n, lo + CHUNK)):
                out_lw[r, i] = out_lw[r, i] - total
                w = out_w[r, i] / s
                out_w[r, i] = w
                part += w * w
            q += part
        lse[r] = total
        ess[r] = 1.0 / q


def _rows(a: ArrayLike) -> tuple[Array, tuple[int, ...]]:
    x = np.ascontiguousarray(a, dtype=np.float64)
    if x.ndim == 0:
        raise ValueError("weights need at least one axis (N,)")
    return x.reshape(-1, x.shape[-1]), x.shape


def _run_update(lw: ArrayLike, ll: ArrayLike | None) -> tuple[Array, Array, Array, Array]:
    lw2, shape = _rows(lw)
    if ll is None:
        ll2 = lw2[:, :0]
    else:
        ll2 = np.ascontiguousarray(np.broadcast_to(np.asarray(ll, dtype=np.float64), shape))
        ll2 = ll2.reshape(lw2.shape)
    out_lw = np.empty_like(lw2)
    out_w = np.empty_like(lw2)
    lse = np.empty(lw2.shape[0])
    ess = np.empty(lw2.shape[0])
    _update_rows(lw2, ll2, ll is not None, out_lw, out_w, lse, ess)
    lead = shape[:-1]
    return out_lw.reshape(shape), out_w.reshape(shape), lse.reshape(lead), ess.reshape(lead)


def log_weight_update(log_w: ArrayLike, loglik: ArrayLike) -> tuple[Array, Array, Array, Array]:
    """Add ``loglik`` to ``log_w`` and normalise each row ``(..., N)`` by log-sum-exp.

    Returns ``(new_log_w, w, log_evidence, ess)``: ``new_log_w`` and ``w = exp(new_log_w)``
    ``(..., N)``; ``log_evidence = logsumexp(log_w + loglik)`` ``(...)`` (the log predictive
    density of the measurement when ``log_w`` was normalised); ``ess = 1 / sum w^2`` ``(...)``.
    NaN sums count as ``-inf``. Rows whose largest sum is not finite are returned raw (see the
    module docstring).
    """
    return _run_update(log_w, loglik)


def normalize_log_weights(log_w: ArrayLike) -> tuple[Array, Array, Array, Array]:
    """:func:`log_weight_update` with no likelihood: ``(log_w - lse, w, lse, ess)``."""
    return _run_update(log_w, None)


def _reference_update(lw: Array, ll: Array | None) -> tuple[Array, Array, Array, Array]:
    with np.errstate(invalid="ignore"):
        v = lw + ll if ll is not None else lw.copy()
    v[np.isnan(v)] = -np.inf
    m = v.max(axis=-1)
    ok = np.isfinite(m)
    shift = np.where(ok, m, 0.0)[..., None]
    with np.errstate(invalid="ignore", over="ignore"):
        e = np.where(ok[..., None], np.exp(v - shift), 0.0)
    s = e.sum(axis=-1)
    with np.errstate(divide="ignore"):
        lse = np.where(ok, m + np.log(np.where(ok, s, 1.0)), m)
    with np.errstate(invalid="ignore"):
        new_lw = np.where(ok[..., None], v - lse[..., None], v)
    w = e / np.where(ok, s, 1.0)[..., None]
    q = np.sum(w * w, axis=-1)
    ess = np.where(q > 0, 1.0 / np.where(q > 0, q, 1.0), 0.0)
    return new_lw, w, lse, ess


def log_weight_update_reference(
    log_w: ArrayLike, loglik: ArrayLike
) -> tuple[Array, Array, Array, Array]:
    """NumPy reference for :func:`log_weight_update`."""
    lw = np.asarray(log_w, dtype=float)
    return _reference_update(lw, np.broadcast_to(np.asarray(loglik, dtype=float), lw.shape))


def normalize_log_weights_reference(log_w: ArrayLike) -> tuple[Array, Array, Array, Array]:
    """NumPy reference for :func:`normalize_log_weights`."""
    return _reference_update(np.asarray(log_w, dtype=float), None)


# ---------------------------------------------------------------------------------------------
# effective sample size  (sum w)^2 / sum w^2
# ---------------------------------------------------------------------------------------------


@numba.njit(cache=True, fastmath=False, nogil=True)
def _ess_rows(w, out):  # pragma: no cover - jit
    rows, n = w.shape
    for r in range(rows):
        s = 0.0
        for lo in range(0, n, CHUNK):
            part = 0.0
            for i in range(lo, min(n, lo + CHUNK)):
                part += w[r, i]
            s += part
        if not s > 0.0:
            out[r] = 0.0
            continue
        q = 0.0
        for lo in range(0, n, CHUNK):
            part = 0.0
            for i in range(lo, min(n, lo + CHUNK)):
                v = w[r, i] / s
                part += v * v
            q += part
        out[r] = 1.0 / q


def effective_sample_size(weights: ArrayLike) -> Array:
    """``(sum w)^2 / sum w^2`` per row of weights ``(..., N)`` >= 0 (0 for an all-zero row)."""
    w2, shape = _rows(weights)
    out = np.empty(w2.shape[0])
    _ess_rows(w2, out)
    return out.reshape(shape[:-1])


def effective_sample_size_reference(weights: ArrayLike) -> Array:
    """NumPy reference for :func:`effective_sample_size`."""
    w = np.asarray(weights, dtype=float)
    s = w.sum(axis=-1, keepdims=True)
    v = w / np.where(s > 0, s, 1.0)  # normalise first: squares of tiny weights would underflow
    q = np.sum(v * v, axis=-1)
    return np.where(q > 0, 1.0 / np.where(q > 0, q, 1.0), 0.0)


# ---------------------------------------------------------------------------------------------
# weighted mean and covariance
# ---------------------------------------------------------------------------------------------


@numba.njit(cache=True, fastmath=False, nogil=True)
def _mean_cov_rows(x, w, mean, cov):  # pragma: no cover - jit
    rows, n, d = x.shape
    part = np.empty(d)
    dev = np.empty(d)
    cpart = np.empty((d, d))
    for r in range(rows):
        # pass 1: sum w and sum w x
        sw = 0.0
        for k in range(d):
            mean[r, k] = 0.0
        for lo in range(0, n, CHUNK):
            pw = 0.0
            part[:] = 0.0
            for i in range(lo, min(n, lo + CHUNK)):
                wi = w[r, i]
                pw += wi
                for k in range(d):
                    part[k] += wi * x[r, i, k]
            sw += pw
            for k in range(d):
                mean[r, k] += part[k]
        for k in range(d):
            mean[r, k] /= sw
        # pass 2: sum w (x - mean)(x - mean)^T, lower triangle
        for a in range(d):
            for b in range(d):
                cov[r, a, b] = 0.0
        for lo in range(0, n, CHUNK):
            cpart[:, :] = 0.0
            for i in range(lo, min(n, lo + CHUNK)):
                wi = w[r, i]
                for k in range(d):
                    dev[k] = x[r, i, k] - mean[r, k]
                for a in range(d):
                    wa = wi * dev[a]
                    for b in range(a + 1):
                        cpart[a, b] += wa * dev[b]
            for a in range(d):
                for b in range(a + 1):
                    cov[r, a, b] += cpart[a, b]
        for a in range(d):
            for b in range(a + 1):
                c = cov[r, a, b] / sw
                cov[r, a, b] = c
                cov[r, b, a] = c


def weighted_mean_cov(states: ArrayLike, weights: ArrayLike) -> tuple[Array, Array]:
    """Weighted mean ``(..., d)`` and covariance ``(..., d, d)`` of ``states`` ``(..., N, d)``.

    ``weights`` ``(..., N)`` need not sum to one (they are divided by their sum). The covariance
    is the weighted second moment about the mean, ``sum_i w_i (x_i - m)(x_i - m)^T / sum_i w_i``.
    """
    x = np.ascontiguousarray(states, dtype=np.float64)
    if x.ndim < 2:
        raise ValueError(f"states.shape={x.shape} is invalid: expected (..., N, d)")
    lead, (n, d) = x.shape[:-2], x.shape[-2:]
    w = np.ascontiguousarray(np.broadcast_to(np.asarray(weights, dtype=np.float64), (*lead, n)))
    x3 = x.reshape(-1, n, d)
    mean = np.empty((x3.shape[0], d))
    cov = np.empty((x3.shape[0], d, d))
    _mean_cov_rows(x3, w.reshape(-1, n), mean, cov)
    return mean.reshape((*lead, d)), cov.reshape((*lead, d, d))


def weighted_mean_cov_reference(states: ArrayLike, weights: ArrayLike) -> tuple[Array, Array]:
    """NumPy reference for :func:`weighted_mean_cov`."""
    x = np.asarray(states, dtype=float)
    w = np.asarray(weights, dtype=float)
    w = w / w.sum(axis=-1, keepdims=True)
    mean = np.einsum("...n,...nd->...d", w, x)
    r = x - mean[..., None, :]
    cov = np.einsum("...n,...ni,...nj->...ij", w, r, r)
    return mean, 0.5 * (cov + np.swapaxes(cov, -1, -2))
