"""Confidence intervals for claims judged over Monte Carlo runs.

An ordering the paper states (``a < b``) holds only if the 95 % Student-t interval of the paired
differences lies on the paper's side of zero; a level the paper prints holds only if the interval
of our mean lies inside a stated equivalence margin about it (two one-sided tests; Wellek 2010,
Ch. 1). Fewer than two values give an infinite interval: nothing is shown.

Where one diverged run decides a mean, the typical run is judged by the median of the paired
differences, with the distribution-free order-statistic interval (Conover 1999, Sec. 3.2).
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


def median_interval(
    values: Sequence[float] | np.ndarray, level: float = LEVEL
) -> tuple[float, float, float]:
    """``(median, low, high)`` of the finite ``values``: ``[x_(k), x_(n-k+1)]`` of the sorted
    values with the largest ``k`` whose coverage ``1 - 2 P(Bin(n, 1/2) <= k - 1)`` is at least
    ``level`` (Conover 1999, Sec. 3.2). Too few values for that (``n < 6`` at 95 %) give
    ``(-inf, inf)``; none give a ``nan`` median."""
    v = np.sort(np.asarray(values, dtype=float))
    v = v[np.isfinite(v)]
    if v.size == 0:
        return math.nan, -math.inf, math.inf
    n = v.size
    k = int(stats.binom.ppf((1 - level) / 2, n, 0.5))  # smallest k with P(Bin <= k) >= tail
    if stats.binom.cdf(k, n, 0.5) > (1 - level) / 2:
        k -= 1  # now P(Bin <= k) <= tail: the interval is [x_(k+1), x_(n-k)] (1-based)
    median = float(np.median(v))
    if k < 0:
        return median, -math.inf, math.inf
    return median, float(v[k]), float(v[n - k - 1])


def paired_median_interval(
    a: Sequence[float] | np.ndarray, b: Sequence[float] | np.ndarray, level: float = LEVEL
) -> tuple[float, float, float]:
    """:func:`median_interval` of ``a - b`` over the pairs where both are finite."""
    return median_interval(np.asarray(a, dtype=float) - np.asarray(b, dtype=float), level)


def median_shown_positive(interval: tuple[float, float, float]) -> bool:
    """The median interval ``(median, low, high)`` lies above zero."""
    return bool(math.isfinite(interval[1]) and interval[1] > 0)
