"""The grid path: each array's unlabelled bearings as a likelihood over Kushwaha's cells, fused
by product, and the peaks of the fused map as position measurements.

For one target at cell ``x`` and an array that reports the bearing set ``Z`` (each target heard
with ``P_D``, clutter with density ``kappa`` per radian), the likelihood ratio of "the target is
at x" is, up to a constant (the single-target clutter likelihood, Bar-Shalom, Daum & Huang
2009, the PDA section)::

    l(x) = 1 - P_D + P_D / kappa * sum_j N(z_j; theta(x), sigma^2)

averaged over the arc the cell subtends (Kushwaha 2010, Eq. 32, with the closed form of
:func:`fusetrack.sensors.mixture_arc_mean`). The arrays are fused by product (Kushwaha 2010,
Eq. 30, :func:`fusetrack.filters.fuse_product`) with no temporal prior, and the peaks are those
of ``kushwaha2010-mcmcda`` (:func:`fusetrack.association.likelihood_peaks`). Two arrays give
the same ghosts as triangulation (each intersection is a peak); with three, a ghost lacks the
third array's factor and falls below the relative threshold.

A peak's covariance is the inverse Fisher information of every array's bearing at it, plus the
cell's quantisation variance ``cell^2 / 12`` per axis.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ...association import likelihood_peaks
from ...core import Measurement
from ...filters import GridSpec, fuse_product
from ...sensors import cell_arcs, mixture_arc_mean
from .scenario import Array, Scene

REL_THRESHOLD = 0.3  # as kushwaha2010-mcmcda
MIN_CLUTTER = 0.05  # bearings per scan: the density is never taken as zero


@lru_cache(maxsize=16)
def _arcs(x: float, y: float, grid: GridSpec) -> tuple[Array, Array]:
    lo, hi, _ = cell_arcs((x, y), 0.0, grid.centres, grid.cell / 2)
    return lo, hi


def array_likelihood(scene: Scene, x: float, y: float, bearings: Array) -> Array:
    """``l(x)`` of one array over the cells (module docstring), ``(cells,)``."""
    lo, hi = _arcs(x, y, scene.grid)
    z = np.asarray(bearings, float)
    base = 1.0 - scene.p_detect
    if z.size == 0:
        return np.full(lo.shape, max(base, 1e-3))
    means = np.concatenate([z - 2 * np.pi, z, z + 2 * np.pi])  # lo/hi may pass +-pi
    sigmas = np.full(means.shape, scene.sigma)
    kappa = max(scene.clutter, MIN_CLUTTER) / (2 * np.pi)
    density = mixture_arc_mean(np.ones(means.size), means, sigmas, lo, hi)
    return np.maximum(base, 1e-3) + scene.p_detect / kappa * density


def fused_map(scene: Scene, scan: dict[str, Array]) -> Array:
    """The product of the arrays' likelihoods, normalised, ``grid.shape``."""
    rows = [array_likelihood(scene, x, y, scan[sid]) for sid, x, y in scene.arrays]
    return fuse_product(np.stack(rows)).reshape(scene.grid.shape)


def peak_cov(scene: Scene, p: Array) -> Array:
    """Inverse Fisher information of all arrays' bearings at ``p`` plus the cell's variance."""
    s = np.array([[x, y] for _, x, y in scene.arrays])
    d = np.asarray(p, float)[None, :] - s
    h = np.column_stack([-d[:, 1], d[:, 0]]) / np.sum(d * d, axis=1)[:, None]
    cov = np.linalg.inv(h.T @ h / scene.sigma**2) + np.eye(2) * scene.grid.cell**2 / 12
    return 0.5 * (cov + cov.T)


def peaks(scene: Scene, scan: dict[str, Array]) -> Array:
    """Peak positions ``(k, 2)`` of the fused map of one scan."""
    g = scene.grid
    return likelihood_peaks(fused_map(scene, scan), g.x, g.y, REL_THRESHOLD)


def peak_measurements(scene: Scene, time: float, scan: dict[str, Array]) -> list[Measurement]:
    """The peaks of one scan as position measurements of sensor ``grid``."""
    return [Measurement(time, "grid", p, covariance=peak_cov(scene, p)) for p in peaks(scene, scan)]
