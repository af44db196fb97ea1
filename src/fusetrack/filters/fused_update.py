"""The weights of a particle step in few passes: likelihoods, log-sum-exp, weights, mean.

The fused update of :class:`~fusetrack.filters.ParticleFilter` made three passes over the
particles: the log-likelihoods of all the step's measurements
(:func:`fusetrack.filters.fused.log_likelihood_sum`, threaded), NumPy's ``exp`` and the
normalisation with the weighted mean (:func:`fusetrack.filters.kernels.normalize_with_mean`),
both on one core. :func:`log_weight_update_rows` does the same arithmetic with its own ``exp``:

* runs of fewer than :data:`~fusetrack.filters.fused.SPLIT_MIN` particles: one work item per
  run (threaded over the runs of a batch) doing all of it while the run's particles are in the
  core's cache: the per-chunk likelihood code (:func:`fusetrack.filters.fused.llsum_chunk`),
  ``exp(v - max)`` by :func:`exp_nonpositive`, the normalisation code
  (:func:`fusetrack.filters.kernels.normalize_mean_row`);
* larger runs: three threaded loops over (run, chunk) work items: the likelihoods; ``exp`` with
  each chunk's sums (:func:`~fusetrack.filters.kernels.chunk_moments`); after the chunks' sums
  are added in chunk order, the normalised log-weights and weights. The chunks and their order
  are the per-run path's, so both paths give the same bits, whatever the threads.

``exp`` cannot be NumPy's inside a Numba loop, and libm's scalar ``exp`` costs 13-17 ns per
particle on this machine (NumPy's SIMD one: under 1 ns), so :func:`exp_nonpositive` is fdlibm's
``exp`` (Remez polynomial on ``|r| <= ln 2 / 2``, scaled by ``2^k`` built from its exponent bits),
written without branches so that the compiler vectorises it: within 1 ulp of ``np.exp``
(89 % of values equal; tested), as fast. Its arguments are ``v - max <= 0``; below -708 (where
``exp`` is subnormal, a weight under 1e-307 of the largest) it returns 0. Every run of fewer
than ``SPLIT_MIN`` particles, alone or in a batch, takes this path, so a batch's run stays
bit-identical to the separate run; the NumPy engine's reference agrees to rounding.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.core.extending import intrinsic
from numpy.typing import NDArray

from .fused import (
    CHUNK,
    PARALLEL_MIN,
    SPLIT_MIN,
    _llsum_parallel,
    _llsum_serial,
    _twins,
    llsum_chunk,
    measurement_rows,
    threaded,
)
from .kernels import chunk_moments, finish_moments, normalize_mean_row

Array = NDArray[np.float64]

__all__ = ["exp_nonpositive", "log_weight_update_rows"]

# fdlibm e_exp.c: exp(r) = 1 + r + r c(r) / (2 - c(r)), c(r) = r - r^2 (P1 + r^2 (P2 + ...))
_P1 = 1.66666666666666019037e-01
_P2 = -2.77777777770155933842e-03
_P3 = 6.61375632143793436117e-05
_P4 = -1.65339022054652515390e-06
_P5 = 4.13813679705723846039e-08
_LN2_HI = 6.93147180369123816490e-01
_LN2_LO = 1.90821492927058770002e-10
_INV_LN2 = 1.44269504088896338700e00
_LOWEST = -708.0  # below: 2^k would be subnormal


@intrinsic
def _pow2(tyctx, k):  # pragma: no cover - compile time
    """``2.0 ** k`` for an ``int64`` ``k`` in ``[-1022, 1023]``: its exponent bits."""
    sig = types.float64(types.int64)

    def codegen(ctx, builder, sig, args):
        i64 = ir.IntType(64)
        bits = builder.shl(builder.add(args[0], ir.Constant(i64, 1023)), ir.Constant(i64, 52))
        return builder.bitcast(bits, ir.DoubleType())

    return sig, codegen


@numba.njit(cache=True, inline="always", error_model="numpy")
def exp_nonpositive(x):  # pragma: no cover - jit
    """``exp(x)`` for ``x <= 0`` (``-inf`` gives 0), within 1 ulp of ``np.exp``; 0 below -708.
    ``x = k ln2 + r``, ``|r| <= ln2 / 2``; fdlibm's rational form of ``exp(r)``; times ``2^k``."""
    xc = max(x, _LOWEST)
    k = math.floor(xc * _INV_LN2 + 0.5)
    hi = xc - k * _LN2_HI
    lo = k * _LN2_LO
    r = hi - lo
    t = r * r
    c = r - t * (_P1 + t * (_P2 + t * (_P3 + t * (_P4 + t * _P5))))
    y = 1.0 - ((lo - (r * c) / (2.0 - c)) - hi)
    y = y * _pow2(np.int64(k))
    return 0.0 if x < _LOWEST else y


