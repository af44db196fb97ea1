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
* :func:`linear_gaussian_draw` -- the first with ``eps`` drawn inside the loop from generators
  given as :mod:`.rng_handles` (one stream, or fixed child streams on both cores), in vectorised
  blocks (:func:`_affine_block`).

Batches with one generator per run use :mod:`.run_streams` (propagation) and, below
:data:`SPLIT_MIN` particles per run, :mod:`.fused_update` (the whole update in one pass per run),
both built from the per-chunk code here.

A model offers a fast path through a small method that returns plain numbers:

* a motion model: ``fused_transition(dt) -> (F, G)`` with ``G G^T = Q(dt)``
  (:class:`~fusetrack.motion.ConstantVelocity` and the other linear-Gaussian models), or None;
* a sensor: ``fused_likelihood() -> (kind, index, position, heading, inv_var, log_norm[,
  chol_inv])`` with ``kind`` one of ``"bearing"``, ``"range"``, ``"range_bearing"``,
  ``"position"`` (the arguments of
  :func:`sensor_params`), or None (then the generic path runs).

The kernels are the NumPy models' arithmetic written per particle, so they agree with the
generic path to rounding (``atan2`` of Numba's libm and NumPy's may differ in the last bit);
the tests compare them. Each row (run) of a batch is computed by the same per-particle
operations whatever the batch size, so a run in a batch is bit-identical to the same run alone.

Threads: loops over at least :data:`PARALLEL_MIN` particles in total use ``numba.prange``
(``parallel=True``), smaller ones the serial compilation of the same code (thread start-up
costs more than it saves below that). ``numba.set_num_threads`` limits the threads. Threaded kernels are called through
:func:`threaded`, which first makes the OpenMP threads wait passively (:func:`passive_threads`).
"""

from __future__ import annotations

import math
import os
import types
from collections.abc import Callable
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from .rng_handles import RunStreams, _bitgen, random_standard_normal

Array = NDArray[np.float64]

BEARING = 0
RANGE = 1
RANGE_BEARING = 2
POSITION = 3
N_PARAMS = 16
PARALLEL_MIN = 1 << 16  # particles (all runs together) from which the threaded loops pay
CHUNK = 4096  # particles per work item of the threaded loops
BLOCK = 256  # particles per block of the propagation (its columns stay in L1)
NOISE_STREAMS = 4  # generators that share a large draw of process noise (fixed: not the threads)
SPLIT_MIN = PARALLEL_MIN  # particles per generator from which the noise is drawn by the streams

_TWO_PI = 2.0 * math.pi

__all__ = [
    "BEARING",
    "KINDS",
    "NOISE_STREAMS",
    "N_PARAMS",
    "PARALLEL_MIN",
    "POSITION",
    "RANGE",
    "RANGE_BEARING",
    "SPLIT_MIN",
    "linear_gaussian_draw",
    "linear_gaussian_step",
    "llsum_chunk",
    "log_likelihood_sum",
    "measurement_rows",
    "passive_threads",
    "sensor_params",
    "split_bounds",
    "standard_normals",
    "threaded",
]


KINDS = {"bearing": BEARING, "range": RANGE, "range_bearing": RANGE_BEARING, "position": POSITION}


def sensor_params(
    kind: str,
    index: tuple[int, ...],
    position: Array,
    heading: float = 0.0,
    inv_var: tuple[float, ...] = (),
    log_norm: float = 0.0,
    chol_inv: Array | None = None,
) -> Array:
    """The parameter vector of one sensor for :func:`log_likelihood_sum`.

    Layout: ``[ix, iy, iz, sx, sy, sz, heading, inv_var_0, inv_var_1, log_norm, l00, l10, l11,
    l20, l21, l22]``; an unused index is -1. ``inv_var`` are ``1 / sigma^2`` of the components
    in measurement order. A position fix (``z = x[index] + position + v``, ``position`` its
    bias) gives ``chol_inv = L^-1`` (lower triangular, ``L L^T = cov``), packed row by row.
    """
    if kind not in KINDS:
        raise ValueError(f"kind={kind!r} is invalid: expected one of {sorted(KINDS)}")
    p = np.zeros(N_PARAMS)
    p[:3] = -1.0
    for k, (i, s) in enumerate(zip(index, np.asarray(position, dtype=float))):
        p[k], p[3 + k] = float(i), float(s)
    p[6] = heading
    for k, v in enumerate(inv_var):
        p[7 + k] = v
    p[9] = log_norm
    if chol_inv is not None:
        li = np.asarray(chol_inv, dtype=float)
        p[10 : 10 + li.shape[0] * (li.shape[0] + 1) // 2] = li[np.tril_indices(li.shape[0])]
    return p


def passive_threads() -> None:
    """Make Numba's OpenMP threads sleep while they wait for work, unless the environment already
    chose (``OMP_WAIT_POLICY``). GNU OpenMP, Numba's threading layer here, spins by default: on a
    machine whose cores are busy with other processes the spinning threads take the CPU from the
    working ones, and the threaded loops ran 2.5x slower than serial ones (likelihood loop at
    N = 1e5, load 12: 32 ms spinning, 12 ms passive, 11 ms serial). OpenMP reads the variable
    once, when Numba starts its threading layer: at the first call of a threaded kernel (or of
    ``numba.get_num_threads``), which is why :func:`threaded` calls this first. Set here rather
    than at import so that importing fusetrack does not change the environment of a process that
    never runs a threaded kernel."""
    global _PASSIVE_DONE
    if not _PASSIVE_DONE:
        os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
        _PASSIVE_DONE = True


_PASSIVE_DONE = False


def threaded(kernel: Any) -> Any:
    """``kernel`` (a ``parallel=True`` dispatcher), after :func:`passive_threads`: call every
    threaded kernel through this."""
    if not _PASSIVE_DONE:
        passive_threads()
    return kernel


def _twins(py: Callable[..., Any]) -> tuple[Any, Any]:
    """Serial and threaded compilations of ``py``. The serial one compiles a renamed copy:
    Numba's on-disk cache is keyed by the function's qualified name and line, so two cached
    dispatchers of one function would keep overwriting (and reloading) each other's entry."""
    twin = types.FunctionType(py.__code__, py.__globals__, py.__name__ + "_serial")
    twin.__qualname__ = py.__qualname__ + "_serial"
    # error_model="numpy": no ZeroDivisionError checks, which stop the loops from vectorising
    serial = numba.njit(cache=True, nogil=True, error_model="numpy")(twin)
    return serial, numba.njit(cache=True, nogil=True, error_model="numpy", parallel=True)(py)


