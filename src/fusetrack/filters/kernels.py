"""Numba kernels for the particle filters' hot loops, each beside the NumPy reference it must match.

Every kernel works on weight rows ``(..., N)`` (leading axes: independent runs) and, where it
draws on states, on ``(..., N, d)``. Sums run in two levels, over chunks of :data:`CHUNK`
particles and then over the chunks' partial sums, which keeps the rounding error of a sum of a
million terms near that of NumPy's pairwise sums; the NumPy references compute the same
quantities with array operations and agree to rounding (about 1e-15 relative), not bit for bit.

* :func:`log_weight_update` -- ``log w += log p(z | x)`` then normalise by log-sum-exp, returning
  the new log-weights, the weights (each ``exp`` computed once), the log-evidence
  ``log sum_i w_i p(z | x_i)`` and the effective sample size. It is the two halves below:
* :func:`add_log_likelihood` -- ``v = log w + log p`` and each row's maximum (no ``exp``), in
  place when asked, so that several measurements accumulate into one buffer;
* :func:`normalize_log_weights` -- ``exp`` once, log-sum-exp, normalised log-weights and
  weights, ESS. Its ``exp`` is NumPy's SIMD one, shared by both engines (see
  ``_exp_shifted``); the sums and the normalisation are Numba loops.
* :func:`weighted_mean` -- weighted mean (one pass);
* :func:`weighted_mean_cov` -- weighted mean and covariance (two passes: the mean, then the
  centred second moment, which is stable however far the cloud is from the origin).
* :func:`effective_sample_size` -- ``(sum w)^2 / sum w^2`` from weights (normalised first, so
  that the squares of tiny weights do not underflow).

A row whose largest log-weight after the update is not finite (every particle's likelihood is
``-inf``, or something returned ``+inf``) is left for the caller to recover: its new log-weights
are the raw sums ``log w + log p`` (NaN read as ``-inf``), its weights and ESS are 0 and its
log-evidence is that largest value (``-inf`` or ``+inf``).

The kernels are serial (``parallel=False``), except :func:`normalize_with_mean` on a batch of
many runs (threaded over the runs, from :data:`~fusetrack.filters.fused.PARALLEL_MIN` particles
in all). Threaded twins over the particles of one row were measured on the 2-core
machines this project runs on and were slower than the serial loops at N = 1e5 and no faster
at 1e6: the passes are memory-bound, and Monte Carlo studies already keep every core busy with
one run per worker (threads inside a kernel would only oversubscribe them).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from .fused import PARALLEL_MIN, _twins, threaded

Array = NDArray[np.float64]

CHUNK = 4096  # particles per partial sum

__all__ = [
    "CHUNK",
    "add_log_likelihood",
    "add_log_likelihood_reference",
    "effective_sample_size",
    "effective_sample_size_reference",
    "log_weight_update",
    "log_weight_update_reference",
    "normalize_log_weights",
    "normalize_log_weights_reference",
    "normalize_with_mean",
    "weighted_mean",
    "weighted_mean_cov",
    "weighted_mean_cov_reference",
    "weighted_mean_reference",
]


# ---------------------------------------------------------------------------------------------
# log-weight update:  log w_i <- log w_i + l_i - logsumexp_j(log w_j + l_j)
#
# Split in two so that several measurements cost one normalisation: add_log_likelihood once per
# measurement (a sum and a running maximum, no exp), then normalize_log_weights once.
# ---------------------------------------------------------------------------------------------


@numba.njit(cache=True, fastmath=False, nogil=True)
def _add_max_rows(lw, ll, has_ll, out, rowmax):  # pragma: no cover - jit
    """``out = lw + ll`` (NaN -> -inf; ``out`` may be ``lw``) and each row's maximum."""
    rows, n = out.shape
    for r in range(rows):
        m = -np.inf
        for i in range(n):
            v = lw[r, i] + ll[r, i] if has_ll else lw[r, i]
            if v != v:
                v = -np.inf
            out[r, i] = v
            if v > m:
                m = v
        rowmax[r] = m


