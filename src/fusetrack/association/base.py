"""The association interface every multi-target associator implements (GNN, JPDA, MHT, MCMCDA).

One scan: the tracks' predicted beliefs and the scan's measurements (any sensors, any kinds) go
in; out comes, for every track, a set of weighted single-measurement hypotheses (measurement
index or ``None`` for "missed", with probability), and the measurements no track claimed, which
an initiator may use. The score of a pair is a :class:`ScanLikelihoods` matrix that the tracker
computes once per scan with the tracks' own filters (``log p(z_j | track i)``), so associators
never know what a belief or a sensor is.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class ScanLikelihoods:
    """Scores of one scan, for ``T`` tracks and ``M`` measurements.

    ``log_likelihood`` ``(T, M)``: ``log P_D,i + log p(z_j | track i)`` (the detection
    probability times the filter's likelihood increment of updating track ``i`` with
    measurement ``j`` alone; :func:`~.gating.scan_likelihoods`), ``-inf`` outside the gate.
    ``log_missed`` ``(T,)``: ``log(1 - P_D P_G)`` of each track. ``log_clutter`` ``(M,)``:
    ``log`` of the clutter (false-alarm) intensity at each measurement, ``log(lambda_c c(z_j))``.
    ``track_ids`` ``(T,)`` the tracks' persistent ids.
    """

    track_ids: tuple[int, ...]
    log_likelihood: Array
    log_missed: Array
    log_clutter: Array

    @property
    def shape(self) -> tuple[int, int]:
        return (len(self.track_ids), int(self.log_clutter.shape[0]))


@dataclass(frozen=True)
class SingleHypothesis:
    """Track ``track_id`` took measurement ``measurement`` (an index into the scan, ``None`` for
    a missed detection) with probability ``probability`` (1 for hard associators)."""

    track_id: int
    measurement: int | None
    probability: float = 1.0


@dataclass(frozen=True)
class Association:
    """One scan's association: each track id's hypotheses (probabilities summing to 1), and the
    indices of measurements that no track used (with probability above the associator's
    threshold), in scan order."""

    hypotheses: Mapping[int, tuple[SingleHypothesis, ...]]
    unassociated: tuple[int, ...] = ()
    info: Mapping[str, object] = field(default_factory=dict)


@dataclass(frozen=True, eq=False)
class AssociationWeights:
    """One scan's association as a matrix, for ``T`` tracks and ``M`` measurements:
    ``weights`` ``(T, M + 1)``, the probability of each single hypothesis (column ``j < M``:
    measurement ``j``, the last column: missed; each row sums to 1), ``unassociated`` and
    ``info`` as in :class:`Association`. A single-scan associator may offer it as
    ``association_weights(scores, rng)`` besides ``associate``: a tracker that works on arrays
    then needs no per-track hypothesis objects."""

    weights: Array
    unassociated: tuple[int, ...] = ()
    info: Mapping[str, object] = field(default_factory=dict)


@runtime_checkable
class Associator(Protocol):
    """Associate one scan: ``associate(scores, rng) -> Association``, pure (the associator holds
    only its configuration). Methods that need several scans (MHT, MCMCDA's window) keep their
    history in an explicit state value of their own, never in the associator object."""

    def associate(
        self, scores: ScanLikelihoods, rng: np.random.Generator | None = None
    ) -> Association: ...


def hypotheses_of(association: Association, track_id: int) -> Sequence[SingleHypothesis]:
    """The hypotheses of one track (a missed detection with probability 1 when it has none)."""
    return association.hypotheses.get(track_id, (SingleHypothesis(track_id, None, 1.0),))


def hypothesis_weights(
    association: Association, track_ids: Sequence[int], n_measurements: int
) -> Array:
    """``(T, M + 1)``: row ``i`` the probabilities of the hypotheses of track ``track_ids[i]``
    (column ``j < M``: measurement ``j``; the last column: missed; a track without
    hypotheses is missed with probability 1). Negative probabilities count as 0."""
    weights = np.zeros((len(track_ids), n_measurements + 1))
    for row, track_id in enumerate(track_ids):
        for h in hypotheses_of(association, track_id):
            if h.probability > 0:
                col = n_measurements if h.measurement is None else h.measurement
                weights[row, col] += h.probability
    return weights