# ---------------------------------------------------------------------------------------------
# propagation: x'_i = F x_{a_i} + G eps_i


@numba.njit(cache=True, inline="always")
def _affine(F, G, xj, e, o):  # pragma: no cover - jit
    """``o = F xj + G e`` for one particle (1-D rows of length ``d``)."""
    d = o.shape[0]
    for a in range(d):
        m = 0.0
        for b in range(d):
            m += F[a, b] * xj[b] + G[a, b] * e[b]
        o[a] = m


def _step_py(x, anc, F, G, eps, out):  # pragma: no cover - jit
    rows, n, _ = out.shape
    nch = (n + CHUNK - 1) // CHUNK
    gather = anc.shape[1] > 0
    for c in numba.prange(rows * nch):
        r = c // nch
        lo = (c % nch) * CHUNK
        hi = min(n, lo + CHUNK)
        xr = x[r]
        er = eps[r]
        orow = out[r]
        ar = anc[r] if gather else anc[0]
        for i in range(lo, hi):
            _affine(F, G, xr[ar[i] if gather else i], er[i], orow[i])


_step_serial, _step_parallel = _twins(_step_py)


@numba.njit(cache=True, inline="always", error_model="numpy")
def _affine_block(F, G, xs, es, ms, orow, lo):  # pragma: no cover - jit
    """``orow[lo + i] = F xs[:, i] + G es[:, i]`` for the ``B`` particles of a block given as
    columns ``xs``, ``es`` ``(d, B)`` (``ms`` ``(B,)`` scratch). Each component is summed in the
    order of :func:`_affine` (the same bits), but the loop over the block's particles is
    innermost and contiguous, so the compiler vectorises it and ``F``, ``G`` are read once per
    block rather than once per particle (about 1 ms less per step at N = 1e5)."""
    d, nb = xs.shape
    for a in range(d):
        ms[:nb] = 0.0
        for b in range(d):
            f = F[a, b]
            g = G[a, b]
            xb = xs[b]
            eb = es[b]
            for i in range(nb):
                ms[i] += f * xb[i] + g * eb[i]
        for i in range(nb):
            orow[lo + i, a] = ms[i]


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
    fn = threaded(_step_parallel) if e.shape[0] * e.shape[1] >= PARALLEL_MIN else _step_serial
    fn(x, anc, np.ascontiguousarray(F, float), np.ascontiguousarray(G, float), e, out)
    return out


