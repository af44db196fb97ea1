"""Resampling schemes: each maps normalised weights ``(..., N)`` to ancestor indices ``(..., N)``.

Multinomial, stratified, systematic (Kitagawa 1996; Douc & Cappé 2005) and residual (Liu & Chen
1998). All are unbiased: the expected number of copies of particle i is ``N * w_i``. Their
variances order as residual, stratified, systematic <= multinomial (systematic is not always
below stratified). Leading axes are independent sets (batched runs), each with its own draws.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numba
import numpy as np
from numpy.typing import NDArray

from .errors import ConfigError, invalid

Resampler = Callable[[NDArray[np.float64], np.random.Generator], NDArray[np.intp]]


@numba.njit(cache=True, nogil=True)
def _inverse_cdf_sorted(weights: np.ndarray, u: np.ndarray) -> np.ndarray:  # pragma: no cover - jit
    """Ancestors for sorted uniforms ``u`` (each row ascending in [0,1)), one linear merge per row.

    The cumulative sum is accumulated left to right and each partial sum divided by the total,
    exactly as ``np.cumsum(w) / cumsum[-1]`` does, so the comparisons (and the indices) are
    bit-identical to :func:`inverse_cdf_reference`; the last cumulative value is exactly 1, so a
    uniform below 1 never lands on trailing zero-weight particles.
    """
    rows, n = weights.shape
    m = u.shape[1]
    out = np.empty((rows, m), dtype=np.intp)
    for r in range(rows):
        total = 0.0
        for i in range(n):
            total += weights[r, i]
        j = 0
        acc = weights[r, 0]
        c = acc / total
        for k in range(m):
            while u[r, k] >= c and j < n - 1:
                j += 1
                acc += weights[r, j]
                c = acc / total
            out[r, k] = j
    return out


@numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def systematic_row(weights, u0, out, counts):  # pragma: no cover - jit
    """Systematic ancestors of one weight row ``(N,)`` into ``out`` ``(N,)``, ``u_k = (k + u0) / N``,
    without divisions and without the merge's unpredictable branch: particle ``i`` (cumulative
    weight ``C_i``) is the ancestor of the ``u_k < C_i`` not taken by ``i - 1``, and there are
    ``K_i = ceil(C_i n / total - u0)`` such ``k`` (clipped to ``[0, n]``); so the ancestor of
    ``k`` is the number of particles with ``K_i <= k``: a histogram of the ``K_i`` and its running
    sum. The same indices as :func:`inverse_cdf` of those ``u`` except where a ``u_k`` and a
    cumulative weight agree to rounding (one comparison in ~1e16); only particles before the last
    positive weight are counted, so trailing zero-weight particles are never chosen. ``counts``
    is scratch of ``N + 1`` integers. Shared by :func:`systematic` and the batched kernels of
    :mod:`fusetrack.filters.run_streams` (the same code: the same indices)."""
    n = weights.shape[0]
    total = 0.0
    last = 0
    for i in range(n):
        wi = weights[i]
        total += wi
        last = i if wi > 0.0 else last
    scale = n / total
    counts[:] = 0
    c = 0.0
    for i in range(last):
        c += weights[i]
        k = min(max(math.ceil(c * scale - u0), 0.0), float(n))
        counts[int(k)] += 1
    a = 0
    for k in range(n):
        a += counts[k]
        out[k] = a


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _systematic_sorted(weights: np.ndarray, u0: np.ndarray) -> np.ndarray:  # pragma: no cover - jit
    """:func:`systematic_row` for every row of ``weights`` ``(R, N)``, row ``r`` with ``u0[r]``."""
    rows, n = weights.shape
    out = np.empty((rows, n), dtype=np.intp)
    counts = np.empty(n + 1, dtype=np.intp)
    for r in range(rows):
        systematic_row(weights[r], u0[r], out[r], counts)
    return out


def inverse_cdf(weights: NDArray[np.float64], u: NDArray[np.float64]) -> NDArray[np.intp]:
    """Indices ``i`` with ``cdf[i-1] <= u < cdf[i]`` for sorted uniforms ``u`` (Numba merge)."""
    w = np.ascontiguousarray(weights, dtype=np.float64)
    lead = w.shape[:-1]
    w2 = w.reshape(-1, w.shape[-1])
    u2 = np.ascontiguousarray(u, dtype=np.float64).reshape(w2.shape[0], -1)
    return _inverse_cdf_sorted(w2, u2).reshape((*lead, u2.shape[-1]))


def inverse_cdf_reference(weights: NDArray[np.float64], u: NDArray[np.float64]) -> NDArray[np.intp]:
    """NumPy reference for :func:`inverse_cdf` (binary search on the cumulative sum)."""
    w = np.asarray(weights, dtype=float)
    cdf = np.cumsum(w, axis=-1)
    cdf /= cdf[..., -1:]
    lead = w.shape[:-1]
    cdf2 = cdf.reshape(-1, w.shape[-1])
    u2 = np.asarray(u, float).reshape(cdf2.shape[0], -1)
    idx = np.stack([np.searchsorted(c, uu, side="right") for c, uu in zip(cdf2, u2)])
    return np.minimum(idx, w.shape[-1] - 1).reshape((*lead, u2.shape[-1]))


def multinomial(weights: NDArray[np.float64], rng: np.random.Generator) -> NDArray[np.intp]:
    """N independent categorical draws (sorted uniforms from exponential spacings)."""
    w = np.asarray(weights, float)
    n = w.shape[-1]
    e = rng.exponential(size=(*w.shape[:-1], n + 1))
    s = np.cumsum(e, axis=-1)
    u = s[..., :-1] / s[..., -1:]
    return inverse_cdf(w, u)


def stratified(weights: NDArray[np.float64], rng: np.random.Generator) -> NDArray[np.intp]:
    """One uniform in each stratum ``[k/N, (k+1)/N)``."""
    w = np.asarray(weights, float)
    n = w.shape[-1]
    u = (np.arange(n) + rng.random((*w.shape[:-1], n))) / n
    return inverse_cdf(w, u)


def systematic(weights: NDArray[np.float64], rng: np.random.Generator) -> NDArray[np.intp]:
    """A single uniform shifted by ``k/N``: the lowest-cost and usually lowest-variance scheme."""
    w = np.ascontiguousarray(weights, dtype=np.float64)
    u0 = rng.random((*w.shape[:-1], 1))  # u_k = (k + u0) / N, made inside the merge
    w2 = w.reshape(-1, w.shape[-1])
    return _systematic_sorted(w2, u0.reshape(-1)).reshape(w.shape)


def systematic_from_uniforms(
    weights: NDArray[np.float64], u0: NDArray[np.float64]
) -> NDArray[np.intp]:
    """:func:`systematic` for weight rows ``(R, N)`` given each row's uniform ``u0`` ``(R,)``
    (drawn by the caller, e.g. one per run from that run's generator)."""
    w = np.ascontiguousarray(weights, dtype=np.float64)
    u = np.ascontiguousarray(u0, dtype=np.float64).reshape(-1)
    return _systematic_sorted(w.reshape(-1, w.shape[-1]), u).reshape(w.shape)


def residual(weights: NDArray[np.float64], rng: np.random.Generator) -> NDArray[np.intp]:
    """``floor(N w_i)`` deterministic copies, the rest drawn multinomially from the residuals."""
    w = np.asarray(weights, float)
    w = w / w.sum(axis=-1, keepdims=True)
    n = w.shape[-1]
    lead = w.shape[:-1]
    w2 = w.reshape(-1, n)
    out = np.empty(w2.shape, dtype=np.intp)
    for r in range(w2.shape[0]):
        copies = np.floor(n * w2[r]).astype(np.intp)
        det = np.repeat(np.arange(n), copies)
        k = n - det.size
        if k > 0:
            res = n * w2[r] - copies
            e = rng.exponential(size=k + 1)
            s = np.cumsum(e)
            extra = inverse_cdf(res[None, :], (s[:-1] / s[-1])[None, :])[0]
            det = np.concatenate([det, extra])
        out[r] = np.sort(det)
    return out.reshape((*lead, n))


RESAMPLERS: dict[str, Resampler] = {
    "multinomial": multinomial,
    "stratified": stratified,
    "systematic": systematic,
    "residual": residual,
}


def get_resampler(name: str | Resampler) -> Resampler:
    """Look a scheme up by name (or pass a callable through)."""
    if callable(name):
        return name
    try:
        return RESAMPLERS[name]
    except KeyError:
        raise ConfigError(invalid("resampler", name, f"one of {sorted(RESAMPLERS)}")) from None
