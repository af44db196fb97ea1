"""Marginal association probabilities ``beta_ij`` of one cluster of tracks and measurements.

Input: ``log_weights`` ``(T, M + 1)``, the log weight of each single hypothesis: column
``j < M`` is ``l_ij - log kappa_j`` (track ``i`` produced ``z_j``; ``-inf`` outside the gate),
column ``M`` is ``log(1 - P_D P_G)`` (track ``i`` missed), as
:func:`~fusetrack.association.scores.log_likelihood_ratios` builds it. A joint event ``theta``
gives every track one column, no measurement to two tracks, and has probability proportional
to ``prod_i exp(log_weights[i, theta_i])`` (the parametric JPDA of Bar-Shalom, Daum & Huang
2009; Fortmann, Bar-Shalom & Scheffe 1983). Output: ``beta`` ``(T, M + 1)``, the probability
that track ``i`` took measurement ``j`` (last column: missed); each row sums to 1.

* :func:`exact_marginals` enumerates the joint events (:func:`joint_events`).
* :func:`belief_propagation_marginals` is the loopy belief propagation of Williams & Lau 2014
  ("Approximate evaluation of marginal association probabilities with belief propagation",
  IEEE Trans. AES 50(4)): two message sweeps per iteration, ``O(T M)`` each, which
  provably converge; accurate to a few percent on dense clusters and exact on trees.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from ..core import ConfigError, invalid
from .base import Array


def joint_events(log_weights: Array, limit: int | None = None) -> Iterator[tuple[int, ...]]:
    """Every feasible joint event: a tuple giving each track's column (``M`` = missed), each
    measurement column at most once, only columns with a finite weight. Events with zero
    probability (a ``-inf`` missed weight) are included; :func:`exact_marginals` drops them.
    Stops with :class:`OverflowError` after ``limit`` events."""
    t, cols = log_weights.shape
    m = cols - 1
    options = [[j for j in range(m) if np.isfinite(log_weights[i, j])] + [m] for i in range(t)]
    count = 0
    event: list[int] = []
    used: set[int] = set()

    def extend(i: int) -> Iterator[tuple[int, ...]]:
        nonlocal count
        if i == t:
            count += 1
            if limit is not None and count > limit:
                raise OverflowError(f"more than {limit} joint events")
            yield tuple(event)
            return
        for j in options[i]:
            if j in used:
                continue
            event.append(j)
            if j < m:
                used.add(j)
            yield from extend(i + 1)
            event.pop()
            used.discard(j)

    yield from extend(0)


def _normalised_rows(log_weights: Array) -> Array:
    """Each row of ``exp(log_weights)`` divided by its maximum (``exp`` cannot overflow)."""
    top = np.max(log_weights, axis=1, keepdims=True)
    top = np.where(np.isfinite(top), top, 0.0)
    return np.asarray(np.exp(log_weights - top))


def exact_marginals(log_weights: Array, limit: int | None = None) -> Array:
    """``beta`` ``(T, M + 1)`` by enumerating every joint event (exponential in the cluster
    size: use on gated clusters); :class:`OverflowError` when there are more than ``limit``.
    When every event has probability zero, every track is missed."""
    t, cols = log_weights.shape
    if t == 1:
        return _lone_track_marginals(log_weights[0], limit)
    events = np.array(list(joint_events(log_weights, limit)), dtype=int).reshape(-1, t)
    beta = np.zeros((t, cols))
    if t == 0:
        return beta
    log_p = log_weights[np.arange(t), events].sum(axis=1)  # (n_events,)
    if not np.isfinite(log_p).any():
        beta[:, -1] = 1.0
        return beta
    p = np.exp(log_p - log_p.max())  # finite max: some event is possible (checked above)
    p /= p.sum()
    for i in range(t):
        beta[i] = np.bincount(events[:, i], weights=p, minlength=cols)
    return beta


def _lone_track_marginals(log_weights: Array, limit: int | None) -> Array:
    """:func:`exact_marginals` of one track, weights ``(M + 1,)``: its events are its gated
    columns and missed (:func:`lone_track_marginals`)."""
    events = np.count_nonzero(np.isfinite(log_weights[:-1])) + 1
    if limit is not None and events > limit:
        raise OverflowError(f"more than {limit} joint events")
    return lone_track_marginals(log_weights[None, :])


def lone_track_marginals(log_weights: Array) -> Array:
    """``beta`` ``(L, M + 1)`` of ``L`` tracks that share no measurement with another track
    (each one a cluster alone): a track's joint events are its gated columns and missed, so
    its ``beta`` is its row of weights normalised (no enumeration), all rows in one pass.
    A track whose every event has probability zero is missed."""
    top = np.max(log_weights, axis=1, initial=-np.inf)
    possible = np.isfinite(top)
    p = np.exp(log_weights - np.where(possible, top, 0.0)[:, None])  # -inf: 0
    p[~possible] = 0.0
    p[~possible, -1] = 1.0
    return np.asarray(p / p.sum(axis=1, keepdims=True))


def belief_propagation_marginals(
    log_weights: Array, max_iterations: int = 200, tolerance: float = 1e-10
) -> Array:
    """Approximate ``beta`` ``(T, M + 1)`` by loopy belief propagation (Williams & Lau 2014).

    With ``psi_ij`` the weights (``psi_i0`` = missed) and ``nu_ji`` = 1 at the start, iterate::

        mu_ij = psi_ij / (psi_i0 + sum_{j' != j} psi_ij' nu_j'i)      track -> measurement
        nu_ji = 1 / (1 + sum_{i' != i} mu_i'j)                          measurement -> track

    until the messages change by less than ``tolerance``; then ``beta_ij ∝ psi_ij nu_ji`` and
    ``beta_i0 ∝ psi_i0``.
    """
    if max_iterations < 1:
        raise ConfigError(invalid("max_iterations", max_iterations, "an integer >= 1"))
    psi = _normalised_rows(log_weights)
    pairs, missed = psi[:, :-1], psi[:, -1]
    nu = np.ones_like(pairs)
    for _ in range(max_iterations):
        weighted = pairs * nu
        mu = pairs / np.maximum(missed[:, None] + weighted.sum(1, keepdims=True) - weighted, 1e-300)
        new_nu = 1.0 / (1.0 + mu.sum(0, keepdims=True) - mu)
        done = np.max(np.abs(new_nu - nu), initial=0.0) < tolerance
        nu = new_nu
        if done:
            break
    beta = np.concatenate([pairs * nu, missed[:, None]], axis=1)
    total = beta.sum(axis=1, keepdims=True)
    beta = np.where(total > 0, beta / np.where(total > 0, total, 1.0), 0.0)
    beta[total[:, 0] == 0, -1] = 1.0
    return np.asarray(beta)
