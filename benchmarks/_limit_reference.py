"""The limit reference of ``pf_bearing.py``: the same bootstrap filter hand-fused in Numba.

Not a library: the fastest plain way we know to write *this one* filter (2-D constant velocity,
bearing sensors, systematic resampling every step) in Numba, to show how far fusetrack's general
filter is from what the machine can do. Per step:

1. noise ``eps ~ N(0, I)`` ``(N, 4)`` and one uniform from NumPy's generator;
2. one parallel pass (serial below 65536 particles, where threads cost more than they save): ``x'_i = F x_{a_i} + G eps_i`` (the resampled parent gathered in the same
   loop) and ``log w_i = -1/2 sum_s wrap(z_s - atan2(y_i - s_y, x_i - s_x))^2 / sigma^2``;
3. one serial pass for the maximum, then one for ``w_i = exp(log w_i - max)``, their sum and the
   weighted mean, then the systematic merge (cumulative sum on the fly) giving next step's
   ancestors ``a``.

The ``atan2`` and ``exp`` here are libm's scalar ones (what a hand-written Numba loop gets);
NumPy's SIMD loops for both are several times faster, which is why a general library that calls
them can beat this reference (see ``REPORT.md``).
"""

from __future__ import annotations

import math
import types

import numba
import numpy as np

from _scenario import Array, Scenario, cv_matrices

_TWO_PI = 2.0 * math.pi


def _predict_weigh_py(x, anc, F, G, eps, sensors, z, inv_var, x_out, logw):  # pragma: no cover
    n = x.shape[0]
    n_s = sensors.shape[0]
    for i in numba.prange(n):
        j = anc[i]
        for a in range(4):
            m = F[a, 0] * x[j, 0] + F[a, 1] * x[j, 1] + F[a, 2] * x[j, 2] + F[a, 3] * x[j, 3]
            m += G[a, 0] * eps[i, 0] + G[a, 1] * eps[i, 1] + G[a, 2] * eps[i, 2]
            m += G[a, 3] * eps[i, 3]
            x_out[i, a] = m
        px = x_out[i, 0]
        py = x_out[i, 1]
        lw = 0.0
        for s in range(n_s):
            r = z[s] - math.atan2(py - sensors[s, 1], px - sensors[s, 0])
            r -= _TWO_PI * math.floor((r + math.pi) / _TWO_PI)  # wrap to [-pi, pi)
            lw -= 0.5 * r * r * inv_var
        logw[i] = lw


# threads pay from about 65k particles; below, the serial compilation of the same loop (a
# renamed copy: Numba's disk cache is keyed by the function's name)
_predict_weigh = numba.njit(cache=True, parallel=True)(_predict_weigh_py)
_serial_py = types.FunctionType(_predict_weigh_py.__code__, globals(), "_predict_weigh_serial")
_serial_py.__qualname__ = "_predict_weigh_serial"
_predict_weigh_serial = numba.njit(cache=True)(_serial_py)
PARALLEL_MIN = 1 << 16


@numba.njit(cache=True, fastmath=False)
def _weigh_estimate_resample(x, logw, u0, anc, est):  # pragma: no cover
    n = x.shape[0]
    m = -np.inf
    for i in range(n):
        if logw[i] > m:
            m = logw[i]
    s = 0.0
    mx = 0.0
    my = 0.0
    for i in range(n):
        w = math.exp(logw[i] - m)
        logw[i] = w
        s += w
        mx += w * x[i, 0]
        my += w * x[i, 1]
    est[0] = mx / s
    est[1] = my / s
    j = 0
    c = logw[0]
    for k in range(n):  # systematic: u_k = (k + u0) / n of the total s
        u = (k + u0) / n * s
        while u >= c and j < n - 1:
            j += 1
            c += logw[j]
        anc[k] = j


class LimitReferencePF:
    """Hand-fused Numba bootstrap filter for the ``pf_bearing`` scenario (see module docstring)."""

    def __init__(self, scn: Scenario, n: int) -> None:
        self.scn, self.n = scn, n
        F, Q = cv_matrices(scn.dt, scn.q)
        self.F, self.G = F, np.linalg.cholesky(Q)
        self.L0 = np.linalg.cholesky(scn.prior_cov)
        self.inv_var = 1.0 / scn.sigma**2
        self.sensors = np.ascontiguousarray(scn.sensors, dtype=float)

    def run(self, seed: int, steps: int) -> Array:
        rng = np.random.default_rng(seed)
        n = self.n
        x = self.scn.prior_mean + rng.standard_normal((n, 4)) @ self.L0.T
        anc = np.arange(n)
        x_new = np.empty((n, 4))
        logw = np.empty(n)
        est = np.empty((steps, 2))
        for k in range(steps):
            eps = rng.standard_normal((n, 4))
            u0 = rng.random()
            z = np.ascontiguousarray(self.scn.z[k])
            fused = _predict_weigh if n >= PARALLEL_MIN else _predict_weigh_serial
            fused(x, anc, self.F, self.G, eps, self.sensors, z, self.inv_var, x_new, logw)
            x, x_new = x_new, x
            _weigh_estimate_resample(x, logw, u0, anc, est[k])
        return est
