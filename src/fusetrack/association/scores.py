"""Checks and derived views of a :class:`~fusetrack.association.ScanLikelihoods` shared by every
associator: one validation (raised before any work) and the log-likelihood-ratio matrix.

Every associator scores a joint event ``theta`` (each track takes at most one measurement, each
measurement goes to at most one track) with the parametric (Poisson clutter) JPDA posterior of
Bar-Shalom, Daum & Huang 2009 (IEEE Control Systems 29(6), the JPDAF section; also Blackman &
Popoli 1999, Ch. 6)::

    P(theta | Z) ∝ prod_{(i,j) in theta} exp(l_ij) / kappa_j * prod_{i missed} (1 - P_D P_G)

up to ``prod_j kappa_j``, a constant of the scan. Here ``exp(l_ij)`` is the weight of "track ``i``
produced ``z_j``", ``P_D p(z_j | track i)``: :func:`~fusetrack.association.scan_likelihoods`
puts ``log P_D`` into ``log_likelihood`` so that the scores alone define the posterior. So a pair enters only through its log
likelihood ratio ``l_ij - log kappa_j`` against clutter and a missed track through
``log_missed_i``: :func:`log_likelihood_ratios` with the missed column appended.
"""

from __future__ import annotations

import numpy as np

from ..core import ConfigError, ShapeError, invalid
from .base import Array, ScanLikelihoods


def validate_scores(scores: ScanLikelihoods, owner: str = "associator") -> None:
    """Raise :class:`~fusetrack.core.ShapeError` (shapes, ids) or
    :class:`~fusetrack.core.ConfigError` (values) unless ``scores`` is a consistent scan:

    ``log_likelihood`` ``(T, M)`` without NaN or ``+inf`` (``-inf`` = outside the gate),
    ``log_missed`` ``(T,)`` in ``[-inf, 0]`` (a log probability), ``log_clutter`` ``(M,)``
    finite, ``track_ids`` unique.
    """
    if not isinstance(scores, ScanLikelihoods):
        raise ConfigError(f"{owner}: " + invalid("scores", scores, "a ScanLikelihoods"))
    try:
        ll, missed, clutter = (
            np.asarray(a, dtype=float)
            for a in (scores.log_likelihood, scores.log_missed, scores.log_clutter)
        )
    except (TypeError, ValueError):
        raise ConfigError(f"{owner}: " + invalid("scores", scores, "numeric arrays")) from None
    t, m = len(scores.track_ids), clutter.shape
    if len(m) != 1:
        raise ShapeError(f"{owner}: " + invalid("log_clutter.shape", m, "(M,)"))
    if ll.shape != (t, m[0]):
        raise ShapeError(
            f"{owner}: "
            + invalid("log_likelihood.shape", ll.shape, f"({t}, {m[0]}): (tracks, measurements)")
        )
    if missed.shape != (t,):
        raise ShapeError(f"{owner}: " + invalid("log_missed.shape", missed.shape, f"({t},)"))
    if len(set(scores.track_ids)) != t:
        raise ShapeError(f"{owner}: " + invalid("track_ids", scores.track_ids, "unique ids"))
    if np.isnan(ll).any() or np.isposinf(ll).any():
        raise ConfigError(
            f"{owner}: "
            + invalid("log_likelihood", ll.tolist(), "finite entries, or -inf outside the gate")
        )
    if np.isnan(missed).any() or (missed > 0).any():
        raise ConfigError(
            f"{owner}: " + invalid("log_missed", missed.tolist(), "log probabilities in [-inf, 0]")
        )
    if not np.isfinite(clutter).all():
        raise ConfigError(f"{owner}: " + invalid("log_clutter", clutter.tolist(), "finite entries"))


def log_likelihood_ratios(scores: ScanLikelihoods) -> Array:
    """``(T, M + 1)``: ``l_ij - log kappa_j`` in column ``j < M`` (``-inf`` outside the gate)
    and ``log_missed_i`` in the last column: the log weight of each single hypothesis."""
    ratios = np.asarray(scores.log_likelihood, float) - np.asarray(scores.log_clutter, float)
    missed = np.asarray(scores.log_missed, float)[:, None]
    return np.concatenate([ratios, missed], axis=1)


def gated_pairs(scores: ScanLikelihoods) -> np.ndarray:
    """``(T, M)`` bool: True where measurement ``j`` is inside track ``i``'s gate."""
    return np.asarray(np.isfinite(scores.log_likelihood))
