"""Whole-run log-likelihood kernels for linear-Gaussian models: the bootstrap particle filter's
estimate and the Kalman filter's exact value, each one Numba call per series.

:class:`~fusetrack.filters.BootstrapFilter` through :func:`~fusetrack.filters.run_filter`
spends ~0.4 ms of Python per step on a 1-D model (validation, dispatch, a ``solve`` per
likelihood, the degeneracy bookkeeping) where the arithmetic of 1000 particles takes ~15 us;
parameter estimation runs the same filter hundreds of times, so here the whole run is one loop:

* :func:`bootstrap_log_likelihoods` -- the estimator of the bootstrap filter with systematic
  resampling when ``ESS < ess_threshold * N`` (Gordon, Salmond & Smith 1993; the log-likelihood
  ``sum_k log sum_i w_i p(z_k | x_i)``, Doucet & Johansen 2009, Eq. 47), drawing from the
  caller's generators exactly as the filter does (the prior's normals, per step the resampling
  uniform and then each particle's normals), so that a seed gives the same value as
  ``run_filter(..., log_likelihood=True)`` to rounding (tested). A step whose evidence is not
  finite or below ``min_log_evidence`` adds it and keeps the weights (the filter's
  ``degenerate="keep"``).
* :func:`kalman_log_likelihood` -- the prediction-error decomposition
  ``sum_k log N(z_k; H m_k^-, H P_k^- H^T + R)`` (Harvey 1989, Sec. 3.4) of the Kalman filter.

Both read the whitened arrays of :func:`~.series.linear_gaussian_arrays`. Several parameter
values (chains) are one call: a loop over them, threaded when there are several.
"""

from __future__ import annotations

import math
import types
from collections.abc import Callable
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from ..core import systematic_row
from ..filters import (
    RunStreams,
    bitgen_from_handle,
    next_double,
    random_standard_normal,
)

Array = NDArray[np.float64]

__all__ = ["bootstrap_log_likelihoods", "kalman_log_likelihood"]


@numba.njit(cache=True, inline="always", error_model="numpy")
def _propagate(bg, x, xn, anc, gather, F, G, eps):  # pragma: no cover - jit
    """``xn[:, i] = F x[:, a_i] + G eps_i`` on columns ``(d, N)`` (``a_i = i`` unless
    ``gather``): the normals drawn particle by particle (the filter's order), then one
    vectorised pass per ``(a, b)``, each component summed in the filter's order (same bits)."""
    d, n = x.shape
    for i in range(n):
        for a in range(d):
            eps[a, i] = random_standard_normal(bg)
    for a in range(d):
        row = xn[a]
        row[:] = 0.0
        for b in range(d):
            f = F[a, b]
            g = G[a, b]
            xb = x[b]
            eb = eps[b]
            if gather:
                for i in range(n):
                    row[i] += f * xb[anc[i]] + g * eb[i]
            else:
                for i in range(n):
                    row[i] += f * xb[i] + g * eb[i]


@numba.njit(cache=True, inline="always", error_model="numpy")
def _weigh(x, lw, uniform, shift, WH, Wz, c, v, res):  # pragma: no cover - jit
    """``v_i = log w_i + c - |Wz - WH x_i|^2 / 2`` on columns ``(d, N)`` (``log w_i = -shift``
    if ``uniform``, else ``lw_i - shift``), one vectorised pass per ``(row, b)``; ``max v``."""
    d, n = x.shape
    v[:] = 0.0
    for r in range(Wz.shape[0]):
        res[:] = Wz[r]
        for b in range(d):
            h = WH[r, b]
            xb = x[b]
            for i in range(n):
                res[i] -= h * xb[i]
        for i in range(n):
            v[i] += res[i] * res[i]
    top = -np.inf
    for i in range(n):
        vi = (-shift if uniform else lw[i] - shift) + (c - 0.5 * v[i])
        v[i] = vi
        top = max(top, vi)
    return top


@numba.njit(cache=True, inline="always", error_model="numpy")
def _step(bg, x, xn, anc, mode, F, G, eps, lw, shift, WH, Wz, c, v, res):
    # pragma: no cover - jit
    """One step on columns ``(d, N)``: (``mode`` 0: no prediction, 1: propagate, 2: propagate
    the ancestors ``anc``) then ``v_i = log w_i + log p(z | x_i)`` with ``log w_i = lw_i -
    shift`` (uniform ``-shift`` after resampling). Returns ``max_i v_i``; the states end in
    ``xn`` (``x`` when ``mode`` is 0)."""
    if x.shape[0] == 1 and Wz.shape[0] == 1:
        return _step_scalar(bg, x, xn, anc, mode, F, G, lw, shift, WH, Wz, c, v)
    if mode == 0:
        return _weigh(x, lw, False, shift, WH, Wz, c, v, res)
    _propagate(bg, x, xn, anc, mode == 2, F, G, eps)
    return _weigh(xn, lw, mode == 2, shift, WH, Wz, c, v, res)


