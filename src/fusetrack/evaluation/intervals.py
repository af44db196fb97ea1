"""Confidence intervals for claims judged over Monte Carlo runs.

An ordering the paper states (``a < b``) holds only if the 95 % Student-t interval of the paired
differences lies on the paper's side of zero; a level the paper prints holds only if the interval
of our mean lies inside a stated equivalence margin about it (two one-sided tests; Wellek 2010,
Ch. 1). Fewer than two values give an infinite interval: nothing is shown.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy import stats

LEVEL = 0.95


def mean_interval(
    values: Sequence[float] | np.ndarray, level: float = LEVEL
) -> tuple[float, float]:
    """``(mean, half-width)`` of the ``level`` Student-t interval of the mean of the finite
    ``values``; the half-width is ``inf`` with fewer than two (the mean ``nan`` with none)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return math.nan, math.inf
    if v.size < 2:
        return float(v.mean()), math.inf
    se = float(v.std(ddof=1)) / math.sqrt(v.size)
    return float(v.mean()), float(stats.t.ppf(0.5 + level / 2, v.size - 1)) * se


def paired_interval(
    a: Sequence[float] | np.ndarray, b: Sequence[float] | np.ndarray, level: float = LEVEL
) -> tuple[float, float]:
    """:func:`mean_interval` of ``a - b`` over the pairs where both are finite."""
    return mean_interval(np.asarray(a, dtype=float) - np.asarray(b, dtype=float), level)


def shown_positive(interval: tuple[float, float]) -> bool:
    """The interval ``(mean, half-width)`` lies above zero."""
    mean, half = interval
    return bool(math.isfinite(mean) and mean - half > 0)


def within_margin(interval: tuple[float, float], target: float, margin: float) -> bool:
    """The interval ``(mean, half-width)`` lies inside ``target ± margin`` (equivalence)."""
    mean, half = interval
    return bool(math.isfinite(mean) and abs(mean - target) + half <= margin)


def interval_values(interval: tuple[float, float], digits: int = 3) -> list[float]:
    """``[mean, half-width]`` rounded, for a claim's ``ours`` column (``inf`` stays ``inf``)."""
    return [round(x, digits) if math.isfinite(x) else x for x in interval]
