"""Fused fast paths of the particle filters, used when the models offer them.

The generic particle step calls the models through NumPy: ``motion.sample`` makes a few
full-size temporaries (``F x``, the noise, ``noise @ G^T``, their sum), every sensor's
``log_likelihood`` a few more (relative coordinates, ``atan2``, two wraps, the square), and the
resampled states are gathered into one more copy. Each is a pass over memory. Here the same
arithmetic runs in two Numba loops that touch each particle once:

* :func:`linear_gaussian_step` -- ``x'_i = F x_{a_i} + G eps_i`` (gather by the ancestors ``a``
  and the linear-Gaussian draw in one pass; ``eps`` are NumPy's standard normals, drawn exactly
  as ``motion.sample`` draws them, so a seed gives the same particles on both paths);
* :func:`log_likelihood_sum` -- ``v_i = log w_i + sum_k log p(z_k | x_i)`` over all the step's
  measurements, with the running maximum after each measurement (what the filter's degeneracy
  bound needs), one pass over the particles.

A model offers a fast path through a small method that returns plain numbers:

* a motion model: ``fused_transition(dt) -> (F, G)`` with ``G G^T = Q(dt)``
  (:class:`~fusetrack.motion.ConstantVelocity` and the other linear-Gaussian models), or None;
* a sensor: ``fused_likelihood() -> (kind, index, position, heading, inv_var, log_norm)``
  with ``kind`` one of ``"bearing"``, ``"range"``, ``"range_bearing"`` (the arguments of
  :func:`sensor_params`), or None (then the generic path runs).

The kernels are the NumPy models' arithmetic written per particle, so they agree with the
generic path to rounding (``atan2`` of Numba's libm and NumPy's may differ in the last bit);
the tests compare them. Each row (run) of a batch is computed by the same per-particle
operations whatever the batch size, so a run in a batch is bit-identical to the same run alone.

Threads: loops over at least :data:`PARALLEL_MIN` particles in total use ``numba.prange``
(``parallel=True``), smaller ones the serial compilation of the same code (thread start-up
costs more than it saves below that). ``numba.set_num_threads`` limits the threads.
"""

from __future__ import annotations

import math
import types
from collections.abc import Callable
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

BEARING = 0
RANGE = 1
RANGE_BEARING = 2
N_PARAMS = 10
PARALLEL_MIN = 1 << 16  # particles (all runs together) from which the threaded loops pay
CHUNK = 4096  # particles per work item of the threaded loops

_TWO_PI = 2.0 * math.pi

__all__ = [
    "BEARING",
    "KINDS",
    "N_PARAMS",
    "PARALLEL_MIN",
    "RANGE",
    "RANGE_BEARING",
    "linear_gaussian_step",
    "log_likelihood_sum",
    "sensor_params",
]


KINDS = {"bearing": BEARING, "range": RANGE, "range_bearing": RANGE_BEARING}


def sensor_params(
    kind: str,
    index: tuple[int, ...],
    position: Array,
    heading: float = 0.0,
    inv_var: tuple[float, ...] = (),
    log_norm: float = 0.0,
) -> Array:
    """The parameter vector of one sensor for :func:`log_likelihood_sum`.

    Layout: ``[ix, iy, iz, sx, sy, sz, heading, inv_var_0, inv_var_1, log_norm]``; ``iz = -1``
    for a 2-D sensor. ``inv_var`` are ``1 / sigma^2`` of the components in measurement order.
    """
    if kind not in KINDS:
        raise ValueError(f"kind={kind!r} is invalid: expected one of {sorted(KINDS)}")
    p = np.zeros(N_PARAMS)
    p[2] = -1.0
    for k, (i, s) in enumerate(zip(index, np.asarray(position, dtype=float))):
        p[k], p[3 + k] = float(i), float(s)
    p[6] = heading
    for k, v in enumerate(inv_var):
        p[7 + k] = v
    p[9] = log_norm
    return p


def _twins(py: Callable[..., Any]) -> tuple[Any, Any]:
    """Serial and threaded compilations of ``py``. The serial one compiles a renamed copy:
    Numba's on-disk cache is keyed by the function's qualified name and line, so two cached
    dispatchers of one function would keep overwriting (and reloading) each other's entry."""
    twin = types.FunctionType(py.__code__, py.__globals__, py.__name__ + "_serial")
    twin.__qualname__ = py.__qualname__ + "_serial"
    serial = numba.njit(cache=True, nogil=True)(twin)
    return serial, numba.njit(cache=True, nogil=True, parallel=True)(py)