@numba.njit(cache=True, inline="always", error_model="numpy")
def _step_scalar(bg, x, xn, anc, mode, F, G, lw, shift, WH, Wz, c, v):  # pragma: no cover - jit
    """:func:`_step` for a scalar state and one measurement row in one fused pass, the model's
    numbers in registers (the same arithmetic and bits; ~1.5 ms less per likelihood at
    T = 100, N = 1000 than the passes of the general case)."""
    n = x.shape[1]
    f, g, h, z = F[0, 0], G[0, 0], WH[0, 0], Wz[0]
    top = -np.inf
    for i in range(n):
        if mode == 0:
            xi = x[0, i]
        else:
            xi = f * x[0, anc[i] if mode == 2 else i] + g * random_standard_normal(bg)
            xn[0, i] = xi
        e = z - h * xi
        vi = (-shift if mode == 2 else lw[i] - shift) + (c - 0.5 * (e * e))
        v[i] = vi
        top = max(top, vi)
    return top


@numba.njit(cache=True, inline="always", error_model="numpy")
def _exp_sums(v, top, e):  # pragma: no cover - jit
    """``e_i = exp(v_i - top)``; returns ``(sum e, sum e^2)``."""
    s = 0.0
    s2 = 0.0
    for i in range(v.shape[0]):
        ei = math.exp(v[i] - top)
        e[i] = ei
        s += ei
        s2 += ei * ei
    return s, s2


@numba.njit(cache=True, inline="always", error_model="numpy")
def _one_run(handle, mean0, L0, F, G, step_dt, WH, Wz, c, n, ess_frac, min_log_ev):
    # pragma: no cover - jit
    """The bootstrap filter's log-likelihood estimate of one parameter value (module docs).
    The weights live as ``lw`` (unnormalised logs, ``log w = lw - shift``) and ``e`` (their
    exponentials, unnormalised: systematic resampling normalises)."""
    bg = bitgen_from_handle(handle)
    d = mean0.shape[0]
    x = np.empty((d, n))  # particles as columns: the passes over them vectorise
    xn = np.empty((d, n))
    eps = np.empty((d, n))
    for i in range(n):  # the prior: standard_normal((n, d)) @ L0.T + mean0
        for a in range(d):
            eps[a, 0] = random_standard_normal(bg)
        for a in range(d):
            s = 0.0
            for b in range(d):
                s += eps[b, 0] * L0[a, b]
            x[a, i] = s + mean0[a]
    log_n = math.log(n)
    lw = np.zeros(n)
    v = np.empty(n)
    res = np.empty(n)
    e = np.ones(n)
    anc = np.empty(n, dtype=np.intp)
    counts = np.empty(n + 1, dtype=np.intp)
    shift = log_n
    ess = float(n)
    total = 0.0
    for k in range(step_dt.shape[0]):
        u = max(step_dt[k], 0)
        mode = 0
        if step_dt[k] >= 0:
            mode = 1
            if ess < ess_frac * n:
                mode = 2
                systematic_row(e, next_double(bg), anc, counts)
                shift = log_n
        top = _step(bg, x, xn, anc, mode, F[u], G[u], eps, lw, shift, WH[k], Wz[k], c[k], v, res)
        if mode:
            x, xn = xn, x
        s, s2 = _exp_sums(v, top, e) if top > -np.inf else (0.0, 0.0)
        lse = top + math.log(s) if s > 0.0 else -np.inf
        total += lse
        if lse >= min_log_ev and lse < np.inf:
            lw, v = v, lw
            shift = lse
            ess = s * s / s2
        elif mode == 2:  # degenerate after resampling: uniform weights kept (degenerate="keep")
            lw[:] = 0.0
            e[:] = 1.0
            ess = float(n)
        else:  # degenerate: the previous weights kept (degenerate="keep")
            for i in range(n):
                e[i] = math.exp(lw[i] - shift)
    return total


def _runs_py(handles, mean0, L0, F, G, step_dt, WH, Wz, c, n, ess_frac, min_log_ev, out):
    # pragma: no cover - jit
    """:func:`_one_run` for each parameter value ``p`` (leading axis of every model array)."""
    for p in numba.prange(handles.shape[0]):
        out[p] = _one_run(
            handles[p], mean0[p], L0[p], F[p], G[p], step_dt, WH[p], Wz[p], c[p], n,
            ess_frac, min_log_ev,
        )  # fmt: skip


