"""Sequential importance sampling with a pluggable proposal (Zhai 2007, Sec. 2.1-2.2, App. A).

One step of :class:`ProposalParticleFilter` is the thesis's loop, shared by every filter of the
dissertation (bootstrap, PF-SP-PEKF, Galerkin and grid proposals, MCMC moves):

1. draw ``x_t^i ~ q(x_t | x_{t-1}^i, z_t)`` from the proposal;
2. weight (Zhai 2007, Eq. 13) ``log w^i = log p(z_t | x_t^i) + log p(x_t^i | x_{t-1}^i) - log q(x_t^i)``
   (the previous weights are equal: every step resamples); with the transition prior as proposal
   the last two terms cancel and ``w^i = p(z_t | x_t^i)``;
3. normalise in the log domain, resample (systematic by default), optionally move each particle
   with an MCMC kernel that leaves ``p(z_t | x) p(x | x_{t-1}^{a_i})`` invariant (Algorithms 8-10);
4. output the mean of the resampled particles and hand it back to the proposal ("feedback").

Proposals: the transition prior (:class:`PriorProposal`), the EKF bank of PF-SP-PEKF
(:mod:`.sp_pekf`), CPF-SP (:mod:`.cpf_sp`), unscented (:mod:`.unscented_proposal`), Galerkin and
discretisation (:mod:`.grid_proposals`), and regime switching (:mod:`.multiple_model`: the
multiple-model filters are this engine with a regime per particle); MCMC moves in
:mod:`.mcmc_moves`.

Pairing (spec Sec. 2.1): when the proposal ignores the particle's own past, Eq. 13 pairs new
particle i with resampled ancestor i ("paired", the thesis's literal weight). ``transition=
"marginal"`` uses ``(1/N) sum_j p(x_t^i | x_{t-1}^j)`` instead (O(N^2), the marginal-proposal weight).

Shapes: particles ``(..., N, d)``; leading axes are independent runs advanced together. A
step's measurements are :class:`~fusetrack.core.Measurement` values ``(m,)`` or ``(..., m)``,
at most one per sensor; values with NaN are skipped and counted. Inside, proposals see them
aligned with ``sensors`` (``zs``: one value or None per sensor) and the filter through a
:class:`ProposalContext` (its models, counters and the step's side inputs).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, Protocol

import numpy as np
from numpy.typing import NDArray
from scipy.special import logsumexp

from ..core import (
    ConfigError,
    Gaussian,
    Measurement,
    MeasurementError,
    MotionModel,
    SensorModel,
    UnknownSensorError,
    check_positive,
    get_resampler,
    invalid,
)
from .mixture_density import gauss_logpdf, gaussian_mixture_ancestors
from .stats import FilterStats
from .weighting import ParticleWeights, draw_ancestors, particle_weights

Array = NDArray[np.float64]
Zs = Sequence[Array | None]


@dataclass
class SISStats(FilterStats):
    """:class:`FilterStats` plus the counters the proposals and moves of this module keep."""

    repaired_channels: int = 0  # EKF channels whose covariance was not PD and was repaired
    dropped_channels: int = 0  # EKF channels with non-finite values, reset from the estimate
    grid_too_small: int = 0  # grid proposals whose window cut off probability mass
    moves_proposed: int = 0
    moves_accepted: int = 0
    zero_acceptance_steps: int = 0  # steps where an MCMC move accepted nothing

    def reset(self) -> None:
        for k in self.as_dict():
            setattr(self, k, 0)

    @property
    def acceptance_rate(self) -> float:
        return self.moves_accepted / self.moves_proposed if self.moves_proposed else float("nan")


class LogLikelihood:
    """``log p(z_t | x)`` summed over the sensors that reported (finite values) at one step."""

    def __init__(self, sensors: Sequence[SensorModel], zs: Zs, stats: FilterStats | None = None):
        if len(zs) != len(sensors):
            raise ConfigError(
                invalid("measurements", f"{len(zs)} entries", f"{len(sensors)} (one per sensor)")
            )
        self.items: list[tuple[SensorModel, Array]] = []
        for s, z in zip(sensors, zs):
            if z is None:
                continue
            za = np.asarray(z, dtype=float)
            if za.ndim == 0:
                za = za[None]
            if not np.all(np.isfinite(za)):
                if stats is not None:
                    stats.skipped_measurements += 1
                continue
            self.items.append((s, za))

    def __call__(self, x: Array) -> Array:
        """``(..., N)`` for particles ``(..., N, d)``."""
        out = np.zeros(x.shape[:-1])
        for s, z in self.items:
            out = out + s.log_likelihood(np.expand_dims(z, -2), x)
        return out

    def __bool__(self) -> bool:
        return bool(self.items)


class Proposal(Protocol):
    """``q(x_t | x_{t-1}, z_t)``: draws particles and returns their log proposal density.

    ``filt`` is the step's :class:`ProposalContext`; everything a proposal carries from step to
    step is its ``state`` (returned by ``initialize``/``draw``/``feedback``, kept in the belief).
    Optional members: ``returns_log_ratio`` (see :meth:`draw`), ``side_inputs`` (measurement ids
    the proposal reads, see :class:`ProposalContext`) and ``reindex(state, ancestors)``, which
    makes per-particle parts of the state (regimes, :mod:`.multiple_model`) follow resampling.
    """

    def initialize(self, prior: Gaussian, particles: Array, rng: np.random.Generator) -> Any: ...

    def draw(
        self, state: Any, prev: Array, zs: Zs, dt: float, rng: np.random.Generator, filt: Any
    ) -> tuple[Array, Array | None, Any]:
        """``(x (..., N, d), log q (..., N) or None for the transition prior, new state)``.

        A proposal with ``returns_log_ratio = True`` returns ``log p(x | z_{1:t-1}) - log q(x)``
        (the predictive density of the previous particle set over the proposal) instead of
        ``log q``; the filter then adds only the likelihood.
        """
        ...

    def feedback(self, state: Any, particles: Array, estimate: Array, filt: Any) -> Any: ...


@dataclass(frozen=True)
class PriorProposal:
    """The transition prior ``p(x_t | x_{t-1})``: the bootstrap filter / condensation."""

    def initialize(self, prior: Gaussian, particles: Array, rng: np.random.Generator) -> None:
        return None

    def draw(
        self, state: Any, prev: Array, zs: Zs, dt: float, rng: np.random.Generator, filt: Any
    ) -> tuple[Array, None, None]:
        return filt.motion.sample(prev, dt, rng), None, None

    def feedback(self, state: Any, particles: Array, estimate: Array, filt: Any) -> None:
        return None


Move = Callable[[Array, Array, Callable[[Array], Array], float, np.random.Generator, Any], Array]
"""An MCMC kernel applied after resampling (Zhai 2007, Algorithms 8-10):
``move(x, parents, loglik, dt, rng, ctx) -> x`` with ``ctx`` the step's
:class:`ProposalContext` (see :mod:`.mcmc_moves`)."""


def is_gaussian_transition(motion: MotionModel, dt: float) -> bool:
    """Whether ``motion.log_density(x', x, dt) = log N(x'; motion.mean(x, dt), noise_cov(dt))``
    with a positive-definite ``noise_cov`` (checked at two random pairs)."""
    try:
        cov = np.asarray(motion.noise_cov(dt), float)
        np.linalg.cholesky(cov)
    except (np.linalg.LinAlgError, ValueError):
        return False
    rng = np.random.default_rng(0)
    x0 = rng.normal(size=(2, cov.shape[0])) + 1.0
    x1 = np.asarray(motion.mean(x0, dt)) + rng.normal(size=x0.shape) * np.sqrt(np.diag(cov))
    ref = gauss_logpdf(x1 - np.asarray(motion.mean(x0, dt)), cov)
    return bool(np.allclose(motion.log_density(x1, x0, dt), ref, rtol=1e-9, atol=1e-9))


def resample_weights(
    weights: ParticleWeights,
    resample: Callable[..., Any],
    rng: np.random.Generator,
    stats: FilterStats,
    owner: str = "particle filter",
) -> NDArray[np.intp]:
    """Ancestor indices ``(..., N)`` from normalised weights (:func:`~.weighting.particle_weights`:
    a run whose weights all vanished keeps them equal); such a run is counted and warned
    (:meth:`~fusetrack.filters.stats.FilterStats.note_degenerate`; never NaN)."""
    if weights.any_degenerate:
        stats.note_degenerate(owner, "every weight of a run was zero; it kept them equal", 5)
    stats.resample_count += 1
    return draw_ancestors(weights, rng, resample)


@dataclass(frozen=True, eq=False)
class SISBelief:
    """What :class:`ProposalParticleFilter` carries from step to step.

    ``states`` ``(..., N, d)`` equally weighted after a step (every step resamples),
    ``estimate`` ``(..., d)`` their mean, ``proposal`` the proposal's own state (an EKF bank, the
    CPF-SP banks, the UKF covariance; None for the transition prior). Between :meth:`predict
    <ProposalParticleFilter.predict>` and :meth:`update <ProposalParticleFilter.update>`,
    ``parents`` ``(..., N, d)`` holds the states each particle was drawn from and ``dt`` the step.
    """

    states: Array
    estimate: Array
    proposal: Any = None
    parents: Array | None = None
    dt: float = 0.0

    @property
    def mean(self) -> Array:
        return self.estimate

    @property
    def cov(self) -> Array:
        """Sample covariance of the (equally weighted) particles, ``(..., d, d)``."""
        dev = self.states - self.estimate[..., None, :]
        n = self.states.shape[-2]
        return np.asarray(np.einsum("...ni,...nj->...ij", dev, dev) / max(n - 1, 1))

    @property
    def batch_shape(self) -> tuple[int, ...]:
        return tuple(self.states.shape[:-2])


@dataclass(frozen=True)
class ProposalContext:
    """What a proposal or a move sees of the filter at one step: its models, its counters and
    the step's side inputs (measurements that no sensor model explains but a proposal reads,
    e.g. CPF-SP's received-intensity shares), keyed by sensor id."""

    motion: MotionModel
    sensors: list[SensorModel]
    stats: SISStats
    side: Mapping[str, Array] = field(default_factory=dict)


