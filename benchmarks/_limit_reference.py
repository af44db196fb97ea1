"""The limit reference of ``pf_bearing.py``: the same bootstrap filter hand-fused in Numba.

Not a library: the fastest plain way we know to write *this one* filter (2-D constant velocity,
bearing sensors, systematic resampling every step) in Numba, to show how far fusetrack's general
filter is from what the machine can do. Per step:

1. one parallel pass (serial below 65536 particles, where threads cost more than they save):
   ``x'_i = F x_{a_i} + G eps_i`` (the resampled parent gathered in the same loop) and
   ``log w_i = -1/2 sum_s e_s^2 / sigma^2``, ``e_s`` the bearing residual of sensor ``s``,
   block by block (1024 particles: propagate the block, then each sensor's residuals on the
   block's contiguous position columns, where the compiler vectorises the arithmetic);
2. one serial pass for the maximum, then one for ``w_i = exp(log w_i - max)``, their sum and the
   weighted mean, then the systematic merge (cumulative sum on the fly) giving next step's
   ancestors ``a``.

The random numbers are NumPy's generator's, drawn exactly as fusetrack draws them so that both
return the same estimates: below 65536 particles ``rng.standard_normal((N, 4))`` before the pass;
from 65536 particles the same trick as fusetrack, the particles cut into 4 contiguous parts whose
normals come from 4 child generators spawned once from ``rng`` (``rng.spawn(4)``), drawn inside the
parallel pass (Numba's implementation of ``Generator.standard_normal``, bit-identical to NumPy's,
on the children's bit-generator handles of ``fusetrack.filters.rng_handles``, as fusetrack does)
so that the draws use both cores. The resampling uniform is ``rng.random()`` each step.

The bearing residual is computed as fusetrack computes it (``fused._abs_angle``: the angle between
the measured direction and the relative position, from a branch-free rational ``atan``) rather
than with libm's scalar ``atan2``, which a hand-written loop would otherwise call and which is
several times slower; ``exp`` is fusetrack's vectorised one (``fused_update.exp_nonpositive``,
within 1 ulp of NumPy's; libm's scalar ``exp`` made this pass 2-3x slower) and the maximum a
vectorised reduction, as in fusetrack (2026-12-02).
"""

from __future__ import annotations

import types

import numba
import numpy as np

from _scenario import Array, Scenario, cv_matrices
from fusetrack.filters.fused import _abs_angle, _max_no_nan, passive_threads
from fusetrack.filters.fused_update import exp_nonpositive
from fusetrack.filters.rng_handles import RunStreams, _bitgen, random_standard_normal

PARALLEL_MIN = 1 << 16
STREAMS = 4
BLOCK = 1024


@numba.njit(cache=True, inline="always", error_model="numpy")
def _block(x, anc, F, G, eps, lo, hi, sensors, cz, sz, half_iv, x_out, logw, px, py):
    # pragma: no cover - jit
    """Propagate particles ``lo:hi`` with noise rows ``eps[0:hi-lo]``, then their log-weights."""
    for i in range(lo, hi):
        j = anc[i]
        k = i - lo
        for a in range(4):
            m = F[a, 0] * x[j, 0] + F[a, 1] * x[j, 1] + F[a, 2] * x[j, 2] + F[a, 3] * x[j, 3]
            m += G[a, 0] * eps[k, 0] + G[a, 1] * eps[k, 1] + G[a, 2] * eps[k, 2]
            m += G[a, 3] * eps[k, 3]
            x_out[i, a] = m
        px[k] = x_out[i, 0]
        py[k] = x_out[i, 1]
        logw[i] = 0.0
    for s in range(sensors.shape[0]):
        c = cz[s]
        sn = sz[s]
        for k in range(hi - lo):
            dx = px[k] - sensors[s, 0]
            dy = py[k] - sensors[s, 1]
            e = _abs_angle(c * dy - sn * dx, c * dx + sn * dy)
            logw[lo + k] -= half_iv * (e * e)


