"""Particle marginal Metropolis-Hastings (Andrieu, Doucet & Holenstein 2010, Sec. 2.4.2).

A random-walk Metropolis-Hastings chain on the parameters ``theta`` whose target is
``p(theta | z_1:T) ∝ p(theta) p(z_1:T | theta)``, with the likelihood replaced by a particle
filter's unbiased estimate: the chain still has the exact posterior as its stationary law
(ibid., Theorem 4). Accept ``theta' = theta + L eps`` with probability
``min(1, p(theta') p^(z | theta') / (p(theta) p^(z | theta)))``, the current state's estimate
kept, never recomputed. With a Kalman filter as the model the same loop is exact marginal
Metropolis-Hastings.

The user's ``model(theta) -> (filter, prior)`` builds the filter for a parameter vector
(parametrise positive quantities by their logs so that the random walk may go anywhere);
``log_prior(theta)`` is ``log p(theta)`` (``-inf`` outside the support: the model is not built).
The proposal covariance is ``scale**2 I``, ``diag(scale**2)`` or a given matrix; with
``adapt=True`` it is replaced during burn-in by ``2.38**2 / p`` times the covariance of the
chain so far (Haario, Saksman & Tamminen 2001; Roberts & Rosenthal 2001 for the constant),
pooled over chains, and frozen after burn-in, so the kept draws come from a fixed kernel.

Several chains (``theta0`` of shape ``(C, p)``) run in lockstep: their proposals are evaluated
as one batch (:meth:`~.likelihood.LogLikelihood.many`: one kernel call, on Numba's threads with
``threads=True``), each chain's filter drawing from its own child of ``rng``.

>>> import numpy as np
>>> from fusetrack.core import Gaussian, Measurement
>>> from fusetrack.filters import BootstrapFilter
>>> from fusetrack.motion import LinearGaussianMotion
>>> from fusetrack.sensors import LinearGaussianSensor
>>> def model(theta):
...     q, r = np.exp(theta)
...     f = BootstrapFilter(LinearGaussianMotion(F=[[0.9]], Q=[[q]]),
...                         [LinearGaussianSensor("s", H=[[1.0]], R=[[r]])], n_particles=200)
...     return f, Gaussian(np.zeros(1), np.eye(1) * q / (1 - 0.81))
>>> zs = [Measurement(float(t), "s", [np.sin(t)]) for t in range(30)]
>>> log_prior = lambda th: -0.5 * float(th @ th) / 4.0
>>> out = pmmh(model, log_prior, [0.0, 0.0], zs, n_iterations=50, scale=0.3,
...            rng=np.random.default_rng(0))
>>> out.chain.shape, 0.0 < out.acceptance_rate < 1.0
((51, 1, 2), True)
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ConfigError, Filter, Measurement, invalid
from .likelihood import LogLikelihood
from .series import Series

Array = NDArray[np.float64]
Model = Callable[[Array], tuple[Filter[Any], Any]]

__all__ = ["PMMHResult", "pmmh", "proposal_covariance"]

_OPTIMAL = 2.38  # Roberts & Rosenthal 2001: 2.38^2 / p times the target covariance


@dataclass(frozen=True, eq=False)
class PMMHResult:
    """A PMMH run: ``chain`` ``(n_iterations + 1, C, p)`` (row 0: the start),
    ``log_likelihoods`` and ``log_priors`` ``(n_iterations + 1, C)`` of each state,
    ``accepted`` ``(n_iterations, C)``, the ``burn_in`` iterations, and the proposal
    covariance used after burn-in."""

    chain: Array
    log_likelihoods: Array
    log_priors: Array
    accepted: NDArray[np.bool_]
    burn_in: int
    proposal_cov: Array

    @property
    def acceptance_rate(self) -> float:
        """Fraction of accepted proposals after burn-in (all iterations if none are left)."""
        kept = self.accepted[self.burn_in :]
        return float((kept if kept.size else self.accepted).mean())

    @property
    def posterior(self) -> Array:
        """The draws after burn-in, chains pooled: ``(K * C, p)``."""
        kept = self.chain[1 + self.burn_in :]
        return kept.reshape(-1, kept.shape[-1])


def proposal_covariance(scale: ArrayLike, p: int) -> Array:
    """``(p, p)`` covariance of the random walk from a scalar step (``scale**2 I``), one step
    per parameter (``diag(scale**2)``) or a covariance matrix."""
    s = np.asarray(scale, dtype=float)
    if s.ndim == 0:
        s = np.full(p, float(s))
    cov = np.diag(s * s) if s.ndim == 1 else s
    if (
        cov.shape != (p, p)
        or not np.all(np.isfinite(cov))
        or not np.allclose(cov, cov.T)
        or np.linalg.eigvalsh(cov).min() <= 0
        or (s.ndim == 1 and np.any(s <= 0))
    ):
        raise ConfigError(
            invalid(
                "scale",
                np.asarray(scale).tolist(),
                f"a positive step, {p} positive steps or a ({p}, {p}) covariance",
            )
        )
    return cov


def _start(theta0: ArrayLike) -> Array:
    th = np.array(theta0, dtype=float)
    if th.ndim == 1:
        th = th[None]
    if th.ndim != 2 or 0 in th.shape or not np.all(np.isfinite(th)):
        raise ConfigError(invalid("theta0", theta0, "finite parameters (p,) or chains (C, p)"))
    return th


def _check_counts(n_iterations: int, burn_in: int) -> None:
    for name, value, low in (("n_iterations", n_iterations, 1), ("burn_in", burn_in, 0)):
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < low:
            raise ConfigError(invalid(name, value, f"an integer >= {low}"))
    if burn_in >= n_iterations:
        raise ConfigError(invalid("burn_in", burn_in, f"< n_iterations = {n_iterations}"))


class _Target:
    """``log p(theta)`` and ``log p^(z | theta)`` for a batch of chains."""

    def __init__(
        self, model: Model, log_prior: Callable[[Array], float], evaluate: LogLikelihood
    ) -> None:
        self.model = model
        self.log_prior = log_prior
        self.evaluate = evaluate

    def __call__(
        self, thetas: Array, rngs: list[np.random.Generator], threads: bool
    ) -> tuple[Array, Array]:
        lp = np.array([float(self.log_prior(th)) for th in thetas])
        if np.any(np.isnan(lp)) or np.any(lp == np.inf):
            raise ConfigError(invalid("log_prior", lp.tolist(), "finite values or -inf"))
        ll = np.full(lp.shape, -np.inf)
        live = np.flatnonzero(lp > -np.inf)
        if live.size:
            models = [self.model(thetas[c]) for c in live]
            ll[live] = self.evaluate.many(models, [rngs[c] for c in live], threads=threads)
        ll[np.isnan(ll)] = -np.inf
        return lp, ll


def _adapted(chain: Array, fixed: Array) -> Array:
    """Haario et al. 2001: ``2.38^2 / p`` times the pooled covariance of the chain so far (plus
    a small multiple of the initial covariance so it stays positive definite)."""
    p = chain.shape[-1]
    flat = chain.reshape(-1, p)
    emp = np.atleast_2d(np.cov(flat, rowvar=False))
    return (_OPTIMAL**2 / p) * emp + 1e-6 * fixed


def pmmh(
    model: Model,
    log_prior: Callable[[Array], float],
    theta0: ArrayLike,
    measurements: Iterable[Measurement | tuple[Any, ...]] | Series,
    *,
    n_iterations: int,
    rng: np.random.Generator,
    scale: ArrayLike = 0.1,
    burn_in: int = 0,
    adapt: bool = False,
    t0: float | None = None,
    threads: bool = False,
) -> PMMHResult:
    """Run PMMH (module docstring) from ``theta0`` (``(p,)`` or ``(C, p)`` chains) for
    ``n_iterations`` on ``measurements`` (prior at ``t0``, default the first measurement's
    time). The first ``burn_in`` iterations are discarded by :attr:`PMMHResult.posterior`
    and, with ``adapt``, tune the proposal. ``rng`` draws the proposals and acceptances; each
    chain's filter draws from its own child of it (``rng.spawn``)."""
    theta = _start(theta0)
    C, p = theta.shape
    _check_counts(n_iterations, burn_in)
    if not isinstance(rng, np.random.Generator):
        raise ConfigError(invalid("rng", rng, "a numpy Generator (np.random.default_rng(seed))"))
    cov0 = proposal_covariance(scale, p)
    target = _Target(model, log_prior, LogLikelihood(measurements, t0))
    rngs = rng.spawn(C)
    chain = np.empty((n_iterations + 1, C, p))
    lls = np.empty((n_iterations + 1, C))
    lps = np.empty((n_iterations + 1, C))
    accepted = np.zeros((n_iterations, C), dtype=bool)
    chain[0] = theta
    lps[0], lls[0] = target(theta, rngs, threads)
    if not np.all(np.isfinite(lps[0] + lls[0])):
        raise ConfigError(
            invalid("theta0", theta.tolist(), "a start with finite log prior and log-likelihood")
        )
    cov = cov0
    L = np.linalg.cholesky(cov)
    adapt_from = max(2 * p, burn_in // 4)
    for it in range(n_iterations):
        if adapt and adapt_from <= it < burn_in:
            cov = _adapted(chain[: it + 1], cov0)
            L = np.linalg.cholesky(cov)
        prop = chain[it] + rng.standard_normal((C, p)) @ L.T
        lp, ll = target(prop, rngs, threads)
        log_u = np.log(rng.random(C))
        with np.errstate(invalid="ignore"):
            take = log_u < (lp + ll) - (lps[it] + lls[it])
        accepted[it] = take
        chain[it + 1] = np.where(take[:, None], prop, chain[it])
        lls[it + 1] = np.where(take, ll, lls[it])
        lps[it + 1] = np.where(take, lp, lps[it])
    return PMMHResult(chain, lls, lps, accepted, burn_in, cov)