@numba.njit(cache=True, fastmath=False, nogil=True)
def _finish_rows(v, e, rowmax, lse, ess):  # pragma: no cover - jit
    """Given ``e = exp(v - rowmax)``: ``lse = rowmax + log sum e``, ``v -= lse``, ``e /= sum e``
    (the weights), ``ess = 1 / sum w^2``. Rows with a non-finite maximum get ``e = 0``."""
    rows, n = v.shape
    for r in range(rows):
        m = rowmax[r]
        if not math.isfinite(m):  # degenerate row: the caller recovers
            for i in range(n):
                e[r, i] = 0.0
            lse[r] = m
            ess[r] = 0.0
            continue
        s = 0.0
        for lo in range(0, n, CHUNK):
            part = 0.0
            for i in range(lo, min(n, lo + CHUNK)):
                part += e[r, i]
            s += part
        total = m + math.log(s)
        q = 0.0
        for lo in range(0, n, CHUNK):
            part = 0.0
            for i in range(lo, min(n, lo + CHUNK)):
                v[r, i] = v[r, i] - total
                w = e[r, i] / s
                e[r, i] = w
                part += w * w
            q += part
        lse[r] = total
        ess[r] = 1.0 / q


def _rows(a: ArrayLike) -> tuple[Array, tuple[int, ...]]:
    x = np.ascontiguousarray(a, dtype=np.float64)
    if x.ndim == 0:
        raise ValueError("weights need at least one axis (N,)")
    return x.reshape(-1, x.shape[-1]), x.shape


def _exp_shifted(v: Array, rowmax: Array) -> Array:
    """``exp(v - rowmax)`` per row (shift 0 on rows with a non-finite maximum).

    The one ``exp`` of an update. It is NumPy's: its SIMD ``exp`` is 2-3 times faster than a
    scalar ``math.exp`` loop in Numba (which cannot vectorise it without ``fastmath``), so both
    engines share this call. (The one-pass update of :mod:`fusetrack.filters.fused_update`, used
    below 65 536 particles per run, has its own vectorised ``exp`` within 1 ulp of this one.)
    """
    shift = np.where(np.isfinite(rowmax), rowmax, 0.0)
    e = np.subtract(v, shift[..., None])
    with np.errstate(over="ignore", invalid="ignore"):
        np.exp(e, out=e)
    return e


def add_log_likelihood(
    log_w: ArrayLike, loglik: ArrayLike, out: Array | None = None
) -> tuple[Array, Array]:
    """``v = log_w + loglik`` (NaN -> ``-inf``) and its maximum per row ``(...)``.

    ``out`` (a C-contiguous float array shaped like ``log_w``, possibly ``log_w`` itself) is
    filled in place when given, so a sequence of measurements needs one buffer.
    """
    lw2, shape = _rows(log_w)
    ll2 = np.ascontiguousarray(np.broadcast_to(np.asarray(loglik, dtype=np.float64), shape))
    dest = np.empty(shape) if out is None else out
    if dest.shape != shape or dest.dtype != np.float64 or not dest.flags.c_contiguous:
        raise ValueError(f"out.shape={dest.shape} is invalid: expected C-contiguous {shape}")
    rowmax = np.empty(lw2.shape[0])
    _add_max_rows(lw2, ll2.reshape(lw2.shape), True, dest.reshape(lw2.shape), rowmax)
    return dest, rowmax.reshape(shape[:-1])


def add_log_likelihood_reference(
    log_w: ArrayLike, loglik: ArrayLike, out: Array | None = None
) -> tuple[Array, Array]:
    """NumPy reference for :func:`add_log_likelihood`."""
    with np.errstate(invalid="ignore"):
        v = np.add(log_w, loglik, out=out)
    v[np.isnan(v)] = -np.inf
    return v, v.max(axis=-1)


