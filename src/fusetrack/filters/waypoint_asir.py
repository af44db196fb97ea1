"""The auxiliary SIR particle filter of Ercan et al. 2013, Algorithm 1 (with the spec's fixes).

One step, for particles ``u_l(t-1)`` with weights ``w_l(t-1)`` and a likelihood ``f(Z | u)``:

1. ``kappa_l = E[u(t) | u_l(t-1)]``; first-stage weights ``w_l(t-1) f(Z | kappa_l)``, normalised;
2. parents ``pi_l`` by systematic resampling of the first-stage weights;
3. ``u_l(t) ~ f(u | u_{pi_l}(t-1))`` (the waypoint-regime dynamics, Sec. 4.1);
4. second-stage weights ``f(Z | u_l(t)) / f(Z | kappa_{pi_l})``, normalised.

Algorithm 1 prints ``f(Z | kappa_l)`` in step 4; the parent's point ``kappa_{pi_l}`` is right
(standard ASIR, Pitt & Shephard 1999; spec §8 item 5). The likelihood can vanish for every particle
(hard consistency constraints); then the first stage is skipped (weights ``w(t-1)``). If the
second stage vanishes too, the spec (§8 item 7) draws the particles afresh over the room; that
throws away a cloud that is usually only slightly off (a narrow occluder shadow no particle fell
in), so here the step's readings are ignored instead (predicted particles, equal weights), and
the cloud is drawn afresh only after ``patience`` such steps in a row. All three events are
counted in :class:`ASIRStats`; weights never become NaN.

The filter is pure: everything carried between steps (particles, weights, the count of
consecutive ignored steps) is an :class:`ASIRBelief`. It is a
:class:`~fusetrack.core.SteppingFilter`: the first stage looks at ``Z(t)``, so :meth:`WaypointASIR.step`
is Algorithm 1, and ``update(predict(...))`` is the plain SIR step with the same target. The
likelihood ``f(Z | u)`` is a sensor component (``log_likelihood(value, positions)``) that reads each
:class:`~fusetrack.core.Measurement` value; for Ercan et al. the value carries the step's readings,
selected cameras and occluder priors
(:class:`~fusetrack.sensors.occlusion_aware_camera.OcclusionAwareCameraSensor`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from ..core import ConfigError, Measurement, UnknownSensorError, check_positive, invalid
from ..motion import WaypointRegimeDynamics
from ..world import Room
from .weighting import draw_ancestors, particle_weights

Array = NDArray[np.float64]
LogLikelihood = Callable[[Array], Array]


class PositionLikelihood(Protocol):
    """A sensor model that scores particle positions ``(L, 2)`` against one report's value."""

    @property
    def sensor_id(self) -> str: ...

    def log_likelihood(self, z: Any, x: Array) -> Array: ...


@dataclass
class ASIRStats:
    """Diagnostic counters of one filter's life (not part of the belief)."""

    steps: int = 0
    first_stage_fallbacks: int = 0
    ignored_steps: int = 0
    reinitialisations: int = 0

    def as_dict(self) -> dict[str, int]:
        """The counters as a plain dict (a snapshot, as :func:`~fusetrack.filters.run_filter` reads)."""
        return asdict(self)


@dataclass(frozen=True, eq=False)
class ASIRBelief:
    """Particles ``(L, 5)`` ``[x, y, tau_x, tau_y, s]``, normalised weights ``(L,)`` and the
    number of consecutive steps whose readings were ignored (all weights vanished)."""

    particles: Array
    weights: Array
    ignored: int = 0

    @property
    def mean(self) -> Array:
        return np.asarray(self.weights @ self.particles)

    @property
    def position(self) -> Array:
        """The position estimate ``x_hat = sum_l w_l x_l`` (Algorithm 3)."""
        return np.asarray(self.weights @ self.particles[:, :2])

    @property
    def cov(self) -> Array:
        r = self.particles - self.mean
        return np.asarray((r * self.weights[:, None]).T @ r)