def sensor_measurements(
    sensors: Sequence[SensorModel], zs: Zs, time: float = 0.0
) -> list[Measurement]:
    """A sensor-aligned step (one value or None per sensor) as measurements at ``time``."""
    return [
        Measurement(time, s.sensor_id, np.asarray(z, dtype=float))
        for s, z in zip(sensors, zs)
        if z is not None
    ]


def aligned_values(
    sensors: Sequence[SensorModel],
    measurements: Sequence[Measurement],
    side_ids: Sequence[str] = (),
) -> tuple[list[Array | None], dict[str, Array]]:
    """The step's values aligned with ``sensors`` (None where a sensor did not report) and the
    side inputs whose ids are in ``side_ids``; any other sensor id raises
    :class:`~fusetrack.core.UnknownSensorError`, a second report of one sensor
    :class:`~fusetrack.core.MeasurementError`."""
    index = {s.sensor_id: k for k, s in enumerate(sensors)}
    zs: list[Array | None] = [None] * len(sensors)
    side: dict[str, Array] = {}
    for m in measurements:
        k = index.get(m.sensor_id)
        if k is None:
            if m.sensor_id not in side_ids:
                valid = sorted(index) + sorted(side_ids)
                raise UnknownSensorError(invalid("sensor_id", m.sensor_id, f"one of {valid}"))
            side[m.sensor_id] = m.value
        elif zs[k] is not None:
            raise MeasurementError(
                invalid("measurements", f"two reports of {m.sensor_id!r}", "one per sensor a step")
            )
        else:
            zs[k] = m.value
    return zs, side