def normalize_log_weights(
    log_w: ArrayLike, rowmax: ArrayLike | None = None, *, overwrite: bool = False
) -> tuple[Array, Array, Array, Array]:
    """Normalise each row ``(..., N)`` by log-sum-exp: ``(log_w - lse, w, lse, ess)``.

    ``lse = logsumexp(log_w)`` ``(...)``; ``w = exp(log_w - lse)``; ``ess = 1 / sum w^2``.
    ``rowmax`` (each row's maximum, as :func:`add_log_likelihood` returns it) saves a pass when
    ``overwrite=True``, which also lets the result reuse ``log_w``'s buffer. NaN counts as
    ``-inf``; a row whose maximum is not finite is returned raw (see the module docstring).
    """
    lw2, shape = _rows(log_w)
    if rowmax is None or not overwrite:
        v = lw2 if overwrite else np.empty_like(lw2)
        m = np.empty(lw2.shape[0])
        _add_max_rows(lw2, lw2[:, :0], False, v, m)
    else:
        v, m = lw2, np.ascontiguousarray(rowmax, dtype=np.float64).reshape(-1)
    e = _exp_shifted(v, m)
    lse = np.empty(v.shape[0])
    ess = np.empty(v.shape[0])
    _finish_rows(v, e, m, lse, ess)
    lead = shape[:-1]
    return v.reshape(shape), e.reshape(shape), lse.reshape(lead), ess.reshape(lead)


def normalize_log_weights_reference(
    log_w: ArrayLike, rowmax: ArrayLike | None = None, *, overwrite: bool = False
) -> tuple[Array, Array, Array, Array]:
    """NumPy reference for :func:`normalize_log_weights` (``rowmax`` and ``overwrite`` are
    accepted for the same signature and not needed)."""
    v = np.array(log_w, dtype=float)
    v[np.isnan(v)] = -np.inf
    m = v.max(axis=-1)
    ok = np.isfinite(m)
    e = _exp_shifted(v, m)
    e[~ok] = 0.0
    s = e.sum(axis=-1)
    with np.errstate(divide="ignore"):
        lse = np.where(ok, m + np.log(np.where(ok, s, 1.0)), m)
    with np.errstate(invalid="ignore"):
        v = np.where(ok[..., None], v - lse[..., None], v)
    w = e / np.where(ok, s, 1.0)[..., None]
    q = np.sum(w * w, axis=-1)
    ess = np.where(q > 0, 1.0 / np.where(q > 0, q, 1.0), 0.0)
    return v, w, lse, ess


def log_weight_update(log_w: ArrayLike, loglik: ArrayLike) -> tuple[Array, Array, Array, Array]:
    """Add ``loglik`` to ``log_w`` and normalise each row ``(..., N)`` by log-sum-exp.

    Returns ``(new_log_w, w, log_evidence, ess)``: ``new_log_w`` and ``w = exp(new_log_w)``
    ``(..., N)``; ``log_evidence = logsumexp(log_w + loglik)`` ``(...)`` (the log predictive
    density of the measurement when ``log_w`` was normalised); ``ess = 1 / sum w^2`` ``(...)``.
    NaN sums count as ``-inf``. Rows whose largest sum is not finite are returned raw (see the
    module docstring).
    """
    v, m = add_log_likelihood(log_w, loglik)
    return normalize_log_weights(v, m, overwrite=True)


def log_weight_update_reference(
    log_w: ArrayLike, loglik: ArrayLike
) -> tuple[Array, Array, Array, Array]:
    """NumPy reference for :func:`log_weight_update`."""
    lw = np.asarray(log_w, dtype=float)
    v, _ = add_log_likelihood_reference(lw, np.broadcast_to(np.asarray(loglik, float), lw.shape))
    return normalize_log_weights_reference(v)


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
def _mean_rows(x, w, mean, sw):  # pragma: no cover - jit
    """``sw[r] = sum_i w_ri`` and ``mean[r] = sum_i w_ri x_ri / sw[r]``."""
    rows, n, d = x.shape
    part = np.empty(d)
    for r in range(rows):
        total = 0.0
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
            total += pw
            for k in range(d):
                mean[r, k] += part[k]
        for k in range(d):
            mean[r, k] /= total
        sw[r] = total