def _serial_twin(py: Callable[..., Any]) -> types.FunctionType:
    """A renamed copy of ``py`` (Numba's disk cache is keyed by the qualified name)."""
    twin = types.FunctionType(py.__code__, py.__globals__, py.__name__ + "_serial")
    twin.__qualname__ = py.__qualname__ + "_serial"
    return twin


_runs_serial = numba.njit(cache=True, nogil=True, error_model="numpy")(_serial_twin(_runs_py))
_runs_parallel = numba.njit(cache=True, nogil=True, error_model="numpy", parallel=True)(_runs_py)


def bootstrap_log_likelihoods(
    streams: RunStreams,
    mean0: Array,
    L0: Array,
    F: Array,
    G: Array,
    step_dt: NDArray[np.intp],
    WH: Array,
    Wz: Array,
    c: Array,
    n_particles: int,
    ess_threshold: float,
    min_log_evidence: float,
    threads: bool = False,
) -> Array:
    """The bootstrap filter's log-likelihood estimate for ``P`` parameter values at once,
    value ``p`` drawn from ``streams.gens[p]`` (distinct generators: ``P`` runs, no shared
    state). Arrays as :class:`~.series.LinearGaussianArrays` with a leading axis ``P``
    (``step_dt`` shared); ``L0`` the prior's square-root factor. ``threads``: spread the values
    over Numba's threads (only worth it for several). Returns ``(P,)``."""
    if not streams.distinct:
        raise ValueError("streams: a generator appears more than once")
    out = np.empty(len(streams.gens))
    fn = _runs_parallel if threads and out.size > 1 else _runs_serial
    fn(
        streams.handles, mean0, L0, F, G, step_dt, WH, Wz, c, int(n_particles),
        float(ess_threshold), float(min_log_evidence), out,
    )  # fmt: skip
    return out


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _kalman(mean0, cov0, F, Q, step_dt, WH, Wz, c):  # pragma: no cover - jit
    """The prediction-error decomposition on whitened rows (``R = I``; Joseph-form update)."""
    if mean0.shape[0] == 1 and Wz.shape[1] == 1:
        return _kalman_scalar(mean0[0], cov0[0, 0], F, Q, step_dt, WH, Wz, c)
    m = mean0.copy()
    P = cov0.copy()
    eye = np.eye(Wz.shape[1])
    total = 0.0
    for k in range(step_dt.shape[0]):
        u = step_dt[k]
        if u >= 0:
            m = F[u] @ m
            P = F[u] @ P @ F[u].T + Q[u]
        H = WH[k]
        PHt = P @ H.T
        S = H @ PHt + eye
        y = Wz[k] - H @ m
        L = np.linalg.cholesky(S)
        alpha = np.linalg.solve(L, y)
        total += c[k] - np.log(np.diag(L)).sum() - 0.5 * (alpha @ alpha)
        K = np.linalg.solve(S, PHt.T).T
        m = m + K @ y
        IKH = np.eye(m.shape[0]) - K @ H
        P = IKH @ P @ IKH.T + K @ K.T
    return total


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _kalman_scalar(m, P, F, Q, step_dt, WH, Wz, c):  # pragma: no cover - jit
    """:func:`_kalman` for a scalar state and one row, without small-matrix allocations."""
    total = 0.0
    for k in range(step_dt.shape[0]):
        u = step_dt[k]
        if u >= 0:
            f = F[u, 0, 0]
            m = f * m
            P = f * P * f + Q[u, 0, 0]
        h = WH[k, 0, 0]
        S = h * P * h + 1.0
        y = Wz[k, 0] - h * m
        total += c[k] - 0.5 * (math.log(S) + y * y / S)
        K = P * h / S
        m += K * y
        a = 1.0 - K * h
        P = a * P * a + K * K
    return total


def kalman_log_likelihood(
    mean0: Array,
    cov0: Array,
    F: Array,
    G: Array,
    step_dt: NDArray[np.intp],
    WH: Array,
    Wz: Array,
    c: Array,
) -> float:
    """The Kalman filter's exact ``log p(z_1:T)`` (module docstring) on whitened arrays
    (:class:`~.series.LinearGaussianArrays`; ``Q = G G^T``)."""
    Q = np.ascontiguousarray(G @ np.swapaxes(G, -1, -2))
    return float(_kalman(mean0, cov0, F, Q, step_dt, WH, Wz, c))
