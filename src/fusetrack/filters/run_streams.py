"""Each run's own NumPy generator inside one threaded Numba loop over a batch of runs.

Batched Monte Carlo (R runs as one ``(R, N, d)`` array, one :class:`numpy.random.Generator` per
run) must draw, run by run, exactly what R separate runs draw, so that run ``r`` of the batch is
bit-identical to the separate run ``r``. Drawing run by run in NumPy costs one generator call per
run per step; handing the generators to a Numba function costs 20-50 us per generator per call
(Numba builds each Generator's type and unboxes its ctypes interface), and a ``numba.typed.List``
of them compiles for about 9 s in every new process (that type does not cache).

Here every generator is reduced, once, to four integers from NumPy's documented C interface of
its bit generator (``bit_generator.ctypes``: the address of its state and of its ``next_uint64``,
``next_uint32`` and ``next_double`` functions), a row of a ``(R, 4)`` ``uint64`` array
(:func:`generator_handles`). Inside a kernel, :func:`_bitgen` rebuilds Numba's bit-generator
struct from a row, and Numba's own implementations of NumPy's distributions run on it:
``random_standard_normal`` is NumPy's ziggurat (the same numbers as ``Generator.standard_normal``,
bit for bit; tested) and ``next_double`` is ``Generator.random``. The arguments are plain arrays,
so the kernels are cached on disk like any other (no compile in a new process).

:func:`linear_gaussian_runs` is the batch's propagation, one run per work item over both cores
(``numba.prange`` over the runs), each work item touching only its own run's generator:

1. if the run is resampled: its uniform ``u0 = rng.random()`` and the systematic ancestors
   (:func:`fusetrack.core.resampling.systematic_row`, the code :func:`~fusetrack.core.resampling.systematic`
   runs);
2. per particle, ``d`` standard normals ``eps`` in order and ``x'_i = F x_{a_i} + G eps_i``
   (:func:`fusetrack.filters.fused._affine`, the code of :func:`~fusetrack.filters.fused.linear_gaussian_step`).

That is the order in which a separate run draws (``systematic``'s ``rng.random``, then
``rng.standard_normal((N, d))``), so the result does not depend on the batch or the threads.

Safety: the handles are raw pointers into the generators' bit generators, valid while those
objects live; :class:`RunStreams` keeps the generators with their handles. A generator's state
is advanced by one thread only (its run's work item) and NumPy's per-generator lock is not taken:
do not draw from the same generators in other Python threads during a call.
"""

from __future__ import annotations

import ctypes
from collections.abc import Sequence

import numba
import numpy as np
from numba import types
from numba.core import cgutils
from numba.core.extending import intrinsic
from numba.np.random.distributions import random_standard_normal
from numba.np.random.generator_core import next_double
from numpy.typing import NDArray

from ..core.resampling import systematic_row
from .fused import PARALLEL_MIN, _twins, threaded

Array = NDArray[np.float64]

BLOCK = 256  # particles per block of the propagation (columns that stay in L1)
KEEP, GATHER, SYSTEMATIC = 0, 1, 2
"""Per-run modes of :func:`linear_gaussian_runs`: propagate every particle, propagate the given
ancestors, resample systematically first."""

__all__ = [
    "GATHER",
    "KEEP",
    "SYSTEMATIC",
    "RunStreams",
    "generator_handles",
    "linear_gaussian_runs",
    "linear_gaussian_runs_reference",
]


def _address(fn: object) -> int:
    value = ctypes.cast(fn, ctypes.c_void_p).value  # type: ignore[arg-type]
    return int(value or 0)


def generator_handles(gens: Sequence[np.random.Generator]) -> NDArray[np.uint64]:
    """``(R, 4)`` rows ``[state, next_uint64, next_uint32, next_double]`` (addresses) of the
    generators' bit generators, from NumPy's ``bit_generator.ctypes`` interface."""
    out = np.empty((len(gens), 4), dtype=np.uint64)
    for j, g in enumerate(gens):
        c = g.bit_generator.ctypes
        out[j] = (
            int(c.state_address),
            _address(c.next_uint64),
            _address(c.next_uint32),
            _address(c.next_double),
        )
    return out


class RunStreams:
    """The handles of a sequence of generators, with the generators (which keep the pointed-to
    states alive). :meth:`matches` tells whether another sequence holds the same objects."""

    def __init__(self, gens: Sequence[np.random.Generator]) -> None:
        self.gens = tuple(gens)
        self.handles = generator_handles(self.gens)

    def matches(self, gens: Sequence[np.random.Generator]) -> bool:
        return len(gens) == len(self.gens) and all(a is b for a, b in zip(gens, self.gens))


@intrinsic
def _bitgen(tyctx, handle):  # pragma: no cover - compile time
    """Numba's bit-generator struct (what unboxing a ``BitGenerator`` builds) from one row of
    :func:`generator_handles`."""
    bg_type = types.NumPyRandomBitGeneratorType("bit_generator")
    sig = bg_type(handle)

    def codegen(ctx, builder, sig, args):
        row = ctx.make_array(sig.args[0])(ctx, builder, args[0])

        def item(i: int):
            idx = [ctx.get_constant(types.intp, i)]
            return builder.load(cgutils.get_item_pointer(ctx, builder, sig.args[0], row, idx))

        bg = cgutils.create_struct_proxy(bg_type)(ctx, builder)
        bg.parent = cgutils.get_null_value(bg.parent.type)
        bg.state_address = item(0)
        bg.state = item(0)
        bg.fnptr_next_uint64 = item(1)
        bg.fnptr_next_uint32 = item(2)
        bg.fnptr_next_double = item(3)
        bg.bit_generator = ctx.get_constant(types.uintp, 0)
        return bg._getvalue()

    return sig, codegen