# ---------------------------------------------------------------------------------------------
# propagation with the draw inside the loop: x'_i = F x_{a_i} + G eps_i, eps_i from streams


def _draw_step_py(handles, x, anc, F, G, out):  # pragma: no cover - jit
    """:func:`_step_py` with ``eps`` drawn in the loop: the particles of all rows, flattened
    (run-major), are cut into ``len(handles)`` contiguous equal parts and part ``c`` draws its
    ``d`` normals per particle, in order, from generator ``c`` (what ``standard_normal`` of
    that part's shape ``(m, d)`` would return; generators as :mod:`.rng_handles` handles).
    Block by block: the block's normals and parents as columns, then :func:`_affine_block`."""
    rows, n, d = out.shape
    nx = x.shape[1]
    xf = x.reshape(rows * nx, d)
    of = out.reshape(rows * n, d)
    total = rows * n
    nst = handles.shape[0]
    per = (total + nst - 1) // nst
    gather = anc.shape[1] > 0
    for c in numba.prange(nst):
        bg = _bitgen(handles[c])
        xs = np.empty((d, BLOCK))
        es = np.empty((d, BLOCK))
        ms = np.empty(BLOCK)
        end = min(total, (c + 1) * per)
        for lo in range(c * per, end, BLOCK):
            nb = min(BLOCK, end - lo)
            for k in range(nb):
                p = lo + k
                r = p // n
                i = p - r * n
                j = r * nx + (anc[r, i] if gather else i)
                for a in range(d):
                    es[a, k] = random_standard_normal(bg)
                    xs[a, k] = xf[j, a]
            _affine_block(F, G, xs[:, :nb], es[:, :nb], ms, of, lo)


_draw_step_serial, _draw_step_parallel = _twins(_draw_step_py)


