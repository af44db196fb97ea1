"""Univariate slice sampling with stepping out and shrinkage (Neal 2003, Figs. 3 and 5).

Kushwaha 2010 (Ch. IV, Alg. 1) draws every univariate conditional of its Gibbs sampler this way,
for its robustness to the step size and to multimodal, non-log-concave densities.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..core.errors import ConfigError, invalid


@dataclass(frozen=True)
class SliceDraw:
    """A draw ``x`` with its log-density ``logp`` and the number of density evaluations it took."""

    x: float
    logp: float
    evaluations: int


def slice_sample(
    logp: Callable[[float], float],
    x0: float,
    rng: np.random.Generator,
    *,
    width: float = 1.0,
    lower: float = -math.inf,
    upper: float = math.inf,
    logp0: float | None = None,
    max_steps_out: int = 8,
    max_evaluations: int = 50,
) -> SliceDraw:
    """One slice-sampling update of ``x0`` under the unnormalised log-density ``logp`` on
    ``[lower, upper]``. The level is ``log y = logp(x0) - Exp(1)``; the interval of ``width`` is
    placed at random around ``x0``, stepped out at most ``max_steps_out`` times each way, then shrunk
    towards ``x0`` until a point above the level is found. After ``max_evaluations`` evaluations
    ``x0`` is kept (a valid, if lazy, Markov step)."""
    if not (width > 0 and math.isfinite(width)):
        raise ConfigError(invalid("width", width, "a finite width > 0"))
    if not lower <= x0 <= upper:
        raise ConfigError(invalid("x0", x0, f"a point in [{lower}, {upper}]"))
    evals = 0
    if logp0 is None:
        logp0 = logp(x0)
        evals += 1
    if not math.isfinite(logp0):
        return SliceDraw(x0, logp0, evals)
    level = logp0 - rng.exponential()
    left = x0 - width * rng.random()
    right = left + width
    j = int(rng.integers(0, max_steps_out + 1))
    k = max_steps_out - j
    while j > 0 and left > lower and evals < max_evaluations:
        evals += 1
        if not logp(left) > level:
            break
        left -= width
        j -= 1
    while k > 0 and right < upper and evals < max_evaluations:
        evals += 1
        if not logp(right) > level:
            break
        right += width
        k -= 1
    left, right = max(left, lower), min(right, upper)
    while evals < max_evaluations:
        x = left + (right - left) * rng.random()
        lp = logp(x)
        evals += 1
        if lp > level:
            return SliceDraw(x, lp, evals)
        if x < x0:
            left = x
        else:
            right = x
    return SliceDraw(x0, logp0, evals)