@numba.njit(cache=True, inline="always", error_model="numpy")
def _affine_block(F, G, xs, es, ms, orow, lo):  # pragma: no cover - jit
    """``orow[lo + i] = F xs[:, i] + G es[:, i]`` for the ``B`` particles of a block given as
    columns ``xs``, ``es`` ``(d, B)`` (``ms`` ``(B,)`` scratch). Each component is summed in the
    order of :func:`fusetrack.filters.fused._affine` (the same bits), but the loop over the
    block's particles is innermost and contiguous, so the compiler vectorises it and ``F``, ``G``
    are read once per block rather than once per particle."""
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


def _runs_py(handles, x, F, G, w, mode, anc, out):  # pragma: no cover - jit
    """Run ``r`` (one work item): by ``mode[r]``, systematic ancestors from ``w[r]`` with
    ``u0`` from the run's stream, the given ``anc[r]``, or none; then ``d`` normals per particle
    from the run's stream and ``out[r, i] = F x[r, a_i] + G eps_i``, block by block."""
    rows, n, d = out.shape
    for r in numba.prange(rows):
        bg = _bitgen(handles[r])
        m = mode[r]
        a = anc[r] if m == GATHER else np.empty(n if m == SYSTEMATIC else 0, dtype=np.intp)
        if m == SYSTEMATIC:
            systematic_row(w[r], next_double(bg), a, np.empty(n + 1, dtype=np.intp))
        xs = np.empty((d, BLOCK))
        es = np.empty((d, BLOCK))
        ms = np.empty(BLOCK)
        xr = x[r]
        for lo in range(0, n, BLOCK):
            nb = min(BLOCK, n - lo)
            for i in range(nb):
                j = a[lo + i] if m != KEEP else lo + i
                for k in range(d):
                    es[k, i] = random_standard_normal(bg)
                    xs[k, i] = xr[j, k]
            _affine_block(F, G, xs[:, :nb], es[:, :nb], ms, out[r], lo)


_runs_serial, _runs_parallel = _twins(_runs_py)


def linear_gaussian_runs(
    streams: RunStreams,
    states: Array,
    F: Array,
    G: Array,
    mode: NDArray[np.int64],
    weights: Array | None = None,
    ancestors: NDArray[np.intp] | None = None,
) -> Array:
    """``F x_{a_i} + G eps_i`` for states ``(R, N, d)``, run ``r`` drawing from
    ``streams.gens[r]`` (see the module docstring); ``mode`` ``(R,)``: :data:`KEEP`
    (``a_i = i``), :data:`GATHER` (``a = ancestors[r]``, ``(R, N)``) or :data:`SYSTEMATIC`
    (resampled by ``weights[r]``, ``(R, N)``, normalised). Returns a new ``(R, N, d)`` array.
    The NumPy reference is :func:`linear_gaussian_runs_reference`."""
    x = np.ascontiguousarray(states, dtype=np.float64)
    rows, n, d = x.shape
    mode = np.ascontiguousarray(mode, dtype=np.int64)
    w = _EMPTY_W if weights is None else np.ascontiguousarray(weights, dtype=np.float64)
    anc = _EMPTY_A if ancestors is None else np.ascontiguousarray(ancestors, dtype=np.intp)
    if (mode == SYSTEMATIC).any() and w.shape != (rows, n):
        raise ValueError(f"weights.shape={w.shape} is invalid: expected {(rows, n)}")
    if (mode == GATHER).any() and anc.shape != (rows, n):
        raise ValueError(f"ancestors.shape={anc.shape} is invalid: expected {(rows, n)}")
    out = np.empty((rows, n, d))
    fn = threaded(_runs_parallel) if rows > 1 and rows * n >= PARALLEL_MIN else _runs_serial
    F = np.ascontiguousarray(F, dtype=np.float64)
    G = np.ascontiguousarray(G, dtype=np.float64)
    fn(streams.handles, x, F, G, w, mode, anc, out)
    return out


_EMPTY_W = np.zeros((0, 0))
_EMPTY_A = np.zeros((0, 0), dtype=np.intp)


def linear_gaussian_runs_reference(
    gens: Sequence[np.random.Generator],
    states: Array,
    F: Array,
    G: Array,
    mode: NDArray[np.int64],
    weights: Array | None = None,
    ancestors: NDArray[np.intp] | None = None,
) -> Array:
    """NumPy reference of :func:`linear_gaussian_runs`: run by run, ``rng.random()`` and
    :func:`~fusetrack.core.resampling.systematic_from_uniforms` for a resampled run, then
    ``x[a] @ F.T + rng.standard_normal((N, d)) @ G.T``."""
    from ..core.resampling import systematic_from_uniforms

    x = np.asarray(states, dtype=float)
    out = np.empty_like(x)
    n, d = x.shape[-2:]
    for r, g in enumerate(gens):
        if mode[r] == SYSTEMATIC:
            a = systematic_from_uniforms(np.asarray(weights)[r : r + 1], np.array([g.random()]))[0]
        elif mode[r] == GATHER:
            a = np.asarray(ancestors)[r]
        else:
            a = np.arange(n)
        out[r] = x[r, a] @ np.asarray(F).T + g.standard_normal((n, d)) @ np.asarray(G).T
    return out