def _with_noise_py(x, anc, F, G, eps, sensors, cz, sz, half_iv, x_out, logw):  # pragma: no cover
    n = x.shape[0]
    for b in numba.prange((n + BLOCK - 1) // BLOCK):
        lo = b * BLOCK
        hi = min(n, lo + BLOCK)
        px = np.empty(BLOCK)
        py = np.empty(BLOCK)
        _block(x, anc, F, G, eps[lo:hi], lo, hi, sensors, cz, sz, half_iv, x_out, logw, px, py)


def _draw_py(handles, x, anc, F, G, sensors, cz, sz, half_iv, x_out, logw):  # pragma: no cover
    n = x.shape[0]
    per = (n + handles.shape[0] - 1) // handles.shape[0]
    for c in numba.prange(handles.shape[0]):
        g = _bitgen(handles[c])
        eps = np.empty((BLOCK, 4))
        px = np.empty(BLOCK)
        py = np.empty(BLOCK)
        for lo in range(c * per, min(n, (c + 1) * per), BLOCK):
            hi = min(n, (c + 1) * per, lo + BLOCK)
            for k in range(hi - lo):
                for a in range(4):
                    eps[k, a] = random_standard_normal(g)
            _block(x, anc, F, G, eps, lo, hi, sensors, cz, sz, half_iv, x_out, logw, px, py)


def _compile(py, name: str, parallel: bool):  # type: ignore[no-untyped-def]
    """Numba's disk cache is keyed by the function's name: serial and threaded copies get
    their own names."""
    fn = types.FunctionType(py.__code__, globals(), name)
    fn.__qualname__ = name
    return numba.njit(cache=True, parallel=parallel, error_model="numpy")(fn)


_with_noise = _compile(_with_noise_py, "_with_noise_parallel", True)
_with_noise_serial = _compile(_with_noise_py, "_with_noise_serial", False)
_draw = _compile(_draw_py, "_draw_parallel", True)


@numba.njit(cache=True, fastmath=False)
def _weigh_estimate_resample(x, logw, u0, anc, est):  # pragma: no cover
    n = x.shape[0]
    m = _max_no_nan(logw)
    for i in range(n):  # vectorised: fusetrack's branch-free exp (libm's costs 13-17 ns)
        logw[i] = exp_nonpositive(logw[i] - m)
    s = 0.0
    mx = 0.0
    my = 0.0
    for i in range(n):
        w = logw[i]
        s += w
        mx += w * x[i, 0]
        my += w * x[i, 1]
    est[0] = mx / s
    est[1] = my / s
    j = 0
    c = logw[0]
    step = s / n
    for k in range(n):  # systematic: u_k = (k + u0) / n of the total s
        u = (k + u0) * step
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
        self.half_iv = 0.5 / scn.sigma**2
        self.sensors = np.ascontiguousarray(scn.sensors, dtype=float)
        self.cz = np.ascontiguousarray(np.cos(scn.z))  # (steps, sensors): the measured directions
        self.sz = np.ascontiguousarray(np.sin(scn.z))

    def run(self, seed: int, steps: int) -> Array:
        rng = np.random.default_rng(seed)
        n = self.n
        x = self.scn.prior_mean + rng.standard_normal((n, 4)) @ self.L0.T
        # RunStreams keeps the children alive: their handles are pointers into them
        kids = RunStreams(rng.spawn(STREAMS)) if n >= PARALLEL_MIN else None
        streams = None if kids is None else kids.handles
        if streams is not None:
            passive_threads()  # as fusetrack's threaded kernels: OpenMP threads sleep when idle
        anc = np.arange(n)
        x_new = np.empty((n, 4))
        logw = np.empty(n)
        est = np.empty((steps, 2))
        F, G, sensors, half_iv = self.F, self.G, self.sensors, self.half_iv
        for k in range(steps):
            cz, sz = self.cz[k], self.sz[k]
            if streams is not None:
                _draw(streams, x, anc, F, G, sensors, cz, sz, half_iv, x_new, logw)
            else:
                eps = rng.standard_normal((n, 4))
                _with_noise_serial(x, anc, F, G, eps, sensors, cz, sz, half_iv, x_new, logw)
            u0 = rng.random()
            x, x_new = x_new, x
            _weigh_estimate_resample(x, logw, u0, anc, est[k])
        return est
