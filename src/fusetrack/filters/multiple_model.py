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
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import (
    ConfigError,
    Gaussian,
    Measurement,
    MotionModel,
    Particles,
    SensorModel,
    invalid,
)
from ..motion import MarkovSwitching
from .grid_proposals import DiscretisationProposal, complete_from_ancestors, sample_cells
from .proposals import Array, LogLikelihood, ProposalContext, Zs, check_generator
from .sis import ProposalParticleFilter
from .sp_pekf import BankState, SPPEKFBank, gaussian_draw_rows

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
class RegimeState:
    """The per-particle part of a regime-switching belief: ``modes`` ``(..., N)`` (the regime
    of each particle, resampled with it) and the SP-PEKF bank state of each regime (MMPF-SP)."""

    modes: IntArray
    n_models: int
    banks: tuple[BankState | Gaussian | None, ...] = ()

    @property
    def model_probs(self) -> Array:
        """Regime shares of the (equally weighted) particles, ``(..., M)`` (Fig 28)."""
        m = self.n_models
        return np.asarray((self.modes[..., None] == np.arange(m)).mean(axis=-2), dtype=np.float64)


@dataclass(frozen=True, eq=False)
class RegimeSwitchingProposal:
    """Jump-Markov proposal (Zhai 2007, Algorithms 3, 4, 7): each particle draws its regime from
    its row of ``transition`` (Eq. 47), then its state from that regime's proposal:

    ``"prior"``
        the regime's motion model (MM-bootstrap, Sec. 3.4.4);
    ``"sp-pekf"``
        the moment-matched Gaussian of an SP-PEKF bank run under that regime (MMPF-SP, Eq. 54;
        weight ``p(x | x_{t-1}, r) / q(x | r)``, Eq. 53);
    ``"cells"``
        the regime's discretisation cells with the marginal weight (Algorithm 7).

    ``motion`` is the switching motion (:class:`~fusetrack.motion.MarkovSwitching`: a state
    draw given each particle's regime); ``transition`` the checked matrix the regimes are drawn
    from (the switching motion's copy is renormalised, which could move a draw by a rounding).
    It returns the weight ratio (``returns_log_ratio``): the filter adds the likelihood (Eq. 48).
    Regimes follow their particles through resampling (:meth:`reindex`); after it bank ``r`` is
    re-partitioned at the mean of the particles in regime ``r`` (or the overall mean when there
    are none; MISSING in the thesis, spec choice).
    """

    motion: MarkovSwitching
    transition: Array
    kind: Literal["prior", "sp-pekf", "cells"] = "prior"
    n_channels: int = 10
    initial_probs: Array | None = None
    cell_proposal: DiscretisationProposal = field(default_factory=DiscretisationProposal)

    returns_log_ratio = True

    @property
    def models(self) -> tuple[MotionModel, ...]:
        return self.motion.models

    def _banks(self, ctx: ProposalContext) -> list[SPPEKFBank]:
        return [SPPEKFBank(m, ctx.sensors, self.n_channels, stats=ctx.stats) for m in self.models]

    def initialize(
        self, prior: Gaussian, particles: Array, rng: np.random.Generator
    ) -> RegimeState:
        """Regimes from ``initial_probs``, then each regime's bank from the prior."""
        batch = particles.shape[:-2]
        p0 = self.initial_probs if self.initial_probs is not None else np.ones(1)
        modes = sample_regimes(
            np.zeros(particles.shape[:-1], dtype=np.intp), np.tile(p0, (1, 1)), rng
        )
        banks: tuple[BankState | Gaussian | None, ...] = ()
        if self.kind == "sp-pekf":
            banks = tuple(
                SPPEKFBank(m, [], self.n_channels).initialize(prior, rng, batch)
                for m in self.models
            )
        return RegimeState(modes, len(self.models), banks)

    def draw(
        self,
        state: RegimeState,
        prev: Array,
        zs: Zs,
        dt: float,
        rng: np.random.Generator,
        filt: ProposalContext,
    ) -> tuple[Array, Array, RegimeState]:
        modes = sample_regimes(state.modes, self.transition, rng)  # Eq. 47
        if self.kind == "prior":  # the switching motion (MM-bootstrap, Sec. 3.4.4)
            x = self.motion.sample(prev, dt, rng, modes)
            # 0 where the previous particle's likelihood is finite (NaN, i.e. no weight,
            # elsewhere: as this filter always computed it)
            log_r = LogLikelihood(filt.sensors, zs)(prev) * 0.0
            return x, log_r, RegimeState(modes, len(self.models), state.banks)
        x = np.empty_like(prev)
        log_r = np.zeros(prev.shape[:-1])  # every particle's entry is set below
        banks = list(state.banks)
        steppers = self._banks(filt) if self.kind == "sp-pekf" else []
        for r, model in enumerate(self.models):
            sel = modes == r
            if self.kind == "cells":
                if np.any(sel):
                    x[sel], log_r[sel] = self._from_cells(
                        r, prev, state.modes, int(sel.sum()), zs, dt, rng, filt
                    )
                continue
            predicted = steppers[r].predict(banks[r], dt, rng)  # type: ignore[arg-type]
            bs = steppers[r].update_aligned(predicted, zs)  # Eq. 54
            banks[r] = bs
            # only regime r's particles are drawn from bank r (the generator advances by all N)
            draw, log_q = gaussian_draw_rows(bs.mean, bs.total_cov, sel, rng)
            x[sel] = draw
            lt = np.asarray(model.log_density(draw, prev[sel], dt))
            log_r[sel] = lt - log_q  # Eq. 53 (likelihood added by the filter)
        return x, log_r, RegimeState(modes, len(self.models), tuple(banks))

    def model_cells(
        self, r: int, prev: Array, zs: Zs, dt: float, filt: ProposalContext
    ) -> tuple[Array, Array, Array]:
        """Regime ``r``'s cells (Algorithm 7, step 2): ``prev``'s cells propagated through model
        ``r`` and weighted by the measurement (Eqs. 78-79): centres ``(C, d)``, weights ``(C,)``
        and the side ``Δ`` of the position boxes."""
        view = ProposalContext(self.models[r], filt.sensors, filt.stats)
        return self.cell_proposal.cells(prev, zs, dt, view)

    def _from_cells(
        self,
        r: int,
        prev: Array,
        prev_modes: IntArray,
        n_r: int,
        zs: Zs,
        dt: float,
        rng: np.random.Generator,
        filt: ProposalContext,
    ) -> tuple[Array, Array]:
        """Discretisation MMPF (Algorithm 7): ``n_r`` particles from regime r's cells (Eq. 84),
        with log weight ``log p̂(p, r) - log q(p, r)``."""
        if prev.ndim != 2:
            raise ConfigError(invalid("batch_shape", prev.shape[:-2], "() for proposal='cells'"))
        model = self.models[r]
        centre, w, delta = self.model_cells(r, prev, zs, dt, filt)
        pos = list(model.position_index)  # type: ignore[attr-defined]
        p, log_q = sample_cells(centre[:, pos], w, delta, n_r, rng)
        log_a = np.log(np.maximum(self.transition[prev_modes, r], 1e-300))
        x, log_pred = complete_from_ancestors(p, prev, model, dt, rng, log_a)
        n = prev.shape[0]
        return x, log_pred - (log_q + np.log(n_r / n))

    def prior_draw(
        self, state: RegimeState, prev: Array, dt: float, rng: np.random.Generator
    ) -> tuple[Array, RegimeState]:
        """The filter's ``predict``: ``r_t`` by Eq. 47, then ``x_t ~ p(x_t | x_{t-1}, r_t)``."""
        modes = sample_regimes(state.modes, self.transition, rng)
        x = self.motion.sample(prev, dt, rng, modes)
        return x, RegimeState(modes, state.n_models, state.banks)

    def reindex(self, state: RegimeState, ancestors: IntArray) -> RegimeState:
        """The regimes follow their particles through resampling."""
        modes = np.take_along_axis(state.modes, ancestors, axis=-1)
        return RegimeState(modes, state.n_models, state.banks)

    def feedback(
        self, state: RegimeState, particles: Array, estimate: Array, filt: ProposalContext
    ) -> RegimeState:
        if self.kind != "sp-pekf":
            return state
        fed = list(state.banks)
        for r, bank in enumerate(self._banks(filt)):
            sel = (state.modes == r)[..., None]
            cnt = sel.sum(axis=-2)
            sub = np.where(cnt > 0, (particles * sel).sum(axis=-2) / np.maximum(cnt, 1), estimate)
            fed[r] = bank.feedback(fed[r], sub)  # type: ignore[arg-type]
        return RegimeState(state.modes, state.n_models, tuple(fed))


