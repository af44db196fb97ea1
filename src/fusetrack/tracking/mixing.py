"""One belief from a track's weighted single-measurement hypotheses (the PDA combination).

Given hypotheses ``j = 0..M`` with probabilities ``beta_j`` (``j = 0``: missed, whose belief is
the prediction) and their posteriors ``N(x_j, P_j)``, the Gaussian that matches the mixture's
first two moments is (Bar-Shalom, Daum & Huang 2009, Eqs. 39-40; Bar-Shalom et al. 2001,
Sec. 11.2.1)::

    x = sum_j beta_j x_j
    P = sum_j beta_j (P_j + (x_j - x)(x_j - x)^T)

For a Kalman filter this is exactly the PDAF update ``P = beta_0 P^- + (1 - beta_0) P^+ + P~``
with the spread of the innovations ``P~ = K (sum_j beta_j nu_j nu_j^T - nu nu^T) K^T``.

Beliefs that are not :class:`~fusetrack.core.Gaussian` (particles, grids, model-conditioned
beliefs) are not mixed: the track keeps the posterior of its most probable hypothesis (the
first of equals). A particle filter may resample inside each update, so the hypotheses'
particle sets need not share their states, and a mixture would multiply the particle count.

:func:`combine_stacked` is the same combination for many Gaussian tracks at once, on arrays: the
predictions ``(T, d)``, the gated pairs' posteriors ``(P, d)`` and the weights ``(T, M + 1)``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..association import PairPosteriors
from ..core import ConfigError, Gaussian, invalid


def combine_hypotheses(beliefs: Sequence[Any], probabilities: Sequence[float]) -> Any:
    """The belief of a track from its hypotheses' ``beliefs`` and ``probabilities`` (module
    docstring): the moment-matched Gaussian when all are Gaussian, else the most probable one.
    The probabilities are normalised; they must be finite, ``>= 0`` and not all 0."""
    if len(beliefs) == 1 and len(probabilities) == 1:  # one certain hypothesis (GNN): as is
        only = float(probabilities[0])
        if not (math.isfinite(only) and only > 0):
            raise ConfigError(invalid("probabilities", [only], "finite values >= 0, not all 0"))
        return beliefs[0]
    p = np.asarray(probabilities, dtype=float)
    if len(beliefs) != p.size or p.size == 0:
        raise ConfigError(
            invalid("probabilities", p.tolist(), f"{len(beliefs)} values, one per belief (>= 1)")
        )
    total = p.sum()
    if not (math.isfinite(total) and p.min() >= 0 and total > 0):  # inf/NaN: a non-finite sum
        raise ConfigError(invalid("probabilities", p.tolist(), "finite values >= 0, not all 0"))
    p = p / total
    best = int(np.argmax(p))
    if p[best] == 1.0 or not all(isinstance(b, Gaussian) for b in beliefs):
        return beliefs[best]
    means = np.array([b.mean for b in beliefs])  # (J, d)
    covs = np.array([b.cov for b in beliefs])  # (J, d, d)
    mean = np.einsum("j,jd->d", p, means)
    spread = means - mean
    cov = np.einsum("j,jde->de", p, covs) + np.einsum("j,jd,je->de", p, spread, spread)
    return Gaussian(mean, 0.5 * (cov + cov.T))


def combine_stacked(prior: Gaussian, posteriors: PairPosteriors, weights: np.ndarray) -> Gaussian:
    """:func:`combine_hypotheses` of ``T`` Gaussian tracks at once (Bar-Shalom, Daum & Huang
    2009, Eqs. 39-40). ``prior`` ``(T, d)``: the predictions (the missed hypotheses);
    ``posteriors``: track row ``rows[p]`` updated with measurement ``cols[p]``; ``weights``
    ``(T, M + 1)``: each track's normalised hypothesis weights (last column: missed), positive
    only on pairs in ``posteriors`` and the missed column. A track with one hypothesis of
    weight 1 gets its belief exactly (``0 x + 1 y = y``). Returns the ``(T, d)`` mixture."""
    rows, post = posteriors.rows, posteriors.stacked
    w_pair = weights[rows, posteriors.cols]  # (P,)
    w_missed = weights[:, -1]  # (T,)
    mean = np.zeros_like(prior.mean)
    np.add.at(mean, rows, w_pair[:, None] * post.mean)
    mean += w_missed[:, None] * prior.mean
    spread_pair = post.mean - mean[rows]
    spread_missed = prior.mean - mean
    cov = np.zeros_like(prior.cov)
    outer_pair = spread_pair[:, :, None] * spread_pair[:, None, :]
    np.add.at(cov, rows, w_pair[:, None, None] * (post.cov + outer_pair))
    outer_missed = spread_missed[:, :, None] * spread_missed[:, None, :]
    cov += w_missed[:, None, None] * (prior.cov + outer_missed)
    return Gaussian(mean, 0.5 * (cov + np.swapaxes(cov, -1, -2)))
