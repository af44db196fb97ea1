"""Each run's own NumPy generator inside one threaded Numba loop over a batch of runs.

Batched Monte Carlo (R runs as one ``(R, N, d)`` array, one :class:`numpy.random.Generator` per
run) must draw, run by run, exactly what R separate runs draw, so that run ``r`` of the batch is
bit-identical to the separate run ``r``. Drawing run by run in NumPy costs one generator call
per run per step (and keeps the draws on one core). Here the run generators enter one kernel as
handles (:mod:`fusetrack.filters.rng_handles`: plain integers, cached kernels, no per-generator
cost per call), and :func:`linear_gaussian_runs`, the batch's propagation, takes one run per
work item over both cores (``numba.prange`` over the runs), each work item touching only its
own run's generator:

1. if the run is resampled: its uniform ``u0 = rng.random()`` and the systematic ancestors
   (:func:`fusetrack.core.resampling.systematic_row`, the code of
   :func:`~fusetrack.core.resampling.systematic`);
2. per particle, ``d`` standard normals ``eps`` in order and ``x'_i = F x_{a_i} + G eps_i``
   (:func:`fusetrack.filters.fused._affine_block`, the arithmetic of
   :func:`~fusetrack.filters.fused.linear_gaussian_step`).

That is the order in which a separate run draws (``systematic``'s ``rng.random``, then
``rng.standard_normal((N, d))``), so the result does not depend on the batch or the threads.
"""

from __future__ import annotations

from collections.abc import Sequence

import numba
import numpy as np
from numpy.typing import NDArray

from ..core import systematic_from_uniforms, systematic_row
from .fused import BLOCK, PARALLEL_MIN, _affine_block, _twins, threaded
from .rng_handles import RunStreams, _bitgen, next_double, random_standard_normal

Array = NDArray[np.float64]

KEEP, GATHER, SYSTEMATIC = 0, 1, 2
"""Per-run modes of :func:`linear_gaussian_runs`: propagate every particle, propagate the given
ancestors, resample systematically first."""

__all__ = [
    "GATHER",
    "KEEP",
    "SYSTEMATIC",
    "RunStreams",
    "linear_gaussian_runs",
    "linear_gaussian_runs_reference",
]


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
    if len(streams.gens) != rows or not streams.distinct:
        raise ValueError(
            f"streams: expected {rows} distinct generators (one per run), got "
            f"{len(streams.gens)}{'' if streams.distinct else ' with repeats'}"
        )
    if mode.shape != (rows,) or not np.isin(mode, (KEEP, GATHER, SYSTEMATIC)).all():
        raise ValueError(f"mode: expected {rows} values in (KEEP, GATHER, SYSTEMATIC)")
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