class MultipleModelParticleFilter(ProposalParticleFilter):
    """Jump-Markov particle filter: the one SIS engine (:class:`ProposalParticleFilter`) with a
    :class:`RegimeSwitchingProposal` — MM-bootstrap (``proposal="prior"``), MMPF-SP
    (``"sp-pekf"``) or the discretisation MMPF (``"cells"``). The belief is a
    :class:`~fusetrack.filters.SISBelief` whose ``proposal`` is a :class:`RegimeState`
    (``modes``, ``model_probs``, banks). ``predict`` draws regimes (Eq. 47) and states from each
    regime's motion model (the proposal's ``prior_draw``); followed by ``update`` it is the
    MM-bootstrap step.

    >>> from fusetrack.motion import ConstantVelocity
    >>> from fusetrack.motion.maneuver import ManeuverTurn
    >>> from fusetrack.sensors import Bearing
    >>> models = [ConstantVelocity(q=0.01), ManeuverTurn(0.5, 1, 0.01), ManeuverTurn(0.5, -1, 0.01)]
    >>> pi = [[0.8, 0.1, 0.1], [0.2, 0.7, 0.1], [0.2, 0.1, 0.7]]
    >>> mm = MultipleModelParticleFilter(models, pi, [Bearing("b", [0, 0], 0.05)], 500)
    >>> rng = np.random.default_rng(0)
    >>> s = mm.initialize(Gaussian(np.array([10.0, 30, 1, 0]), np.diag([1, 1, 0.1, 0.1])), rng)
    >>> s = mm.step(s, 1.0, [Measurement(1.0, "b", [1.25])], rng)
    >>> s.proposal.model_probs.shape
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
        models = list(models)
        if not models:
            raise ConfigError(invalid("models", models, "at least one motion model"))
        dims = {m.dim for m in models}
        if len(dims) != 1:
            raise ConfigError(invalid("models", sorted(dims), "models sharing one state dimension"))
        if proposal not in ("prior", "sp-pekf", "cells"):
            raise ConfigError(invalid("proposal", proposal, "'prior', 'sp-pekf' or 'cells'"))
        p = check_transition(transition, len(models))
        switching = RegimeSwitchingProposal(
            MarkovSwitching(tuple(models), p),
            p,
            proposal,
            n_channels,
            check_initial_probs(initial_probs, len(models)),
        )
        # motion: the first regime's model, used only where no regime is drawn (never: the
        # proposal and predict draw per regime); the proposal's ratio needs no transition density
        super().__init__(models[0], sensors, switching, n_particles, resampler=resampler)
        self.models = models
        self.switching = switching

    def cells(
        self, belief: Particles, dt: float, measurements: Sequence[Measurement]
    ) -> list[tuple[Array, Array, Array]]:
        """Each model's cells for the step from ``belief`` (Algorithm 7, step 2; Fig 55): per
        model, the centres ``(C, d)``, weights ``(C,)`` and box side ``Δ`` (one set, no batch)."""
        if belief.states.ndim != 2:
            raise ConfigError(invalid("belief.batch_shape", belief.batch_shape, "() (one set)"))
        zs, side, _ = self._step_inputs(measurements, belief.batch_shape)
        ctx = self.context(side)
        return [
            self.switching.model_cells(r, belief.states, zs, dt, ctx)
            for r in range(len(self.models))
        ]

    def propose(
        self,
        belief: Particles,
        dt: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator,
    ) -> tuple[Array, IntArray]:
        """The step's draw alone (Algorithm 7, steps 1-3; Fig 56): the proposed particles
        ``(..., N, d)``, before weighting and resampling, and their regimes ``(..., N)``."""
        zs, side, _ = self._step_inputs(measurements, belief.batch_shape)
        gen = check_generator(rng)
        regimes = getattr(belief, "proposal", None)
        if not isinstance(regimes, RegimeState):
            raise ConfigError(
                invalid("belief.proposal", regimes, "a RegimeState (from initialize)")
            )
        x, _, state = self.switching.draw(regimes, belief.states, zs, dt, gen, self.context(side))
        return x, state.modes


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
