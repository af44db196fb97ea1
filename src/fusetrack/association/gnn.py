"""Global nearest neighbour: the single most likely joint association of one scan.

The best joint event (each track takes at most one measurement, each measurement at most one
track) maximises ``sum_{(i,j)} (l_ij - log kappa_j) + sum_{i missed} log(1 - P_D P_G)`` (see
:mod:`fusetrack.association.scores`). It is an optimal 2-D assignment on the augmented
``(T + M) x (M + T)`` cost matrix (Blackman & Popoli 1999, Ch. 6; solved by
:func:`scipy.optimize.linear_sum_assignment`)::

                 measurements j          missed i'
    track i   [ -(l_ij - log kappa_j)  | -log_missed_i if i' = i else forbidden ]
    clutter j'[ 0 if j' = j else forbid | 0                                     ]

A track is thus missed, or a measurement left as clutter, exactly when that is more likely
than any assignment using it. Unlike a greedy nearest-neighbour pass, one track's best
measurement is given up when that lets another track keep a much better one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from .base import Array, Association, AssociationWeights, ScanLikelihoods, SingleHypothesis
from .scores import log_likelihood_ratios, validate_scores


def _augmented_costs(scores: ScanLikelihoods) -> tuple[Array, float]:
    """The augmented cost matrix and the finite stand-in for forbidden / impossible entries."""
    t, m = scores.shape
    weights = log_likelihood_ratios(scores)
    finite = np.abs(weights[np.isfinite(weights)])
    # larger than any sum of finite costs: a forbidden entry is used only if nothing else fits
    big = (t + m + 1) * (float(finite.max(initial=0.0)) + 1.0)
    costs = np.full((t + m, m + t), big)
    pair = -weights[:, :m]
    costs[:t, :m] = np.where(np.isfinite(pair), pair, big)
    missed = -weights[:, m]
    costs[np.arange(t), m + np.arange(t)] = np.where(np.isfinite(missed), missed, big)
    costs[t + np.arange(m), np.arange(m)] = 0.0
    costs[t:, m:] = 0.0
    return costs, big


@dataclass(frozen=True)
class GlobalNearestNeighbour:
    """Optimal hard assignment of one scan (GNN; Blackman & Popoli 1999, Ch. 6).

    ``associate(scores)`` gives every track one hypothesis with probability 1: its measurement
    or ``None`` (missed). ``unassociated`` are the measurements no track took. ``info`` holds
    ``log_ratio``: the chosen event's ``sum (l_ij - log kappa_j) + sum log_missed``. A track
    whose only feasible choice has probability zero (``log_missed = -inf`` and no gated
    measurement left) is reported missed.
    """

    def association_weights(
        self, scores: ScanLikelihoods, rng: np.random.Generator | None = None
    ) -> AssociationWeights:
        """The answer of :meth:`associate` as a matrix ``(T, M + 1)`` of zeros and ones."""
        validate_scores(scores, "GlobalNearestNeighbour")
        t, m = scores.shape
        costs, big = _augmented_costs(scores)
        rows, cols = linear_sum_assignment(costs)
        chosen = cols[rows < t][np.argsort(rows[rows < t])]  # each track's column
        taken = (chosen < m) & (costs[np.arange(t), np.minimum(chosen, m + t - 1)] < big)
        column = np.where(taken, chosen, m)  # a forbidden or missed-column choice: missed
        weights = np.zeros((t, m + 1))
        weights[np.arange(t), column] = 1.0
        log_ratio = float(sum(log_likelihood_ratios(scores)[np.arange(t), column].tolist()))
        used = set(column[taken].tolist())
        unassociated = tuple(j for j in range(m) if j not in used)
        return AssociationWeights(weights, unassociated, {"log_ratio": log_ratio})

    def associate(
        self, scores: ScanLikelihoods, rng: np.random.Generator | None = None
    ) -> Association:
        answer = self.association_weights(scores, rng)
        m = scores.shape[1]
        columns = np.argmax(answer.weights, axis=1).tolist()
        hypotheses = {
            track_id: (SingleHypothesis(track_id, j if j < m else None, 1.0),)
            for track_id, j in zip(scores.track_ids, columns, strict=True)
        }
        return Association(hypotheses, answer.unassociated, answer.info)
