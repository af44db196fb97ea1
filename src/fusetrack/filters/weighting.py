"""Particle weights, written once: every particle filter in fusetrack normalises, measures,
recovers from degeneracy and resamples through here (or, batched, through the same kernels).

1. :func:`particle_weights` normalises log-weights ``(..., N)`` per run on the shared kernel
   (:func:`~fusetrack.filters.kernels.normalize_log_weights`: log-sum-exp, NaN as ``-inf``) and
   reports the log of the weight sum (with equal prior weights, ``log_sum - log N`` is the
   log-evidence ``log p(z_k | z_1:k-1)``), the effective sample size and which runs degenerated
   (no finite weight). A degenerate run gets equal weights, never NaN: what the filter then does
   (keep the prediction, ignore the measurement, start over) is its own recovery policy.
2. :func:`draw_ancestors` resamples normalised weights with any scheme of
   :mod:`fusetrack.core.resampling` (systematic by default: one uniform per run).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import Resampler, get_resampler
from . import kernels

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class ParticleWeights:
    """Normalised weights of particle sets ``(..., N)``.

    ``weights`` sum to 1 per run (equal on a degenerate run); ``log_sum`` ``(...)`` is
    ``log sum_i exp(log_w_i)`` of the log-weights given (``-inf``/NaN on a degenerate run);
    ``ess`` ``(...)`` is ``1 / sum w^2``; ``degenerate`` ``(...)`` marks runs with no finite weight.
    """

    weights: Array
    log_sum: Array
    ess: Array
    degenerate: NDArray[np.bool_]

    @property
    def any_degenerate(self) -> bool:
        return bool(np.any(self.degenerate))


def particle_weights(log_weights: ArrayLike) -> ParticleWeights:
    """Normalise log-weights ``(..., N)`` per run (see the module docstring)."""
    _, w, lse, ess = kernels.normalize_log_weights(log_weights)
    degenerate = ~np.isfinite(lse)
    if np.any(degenerate):
        w[degenerate] = 1.0 / w.shape[-1]
        ess = np.where(degenerate, float(w.shape[-1]), ess)
    return ParticleWeights(w, lse, ess, degenerate)


def draw_ancestors(
    weights: ParticleWeights | ArrayLike,
    rng: np.random.Generator,
    resampler: str | Resampler = "systematic",
) -> NDArray[np.intp]:
    """Ancestor indices ``(..., N)`` resampled from normalised ``weights`` ``(..., N)``."""
    w = weights.weights if isinstance(weights, ParticleWeights) else np.asarray(weights, float)
    return np.asarray(get_resampler(resampler)(w, rng), dtype=np.intp)