def _update_py(x, lw, kinds, params, zc, usable, v, e, lse, ess, mean, cmax):
    # pragma: no cover - jit
    """Run ``r`` (one work item): the log-likelihood sums into ``v[r]`` chunk by chunk (running
    maxima ``cmax[r, chunk, k]``), ``e[r] = exp(v[r] - max)``, then the normalisation."""
    rows, n, _ = x.shape
    nk = kinds.shape[0]
    nch = (n + CHUNK - 1) // CHUNK
    for r in numba.prange(rows):
        width = min(n, CHUNK)
        px = np.empty(width)
        py = np.empty(width)
        pz = np.empty(width)
        m = -np.inf
        for ch in range(nch):
            lo = ch * CHUNK
            hi = min(n, lo + CHUNK)
            w = hi - lo
            cm = cmax[r, ch]
            llsum_chunk(x, r, lo, lw, kinds, params, zc, usable, v[r, lo:hi], px[:w], py[:w],
                        pz[:w], cm)  # fmt: skip
            m = max(m, cm[nk - 1]) if nk > 0 else m
        if math.isfinite(m):
            vr = v[r]
            er = e[r]
            for i in range(n):
                er[i] = exp_nonpositive(vr[i] - m)
        normalize_mean_row(v, e, m, x, r, lse, ess, mean)


_update_serial, _update_parallel = _twins(_update_py)


def _exp_moments_py(v, m, x, e, parts):  # pragma: no cover - jit
    """Work item (run ``r``, chunk ``c``): ``e = exp(v - m[r])`` and the chunk's
    :func:`~fusetrack.filters.kernels.chunk_moments` into ``parts[r, c]`` (0 for a row with a
    non-finite maximum)."""
    rows, n = v.shape
    nch = parts.shape[1]
    for item in numba.prange(rows * nch):
        r = item // nch
        c = item % nch
        lo = c * CHUNK
        hi = min(n, lo + CHUNK)
        mr = m[r]
        finite = math.isfinite(mr)
        for i in range(lo, hi):
            e[r, i] = exp_nonpositive(v[r, i] - mr) if finite else 0.0
        chunk_moments(e, x, r, lo, hi, parts[r, c])


def _finish_py(parts, m, v, e, lse, ess, mean):  # pragma: no cover - jit
    """Per row, :func:`~fusetrack.filters.kernels.finish_moments` (serial, chunk order), then
    work items (run, chunk): ``v -= lse``, ``e *= 1 / s``."""
    rows, n = v.shape
    nch = parts.shape[1]
    total = np.empty(rows)
    inv = np.empty(rows)
    for r in range(rows):
        total[r], inv[r] = finish_moments(parts[r], m[r], r, lse, ess, mean)
    for item in numba.prange(rows * nch):
        r = item // nch
        if math.isfinite(m[r]):
            c = item % nch
            for i in range(c * CHUNK, min(n, (c + 1) * CHUNK)):
                v[r, i] = v[r, i] - total[r]
                e[r, i] = e[r, i] * inv[r]


_exp_moments_serial, _exp_moments_parallel = _twins(_exp_moments_py)
_finish_serial, _finish_parallel = _twins(_finish_py)


def log_weight_update_rows(
    states: Array,
    log_w: Array,
    kinds: NDArray[np.int64],
    params: Array,
    z: Array,
    usable: NDArray[np.bool_],
) -> tuple[Array, Array, Array, Array, Array, Array]:
    """``(lw, w, lse, ess, mean, maxima)`` after all the step's measurements, in one pass per
    run: ``v = log_w + sum_k log p(z_k | x)`` (arguments as
    :func:`~fusetrack.filters.fused.log_likelihood_sum`), ``lse = logsumexp(v)``,
    ``lw = v - lse``, ``w = exp(lw)``, ``ess = 1 / sum w^2``, ``mean`` the weighted mean
    ``(R, d)``, ``maxima`` ``(R, K)`` the running maxima of the degeneracy bound. A row whose
    maximum is not finite is returned raw, as by
    :func:`~fusetrack.filters.kernels.normalize_with_mean`. The references are those two
    functions (with NumPy's ``exp``)."""
    x = np.ascontiguousarray(states, dtype=np.float64)
    rows, n, d = x.shape
    kinds, params, zc = measurement_rows(kinds, params, z)
    nch = (n + CHUNK - 1) // CHUNK
    v = np.empty((rows, n))
    e = np.empty((rows, n))
    lse = np.empty(rows)
    ess = np.empty(rows)
    mean = np.empty((rows, d))
    cmax = np.empty((rows, nch, kinds.shape[0]))
    lw = np.ascontiguousarray(log_w, dtype=np.float64)
    use = np.ascontiguousarray(usable, dtype=np.bool_)
    threads = rows * n >= PARALLEL_MIN
    if n < SPLIT_MIN:  # one work item per run: its particles stay in cache
        fn = threaded(_update_parallel) if threads and rows > 1 else _update_serial
        fn(x, lw, kinds, params, zc, use, v, e, lse, ess, mean, cmax)
        return v, e, lse, ess, mean, cmax.max(axis=1)
    # large runs: work items (run, chunk) for each of the three steps, on both cores
    llsum = threaded(_llsum_parallel) if threads else _llsum_serial
    llsum(x, lw, kinds, params, zc, use, v, cmax)
    maxima = cmax.max(axis=1)
    m = np.ascontiguousarray(maxima[:, -1])
    parts = np.empty((rows, nch, 2 + d))
    (threaded(_exp_moments_parallel) if threads else _exp_moments_serial)(v, m, x, e, parts)
    (threaded(_finish_parallel) if threads else _finish_serial)(parts, m, v, e, lse, ess, mean)
    return v, e, lse, ess, mean, maxima