# ---------------------------------------------------------------------------------------------
# per-particle arithmetic (inlined into the loops)


@numba.njit(cache=True, inline="always")
def _wrap(a):  # pragma: no cover - jit
    """``core.angles.wrap_angle_inplace`` for one value: ``a - 2 pi rint(a / 2 pi)`` into [-pi, pi)."""
    a = a - _TWO_PI * np.rint(a / _TWO_PI)
    if a < -math.pi:
        a += _TWO_PI
    if a >= math.pi:
        a -= _TWO_PI
    return a


@numba.njit(cache=True, inline="always")
def _sensor_ll(kind, p, k, z0, z1, x, r, i, ang):  # pragma: no cover - jit
    """``log p(z | x)`` of sensor ``k`` (``SensorBase.log_likelihood``, diagonal ``R``) for
    particle ``x[r, i]``; ``ang`` is its ``atan2(d_y, d_x)`` (precomputed, angular kinds only)."""
    dx = x[r, i, int(p[k, 0])] - p[k, 3]
    dy = x[r, i, int(p[k, 1])] - p[k, 4]
    if kind == 0:  # Bearing: wrap(z - wrap(atan2(dy, dx) - heading))
        b = ang
        if p[k, 6] != 0.0:
            b -= p[k, 6]
        e = _wrap(z0 - _wrap(b))
        return p[k, 9] - 0.5 * (e * e * p[k, 7])
    if kind == 1:  # Range in 2-D or 3-D: z - |d|
        s = 0.0 + dx * dx + dy * dy
        if p[k, 2] >= 0.0:
            dz = x[r, i, int(p[k, 2])] - p[k, 5]
            s += dz * dz
        e = z0 - math.sqrt(s)
        return p[k, 9] - 0.5 * (e * e * p[k, 7])
    # RangeBearing: [z0 - hypot(dx, dy), wrap(z1 - wrap(atan2(dy, dx) - heading))]
    b = ang
    if p[k, 6] != 0.0:
        b -= p[k, 6]
    e0 = z0 - math.hypot(dx, dy)
    e1 = _wrap(z1 - _wrap(b))
    return p[k, 9] - 0.5 * (e0 * e0 * p[k, 7] + e1 * e1 * p[k, 8])


# ---------------------------------------------------------------------------------------------
# propagation: x'_i = F x_{a_i} + G eps_i


def _step_py(x, anc, F, G, eps, out):  # pragma: no cover - jit
    rows, n, d = out.shape
    nch = (n + CHUNK - 1) // CHUNK
    gather = anc.shape[1] > 0
    for c in numba.prange(rows * nch):
        r = c // nch
        lo = (c % nch) * CHUNK
        hi = min(n, lo + CHUNK)
        for i in range(lo, hi):
            j = anc[r, i] if gather else i
            for a in range(d):
                m = 0.0
                for b in range(d):
                    m += F[a, b] * x[r, j, b]
                s = 0.0
                for b in range(d):
                    s += G[a, b] * eps[r, i, b]
                out[r, i, a] = m + s


_step_serial, _step_parallel = _twins(_step_py)


def linear_gaussian_step(
    states: Array, F: Array, G: Array, eps: Array, ancestors: NDArray[np.intp] | None = None
) -> Array:
    """``F x_{a_i} + G eps_i`` for states ``(R, N, d)``, noise ``(R, N, d)`` and ancestors
    ``(R, N)`` (None: ``a_i = i``). Returns a new array ``(R, N, d)``.

    The NumPy reference is ``states[r, a] @ F.T + eps @ G.T`` (``motion.sample`` after a gather).
    """
    x = np.ascontiguousarray(states, dtype=np.float64)
    e = np.ascontiguousarray(eps, dtype=np.float64)
    anc = np.zeros((x.shape[0], 0), dtype=np.intp) if ancestors is None else ancestors
    anc = np.ascontiguousarray(anc, dtype=np.intp)
    out = np.empty(e.shape)
    fn = _step_parallel if e.shape[0] * e.shape[1] >= PARALLEL_MIN else _step_serial
    fn(x, anc, np.ascontiguousarray(F, float), np.ascontiguousarray(G, float), e, out)
    return out


# ---------------------------------------------------------------------------------------------
# weighting: v_i = log w_i + sum_k log p(z_k | x_i), with the running maxima


