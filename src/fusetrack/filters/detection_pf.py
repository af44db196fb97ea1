"""A particle filter on angular detection functions: the grid-free back end (beyond Kushwaha 2010).

The grid SBE of Kushwaha 2010 evaluates each sensor's detection function on 2800 cells. Here the
same detection functions weight particles in a continuous state [x, y, vx, vy]: a particle's
weight is the product over sensors (Kushwaha 2010, Eq. 30) of the sensor's normalised detection
function at the particle's bearing -- :class:`~fusetrack.sensors.DetectionFunctionSensor`, the
piecewise-linear beams of an acoustic node (Eq. 34) or the Gaussian mixture of a camera
(Eq. 35). Motion is any :mod:`fusetrack.motion` model (constant velocity by default) instead of
the grid's shift-and-box.

It is the shared particle engine (:class:`~.particle.ParticleFilter`) with the detection
functions as likelihood-only sensors and systematic resampling before every prediction
(``ess_threshold=1``); the belief is a :class:`~fusetrack.core.Particles` whose weights are
those of the last update.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import MotionModel, Particles
from ..sensors import DetectionFunctionSensor
from .particle import ParticleFilter
from .weighting import particle_weights

Array = NDArray[np.float64]


class DetectionParticleFilter(ParticleFilter):
    """Bootstrap particle filter weighting by the detection functions of ``sensors`` (by id),
    resampling (systematic) before every prediction."""

    def __init__(
        self,
        motion: MotionModel,
        sensors: Mapping[str, DetectionFunctionSensor],
        n_particles: int = 2000,
    ) -> None:
        super().__init__(motion, dict(sensors), n_particles, ess_threshold=1.0)  # type: ignore[arg-type]

    def initial_belief(
        self, positions: ArrayLike, velocity_std: float, rng: np.random.Generator
    ) -> Particles:
        """Particles at ``positions (N, 2)`` (e.g. drawn from a grid prior) with N(0, σ²)
        velocities, equally weighted (not resampled before the first prediction)."""
        pos = np.asarray(positions, float).reshape(-1, 2)
        vel = rng.normal(0.0, velocity_std, pos.shape)
        states = np.concatenate([pos, vel], axis=1)
        return self._particles(states, self._uniform(1, states.shape[0]))


def position_estimate(belief: Particles) -> tuple[Array, Array]:
    """Weighted mean and covariance of the position ``(x, y)`` of a (weighted) particle belief."""
    x = belief.states
    w = particle_weights(belief.log_weights).weights
    mean = w @ x[:, :2]
    r = x[:, :2] - mean
    return mean, (r * w[:, None]).T @ r
