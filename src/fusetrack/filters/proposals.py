"""The pluggable parts of a proposal-driven particle filter (Zhai 2007, Sec. 2.1-2.2, App. A).

:class:`~fusetrack.filters.ParticleFilter` with ``resample="every_update"`` runs the thesis's
loop (:class:`~fusetrack.filters.ProposalParticleFilter` is that configuration); this module
holds what plugs into it:

- a :class:`Proposal` ``q(x_t | x_{t-1}, z_t)`` (:class:`PriorProposal`: the transition prior;
  the EKF bank of PF-SP-PEKF, :mod:`.sp_pekf`; CPF-SP, :mod:`.cpf_sp`; unscented,
  :mod:`.unscented_proposal`; Galerkin and discretisation, :mod:`.grid_proposals`; regime
  switching, :mod:`.multiple_model`), whose weight is Zhai 2007, Eq. 13;
- a :data:`Move`, an MCMC kernel applied after resampling (Algorithms 8-10, :mod:`.mcmc_moves`);
- what they see of the filter: the step's :class:`ProposalContext`, its :class:`LogLikelihood`,
  the measurements aligned with the sensors (:func:`aligned_values`), the counters
  (:class:`SISStats`);
- :class:`SISBelief`, the particle set such a filter carries (equally weighted after every
  update, with its estimate and the proposal's own state).

Pairing (spec Sec. 2.1): when the proposal ignores the particle's own past, Eq. 13 pairs new
particle i with resampled ancestor i ("paired", the thesis's literal weight); "marginal" uses
``(1/N) sum_j p(x_t^i | x_{t-1}^j)`` instead (O(N^2), :func:`log_transition`).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Hashable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, cast

import numpy as np
from numpy.typing import NDArray
from scipy.special import logsumexp

from ..core import (
    ConfigError,
    Gaussian,
    Measurement,
    MeasurementError,
    MotionModel,
    Particles,
    SensorModel,
    UnknownSensorError,
    invalid,
)
from .mixture_density import gauss_logpdf, gaussian_mixture_ancestors
from .stats import FilterStats

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
    """``log p(z_t | x)`` summed over the sensors that reported (finite values) at one step: the
    view of the step's likelihood that proposals and MCMC moves evaluate at particles of their
    own. (The filter weighs through :class:`~fusetrack.filters.ParticleFilter`'s likelihood
    pass, which counts skipped reports; this one does not.)"""

    def __init__(self, sensors: Sequence[SensorModel], zs: Zs):
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
    with a positive-definite ``noise_cov`` (checked at two random pairs; once per hashable
    ``(motion, dt)``)."""
    try:
        hash((motion, dt))
    except TypeError:  # a model with array fields: checked each time
        return _check_gaussian_transition(motion, dt)
    return _cached_gaussian_transition(cast(Hashable, motion), dt)


@functools.lru_cache(maxsize=64)
def _cached_gaussian_transition(motion: Any, dt: float) -> bool:
    return _check_gaussian_transition(motion, dt)


def _check_gaussian_transition(motion: MotionModel, dt: float) -> bool:
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


def check_generator(rng: np.random.Generator | None) -> np.random.Generator:
    """``rng`` when it is a numpy Generator (these filters draw from one), else ConfigError."""
    if not isinstance(rng, np.random.Generator):
        raise ConfigError(invalid("rng", rng, "a numpy.random.Generator"))
    return rng


def log_transition(
    motion: MotionModel, x: Array, prev: Array, dt: float, pairing: str = "paired"
) -> Array:
    """``log p(x^i | x_{t-1}^i)`` (``"paired"``) or ``log (1/N) sum_j p(x^i | x_{t-1}^j)``
    (``"marginal"``; one O(N^2) Numba pass per run for a Gaussian transition)."""
    if pairing == "paired":
        return np.asarray(motion.log_density(x, prev, dt))
    if is_gaussian_transition(motion, dt):
        cov = np.asarray(motion.noise_cov(dt), float)
        m = np.asarray(motion.mean(prev, dt))
        xs, ms = x.reshape(-1, *x.shape[-2:]), m.reshape(-1, *m.shape[-2:])
        lse = [
            gaussian_mixture_ancestors(a, b, cov, np.zeros(len(b)), np.zeros(len(a)))[0]
            for a, b in zip(xs, ms)
        ]
        return np.asarray(np.reshape(lse, x.shape[:-1]) - np.log(prev.shape[-2]))
    lp = motion.log_density(x[..., :, None, :], prev[..., None, :, :], dt)
    return np.asarray(logsumexp(lp, axis=-1) - np.log(prev.shape[-2]))


def _no_estimate() -> Array:
    return np.zeros(0)


@dataclass(frozen=True, eq=False)
class SISBelief(Particles):
    """The :class:`~fusetrack.core.Particles` a filter with ``resample="every_update"`` carries.

    ``states`` ``(..., N, d)`` and ``log_weights`` (equal after an update: it resamples),
    ``estimate`` ``(..., d)`` (the mean of the resampled particles, or the weighted mean before
    resampling with ``estimate="weighted"``), ``proposal`` the proposal's own state (an EKF bank,
    the CPF-SP banks, the regimes; None for the transition prior). Between ``predict`` and
    ``update``, ``parents`` ``(..., N, d)`` holds the states each particle was drawn from and
    ``dt`` the step (the MCMC move needs them).
    """

    estimate: Array = field(default_factory=_no_estimate)
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