@numba.njit(cache=True, fastmath=False, nogil=True)
def _mean_cov_rows(x, w, mean, cov):  # pragma: no cover - jit
    rows, n, d = x.shape
    sw = np.empty(rows)
    _mean_rows(x, w, mean, sw)  # pass 1: the mean
    dev = np.empty(d)
    cpart = np.empty((d, d))
    for r in range(rows):
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
                c = cov[r, a, b] / sw[r]
                cov[r, a, b] = c
                cov[r, b, a] = c


def _states_weights(states: ArrayLike, weights: ArrayLike) -> tuple[Array, Array, tuple[int, ...]]:
    x = np.ascontiguousarray(states, dtype=np.float64)
    if x.ndim < 2:
        raise ValueError(f"states.shape={x.shape} is invalid: expected (..., N, d)")
    lead, (n, d) = x.shape[:-2], x.shape[-2:]
    w = np.ascontiguousarray(np.broadcast_to(np.asarray(weights, dtype=np.float64), (*lead, n)))
    return x.reshape(-1, n, d), w.reshape(-1, n), lead


def weighted_mean(states: ArrayLike, weights: ArrayLike) -> Array:
    """Weighted mean ``(..., d)`` of ``states`` ``(..., N, d)`` (weights need not sum to one)."""
    x3, w2, lead = _states_weights(states, weights)
    mean = np.empty((x3.shape[0], x3.shape[2]))
    _mean_rows(x3, w2, mean, np.empty(x3.shape[0]))
    return mean.reshape((*lead, x3.shape[2]))


def weighted_mean_reference(states: ArrayLike, weights: ArrayLike) -> Array:
    """NumPy reference for :func:`weighted_mean`."""
    w = np.asarray(weights, dtype=float)
    w = w / w.sum(axis=-1, keepdims=True)
    return np.asarray(np.einsum("...n,...nd->...d", w, np.asarray(states, dtype=float)))


def weighted_mean_cov(states: ArrayLike, weights: ArrayLike) -> tuple[Array, Array]:
    """Weighted mean ``(..., d)`` and covariance ``(..., d, d)`` of ``states`` ``(..., N, d)``.

    ``weights`` ``(..., N)`` need not sum to one (they are divided by their sum). The covariance
    is the weighted second moment about the mean, ``sum_i w_i (x_i - m)(x_i - m)^T / sum_i w_i``.
    """
    x3, w2, lead = _states_weights(states, weights)
    d = x3.shape[2]
    mean = np.empty((x3.shape[0], d))
    cov = np.empty((x3.shape[0], d, d))
    _mean_cov_rows(x3, w2, mean, cov)
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


# ---------------------------------------------------------------------------------------------
# normalisation and weighted mean together (the particle filters' fused update)
# ---------------------------------------------------------------------------------------------


@numba.njit(cache=True, inline="always", error_model="numpy")
def chunk_moments(e, x, r, lo, hi, out):  # pragma: no cover - jit
    """``out = [sum e, sum e^2, sum e x_0, ..., sum e x_{d-1}]`` over particles ``lo:hi`` of
    row ``r`` (in index order; one chunk of :func:`normalize_mean_row`'s sums)."""
    d = x.shape[2]
    ps = 0.0
    pq = 0.0
    for k in range(d):
        out[2 + k] = 0.0
    for i in range(lo, hi):
        ei = e[r, i]
        ps += ei
        pq += ei * ei
        for k in range(d):
            out[2 + k] += ei * x[r, i, k]
    out[0] = ps
    out[1] = pq