class ProposalParticleFilter:
    """SIS with proposal ``proposal``, resampling every step, optional MCMC ``move``: a
    :class:`~fusetrack.core.SteppingFilter` over :class:`SISBelief`.

    ``step(belief, dt, measurements, rng)`` draws from the proposal with the measurements in view
    (the thesis's loop, module docstring); ``predict`` draws from the transition prior and
    ``update`` weights by the likelihood, resamples and moves: their composition is the
    bootstrap step (the proposal's state is carried through and fed back the particle
    estimate). Measurements name the filter's sensors; ``proposal.side_inputs`` lists other ids
    the proposal reads (e.g. CPF-SP's sensor weights).

    >>> from fusetrack.motion.benchmark import ScalarBenchmark
    >>> from fusetrack.sensors.power import Power
    >>> pf = ProposalParticleFilter(ScalarBenchmark(), [Power("z", 3)], n_particles=100)
    >>> rng = np.random.default_rng(0)
    >>> b = pf.initialize(Gaussian(np.zeros(1), np.eye(1)), rng)
    >>> b = pf.step(b, 1.0, [Measurement(1.0, "z", [8.0])], rng)
    >>> bool(abs(b.mean[0] - 2.0) < 0.2)
    True
    """

    def __init__(
        self,
        motion: MotionModel,
        sensors: Sequence[SensorModel] | SensorModel,
        proposal: Proposal | None = None,
        n_particles: int = 200,
        *,
        resampler: str | Callable[..., Any] = "systematic",
        move: Move | None = None,
        transition: Literal["paired", "marginal"] = "paired",
    ) -> None:
        self.motion = motion
        self.sensors: list[SensorModel] = (
            [sensors] if hasattr(sensors, "sensor_id") else list(sensors)  # type: ignore[list-item]
        )
        self.proposal: Proposal = proposal if proposal is not None else PriorProposal()
        if isinstance(n_particles, bool) or int(n_particles) != n_particles or n_particles < 1:
            raise ConfigError(invalid("n_particles", n_particles, "an integer >= 1"))
        self.n_particles = int(n_particles)
        self.resample = get_resampler(resampler)
        self.move = move
        if transition not in ("paired", "marginal"):
            raise ConfigError(invalid("transition", transition, "'paired' or 'marginal'"))
        self.transition = transition
        self.stats = SISStats()
        self._side_ids: tuple[str, ...] = tuple(getattr(self.proposal, "side_inputs", ()))

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}(proposal={type(self.proposal).__name__}, "
            f"n_particles={self.n_particles}, move={type(self.move).__name__ if self.move else None})"
        )

    def context(self, side: Mapping[str, Array] | None = None) -> ProposalContext:
        """The view of this filter that proposals and moves get (see :class:`ProposalContext`)."""
        return ProposalContext(self.motion, self.sensors, self.stats, side or {})

    def initialize(
        self, prior: Gaussian, rng: np.random.Generator, batch_shape: tuple[int, ...] = ()
    ) -> SISBelief:
        """Particles drawn from ``prior``, shape ``(*batch_shape, N, d)``."""
        mean, cov = np.asarray(prior.mean, float), np.asarray(prior.cov, float)
        g = np.linalg.cholesky(cov + 1e-300 * np.eye(len(mean)))
        x = mean + rng.standard_normal((*batch_shape, self.n_particles, len(mean))) @ g.T
        return SISBelief(
            x,
            np.broadcast_to(mean, (*batch_shape, len(mean))).copy(),
            self.proposal.initialize(prior, x, rng),
        )

    def log_transition(self, x: Array, prev: Array, dt: float) -> Array:
        """``log p(x^i | x_{t-1}^i)`` (paired) or ``log (1/N) sum_j p(x^i | x_{t-1}^j)``."""
        if self.transition == "paired":
            return np.asarray(self.motion.log_density(x, prev, dt))
        if is_gaussian_transition(self.motion, dt):  # one O(N^2) Numba pass per run
            cov = np.asarray(self.motion.noise_cov(dt), float)
            m = np.asarray(self.motion.mean(prev, dt))
            xs, ms = x.reshape(-1, *x.shape[-2:]), m.reshape(-1, *m.shape[-2:])
            lse = [
                gaussian_mixture_ancestors(a, b, cov, np.zeros(len(b)), np.zeros(len(a)))[0]
                for a, b in zip(xs, ms)
            ]
            return np.asarray(np.reshape(lse, x.shape[:-1]) - np.log(prev.shape[-2]))
        lp = self.motion.log_density(x[..., :, None, :], prev[..., None, :, :], dt)
        return np.asarray(logsumexp(lp, axis=-1) - np.log(prev.shape[-2]))

    def step(
        self,
        belief: SISBelief,
        dt: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> SISBelief:
        """Draw ``x_t ~ q(x_t | x_{t-1}, z_t)``, weight (Eq. 13), resample, move, feed back."""
        return self.step_with_likelihood(belief, dt, measurements, rng)[0]

    def step_with_likelihood(
        self,
        belief: SISBelief,
        dt: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> tuple[SISBelief, Array]:
        """:meth:`step`, and ``log p(z_t | z_1:t-1)`` estimated with this proposal: the log mean
        of the incremental weights (the particles are equally weighted after every step), 0 where
        no sensor reported."""
        check_positive("dt", dt)
        gen = check_generator(rng)
        zs, side = aligned_values(self.sensors, measurements, self._side_ids)
        ctx = self.context(side)
        prev = belief.states
        loglik = LogLikelihood(self.sensors, zs, self.stats)
        x, log_q, pstate = self.proposal.draw(belief.proposal, prev, zs, dt, gen, ctx)
        if log_q is None:
            log_w = loglik(x) if loglik else np.zeros(x.shape[:-1])
        elif getattr(self.proposal, "returns_log_ratio", False):
            # the proposal already returned log(p(x_t | z_{1:t-1}) / q(x_t)) (exact marginal weight)
            log_w = (loglik(x) if loglik else 0.0) + log_q
        else:
            log_w = loglik(x) + self.log_transition(x, prev, dt) - log_q
        pw = particle_weights(log_w)
        increment = pw.log_mean if loglik else np.zeros(np.shape(log_w)[:-1])
        return self._select(x, prev, pw, loglik, pstate, dt, gen, ctx), increment

    def predict(
        self, belief: SISBelief, dt: float, rng: np.random.Generator | None = None
    ) -> SISBelief:
        """``x_t ~ p(x_t | x_{t-1})`` for every particle; the parents wait for :meth:`update`."""
        check_positive("dt", dt)
        x = np.asarray(self.motion.sample(belief.states, dt, check_generator(rng)), dtype=float)
        return SISBelief(x, x.mean(axis=-2), belief.proposal, belief.states, dt)

    def update(
        self,
        belief: SISBelief,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> SISBelief:
        """Weight the predicted particles by ``p(z_t | x_t)``, resample, move, feed back."""
        return self.update_with_likelihood(belief, measurements, rng)[0]

    def update_with_likelihood(
        self,
        belief: SISBelief,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> tuple[SISBelief, Array]:
        """:meth:`update` and ``log p(z_t | z_1:t-1)`` ``(...)`` per run, estimated by
        ``log (1/N) sum_i p(z_t | x_t^i)`` over the equally weighted predicted particles
        (0 when no sensor reported)."""
        zs, side = aligned_values(self.sensors, measurements, self._side_ids)
        loglik = LogLikelihood(self.sensors, zs, self.stats)
        if not loglik:
            return belief, np.zeros(belief.batch_shape)
        parents = belief.parents if belief.parents is not None else belief.states
        x = belief.states
        pw = particle_weights(loglik(x))
        return self._select(
            x,
            parents,
            pw,
            loglik,
            belief.proposal,
            belief.dt,
            check_generator(rng),
            self.context(side),
        ), pw.log_mean

    def _select(
        self,
        x: Array,
        prev: Array,
        weights: ParticleWeights,
        loglik: LogLikelihood,
        pstate: Any,
        dt: float,
        rng: np.random.Generator,
        ctx: ProposalContext,
    ) -> SISBelief:
        """Resample by ``weights``, move (with the likelihood in view), estimate, feed back."""
        idx = resample_weights(weights, self.resample, rng, self.stats, type(self).__name__)
        x_res = np.take_along_axis(x, idx[..., None], axis=-2)
        reindex = getattr(self.proposal, "reindex", None)
        if reindex is not None:  # per-particle parts of the proposal state (regimes)
            pstate = reindex(pstate, idx)
        if self.move is not None and loglik:
            parents = np.take_along_axis(prev, idx[..., None], axis=-2)
            x_res = self.move(x_res, parents, loglik, dt, rng, ctx)
        est = x_res.mean(axis=-2)
        pstate = self.proposal.feedback(pstate, x_res, est, ctx)
        return SISBelief(x_res, est, pstate)


def check_generator(rng: np.random.Generator | None) -> np.random.Generator:
    """``rng`` when it is a numpy Generator (these filters draw from one), else ConfigError."""
    if not isinstance(rng, np.random.Generator):
        raise ConfigError(invalid("rng", rng, "a numpy.random.Generator"))
    return rng
