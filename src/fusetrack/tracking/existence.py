"""The probability that a track is a real target, updated every scan as in the integrated
probabilistic data association filter (IPDA; Musicki, Evans & Stankovic 1994, "Integrated
probabilistic data association", IEEE TAC 39(6); Markov chain one existence model).

Prediction (Markov chain one: a target survives a scan with probability ``P_S``)::

    r^- = P_S r

Update with the track's validated measurements ``j`` (here: those of its association
hypotheses), ``l_j = P_D p(z_j | track) / (clutter density at z_j)``::

    delta = P_D P_G - sum_j l_j
    r^+   = (1 - delta) r^- / (1 - delta r^-)

A missed scan (no measurement) gives ``delta = P_D P_G`` and lowers ``r``; a measurement much
likelier under the track than as clutter raises it. The result is clipped to
``[0, 1 - 1e-9]`` so that a track once certain can still lose its existence.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

MAX_EXISTENCE = 1.0 - 1e-9


def predict_existence(existence: float, survival_probability: float) -> float:
    """``r^- = P_S r`` (Markov chain one: the target survives the scan with ``P_S``)."""
    return float(survival_probability * existence)


def update_existence(
    existence: float, detection_gate: float, log_likelihood_ratios: Sequence[float]
) -> float:
    """``r^+`` from ``r^-`` (module docstring); ``detection_gate = P_D P_G`` and
    ``log_likelihood_ratios`` the ``log l_j`` of the track's measurements this scan."""
    total = (  # a missed track has none: skip the array
        float(np.exp(np.asarray(log_likelihood_ratios, dtype=float)).sum())
        if len(log_likelihood_ratios)
        else 0.0
    )
    return float(update_existences(existence, detection_gate, total))


def update_existences(
    existence: ArrayLike, detection_gate: float, likelihood_ratio_sum: ArrayLike
) -> NDArray[np.float64]:
    """:func:`update_existence` of many tracks at once: ``r^-`` ``(n,)`` and each track's
    ``sum_j l_j`` ``(n,)`` (0 for a missed track) give ``r^+`` ``(n,)``."""
    r = np.asarray(existence, dtype=float)
    delta = detection_gate - np.asarray(likelihood_ratio_sum, dtype=float)
    denominator = 1.0 - delta * r
    # denominator <= 0: r^- = 1 and delta = 1, a certain target certainly missed
    safe = np.where(denominator > 0.0, denominator, 1.0)
    updated = np.minimum(np.maximum((1.0 - delta) * r / safe, 0.0), MAX_EXISTENCE)
    return np.asarray(np.where(denominator > 0.0, updated, 0.0))