def split_bounds(total: int, parts: int) -> list[tuple[int, int]]:
    """The ``[lo, hi)`` particle ranges of the ``parts`` noise streams over ``total`` particles
    (as :func:`linear_gaussian_draw` cuts them)."""
    per = -(-total // parts)
    return [(min(total, c * per), min(total, (c + 1) * per)) for c in range(parts)]


def standard_normals(streams: tuple[np.random.Generator, ...], shape: tuple[int, ...]) -> Array:
    """NumPy reference of the draws of :func:`linear_gaussian_draw`: normals of ``shape``
    ``(..., d)`` whose particles (all leading axes flattened) are cut into ``len(streams)``
    contiguous parts, part ``c`` drawn by ``streams[c].standard_normal``. One stream is
    ``streams[0].standard_normal(shape)``."""
    if len(streams) == 1:
        return streams[0].standard_normal(shape)
    d = shape[-1]
    flat = np.empty((int(np.prod(shape[:-1], dtype=np.int64)), d))
    for g, (lo, hi) in zip(streams, split_bounds(flat.shape[0], len(streams))):
        g.standard_normal(out=flat[lo:hi])
    return flat.reshape(shape)


def linear_gaussian_draw(
    states: Array,
    F: Array,
    G: Array,
    streams: tuple[np.random.Generator, ...] | RunStreams,
    ancestors: NDArray[np.intp] | None = None,
) -> Array:
    """``F x_{a_i} + G eps_i`` for states ``(R, N, d)`` with ``eps`` drawn inside the loop from
    the generators ``streams`` (or their :class:`~fusetrack.filters.rng_handles.RunStreams`,
    which a caller keeps to save making the handles at every call; Numba's implementation of
    ``Generator.standard_normal``, the same numbers as NumPy's). Several streams fill their
    parts of the particles on parallel threads; the result depends on the streams, never on the
    number of threads.

    The NumPy reference is ``states[r, a] @ F.T + standard_normals(streams, shape) @ G.T``.
    """
    runs = streams if isinstance(streams, RunStreams) else RunStreams(streams)
    if not runs.distinct:  # two threads would advance one generator
        raise ValueError("streams: a generator appears more than once")
    x = np.ascontiguousarray(states, dtype=np.float64)
    anc = _NO_ANCESTORS if ancestors is None else np.ascontiguousarray(ancestors, dtype=np.intp)
    out = np.empty(x.shape if ancestors is None else (x.shape[0], anc.shape[1], x.shape[2]))
    fn = threaded(_draw_step_parallel) if len(runs.gens) > 1 else _draw_step_serial
    fn(runs.handles, x, anc, np.ascontiguousarray(F, float), np.ascontiguousarray(G, float), out)
    return out


_NO_ANCESTORS = np.zeros((1, 0), dtype=np.intp)


# ---------------------------------------------------------------------------------------------
# weighting: v_i = log w_i + sum_k log p(z_k | x_i), with the running maxima
#
# Angles without atan2 of the state: the residual of a bearing z (sensor heading h) is the
# angle between the direction phi = z + h and the relative position (dx, dy),
#     wrap(z - wrap(atan2(dy, dx) - h)) = -atan2(c_phi dy - s_phi dx, c_phi dx + s_phi dy),
# and only its square enters the Gaussian, so |atan2(s, c)| = atan2(|s|, c) is all that is
# needed. cos/sin of phi are computed once per (run, measurement); per particle the angle comes
# from a branch-free rational approximation of atan on [0, 1] (Cephes' atan, about 1 ulp), which
# the compiler vectorises, where libm's scalar atan2 cannot be.

_PIO2 = math.pi / 2.0
_PIO4 = math.pi / 4.0
_MOREBITS = 6.123233995736765886130e-17  # pi/2 - float(pi/2)
_P0, _P1, _P2, _P3, _P4 = (
    -8.750608600031904122785e-1,
    -1.615753718733365076637e1,
    -7.500855792314704667340e1,
    -1.228866684490136173410e2,
    -6.485021904942025371773e1,
)
_Q0, _Q1, _Q2, _Q3, _Q4 = (
    2.485846490142306297962e1,
    1.650270098316988542046e2,
    4.328810604912902668951e2,
    4.853903996359136964868e2,
    1.945506571482613964425e2,
)


@numba.njit(cache=True, inline="always", error_model="numpy")
def _abs_angle(s, c):  # pragma: no cover - jit
    """``|atan2(s, c)|`` in ``[0, pi]`` without branches (Cephes ``atan`` on ``[0, 1]``:
    ``t > 0.66`` is reduced by ``atan t = pi/4 + atan((t - 1) / (t + 1))``)."""
    a_s = abs(s)
    a_c = abs(c)
    steep = a_s > a_c
    lo = min(a_s, a_c)
    hi = max(a_s, a_c)
    hi = hi if hi > 0.0 else 1.0  # (0, 0): angle 0, as atan2(0, 0)
    big = lo > 0.66 * hi
    num = lo - hi if big else lo
    den = lo + hi if big else hi
    t = num / den
    z = t * t
    p = (((_P0 * z + _P1) * z + _P2) * z + _P3) * z + _P4
    q = ((((z + _Q0) * z + _Q1) * z + _Q2) * z + _Q3) * z + _Q4
    y = t + t * (z * p / q)
    y = y + (_PIO4 + 0.5 * _MOREBITS) if big else y  # atan(lo / hi) in [0, pi/4]
    y = (_PIO2 - y) + _MOREBITS if steep else y  # atan(a_s / a_c) in [0, pi/2]
    return (2.0 * _PIO2 - y) + 2.0 * _MOREBITS if c < 0.0 else y


@numba.njit(cache=True, inline="always", error_model="numpy")
def _add_bearing(px, py, sx, sy, cphi, sphi, half_iv, log_norm, out):  # pragma: no cover - jit
    """``out += log p(z | x)`` of a bearing for contiguous position columns ``px, py``."""
    for i in range(out.shape[0]):
        dx = px[i] - sx
        dy = py[i] - sy
        at = (dx == 0.0) & (dy == 0.0)  # atan2(0, 0) = 0: the direction (1, 0)
        dx = 1.0 if at else dx
        e = _abs_angle(cphi * dy - sphi * dx, cphi * dx + sphi * dy)
        v = out[i] + (log_norm - half_iv * (e * e))
        out[i] = -np.inf if v != v else v


@numba.njit(cache=True, inline="always", error_model="numpy")
def _add_range(px, py, pz, sx, sy, sz, z0, half_iv, log_norm, out):  # pragma: no cover - jit
    """``out += log p(z | x)`` of a range (``pz`` empty in 2-D)."""
    three = pz.shape[0] > 0
    for i in range(out.shape[0]):
        dx = px[i] - sx
        dy = py[i] - sy
        s = dx * dx + dy * dy
        if three:
            dz = pz[i] - sz
            s += dz * dz
        e = z0 - math.sqrt(s)
        v = out[i] + (log_norm - half_iv * (e * e))
        out[i] = -np.inf if v != v else v


@numba.njit(cache=True, inline="always", error_model="numpy")
def _add_range_bearing(px, py, sx, sy, z0, cphi, sphi, h0, h1, log_norm, out):
    # pragma: no cover - jit
    """``out += log p(z | x)`` of a range-bearing pair."""
    for i in range(out.shape[0]):
        dx = px[i] - sx
        dy = py[i] - sy
        e0 = z0 - math.sqrt(dx * dx + dy * dy)
        at = (dx == 0.0) & (dy == 0.0)
        dx = 1.0 if at else dx
        e1 = _abs_angle(cphi * dy - sphi * dx, cphi * dx + sphi * dy)
        v = out[i] + (log_norm - (h0 * (e0 * e0) + h1 * (e1 * e1)))
        out[i] = -np.inf if v != v else v


@numba.njit(cache=True, inline="always", error_model="numpy")
def _add_position(px, py, pz, k, z, p, log_norm, out):  # pragma: no cover - jit
    """``out += log p(z | x)`` of a position fix with ``k`` components: ``r = z - x - bias``,
    ``u = L^-1 r``, ``log_norm - |u|^2 / 2`` (``z`` its 3 padded values, ``p`` its params)."""
    for i in range(out.shape[0]):
        e0 = z[0] - (px[i] + p[3])
        u = p[10] * e0
        q = u * u
        if k >= 2:
            e1 = z[1] - (py[i] + p[4])
            u = p[11] * e0 + p[12] * e1
            q += u * u
            if k >= 3:
                e2 = z[2] - (pz[i] + p[5])
                u = p[13] * e0 + p[14] * e1 + p[15] * e2
                q += u * u
        v = out[i] + (log_norm - 0.5 * q)
        out[i] = -np.inf if v != v else v


@numba.njit(cache=True, inline="always")
def _column(x, r, lo, j, col):  # pragma: no cover - jit
    """``col[i] = x[r, lo + i, j]``: one state component of a chunk, contiguous (the loops
    above vectorise on contiguous columns, not on the strided state rows)."""
    for i in range(col.shape[0]):
        col[i] = x[r, lo + i, j]


@numba.njit(cache=True, nogil=True, fastmath={"nnan", "nsz"})
def _max_no_nan(v):  # pragma: no cover - jit
    """``max(v)`` (``-inf`` if empty) of values that are never NaN (the loops above turn NaN
    into ``-inf``): told so, the compiler vectorises the reduction, which it must not for a
    maximum that has to propagate NaN. The maximum is exact either way."""
    m = -np.inf
    for i in range(v.shape[0]):
        m = max(m, v[i])
    return m


@numba.njit(cache=True, inline="always", error_model="numpy")
def llsum_chunk(x, r, lo, lw, kinds, params, zc, usable, o, px, py, pz, cm):
    # pragma: no cover - jit
    """Particles ``lo .. lo + len(o)`` of run ``r``: ``o = lw + sum_k ll_k`` (NaN -> -inf) and
    ``cm[k]`` = max of the running sum after measurement ``k`` (``px, py, pz``: scratch columns
    as long as ``o``). One loop per measurement over contiguous position columns (vectorised).
    Shared by :func:`_llsum_py` and the one-pass update of :mod:`.fused_update`."""
    nk = kinds.shape[0]
    m = o.shape[0]
    for i in range(m):
        v = lw[r, lo + i]
        o[i] = -np.inf if v != v else v
    have = (-1, -1, -1)  # which state components px, py, pz hold
    for k in range(nk):
        if usable[r, k]:
            p = params[k]
            kind = kinds[k]
            ix = int(p[0])
            iy = int(p[1])
            iz = int(p[2])
            if ix != have[0]:
                _column(x, r, lo, ix, px)
            if iy >= 0 and iy != have[1]:
                _column(x, r, lo, iy, py)
            if iz >= 0 and iz != have[2]:
                _column(x, r, lo, iz, pz)
            have = (ix, iy if iy >= 0 else have[1], iz if iz >= 0 else have[2])
            z = zc[r, k]
            if kind == 0:
                _add_bearing(px, py, p[3], p[4], z[3], z[4], 0.5 * p[7], p[9], o)
            elif kind == 1:
                pz3 = pz[: m if iz >= 0 else 0]
                _add_range(px, py, pz3, p[3], p[4], p[5], z[0], 0.5 * p[7], p[9], o)
            elif kind == 2:
                _add_range_bearing(
                    px, py, p[3], p[4], z[0], z[3], z[4], 0.5 * p[7], 0.5 * p[8], p[9], o
                )
            else:
                dims = 1 + (iy >= 0) + (iz >= 0)
                _add_position(px, py, pz, dims, z, p, p[9], o)
        cm[k] = _max_no_nan(o)


def _llsum_py(x, lw, kinds, params, zc, usable, out, cmax):  # pragma: no cover - jit
    """``out[r, i] = lw[r, i] + sum_k ll_k`` (NaN -> -inf), ``cmax[r, c, k]`` = max over chunk
    ``c`` of the running sum after measurement ``k``. Unusable ``(r, k)`` add 0. ``zc[r, k]`` is
    ``[z0, z1, z2, cos phi, sin phi]`` with ``phi`` the bearing component plus the heading.
    Work items: (run, chunk of :data:`CHUNK` particles), :func:`llsum_chunk` each."""
    rows, n, _ = x.shape
    nch = (n + CHUNK - 1) // CHUNK
    for c in numba.prange(rows * nch):
        r = c // nch
        ch = c % nch
        lo = ch * CHUNK
        hi = min(n, lo + CHUNK)
        px = np.empty(hi - lo)
        py = np.empty(hi - lo)
        pz = np.empty(hi - lo)
        llsum_chunk(x, r, lo, lw, kinds, params, zc, usable, out[r, lo:hi], px, py, pz, cmax[r, ch])


_llsum_serial, _llsum_parallel = _twins(_llsum_py)


def measurement_rows(
    kinds: NDArray[np.int64], params: Array, z: Array
) -> tuple[NDArray[np.int64], Array, Array]:
    """The kernels' form of the measurements: contiguous ``kinds``, ``params`` and ``zc``
    ``(R, K, 5)``, each value padded to 3 components followed by ``cos phi, sin phi`` (``phi``
    the bearing component plus the sensor's heading)."""
    kinds = np.ascontiguousarray(kinds, dtype=np.int64)
    params = np.ascontiguousarray(params, dtype=np.float64)
    z = np.asarray(z, dtype=np.float64)
    zc = np.zeros((z.shape[0], kinds.shape[0], 5))
    zc[..., : z.shape[-1]] = z
    phi = np.where(kinds == RANGE_BEARING, zc[..., 1], zc[..., 0]) + params[:, 6]
    np.cos(phi, out=zc[..., 3])
    np.sin(phi, out=zc[..., 4])
    return kinds, params, zc


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
    sensors' ``fused_likelihood``; ``z`` ``(R, K, m)``, ``m <= 3`` (each measurement's value per
    run, padded);
    ``usable`` ``(R, K)`` (False: that measurement leaves that run alone). One pass over the
    particles (threaded from :data:`PARALLEL_MIN` particles in total).
    """
    x = np.ascontiguousarray(states, dtype=np.float64)
    rows, n, _ = x.shape
    kinds, params, zc = measurement_rows(kinds, params, z)
    nch = (n + CHUNK - 1) // CHUNK
    out = np.empty((rows, n))
    cmax = np.empty((rows, nch, kinds.shape[0]))
    (threaded(_llsum_parallel) if rows * n >= PARALLEL_MIN else _llsum_serial)(
        x,
        np.ascontiguousarray(log_w, dtype=np.float64),
        kinds,
        params,
        zc,
        np.ascontiguousarray(usable, dtype=np.bool_),
        out,
        cmax,
    )
    return out, cmax.max(axis=1)