@dataclass
class WaypointASIR:
    """ASIR on the waypoint-regime state ``[x, y, tau_x, tau_y, s]`` in a room: a
    :class:`~fusetrack.core.SteppingFilter` over :class:`ASIRBelief`.

    ``sensors`` score positions against the values of the measurements naming them; a step's
    ``f(Z | u)`` is the product over its measurements. The dynamics advance one step of the
    paper's fixed period per call, so ``dt`` only says whether to predict (``dt > 0``).
    """

    room: Room
    dynamics: WaypointRegimeDynamics = field(default_factory=WaypointRegimeDynamics)
    n_particles: int = 1000
    initial_speed: float = 1.0
    patience: int = 5
    sensors: Sequence[PositionLikelihood] = ()
    stats: ASIRStats = field(default_factory=ASIRStats)

    def __post_init__(self) -> None:
        self.n_particles = int(check_positive("n_particles", self.n_particles))
        check_positive("initial_speed", self.initial_speed)

    def _sample_free(self, rng: np.random.Generator, n: int) -> Array:
        return self.room.sample_free(rng, n)

    def initialize(self, rng: np.random.Generator) -> ASIRBelief:
        """Particles uniform over the free floor, equal weights (Sec. 6.1)."""
        u = self.dynamics.initial(self.n_particles, rng, self._sample_free, self.initial_speed)
        return ASIRBelief(u, np.full(self.n_particles, 1.0 / self.n_particles))

    def propagate(self, u: Array, rng: np.random.Generator) -> Array:
        """``u(t) ~ f(u | u(t-1))``: also the predicted cloud the camera selection uses (Alg. 3)."""
        return self.dynamics.sample(u, rng, self._sample_free, self.room.free)

    def likelihood_of(self, measurements: Sequence[Measurement]) -> LogLikelihood:
        """``log f(Z | u)`` of the step's measurements as a function of positions ``(L, 2)``."""
        by_id = {s.sensor_id: s for s in self.sensors}
        pairs = []
        for m in measurements:
            if m.sensor_id not in by_id:
                raise UnknownSensorError(
                    invalid("sensor_id", m.sensor_id, f"one of {sorted(by_id)}")
                )
            pairs.append((by_id[m.sensor_id], m.value))

        def log_f(x: Array) -> Array:
            total = pairs[0][0].log_likelihood(pairs[0][1], x)
            for sensor, value in pairs[1:]:
                total = total + sensor.log_likelihood(value, x)
            return total

        return log_f

    def predict(
        self, belief: ASIRBelief, dt: float, rng: np.random.Generator | None = None
    ) -> ASIRBelief:
        """Every particle moved by the waypoint-regime dynamics (Sec. 4.1); weights kept."""
        if dt <= 0:
            return belief
        u = self.propagate(belief.particles, _require(rng))
        return ASIRBelief(u, belief.weights, belief.ignored)

    def update(
        self,
        belief: ASIRBelief,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> ASIRBelief:
        """Weights times ``f(Z | u)`` (Eq. 6), normalised; readings ignored if all vanish."""
        if not measurements:
            return belief
        self.stats.steps += 1
        with np.errstate(divide="ignore"):
            log_w = np.log(belief.weights) + self.likelihood_of(measurements)(
                belief.particles[:, :2]
            )
        if not np.any(np.isfinite(log_w)):
            return self._ignore(belief, rng, belief.particles)
        return ASIRBelief(belief.particles, _weights_of(log_w))

    def step(
        self,
        belief: ASIRBelief,
        dt: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> ASIRBelief:
        """One ASIR step (Algorithm 1) with ``f(Z | u)`` from the step's measurements."""
        rng = _require(rng)
        if not measurements:
            return self.predict(belief, dt, rng)
        log_likelihood = self.likelihood_of(measurements)
        u, w = belief.particles, belief.weights
        self.stats.steps += 1
        kappa = self.dynamics.mean(u)
        log_l1 = log_likelihood(kappa[:, :2])
        with np.errstate(divide="ignore"):
            log_first = np.log(w) + log_l1
        if not np.any(np.isfinite(log_first)):
            self.stats.first_stage_fallbacks += 1
            log_first = np.log(np.maximum(w, 1e-300))
            log_l1 = np.zeros_like(log_l1)
        parents = draw_ancestors(particle_weights(log_first), rng)
        new = self.propagate(u.take(parents, axis=0), rng)  # the rows u[parents], 4x faster
        log_l2 = log_likelihood(new[:, :2])
        denom = log_l1[parents]
        log_w2 = log_l2 - np.where(np.isfinite(denom), denom, 0.0)
        if not np.any(np.isfinite(log_w2)):
            return self._ignore(belief, rng)
        return ASIRBelief(new, _weights_of(log_w2))

    def _ignore(
        self, belief: ASIRBelief, rng: np.random.Generator | None, predicted: Array | None = None
    ) -> ASIRBelief:
        """Every weight vanished: the step's readings are ignored (the ``predicted`` particles,
        drawn here when not given, with the old weights), or after ``patience`` such steps in a
        row the cloud starts over uniform over the room."""
        self.stats.ignored_steps += 1
        if belief.ignored + 1 >= self.patience:
            self.stats.reinitialisations += 1
            return self.initialize(_require(rng))
        u = self.propagate(belief.particles, _require(rng)) if predicted is None else predicted
        return ASIRBelief(u, belief.weights, belief.ignored + 1)


def _require(rng: np.random.Generator | None) -> np.random.Generator:
    if rng is None:
        raise ConfigError(invalid("rng", rng, "a numpy Generator (the ASIR draws particles)"))
    return rng


def _weights_of(log_w: Array) -> Array:
    """Normalised weights of ``log_w`` (the shared :func:`~.weighting.particle_weights`)."""
    return particle_weights(log_w).weights
