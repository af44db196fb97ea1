"""A particle filter on angular detection functions: the grid-free back end (beyond Kushwaha 2010).

The grid SBE of Kushwaha 2010 evaluates each sensor's detection function on 2800 cells. Here the
same detection functions weight particles in a continuous state [x, y, vx, vy]: a particle's
weight is the product over sensors (Kushwaha 2010, Eq. 30) of the sensor's normalised detection
function at the particle's bearing -- :class:`~fusetrack.sensors.bearing_detection.DetectionFunctionSensor`,
the piecewise-linear beams of an acoustic node (Eq. 34) or the Gaussian mixture of a camera
(Eq. 35). Motion is any :mod:`fusetrack.motion` model (constant velocity by default) instead of
the grid's shift-and-box; resampling is systematic every step.

The filter is pure: the belief is a :class:`~fusetrack.core.beliefs.Particles` whose weights are
those of the last update (``info["resample"]``: resample before the next prediction, which is
where the systematic draw happens). A step whose weights all vanish keeps the predicted particles
with equal weights and is counted in ``stats.degenerate_steps``. The particle loop stays private
(not the shared engine) so that the published runs' random draws are unchanged.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import Measurement, MeasurementError, MotionModel, Particles, invalid, systematic
from ..sensors import DetectionFunctionSensor

Array = NDArray[np.float64]


@dataclass
class DetectionPFStats:
    """Diagnostic counters (not part of the belief)."""

    degenerate_steps: int = 0


def _normalised(log_w: Array) -> tuple[Array, float, float]:
    """Weights ``w / sum w``, ``max log w`` and ``sum exp(log w - max)``."""
    m = float(log_w.max())
    w = np.exp(log_w - m)
    total = float(w.sum())
    return w / total, m, total


@dataclass
class DetectionParticleFilter:
    """Bootstrap particle filter weighting by the detection functions of ``sensors`` (by id)."""

    motion: MotionModel
    sensors: Mapping[str, DetectionFunctionSensor]
    n_particles: int = 2000
    stats: DetectionPFStats = field(default_factory=DetectionPFStats)

    def initial_belief(
        self, positions: ArrayLike, velocity_std: float, rng: np.random.Generator
    ) -> Particles:
        """Particles at ``positions (N, 2)`` (e.g. drawn from a grid prior) with N(0, σ²) velocities."""
        pos = np.asarray(positions, float).reshape(-1, 2)
        vel = rng.normal(0.0, velocity_std, pos.shape)
        return Particles.uniform(np.concatenate([pos, vel], axis=1))

    def predict(
        self, belief: Particles, dt: float, rng: np.random.Generator | None = None
    ) -> Particles:
        """Resample the last update's weights (systematic), then move every particle by ``dt``."""
        gen = np.random.default_rng() if rng is None else rng
        x = belief.states
        if belief.info.get("resample"):
            w, _, _ = _normalised(belief.log_weights)
            x = x[systematic(w, gen)]
        return Particles.uniform(self.motion.sample(x, dt, gen))

    def update(
        self,
        belief: Particles,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> Particles:
        """Weight by the product of the reporting sensors' detection functions (Eq. 30)."""
        return self.update_with_likelihood(belief, measurements, rng)[0]

    def update_with_likelihood(
        self,
        belief: Particles,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> tuple[Particles, Array]:
        """:meth:`update` and ``log p(z_k | z_1:k-1)`` (the mean weight; NaN if degenerate)."""
        x = belief.states
        log_w = np.zeros(x.shape[0])
        for m in measurements:
            sensor = self.sensors.get(m.sensor_id)
            if sensor is None:
                raise MeasurementError(
                    invalid("sensor_id", m.sensor_id, f"one of {sorted(self.sensors)}")
                )
            log_w += sensor.log_likelihood(m.value, x)
        m_ = log_w.max()
        total = np.exp(log_w - m_).sum()
        if not np.isfinite(total) or total <= 0:
            self.stats.degenerate_steps += 1
            return Particles(x, np.zeros(x.shape[0]), {"resample": True}), np.array(np.nan)
        log_evidence = float(m_ + np.log(total / x.shape[0]))
        return Particles(x, log_w, {"resample": True}), np.array(log_evidence)


def position_estimate(belief: Particles) -> tuple[Array, Array]:
    """Weighted mean and covariance of the position ``(x, y)`` of a (weighted) particle belief."""
    x = belief.states
    w, _, _ = _normalised(belief.log_weights)
    mean = w @ x[:, :2]
    r = x[:, :2] - mean
    return mean, (r * w[:, None]).T @ r
