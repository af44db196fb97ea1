"""Beliefs over the state: Gaussian, weighted particles, a grid, and a Gaussian mixture.

Each belief is an immutable value with ``mean`` and ``cov``; filters return new beliefs.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import logsumexp

from .errors import ShapeError, invalid
from .resampling import Resampler, get_resampler


def _symmetrise(c: NDArray[np.float64]) -> NDArray[np.float64]:
    return 0.5 * (c + np.swapaxes(c, -1, -2))


@dataclass(frozen=True, eq=False)
class Gaussian:
    """``N(mean, cov)`` with ``mean`` ``(..., d)`` and ``cov`` ``(..., d, d)`` (leading axes: batch)."""

    mean: NDArray[np.float64]
    cov: NDArray[np.float64]

    def __post_init__(self) -> None:
        m = np.asarray(self.mean, dtype=float)
        c = np.asarray(self.cov, dtype=float)
        if m.ndim == 0:
            m = m[None]
        if c.ndim == 0:
            c = c[None, None]
        d = m.shape[-1]
        if c.shape[-2:] != (d, d):
            raise ShapeError(
                invalid("cov.shape", c.shape, f"(..., {d}, {d}) to match mean of size {d}")
            )
        object.__setattr__(self, "mean", m)
        object.__setattr__(self, "cov", c)

    @property
    def dim(self) -> int:
        return int(self.mean.shape[-1])

    def unstack(self) -> list[Gaussian]:
        """The entries of a batched ``(K, d)`` Gaussian as ``K`` Gaussians ``(d,)`` (views of
        its rows, not checked again: the batch was)."""
        out = []
        for m, c in zip(self.mean, self.cov, strict=True):
            g = object.__new__(Gaussian)
            g.__dict__.update(mean=m, cov=c)
            out.append(g)
        return out

    def logpdf(self, x: ArrayLike) -> NDArray[np.float64]:
        """Log density at ``x`` ``(..., d)``."""
        x = np.asarray(x, float)
        L = np.linalg.cholesky(self.cov)
        r = x - self.mean
        z = np.linalg.solve(L, r[..., None])[..., 0]
        logdet = 2.0 * np.log(np.diagonal(L, axis1=-2, axis2=-1)).sum(-1)
        return -0.5 * (np.sum(z * z, -1) + logdet + self.dim * np.log(2 * np.pi))

    def sample(self, rng: np.random.Generator, n: int | None = None) -> NDArray[np.float64]:
        """Draw ``(..., n, d)`` (or ``(..., d)`` when ``n`` is None)."""
        L = np.linalg.cholesky(self.cov)
        if n is None:
            e = rng.standard_normal(self.mean.shape)
            return self.mean + np.einsum("...ij,...j->...i", L, e)
        e = rng.standard_normal((*self.mean.shape[:-1], n, self.dim))
        return self.mean[..., None, :] + np.einsum("...ij,...nj->...ni", L, e)


@dataclass(frozen=True, eq=False)
class Particles:
    """Weighted samples: ``states`` ``(..., N, d)``, ``log_weights`` ``(..., N)`` (unnormalised ok).

    Leading axes are independent sets: Monte Carlo runs or targets.
    """

    states: NDArray[np.float64]
    log_weights: NDArray[np.float64]
    info: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        s = np.asarray(self.states, dtype=float)
        lw = np.asarray(self.log_weights, dtype=float)
        if s.ndim < 2:
            raise ShapeError(invalid("states.shape", s.shape, "(..., N, d)"))
        if lw.shape != s.shape[:-1]:
            raise ShapeError(
                invalid("log_weights.shape", lw.shape, f"{s.shape[:-1]} to match states")
            )
        object.__setattr__(self, "states", s)
        object.__setattr__(self, "log_weights", lw)

    @classmethod
    def uniform(cls, states: ArrayLike) -> Particles:
        s = np.asarray(states, float)
        return cls(s, np.full(s.shape[:-1], -np.log(s.shape[-2])))

    @classmethod
    def from_gaussian(cls, prior: Gaussian, n: int, rng: np.random.Generator) -> Particles:
        return cls.uniform(prior.sample(rng, n))

    @property
    def n(self) -> int:
        return int(self.states.shape[-2])

    @property
    def dim(self) -> int:
        return int(self.states.shape[-1])

    @property
    def batch_shape(self) -> tuple[int, ...]:
        return tuple(self.states.shape[:-2])

    @property
    def weights(self) -> NDArray[np.float64]:
        """Normalised weights ``(..., N)``."""
        lw = self.log_weights
        w = np.exp(lw - lw.max(axis=-1, keepdims=True))
        return w / w.sum(axis=-1, keepdims=True)

    def normalized(self) -> Particles:
        lw = self.log_weights - logsumexp(self.log_weights, axis=-1, keepdims=True)
        return Particles(self.states, lw, self.info)

    @property
    def ess(self) -> NDArray[np.float64]:
        """Effective sample size ``1 / sum w_i^2``."""
        w = self.weights
        return 1.0 / np.sum(w * w, axis=-1)

    @property
    def mean(self) -> NDArray[np.float64]:
        return np.einsum("...n,...nd->...d", self.weights, self.states)

    @property
    def cov(self) -> NDArray[np.float64]:
        w = self.weights
        r = self.states - self.mean[..., None, :]
        return _symmetrise(np.einsum("...n,...ni,...nj->...ij", w, r, r))

    def to_gaussian(self) -> Gaussian:
        return Gaussian(self.mean, self.cov)

    def resample(
        self, rng: np.random.Generator, scheme: str | Resampler = "systematic"
    ) -> Particles:
        """Equal-weight particles drawn with ``scheme`` (see :mod:`fusetrack.core.resampling`)."""
        idx = get_resampler(scheme)(self.weights, rng)
        states = np.take_along_axis(self.states, idx[..., None], axis=-2)
        return Particles.uniform(states)


@dataclass(frozen=True, eq=False)
class GridBelief:
    """A density on a regular grid: ``axes`` (one 1-D array of cell centres per dimension) and
    ``log_prob`` with shape ``(len(axes[0]), len(axes[1]), ...)`` (probability mass per cell)."""

    axes: tuple[NDArray[np.float64], ...]
    log_prob: NDArray[np.float64]

    def __post_init__(self) -> None:
        axes = tuple(np.asarray(a, float) for a in self.axes)
        lp = np.asarray(self.log_prob, float)
        shape = tuple(a.size for a in axes)
        if lp.shape != shape:
            raise ShapeError(
                invalid("log_prob.shape", lp.shape, f"{shape} (one entry per grid cell)")
            )
        object.__setattr__(self, "axes", axes)
        object.__setattr__(self, "log_prob", lp)

    @classmethod
    def uniform(cls, axes: tuple[ArrayLike, ...]) -> GridBelief:
        shape = tuple(np.asarray(a).size for a in axes)
        return cls(
            tuple(np.asarray(a, float) for a in axes), np.full(shape, -np.log(np.prod(shape)))
        )

    @property
    def dim(self) -> int:
        return len(self.axes)

    @property
    def prob(self) -> NDArray[np.float64]:
        p = np.exp(self.log_prob - self.log_prob.max())
        return p / p.sum()

    def normalized(self) -> GridBelief:
        return GridBelief(self.axes, self.log_prob - logsumexp(self.log_prob))

    @property
    def points(self) -> NDArray[np.float64]:
        """Cell centres ``(*shape, d)``."""
        return np.stack(np.meshgrid(*self.axes, indexing="ij"), axis=-1)

    @property
    def mean(self) -> NDArray[np.float64]:
        return np.tensordot(self.prob, self.points, axes=self.dim)

    @property
    def cov(self) -> NDArray[np.float64]:
        r = (self.points - self.mean).reshape(-1, self.dim)
        return _symmetrise(np.einsum("n,ni,nj->ij", self.prob.ravel(), r, r))

    @property
    def map_estimate(self) -> NDArray[np.float64]:
        idx = np.unravel_index(np.argmax(self.log_prob), self.log_prob.shape)
        return np.array([a[i] for a, i in zip(self.axes, idx)])


@dataclass(frozen=True, eq=False)
class GaussianMixture:
    """``sum_k w_k N(mean_k, cov_k)``: ``weights`` ``(K,)``, ``means`` ``(K, d)``, ``covs`` ``(K, d, d)``."""

    weights: NDArray[np.float64]
    means: NDArray[np.float64]
    covs: NDArray[np.float64]

    def __post_init__(self) -> None:
        w = np.asarray(self.weights, float)
        m = np.asarray(self.means, float)
        c = np.asarray(self.covs, float)
        if m.ndim != 2 or w.shape != m.shape[:1] or c.shape != (*m.shape, m.shape[1]):
            raise ShapeError(
                invalid(
                    "(weights, means, covs) shapes",
                    (w.shape, m.shape, c.shape),
                    "(K,), (K, d), (K, d, d)",
                )
            )
        if np.any(w < 0) or not np.isclose(w.sum(), 1.0):
            raise ShapeError(invalid("weights", w, "non-negative numbers summing to 1"))
        object.__setattr__(self, "weights", w)
        object.__setattr__(self, "means", m)
        object.__setattr__(self, "covs", c)

    @property
    def dim(self) -> int:
        return int(self.means.shape[1])

    @property
    def mean(self) -> NDArray[np.float64]:
        return self.weights @ self.means

    @property
    def cov(self) -> NDArray[np.float64]:
        """Moment-matched covariance: within-component plus spread of the means."""
        r = self.means - self.mean
        return _symmetrise(
            np.einsum("k,kij->ij", self.weights, self.covs + r[:, :, None] * r[:, None, :])
        )

    def component(self, k: int) -> Gaussian:
        return Gaussian(self.means[k], self.covs[k])

    def logpdf(self, x: ArrayLike) -> NDArray[np.float64]:
        x = np.asarray(x, float)
        comps = np.stack([self.component(k).logpdf(x) for k in range(len(self.weights))], axis=-1)
        with np.errstate(divide="ignore"):
            return logsumexp(comps + np.log(self.weights), axis=-1)

    def sample(self, rng: np.random.Generator, n: int) -> NDArray[np.float64]:
        ks = rng.choice(len(self.weights), size=n, p=self.weights)
        out = np.empty((n, self.dim))
        for k in np.unique(ks):
            sel = ks == k
            out[sel] = self.component(int(k)).sample(rng, int(sel.sum()))
        return out
