r"""Particle smoothing by backward simulation (FFBSi; Godsill, Doucet & West 2004).

Given the weighted particle sets ``{x_k^i, w_k^i}`` of a forward filter (a
:class:`~fusetrack.core.Particles` per step, as :class:`~fusetrack.filters.ParticleFilter`
returns them after each update) and the transition density ``f(x_{k+1} | x_k)`` of the motion
model (``motion.log_density(x_next, x, dt)``), each of ``M`` trajectories is drawn backwards::

    x~_T  = x_T^i       with probability  w_T^i
    x~_k  = x_k^i       with probability  ∝ w_k^i f(x~_{k+1} | x_k^i)        k = T-1, ..., 1

(Godsill, Doucet & West 2004, "Monte Carlo smoothing for nonlinear time series", JASA 99(465),
156-168: the backward simulation of smoothed trajectories). The trajectories are draws from the
particle approximation of the joint smoothing density ``p(x_1:T | z_1:T)``; their mean and
covariance at each step estimate the smoothed marginals.

**Cost.** ``O(T M N)`` transition densities (``M`` defaults to ``N``). For a linear-Gaussian
motion model (one that offers ``fused_transition(dt)``, the contract the particle filters' fused
step relies on) with a nonsingular ``Q``, the ``M x N`` log densities are one matrix product of
whitened states: ``log f(x' | x) = u^T v - |v|^2 / 2 + c(x')`` with ``u = L^-1 x'``,
``v = L^-1 F x``, ``L L^T = Q``; ``c(x')`` is the same for every candidate ``x`` and drops out
of the draw. This assumes the model's ``log_density`` is the ``N(F x, Q)`` it samples from, as
for every linear-Gaussian model in :mod:`fusetrack.motion`; other models go through
``motion.log_density``.

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
_RANK_RTOL = 1e6 * np.finfo(float).eps  # full rank as the motion models judge it (log_density)


def _categorical(logits: Array, rng: np.random.Generator) -> NDArray[np.intp]:
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


def _whitening(motion: MotionModel, dt: float) -> tuple[Array, Array] | None:
    """``(L^-1 F, L^-1)`` with ``L L^T = Q(dt)`` for a linear-Gaussian model with a
    nonsingular ``Q``, else None (the backward step then calls ``log_density``)."""
    offer = getattr(motion, "fused_transition", None)
    fg = offer(dt) if callable(offer) else None
    if fg is None:
        return None
    f = np.asarray(fg[0], dtype=float)
    q = np.asarray(motion.noise_cov(dt), dtype=float)
    sd = np.sqrt(np.diag(q))
    if not np.all(sd > 0):
        return None
    eig = np.linalg.eigvalsh(q / np.outer(sd, sd))  # rank judged on the correlation matrix
    if not eig[0] > _RANK_RTOL * eig[-1]:
        return None  # singular Q: log_density's degenerate density (-inf off its support)
    w = np.linalg.solve(np.linalg.cholesky(q), np.eye(q.shape[-1]))
    return np.asarray(w @ f), np.asarray(w)


def _backward_logits(motion: MotionModel, x_next: Array, particles: Particles, dt: float) -> Array:
    """``log w_k^i + log f(x_next^j | x_k^i)`` ``(..., M, N)`` for draws ``x_next`` ``(..., M, d)``,
    up to a constant per draw ``j`` (which a categorical draw ignores)."""
    lw = particles.log_weights[..., None, :]
    white = _whitening(motion, dt)
    if white is None:
        logf = motion.log_density(x_next[..., :, None, :], particles.states[..., None, :, :], dt)
        return np.asarray(lw + logf, dtype=float)
    wf, w = white
    v = particles.states @ wf.T  # (..., N, d): L^-1 F x_k^i
    u = x_next @ w.T  # (..., M, d): L^-1 x_next^j
    centre = v.mean(axis=-2, keepdims=True)  # shift both: keeps u.v - |v|^2/2 well conditioned
    u, v = u - centre, v - centre
    return np.asarray(lw + u @ np.swapaxes(v, -1, -2) - 0.5 * np.sum(v * v, axis=-1)[..., None, :])


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
    x = _take(last.states, _categorical(lw, rng))
    out = [x]
    degenerate = False
    for k in range(b - 1, a - 1, -1):
        p = particles[k]
        logits = _backward_logits(motion, x, p, float(dts[k]))  # (..., M, N)
        ok = np.isfinite(logits.max(axis=-1))
        if not ok.all():
            degenerate = True
            logits = np.where(ok[..., None], logits, p.log_weights[..., None, :])
        x = _take(p.states, _categorical(logits, rng))
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
