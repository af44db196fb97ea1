r"""Particle smoothing by backward simulation (FFBSi; Godsill, Doucet & West 2004).

Given the weighted particle sets ``{x_k^i, w_k^i}`` of a forward filter (a
:class:`~fusetrack.core.Particles` per step, as :class:`~fusetrack.filters.ParticleFilter`
returns them after each update) and the transition density ``f(x_{k+1} | x_k)`` of the motion
model (``motion.log_density(x_next, x, dt)``), each of ``M`` trajectories is drawn backwards::

    x~_T  = x_T^i       with probability  w_T^i
    x~_k  = x_k^i       with probability  ∝ w_k^i f(x~_{k+1} | x_k^i)        k = T-1, ..., 1

(Godsill, Doucet & West 2004, "Monte Carlo smoothing for nonlinear time series", JASA 99(465),
156-168: the backward simulation of smoothed trajectories). The trajectories are draws from the particle approximation of
the joint smoothing density ``p(x_1:T | z_1:T)``; their mean and covariance at each step estimate
the smoothed marginals. The cost is ``O(T M N)`` transition densities (``M`` defaults to ``N``).

**Fixed lag.** With ``lag=L`` the draws at step ``k`` come from a backward pass started at step
``min(k + L, T - 1)`` (:func:`~fusetrack.filters.smoothing.fixed_lag`): draws from the marginal
``p(x_k | z_1:k+L)`` — the FFBSi of the data up to ``k + L``. ParticleFilter does not record its
resampling ancestors, so the fixed-lag estimate is built from the transition density rather than
from ancestor paths (which would also collapse onto a few paths for a long lag).

Steps where every ``f(x~_{k+1} | x_k^i)`` of a trajectory vanishes (the motion noise cannot
explain the jump: a degenerate filter) fall back to the filter weights for that trajectory and
warn once with :class:`~fusetrack.core.DegenerateWeightsWarning`; the result never holds NaN.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import (
    ConfigError,
    DegenerateWeightsWarning,
    MotionModel,
    Particles,
    ShapeError,
    invalid,
)
from .smoothing import check_dts, check_lag, fixed_lag

Array = NDArray[np.float64]


def categorical(logits: Array, rng: np.random.Generator) -> NDArray[np.intp]:
    """One index per row of ``logits`` ``(..., N)`` (unnormalised log-probabilities, finite
    maximum), by inverse CDF: ``(...)``."""
    w = np.exp(logits - logits.max(axis=-1, keepdims=True))
    cdf = np.cumsum(w, axis=-1)
    u = rng.random(cdf.shape[:-1]) * cdf[..., -1]
    idx = np.count_nonzero(cdf <= u[..., None], axis=-1)
    return np.minimum(idx, logits.shape[-1] - 1).astype(np.intp)


def _take(states: Array, idx: NDArray[np.intp]) -> Array:
    """``states[..., idx, :]`` row by row: states ``(..., N, d)``, idx ``(..., M)``."""
    return np.take_along_axis(states, idx[..., None], axis=-2)


def _check_particles(particles: Sequence[Particles]) -> tuple[tuple[int, ...], int]:
    """Every step holds particles with one batch shape and state dimension."""
    if not all(isinstance(p, Particles) for p in particles):
        kinds = sorted({type(p).__name__ for p in particles})
        raise ConfigError(invalid("particles", kinds, "a sequence of Particles, one per step"))
    shapes = {(p.batch_shape, p.dim) for p in particles}
    if len(shapes) > 1:
        raise ShapeError(
            invalid("particles (batch_shape, dim)", sorted(shapes), "the same at every step")
        )
    batch, dim = shapes.pop() if shapes else ((), 0)
    return batch, dim


def _backward_pass(
    motion: MotionModel,
    particles: Sequence[Particles],
    dts: Array,
    rng: np.random.Generator,
    m: int,
    a: int,
    b: int,
) -> list[Array]:
    """Draws ``(..., M, d)`` at steps ``a..b`` from one backward pass started at ``b``."""
    last = particles[b]
    lw = np.broadcast_to(last.log_weights[..., None, :], (*last.batch_shape, m, last.n))
    x = _take(last.states, categorical(lw, rng))
    out = [x]
    degenerate = False
    for k in range(b - 1, a - 1, -1):
        p = particles[k]
        logf = np.asarray(
            motion.log_density(x[..., :, None, :], p.states[..., None, :, :], float(dts[k])),
            dtype=float,
        )  # (..., M, N): f(x~_{k+1}^j | x_k^i)
        logits = p.log_weights[..., None, :] + logf
        ok = np.isfinite(logits.max(axis=-1))
        if not ok.all():
            degenerate = True
            logits = np.where(ok[..., None], logits, p.log_weights[..., None, :])
        x = _take(p.states, categorical(logits, rng))
        out.append(x)
    if degenerate:
        warnings.warn(
            "backward simulation: no particle could reach a drawn successor under the motion "
            "model at some step; those draws used the filter weights",
            DegenerateWeightsWarning,
            stacklevel=3,
        )
    return out[::-1]


def backward_simulation(
    motion: MotionModel,
    particles: Sequence[Particles],
    dts: ArrayLike,
    rng: np.random.Generator,
    *,
    n_trajectories: int | None = None,
    lag: int | None = None,
) -> Array:
    """FFBSi draws ``(T, ..., M, d)`` from the filter's particle sets (module docstring).

    Parameters
    ----------
    motion:
        the filter's motion model; its ``log_density(x_next, x, dt)`` weighs the backward step.
    particles:
        the ``T`` filtered particle sets, states ``(..., N, d)`` and log-weights ``(..., N)``.
    dts:
        ``(T - 1,)`` seconds from each step to the next, ``> 0``.
    rng:
        the generator the backward draws come from.
    n_trajectories:
        ``M``, the draws per batch entry; default the last step's particle count ``N``.
    lag:
        None: joint trajectories of the fixed-interval smoothing density; ``L >= 0``: the draws
        at step ``k`` are from ``p(x_k | z_1:k+L)`` (independent passes, so not one trajectory
        across steps).
    """
    batch, dim = _check_particles(particles)
    d = check_dts(dts, len(particles), positive=True)
    check_lag(lag)
    if not isinstance(rng, np.random.Generator):
        raise ConfigError(invalid("rng", rng, "a numpy Generator (np.random.default_rng(seed))"))
    m = n_trajectories
    if m is None:
        m = particles[-1].n if particles else 1
    elif isinstance(m, bool) or not isinstance(m, int | np.integer) or m < 1:
        raise ConfigError(invalid("n_trajectories", n_trajectories, "an integer >= 1 or None"))
    draws = fixed_lag(
        len(particles), lag, lambda a, b: _backward_pass(motion, particles, d, rng, int(m), a, b)
    )
    if not draws:
        return np.empty((0, *batch, int(m), dim))
    return np.stack(draws)
