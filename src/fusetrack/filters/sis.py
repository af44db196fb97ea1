"""Sequential importance sampling with a pluggable proposal (Zhai 2007, Sec. 2.1-2.2, App. A).

:class:`ProposalParticleFilter` is a configuration of the one particle filter,
:class:`~fusetrack.filters.ParticleFilter` with ``resample="every_update"`` and
``estimate="resampled"``: one step is the thesis's loop, shared by every filter of the
dissertation (bootstrap, PF-SP-PEKF, Galerkin and grid proposals, MCMC moves):

1. draw ``x_t^i ~ q(x_t | x_{t-1}^i, z_t)`` from the proposal;
2. weight (Zhai 2007, Eq. 13) ``log w^i = log p(z_t | x_t^i) + log p(x_t^i | x_{t-1}^i) - log q(x_t^i)``
   (the previous weights are equal: every step resamples); with the transition prior as proposal
   the last two terms cancel and ``w^i = p(z_t | x_t^i)``;
3. normalise in the log domain, resample (systematic by default), optionally move each particle
   with an MCMC kernel that leaves ``p(z_t | x) p(x | x_{t-1}^{a_i})`` invariant (Algorithms 8-10);
4. output the mean of the resampled particles and hand it back to the proposal ("feedback").

The parts (proposals, moves, the belief :class:`SISBelief`, the step's context) are in
:mod:`.proposals`, and re-exported here. Shapes: particles ``(..., N, d)``; leading axes are
independent runs advanced together from one generator. A step's measurements are
:class:`~fusetrack.core.Measurement` values ``(m,)`` or ``(..., m)``, at most one per sensor;
values with NaN are skipped and counted.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Literal

import numpy as np  # noqa: F401  (doctest)

from ..core import ConfigError, Gaussian, Measurement, MotionModel, SensorModel, invalid  # noqa: F401
from .particle import ParticleFilter
from .proposals import (
    Array,
    LogLikelihood,
    Move,
    PriorProposal,
    Proposal,
    ProposalContext,
    SISBelief,
    SISStats,
    Zs,
    aligned_values,
    check_generator,
    is_gaussian_transition,
    sensor_measurements,
)

__all__ = [
    "Array",
    "LogLikelihood",
    "Move",
    "PriorProposal",
    "Proposal",
    "ProposalContext",
    "ProposalParticleFilter",
    "SISBelief",
    "SISStats",
    "Zs",
    "aligned_values",
    "check_generator",
    "is_gaussian_transition",
    "sensor_measurements",
]


class ProposalParticleFilter(ParticleFilter):
    """SIS with proposal ``proposal``, resampling every step, optional MCMC ``move``: the
    :class:`~fusetrack.filters.ParticleFilter` configured with ``resample="every_update"``,
    ``estimate="resampled"``, degenerate only where every weight vanished
    (``min_log_evidence=-inf``), over :class:`SISBelief`.

    ``step(belief, dt, measurements, rng)`` draws from the proposal with the measurements in view
    (the thesis's loop, module docstring); ``predict`` draws from the transition prior and
    ``update`` weights by the likelihood, resamples and moves: their composition is the
    bootstrap step (the proposal's state is carried through and fed back the particle
    estimate). Measurements name the filter's sensors; ``proposal.side_inputs`` lists other ids
    the proposal reads (e.g. CPF-SP's sensor weights). ``sensors`` is the list of sensor models.

    >>> from fusetrack.motion.benchmark import ScalarBenchmark
    >>> from fusetrack.sensors.power import Power
    >>> pf = ProposalParticleFilter(ScalarBenchmark(), [Power("z", 3)], n_particles=100)
    >>> rng = np.random.default_rng(0)
    >>> b = pf.initialize(Gaussian(np.zeros(1), np.eye(1)), rng)
    >>> b = pf.step(b, 1.0, [Measurement(1.0, "z", [8.0])], rng)
    >>> bool(abs(b.mean[0] - 2.0) < 0.2)
    True
    """

    stats: SISStats  # ParticleFilter keeps SISStats whenever it has a proposal
    sensors: list[SensorModel]  # type: ignore[assignment]  # the models, in order

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
        if isinstance(n_particles, bool) or int(n_particles) != n_particles or n_particles < 1:
            raise ConfigError(invalid("n_particles", n_particles, "an integer >= 1"))
        super().__init__(
            motion,
            sensors,
            int(n_particles),
            resampler,
            resample="every_update",
            proposal=proposal if proposal is not None else PriorProposal(),
            move=move,
            estimate="resampled",
            transition=transition,
        )
        self.sensors = list(self._by_id.values())

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}(proposal={type(self.proposal).__name__}, "
            f"n_particles={self.n_particles}, move={type(self.move).__name__ if self.move else None})"
        )
