"""Joint probabilistic data association (JPDA) of one scan.

Every track gets the marginal probabilities ``beta_ij`` that it produced measurement ``j``
(and ``beta_i0`` that it was missed) under the parametric JPDA posterior over joint events
(Fortmann, Bar-Shalom & Scheffe 1983; Bar-Shalom, Daum & Huang 2009, the JPDAF section; see
:mod:`fusetrack.association.scores` for the event probability). The tracker then updates each
track with the beta-weighted mixture of its single-measurement updates (the PDA update).

The gate graph is split into independent clusters (:func:`gate_clusters`); a cluster with at
most ``max_exact_events`` joint events is enumerated exactly (:func:`exact_marginals`), a larger
one is approximated by loopy belief propagation (Williams & Lau 2014,
:func:`belief_propagation_marginals`).

Unassociated measurements: measurement ``j`` is reported in ``unassociated`` when the
probability that some existing track produced it, ``sum_i beta_ij``, is below
``unassociated_below`` (0.5 by default: it is more likely clutter or a new target than any
track's), so an initiator may start a track on it while the tracks still use it with their
small ``beta_ij``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..core import ConfigError, invalid
from .base import Array, Association, AssociationWeights, ScanLikelihoods, SingleHypothesis
from .clusters import IntArray, gate_clusters
from .marginals import belief_propagation_marginals, exact_marginals, lone_track_marginals
from .scores import gated_pairs, log_likelihood_ratios, validate_scores


@dataclass(frozen=True)
class JointProbabilisticDataAssociation:
    """JPDA over gated clusters: exact up to ``max_exact_events`` joint events per cluster,
    loopy belief propagation (``bp_iterations``, ``bp_tolerance``) above.

    ``associate(scores)`` gives each track its hypotheses ``(j, beta_ij)`` for every
    measurement with ``beta_ij > 0`` and ``(None, beta_i0)``; ``info`` holds ``beta``
    ``(T, M + 1)`` (last column: missed), ``clusters`` (track rows, measurement columns; the
    clusters of tracks that share a measurement, a track alone in its cluster is not listed)
    and ``approximated`` (how many clusters used belief propagation).
    ``association_weights(scores)`` gives the same answer as a matrix
    (:class:`~fusetrack.association.AssociationWeights`).
    """

    max_exact_events: int = 10_000
    unassociated_below: float = 0.5
    bp_iterations: int = 200
    bp_tolerance: float = 1e-10

    def __post_init__(self) -> None:
        if int(self.max_exact_events) != self.max_exact_events or self.max_exact_events < 0:
            raise ConfigError(invalid("max_exact_events", self.max_exact_events, "an int >= 0"))
        if not 0.0 < self.unassociated_below <= 1.0:
            raise ConfigError(
                invalid("unassociated_below", self.unassociated_below, "a probability in (0, 1]")
            )
        if int(self.bp_iterations) != self.bp_iterations or self.bp_iterations < 1:
            raise ConfigError(invalid("bp_iterations", self.bp_iterations, "an int >= 1"))
        if not self.bp_tolerance > 0:
            raise ConfigError(invalid("bp_tolerance", self.bp_tolerance, "a number > 0"))

    def marginals(
        self, scores: ScanLikelihoods
    ) -> tuple[Array, list[tuple[IntArray, IntArray]], int]:
        """``(beta (T, M + 1), clusters, number of approximated clusters)`` of a valid scan.
        The tracks that share no measurement with another (most, in a sparse scan) are solved
        in one array pass (:func:`lone_track_marginals`); ``clusters`` are the others'."""
        t, m = scores.shape
        weights = log_likelihood_ratios(scores)
        beta = np.zeros((t, m + 1))
        gated = gated_pairs(scores)
        lone = _lone_tracks(gated, self.max_exact_events)
        beta[lone] = lone_track_marginals(weights[lone])
        shared = np.flatnonzero(~lone)
        clusters = (
            [(shared[rows], cols) for rows, cols in gate_clusters(gated[shared])]
            if shared.size
            else []
        )
        approximated = 0
        for tracks, measurements in clusters:
            block: tuple[Any, ...]
            if tracks.size == 1:  # a lone track with too many events: indexed without np.ix_
                block = (tracks[:1, None], [*measurements.tolist(), m])
            else:
                block = np.ix_(tracks, np.append(measurements, m))
            try:
                beta[block] = exact_marginals(weights[block], self.max_exact_events)
            except OverflowError:
                approximated += 1
                beta[block] = belief_propagation_marginals(
                    weights[block], self.bp_iterations, self.bp_tolerance
                )
        return beta, clusters, approximated

    def association_weights(
        self, scores: ScanLikelihoods, rng: np.random.Generator | None = None
    ) -> AssociationWeights:
        """The answer of :meth:`associate` as a matrix: ``beta`` ``(T, M + 1)``."""
        validate_scores(scores, "JointProbabilisticDataAssociation")
        m = scores.shape[1]
        beta, clusters, approximated = self.marginals(scores)
        from_tracks = beta[:, :m].sum(axis=0)
        unassociated = tuple(int(j) for j in np.flatnonzero(from_tracks < self.unassociated_below))
        info = {"beta": beta, "clusters": clusters, "approximated": approximated}
        return AssociationWeights(beta, unassociated, info)

    def associate(
        self, scores: ScanLikelihoods, rng: np.random.Generator | None = None
    ) -> Association:
        answer = self.association_weights(scores, rng)
        hypotheses = {
            track_id: _hypotheses(track_id, answer.weights[i])
            for i, track_id in enumerate(scores.track_ids)
        }
        return Association(hypotheses, answer.unassociated, answer.info)


def _lone_tracks(gated: NDArray[np.bool_], limit: int) -> NDArray[np.bool_]:
    """``(T,)``: the tracks that share none of their gated measurements with another track
    and have at most ``limit`` joint events (their gated measurements and missed)."""
    shared_cols = np.count_nonzero(gated, axis=0) > 1
    alone = ~(gated & shared_cols).any(axis=1)
    return np.asarray(alone & (np.count_nonzero(gated, axis=1) + 1 <= limit))


def _hypotheses(track_id: int, beta_row: Array) -> tuple[SingleHypothesis, ...]:
    """``(j, beta_ij)`` for each measurement with ``beta_ij > 0``, then ``(None, beta_i0)``."""
    detected = [
        SingleHypothesis(track_id, int(j), float(beta_row[j]))
        for j in np.flatnonzero(beta_row[:-1] > 0)
    ]
    return (*detected, SingleHypothesis(track_id, None, float(beta_row[-1])))
