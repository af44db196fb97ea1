"""Multiple-model particle filters (Zhai 2007, Secs. 3.4-3.5, Algorithms 3-4).

The hybrid state is ``[x_t, r_t]``; the regime ``r_t`` follows a Markov chain with row-stochastic
``transition[i, j] = P(r_t = j | r_{t-1} = i)`` (Eq. 40, whose printed index labels are transposed).
Per step (Algorithm 3, Table 6):

1. draw each particle's regime from its row of the transition matrix (Eq. 47);
2. draw its state from the regime's proposal: the regime's motion model (MM-bootstrap, Sec. 3.4.4)
   or, for MMPF-SP (Algorithm 4, Table 7), the moment-matched Gaussian of an SP-PEKF bank run
   under that regime (Eq. 54);
3. weight ``p(z | x) p(x | x_{t-1}, r) / q(x | r)`` (Eqs. 48 and 53), normalise, resample states and
   regimes together (systematic), output the mean of the resampled particles; the model
   probabilities are the regime shares of the resampled particles (Fig 28).

MMPF-SP feedback (MISSING in the thesis; spec choice): bank r is re-partitioned at the mean of the
resampled particles in regime r, or at the overall mean when there are none. Every model must
share the state layout (pad CV/CT into a common 6-D state with :class:`PaddedModel` when CA is in
the set; spec choice 22).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import logsumexp

from ..core.beliefs import Gaussian
from ..core.errors import ConfigError, invalid
from ..core.measurement import Measurement
from ..core.models import MotionModel, SensorModel
from ..core.resampling import get_resampler
from .grid_proposals import DiscretisationProposal, complete_from_ancestors, sample_cells
from .sis import (
    Array,
    LogLikelihood,
    ProposalContext,
    SISStats,
    Zs,
    aligned_values,
    check_generator,
    resample_log_weights,
)
from .sp_pekf import BankState, SPPEKFBank, gaussian_draw

IntArray = NDArray[np.intp]


def check_transition(transition: ArrayLike, n_models: int) -> Array:
    """A row-stochastic ``(M, M)`` array, else :class:`ConfigError` naming what is wrong."""
    p = np.asarray(transition, dtype=float)
    if p.shape != (n_models, n_models):
        raise ConfigError(invalid("transition.shape", p.shape, f"({n_models}, {n_models})"))
    if np.any(p < 0) or not np.allclose(p.sum(axis=1), 1.0, atol=1e-9):
        raise ConfigError(invalid("transition", p.tolist(), "non-negative rows that sum to 1"))
    return p


def check_initial_probs(initial_probs: ArrayLike | None, n_models: int) -> Array:
    """Regime probabilities ``(M,)`` (uniform for None), else :class:`ConfigError`."""
    p0 = (
        np.full(n_models, 1.0 / n_models)
        if initial_probs is None
        else np.asarray(initial_probs, float)
    )
    if p0.shape != (n_models,) or np.any(p0 < 0) or not np.isclose(p0.sum(), 1.0):
        raise ConfigError(
            invalid("initial_probs", p0.tolist(), f"{n_models} probabilities summing to 1")
        )
    return p0


def sample_regimes(modes: IntArray, transition: Array, rng: np.random.Generator) -> IntArray:
    """``r_t ~ Categorical(transition[r_{t-1}])`` for every entry of ``modes`` (Eq. 47)."""
    cdf = np.cumsum(transition, axis=1)
    cdf[:, -1] = 1.0
    u = rng.random(modes.shape)
    return np.asarray((u[..., None] >= cdf[modes]).sum(axis=-1), dtype=np.intp)


def stationary_distribution(transition: ArrayLike) -> Array:
    """The left eigenvector of the transition matrix for eigenvalue 1, normalised."""
    p = np.asarray(transition, float)
    w, v = np.linalg.eig(p.T)
    k = int(np.argmin(np.abs(w - 1.0)))
    s = np.real(v[:, k])
    return np.asarray(s / s.sum(), dtype=np.float64)


@dataclass(frozen=True)
class PaddedModel:
    """A 4-D ``[x, y, vx, vy]`` model acting on a 6-D ``[x, y, vx, vy, ax, ay]`` state.

    The acceleration is set to 0 (spec choice 22: "CV/CT zero the acceleration"); a small variance
    ``acc_var`` on it keeps the transition density of the 6-D state proper.
    """

    inner: MotionModel
    acc_var: float = 1e-4
    dim: int = 6
    position_index: tuple[int, ...] = (0, 1)
    velocity_index: tuple[int, ...] | None = (2, 3)

    def mean(self, x: Array, dt: float) -> Array:
        out = np.zeros(x.shape)
        out[..., :4] = self.inner.mean(x[..., :4], dt)
        return out

    def jacobian(self, x: Array, dt: float) -> Array:
        jac = np.zeros((*x.shape[:-1], 6, 6))
        jac[..., :4, :4] = self.inner.jacobian(x[..., :4], dt)
        return jac

    def noise_cov(self, dt: float) -> Array:
        q = np.zeros((6, 6))
        q[:4, :4] = self.inner.noise_cov(dt)
        q[4, 4] = q[5, 5] = self.acc_var
        return q

    def sample(self, x: Array, dt: float, rng: np.random.Generator) -> Array:
        out = np.empty(x.shape)
        out[..., :4] = self.inner.sample(x[..., :4], dt, rng)
        out[..., 4:] = np.sqrt(self.acc_var) * rng.standard_normal((*x.shape[:-1], 2))
        return out

    def log_density(self, x_next: Array, x: Array, dt: float) -> Array:
        a = x_next[..., 4:]
        return np.asarray(
            self.inner.log_density(x_next[..., :4], x[..., :4], dt)
            - 0.5 * np.sum(a * a, axis=-1) / self.acc_var
            - np.log(2 * np.pi * self.acc_var)
        )


@dataclass(frozen=True, eq=False)
class MMBelief:
    """Particles with a regime each: ``states`` ``(..., N, d)``, ``modes`` ``(..., N)``, equally
    weighted after a step; ``estimate`` ``(..., d)`` their mean, ``model_probs`` ``(..., M)`` the
    regime shares, ``banks`` the SP-PEKF bank state of each regime (MMPF-SP). Between
    ``predict`` and ``update``, ``parents`` holds the states each particle was drawn from."""

    states: Array
    modes: IntArray
    estimate: Array
    model_probs: Array
    banks: tuple[BankState | None, ...] = ()
    parents: Array | None = None

    @property
    def mean(self) -> Array:
        return self.estimate

    @property
    def cov(self) -> Array:
        """Sample covariance of the (equally weighted) particles, ``(..., d, d)``."""
        dev = self.states - self.estimate[..., None, :]
        n = self.states.shape[-2]
        return np.asarray(np.einsum("...ni,...nj->...ij", dev, dev) / max(n - 1, 1))


class MultipleModelParticleFilter:
    """Jump-Markov particle filter: MM-bootstrap (``proposal="prior"``), MMPF-SP
    (``"sp-pekf"``) or the discretisation MMPF (``"cells"``); a
    :class:`~fusetrack.core.SteppingFilter` over :class:`MMBelief`. ``predict`` (regimes by
    Eq. 47, states by each regime's motion model) followed by ``update`` (weight, resample) is
    the MM-bootstrap step.

    >>> from fusetrack.motion import ConstantVelocity
    >>> from fusetrack.motion.maneuver import ManeuverTurn
    >>> from fusetrack.sensors import Bearing
    >>> models = [ConstantVelocity(q=0.01), ManeuverTurn(0.5, 1, 0.01), ManeuverTurn(0.5, -1, 0.01)]
    >>> pi = [[0.8, 0.1, 0.1], [0.2, 0.7, 0.1], [0.2, 0.1, 0.7]]
    >>> mm = MultipleModelParticleFilter(models, pi, [Bearing("b", [0, 0], 0.05)], 500)
    >>> rng = np.random.default_rng(0)
    >>> s = mm.initialize(Gaussian(np.array([10.0, 30, 1, 0]), np.diag([1, 1, 0.1, 0.1])), rng)
    >>> s = mm.step(s, 1.0, [Measurement(1.0, "b", [1.25])], rng)
    >>> s.model_probs.shape
    (3,)
    """

    def __init__(
        self,
        models: Sequence[MotionModel],
        transition: ArrayLike,
        sensors: Sequence[SensorModel] | SensorModel,
        n_particles: int = 1000,
        *,
        proposal: Literal["prior", "sp-pekf", "cells"] = "prior",
        n_channels: int = 10,
        resampler: str = "systematic",
        initial_probs: ArrayLike | None = None,
    ) -> None:
        self.models = list(models)
        if not self.models:
            raise ConfigError(invalid("models", models, "at least one motion model"))
        dims = {m.dim for m in self.models}
        if len(dims) != 1:
            raise ConfigError(invalid("models", sorted(dims), "models sharing one state dimension"))
        self.transition = check_transition(transition, len(self.models))
        self.sensors: list[SensorModel] = (
            [sensors] if hasattr(sensors, "sensor_id") else list(sensors)  # type: ignore[list-item]
        )
        if isinstance(n_particles, bool) or int(n_particles) != n_particles or n_particles < 1:
            raise ConfigError(invalid("n_particles", n_particles, "an integer >= 1"))
        self.n_particles = int(n_particles)
        if proposal not in ("prior", "sp-pekf", "cells"):
            raise ConfigError(invalid("proposal", proposal, "'prior', 'sp-pekf' or 'cells'"))
        self.cell_proposal = DiscretisationProposal()
        self.proposal = proposal
        self.resample = get_resampler(resampler)
        self.initial_probs = check_initial_probs(initial_probs, len(self.models))
        self.stats = SISStats()
        self.banks = (
            [SPPEKFBank(mod, self.sensors, n_channels, stats=self.stats) for mod in self.models]
            if proposal == "sp-pekf"
            else []
        )

    def initialize(
        self, prior: Gaussian, rng: np.random.Generator, batch_shape: tuple[int, ...] = ()
    ) -> MMBelief:
        mean, cov = np.asarray(prior.mean, float), np.asarray(prior.cov, float)
        d, n = len(mean), self.n_particles
        x = mean + rng.standard_normal((*batch_shape, n, d)) @ np.linalg.cholesky(cov).T
        modes = sample_regimes(
            np.zeros((*batch_shape, n), dtype=np.intp), np.tile(self.initial_probs, (1, 1)), rng
        )
        banks = tuple(b.initialize(prior, rng, batch_shape) for b in self.banks)
        return MMBelief(
            x, modes, np.broadcast_to(mean, (*batch_shape, d)).copy(), self._shares(modes), banks
        )

    def _shares(self, modes: IntArray) -> Array:
        m = len(self.models)
        return np.asarray((modes[..., None] == np.arange(m)).mean(axis=-2), dtype=np.float64)

    def _from_cells(
        self,
        r: int,
        prev: Array,
        prev_modes: IntArray,
        n_r: int,
        zs: Zs,
        dt: float,
        rng: np.random.Generator,
    ) -> tuple[Array, Array]:
        """Discretisation MMPF (Algorithm 7): ``n_r`` particles from regime r's cells (Eq. 84),
        with log weight ``log p̂(p, r) - log q(p, r)`` (likelihood added by the caller)."""
        if prev.ndim != 2:
            raise ConfigError(invalid("batch_shape", prev.shape[:-2], "() for proposal='cells'"))
        model = self.models[r]
        view = ProposalContext(model, self.sensors, self.stats)
        centre, w, delta = self.cell_proposal.cells(prev, zs, dt, view)
        pos = list(model.position_index)  # type: ignore[attr-defined]
        p, log_q = sample_cells(centre[:, pos], w, delta, n_r, rng)
        log_a = np.log(np.maximum(self.transition[prev_modes, r], 1e-300))
        x, log_pred = complete_from_ancestors(p, prev, model, dt, rng, log_a)
        n = prev.shape[0]
        return x, log_pred - (log_q + np.log(n_r / n))

    def step(
        self,
        belief: MMBelief,
        dt: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> MMBelief:
        """Regimes (Eq. 47), states from each regime's proposal, weights (Eqs. 48, 53),
        resampling of states and regimes together, bank feedback."""
        gen = check_generator(rng)
        zs, _ = aligned_values(self.sensors, measurements)
        prev = belief.states
        modes = sample_regimes(belief.modes, self.transition, gen)  # Eq. 47
        loglik = LogLikelihood(self.sensors, zs, self.stats)
        x = np.empty_like(prev)
        log_w = loglik(prev) * 0.0
        banks = list(belief.banks)
        for r, model in enumerate(self.models):
            sel = modes == r
            if self.proposal == "cells":
                if np.any(sel):
                    x[sel], log_w[sel] = self._from_cells(
                        r, prev, belief.modes, int(sel.sum()), zs, dt, gen
                    )
                continue
            if self.proposal == "prior":
                if np.any(sel):
                    x[sel] = model.sample(prev[sel], dt, gen)
                continue
            bank = self.banks[r]
            bs = bank.step(banks[r], zs, dt, gen)  # type: ignore[arg-type]  # Eq. 54
            banks[r] = bs
            draw, log_q = gaussian_draw(bs.mean, bs.total_cov, self.n_particles, gen)
            x = np.where(sel[..., None], draw, x)
            lt = np.asarray(model.log_density(draw, prev, dt))
            log_w = np.where(sel, lt - log_q, log_w)  # Eq. 53 (likelihood added below)
        if loglik:
            log_w = log_w + loglik(x)
        return self._select(x, modes, log_w, tuple(banks), gen)

    def predict(
        self, belief: MMBelief, dt: float, rng: np.random.Generator | None = None
    ) -> MMBelief:
        """``r_t`` by Eq. 47 and ``x_t ~ p(x_t | x_{t-1}, r_t)``; the parents wait for update."""
        gen = check_generator(rng)
        prev = belief.states
        modes = sample_regimes(belief.modes, self.transition, gen)
        x = np.empty_like(prev)
        for r, model in enumerate(self.models):
            sel = modes == r
            if np.any(sel):
                x[sel] = model.sample(prev[sel], dt, gen)
        return MMBelief(x, modes, x.mean(axis=-2), self._shares(modes), belief.banks, parents=prev)

    def update(
        self,
        belief: MMBelief,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> MMBelief:
        """Weight by ``p(z_t | x_t)``, resample states and regimes together."""
        return self.update_with_likelihood(belief, measurements, rng)[0]

    def update_with_likelihood(
        self,
        belief: MMBelief,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> tuple[MMBelief, Array]:
        """:meth:`update` and ``log p(z_t | z_1:t-1)`` ``(...)``, estimated by
        ``log (1/N) sum_i p(z_t | x_t^i)`` over the predicted particles (0 with no report)."""
        zs, _ = aligned_values(self.sensors, measurements)
        loglik = LogLikelihood(self.sensors, zs, self.stats)
        if not loglik:
            return belief, np.zeros(belief.states.shape[:-2])
        x = belief.states
        ll = loglik(x)
        increment = np.asarray(logsumexp(ll, axis=-1) - np.log(x.shape[-2]), dtype=float)
        return self._select(x, belief.modes, ll, belief.banks, check_generator(rng)), increment

    def _select(
        self,
        x: Array,
        modes: IntArray,
        log_w: Array,
        banks: tuple[BankState | None, ...],
        rng: np.random.Generator,
    ) -> MMBelief:
        """Resample states and regimes by ``log_w``; estimate; feed every bank its regime's mean
        (the overall mean for a regime with no particle)."""
        idx = resample_log_weights(log_w, self.resample, rng, self.stats)
        x = np.take_along_axis(x, idx[..., None], axis=-2)
        modes = np.take_along_axis(modes, idx, axis=-1)
        est = x.mean(axis=-2)
        fed = list(banks)
        for r, bank in enumerate(self.banks):
            sel = (modes == r)[..., None]
            cnt = sel.sum(axis=-2)
            sub = np.where(cnt > 0, (x * sel).sum(axis=-2) / np.maximum(cnt, 1), est)
            fed[r] = bank.feedback(fed[r], sub)  # type: ignore[arg-type]
        return MMBelief(x, modes, est, self._shares(modes), tuple(fed))


def hmm_filter(transition: ArrayLike, loglik: Array, initial: ArrayLike) -> Array:
    """Exact discrete-state (HMM) forward filter: ``P(r_t | z_{1:t})`` ``(T, M)`` from
    ``loglik (T, M)`` = ``log p(z_t | r_t = m)`` (reference for the multiple-model tests)."""
    p = np.asarray(initial, float)
    P = np.asarray(transition, float)
    out = []
    for ll in loglik:
        p = (p @ P) * np.exp(ll - ll.max())
        p /= p.sum()
        out.append(p)
    return np.array(out)