@numba.njit(cache=True, inline="always", error_model="numpy")
def finish_moments(parts, m, r, lse, ess, mean):  # pragma: no cover - jit
    """Row ``r`` from its chunks' :func:`chunk_moments` ``parts`` ``(chunks, 2 + d)``, summed in
    chunk order: ``lse = m + log s``, ``ess = s^2 / sum e^2``, ``mean = sum e x / s``; returns
    ``(lse, 1 / s)``. A non-finite ``m``: ``lse = m``, ``ess = 0``, ``mean = NaN``, ``(m, 1)``."""
    d = mean.shape[1]
    if not math.isfinite(m):
        lse[r] = m
        ess[r] = 0.0
        for k in range(d):
            mean[r, k] = np.nan
        return m, 1.0
    s = 0.0
    q = 0.0
    acc = np.zeros(d)
    for c in range(parts.shape[0]):
        s += parts[c, 0]
        q += parts[c, 1]
        for k in range(d):
            acc[k] += parts[c, 2 + k]
    total = m + math.log(s)
    inv = 1.0 / s
    lse[r] = total
    ess[r] = s * s / q
    for k in range(d):
        mean[r, k] = acc[k] * inv
    return total, inv


@numba.njit(cache=True, inline="always", error_model="numpy")
def normalize_mean_row(v, e, m, x, r, lse, ess, mean):  # pragma: no cover - jit
    """Row ``r`` of :func:`_normalize_mean_py` (``m`` its maximum): given ``e = exp(v - m)``,
    ``sum e``, ``sum e^2`` and ``sum e x`` in one pass (:func:`chunk_moments` per
    :data:`CHUNK` particles, :func:`finish_moments`); then ``v -= lse``, ``e *= 1/s`` (the
    weights). A non-finite ``m``: ``e = 0``, ``ess = 0``, ``lse = m``, ``mean = NaN``, ``v``
    left raw. Shared with the one-pass update of :mod:`fusetrack.filters.fused_update`."""
    n = v.shape[1]
    if not math.isfinite(m):
        for i in range(n):
            e[r, i] = 0.0
        finish_moments(np.zeros((0, 2 + x.shape[2])), m, r, lse, ess, mean)
        return
    nch = (n + CHUNK - 1) // CHUNK
    parts = np.empty((nch, 2 + x.shape[2]))
    for c in range(nch):
        chunk_moments(e, x, r, c * CHUNK, min(n, (c + 1) * CHUNK), parts[c])
    total, inv = finish_moments(parts, m, r, lse, ess, mean)
    for i in range(n):
        v[r, i] = v[r, i] - total
        e[r, i] = e[r, i] * inv


def _normalize_mean_py(v, e, rowmax, x, lse, ess, mean):  # pragma: no cover - jit
    """:func:`normalize_mean_row` for every row; rows are independent work items (threaded
    over the rows of a batch; each row's arithmetic is the same)."""
    for r in numba.prange(x.shape[0]):
        normalize_mean_row(v, e, rowmax[r], x, r, lse, ess, mean)


_normalize_mean_rows, _normalize_mean_parallel = _twins(_normalize_mean_py)


def normalize_with_mean(
    log_w: Array, rowmax: Array, states: Array
) -> tuple[Array, Array, Array, Array, Array]:
    """:func:`normalize_log_weights` (``overwrite=True``: ``log_w`` rows ``(R, N)`` become the
    normalised log-weights) and the weighted mean of ``states`` ``(R, N, d)`` in the same pass:
    ``(log_w - lse, w, lse, ess, mean)``. The ``exp`` is NumPy's SIMD one (as in
    :func:`normalize_log_weights`; even at ``N = 1000`` it beats libm's scalar ``exp`` in the
    loop). The reference is :func:`normalize_log_weights_reference` then
    :func:`weighted_mean_reference`."""
    v = log_w
    rows, n = v.shape
    m = np.ascontiguousarray(rowmax, dtype=np.float64).reshape(-1)
    e = _exp_shifted(v, m)
    x = np.ascontiguousarray(states, dtype=np.float64).reshape(rows, n, -1)
    lse = np.empty(rows)
    ess = np.empty(rows)
    mean = np.empty((rows, x.shape[2]))
    threads = rows > 1 and rows * n >= PARALLEL_MIN  # one row: serial (memory-bound, see above)
    (threaded(_normalize_mean_parallel) if threads else _normalize_mean_rows)(
        v, e, m, x, lse, ess, mean
    )
    return v, e, lse, ess, mean