def _relative_py(x, params, slots, dxy):  # pragma: no cover - jit
    """``dxy[0, slots[k], r, i] = x[r, i, ix] - sx`` and ``dxy[1, ...]`` the same in y, for the
    angular sensors ``k`` (``slots[k] >= 0``): the arguments of one vectorised ``atan2``."""
    rows, n, _ = x.shape
    nk = slots.shape[0]
    nch = (n + CHUNK - 1) // CHUNK
    for c in numba.prange(rows * nch):
        r = c // nch
        lo = (c % nch) * CHUNK
        hi = min(n, lo + CHUNK)
        for k in range(nk):
            j = slots[k]
            if j < 0:
                continue
            ix = int(params[k, 0])
            iy = int(params[k, 1])
            sx = params[k, 3]
            sy = params[k, 4]
            for i in range(lo, hi):
                dxy[0, j, r, i] = x[r, i, ix] - sx
                dxy[1, j, r, i] = x[r, i, iy] - sy


_relative_serial, _relative_parallel = _twins(_relative_py)


def _llsum_py(x, lw, kinds, params, z, usable, slots, ang, out, cmax):  # pragma: no cover - jit
    """``out[r, i] = lw[r, i] + sum_k ll_k`` (NaN -> -inf), ``cmax[r, c, k]`` = max over chunk
    ``c`` of the running sum after measurement ``k``. Unusable ``(r, k)`` add 0."""
    rows, n, _ = x.shape
    nk = kinds.shape[0]
    nch = (n + CHUNK - 1) // CHUNK
    for c in numba.prange(rows * nch):
        r = c // nch
        ch = c % nch
        lo = ch * CHUNK
        hi = min(n, lo + CHUNK)
        for i in range(lo, hi):
            v = lw[r, i]
            out[r, i] = -np.inf if v != v else v
        for k in range(nk):
            m = -np.inf
            kind = kinds[k]
            j = slots[k]
            z0 = z[r, k, 0]
            z1 = z[r, k, 1]
            use = usable[r, k]
            for i in range(lo, hi):
                v = out[r, i]
                if use:
                    a = ang[j, r, i] if j >= 0 else 0.0
                    v = v + _sensor_ll(kind, params, k, z0, z1, x, r, i, a)
                    if v != v:
                        v = -np.inf
                    out[r, i] = v
                if v > m:
                    m = v
            cmax[r, ch, k] = m


_llsum_serial, _llsum_parallel = _twins(_llsum_py)


def log_likelihood_sum(
    states: Array,
    log_w: Array,
    kinds: NDArray[np.int64],
    params: Array,
    z: Array,
    usable: NDArray[np.bool_],
) -> tuple[Array, Array]:
    """``(v, maxima)``: ``v = log_w + sum_k log p(z_k | x)`` rows ``(R, N)`` and ``maxima``
    ``(R, K)``, the maximum over particles of the running sum after measurement ``k``.

    ``states`` ``(R, N, d)``; ``kinds`` ``(K,)`` and ``params`` ``(K, N_PARAMS)`` from the
    sensors' ``fused_likelihood``; ``z`` ``(R, K, 2)`` (each measurement's value per run, padded);
    ``usable`` ``(R, K)`` (False: that measurement leaves that run alone).
    """
    x = np.ascontiguousarray(states, dtype=np.float64)
    rows, n, _ = x.shape
    kinds = np.ascontiguousarray(kinds, dtype=np.int64)
    params = np.ascontiguousarray(params, dtype=np.float64)
    angular = (kinds == BEARING) | (kinds == RANGE_BEARING)
    slots = np.where(angular, np.cumsum(angular) - 1, -1).astype(np.int64)
    big = rows * n >= PARALLEL_MIN
    # atan2 is NumPy's: its SIMD loop is several times faster than libm's scalar atan2 in Numba
    dxy = np.empty((2, int(angular.sum()), rows, n))
    (_relative_parallel if big else _relative_serial)(x, params, slots, dxy)
    ang = np.arctan2(dxy[1], dxy[0], out=dxy[0])
    nch = (n + CHUNK - 1) // CHUNK
    out = np.empty((rows, n))
    cmax = np.empty((rows, nch, kinds.shape[0]))
    (_llsum_parallel if big else _llsum_serial)(
        x,
        np.ascontiguousarray(log_w, dtype=np.float64),
        kinds,
        params,
        np.ascontiguousarray(z, dtype=np.float64),
        np.ascontiguousarray(usable, dtype=np.bool_),
        slots,
        ang,
        out,
        cmax,
    )
    return out, cmax.max(axis=1)
