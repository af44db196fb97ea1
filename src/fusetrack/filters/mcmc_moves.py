"""MCMC moves after resampling (resample-move; Zhai 2007, Sec. 6.1, Algorithms 8-10).

After resampling, particle i (ancestor ``x_{t-1}^{a_i}``) is moved by a Metropolis-Hastings kernel
whose invariant density is the particle's own target (spec 001, Sec. 3, choice 28)::

    f_i(x) ∝ p(z_t | x) p(x | x_{t-1}^{a_i})

so the particle set still represents the filtering posterior, only with more diversity.

* :class:`MHPriorMove` -- Algorithm 8 with the transition prior as instrumental density; the
  acceptance ratio reduces to the likelihood ratio ``p(z | x*) / p(z | x)``.
* :class:`RandomWalkMove` -- Algorithm 9: ``x' = x + e``, ``e ~ N(0, variance I)``, accept with
  ``f(x') / f(x)``.
* :class:`IndependenceMove` -- Algorithm 10 (Metropolised independence sampler): ``x* ~ N(mean,
  variance I)`` whatever ``x``, accept with ``w(x*) / w(x)``, ``w = f / T``.

Every move counts proposals and acceptances in the filter's ``stats`` and a step where nothing
was accepted in ``stats.zero_acceptance_steps`` (the MIS of Sec. 6.1.2, N(0, 0.15) against a
state of magnitude ~5, is the usual culprit).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..core import check_positive
from .proposals import Array


def _accept(
    x: Array, proposal: Array, log_ratio: Array, rng: np.random.Generator, filt: Any
) -> tuple[Array, NDArray[np.bool_]]:
    log_ratio = np.where(np.isnan(log_ratio), -np.inf, log_ratio)
    ok = np.log(rng.random(log_ratio.shape)) < log_ratio  # u <= min(1, ratio)
    stats = filt.stats
    stats.moves_proposed += int(ok.size)
    n_ok = int(ok.sum())
    stats.moves_accepted += n_ok
    if n_ok == 0:
        stats.zero_acceptance_steps += 1
    return np.asarray(np.where(ok[..., None], proposal, x), dtype=np.float64), ok


def _target(
    x: Array, parents: Array, loglik: Callable[[Array], Array], dt: float, filt: Any
) -> Array:
    return np.asarray(loglik(x) + filt.motion.log_density(x, parents, dt))


@dataclass(frozen=True)
class MetropolisMove:
    """Metropolis-Hastings after resampling (Algorithm 8): ``n_iter`` rounds of propose ``x*`` and
    accept with ``exp(score(x*) - score(x))``. A subclass gives :meth:`propose` and :meth:`score`,
    the log of the quantity whose ratio is the acceptance probability."""

    n_iter: int = field(default=1, kw_only=True)

    def propose(
        self, x: Array, parents: Array, dt: float, rng: np.random.Generator, filt: Any
    ) -> Array:
        raise NotImplementedError

    def score(
        self, x: Array, parents: Array, loglik: Callable[[Array], Array], dt: float, filt: Any
    ) -> Array:
        raise NotImplementedError

    def __call__(
        self,
        x: Array,
        parents: Array,
        loglik: Callable[[Array], Array],
        dt: float,
        rng: np.random.Generator,
        filt: Any,
    ) -> Array:
        score = self.score(x, parents, loglik, dt, filt)
        for _ in range(self.n_iter):
            prop = self.propose(x, parents, dt, rng, filt)
            score_prop = self.score(prop, parents, loglik, dt, filt)
            x, ok = _accept(x, prop, score_prop - score, rng, filt)
            score = np.where(ok, score_prop, score)
        return x


@dataclass(frozen=True)
class MHPriorMove(MetropolisMove):
    """Algorithm 8: MH with the transition prior ``p(x | x_{t-1}^{a_i})`` as instrumental density;
    ``f T`` ratio = likelihood ratio."""

    def propose(
        self, x: Array, parents: Array, dt: float, rng: np.random.Generator, filt: Any
    ) -> Array:
        return np.asarray(filt.motion.sample(parents, dt, rng))

    def score(
        self, x: Array, parents: Array, loglik: Callable[[Array], Array], dt: float, filt: Any
    ) -> Array:
        return np.asarray(loglik(x))


@dataclass(frozen=True)
class RandomWalkMove(MetropolisMove):
    """Algorithm 9: random-walk Metropolis, ``x' = x + N(0, variance I)`` (Sec. 6.1.2: 0.2)."""

    variance: float = 0.2

    def __post_init__(self) -> None:
        check_positive("variance", self.variance)

    def propose(
        self, x: Array, parents: Array, dt: float, rng: np.random.Generator, filt: Any
    ) -> Array:
        return np.asarray(x + np.sqrt(self.variance) * rng.standard_normal(x.shape))

    def score(
        self, x: Array, parents: Array, loglik: Callable[[Array], Array], dt: float, filt: Any
    ) -> Array:
        return _target(x, parents, loglik, dt, filt)


@dataclass(frozen=True)
class IndependenceMove(MetropolisMove):
    """Algorithm 10: Metropolised independence sampler, ``x* ~ N(mean, variance I)`` (0, 0.15);
    accept with ``w(x*) / w(x)``, ``w = f / T``."""

    variance: float = 0.15
    mean: float = 0.0

    def __post_init__(self) -> None:
        check_positive("variance", self.variance)

    def propose(
        self, x: Array, parents: Array, dt: float, rng: np.random.Generator, filt: Any
    ) -> Array:
        return np.asarray(self.mean + np.sqrt(self.variance) * rng.standard_normal(x.shape))

    def score(
        self, x: Array, parents: Array, loglik: Callable[[Array], Array], dt: float, filt: Any
    ) -> Array:
        r = (x - self.mean) ** 2 / self.variance
        log_t = -0.5 * np.sum(r + np.log(2 * np.pi * self.variance), axis=-1)
        return np.asarray(_target(x, parents, loglik, dt, filt) - log_t)
