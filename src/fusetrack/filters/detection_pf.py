"""A particle filter on angular detection functions: the grid-free back end (beyond Kushwaha 2010).

The grid SBE of Kushwaha 2010 evaluates each sensor's detection function on 2800 cells. Here the
same detection functions weight particles in a continuous state [x, y, vx, vy]: a particle's
weight is the product over sensors (Kushwaha 2010, Eq. 30) of the sensor's normalised detection
function at the particle's bearing, ``λ̃_k(θ_k(x))`` — the piecewise-linear beams of an acoustic
node (Eq. 34) or the Gaussian mixture of a camera (Eq. 35), a neutral constant outside a camera's
field of view. Motion is any :mod:`fusetrack.motion` model (constant velocity by default) instead
of the grid's shift-and-box; resampling is systematic every step.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core.models import MotionModel
from ..core.resampling import systematic
from ..sensors.detection_function import AngularSampling, interpolate


@dataclass(frozen=True)
class BearingDetection:
    """One sensor's report at a step: its pose and a detection function over its own bearings.

    Either ``sampling``/``values`` (beams, interpolated) or ``mixture`` = (weights, means, sigmas)
    for a camera with field of view ``fov`` (bearings outside it get the neutral value)."""

    position: tuple[float, float]
    heading: float
    sampling: AngularSampling | None = None
    values: NDArray[np.float64] | None = None
    mixture: tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]] | None = None
    fov: float = 2 * np.pi
    floor: float = 1e-3

    def likelihood(self, xy: ArrayLike) -> NDArray[np.float64]:
        p = np.asarray(xy, float)
        theta = (
            np.arctan2(p[..., 1] - self.position[1], p[..., 0] - self.position[0]) - self.heading
        )
        theta = np.mod(theta + np.pi, 2 * np.pi) - np.pi
        if self.mixture is not None:
            a, mu, sd = self.mixture
            z = (theta[..., None] - mu) / sd
            dens = (a * np.exp(-0.5 * z * z) / (np.sqrt(2 * np.pi) * sd)).sum(-1)
            neutral = 1.0 / self.fov
            dens = np.where(np.abs(theta) <= self.fov / 2, dens, neutral)
            return dens + self.floor * neutral
        assert self.sampling is not None and self.values is not None
        v = np.asarray(self.values, float)
        v = v - v.min()
        total = v.sum()
        if not total > 0:
            return np.ones(theta.shape)
        density = v / (total * self.sampling.step)  # a density over the sensor's bearings
        return interpolate(self.sampling, density, theta) + self.floor / (2 * np.pi)


@dataclass
class DetectionParticleFilter:
    """Bootstrap particle filter whose likelihood is a product of :class:`BearingDetection` s."""

    motion: MotionModel
    n_particles: int = 2000
    particles: NDArray[np.float64] | None = None
    log_evidence: list[float] = field(default_factory=list)
    degenerate_steps: int = 0

    def initialize(
        self, positions: ArrayLike, velocity_std: float, rng: np.random.Generator
    ) -> None:
        """Particles at ``positions (N, 2)`` (e.g. drawn from a grid prior) with N(0, σ²) velocities."""
        pos = np.asarray(positions, float).reshape(-1, 2)
        vel = rng.normal(0.0, velocity_std, pos.shape)
        self.particles = np.concatenate([pos, vel], axis=1)

    def step(
        self, dt: float, detections: Sequence[BearingDetection], rng: np.random.Generator
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Predict by ``dt``, weight by the detections, resample; returns the position mean and covariance."""
        if self.particles is None:
            raise RuntimeError("call initialize() first")
        x = self.motion.sample(self.particles, dt, rng)
        logw = np.zeros(x.shape[0])
        for det in detections:
            logw += np.log(np.maximum(det.likelihood(x[:, :2]), 1e-300))
        m = logw.max()
        w = np.exp(logw - m)
        total = w.sum()
        if not np.isfinite(total) or total <= 0:
            self.degenerate_steps += 1
            w = np.full(x.shape[0], 1.0 / x.shape[0])
        else:
            self.log_evidence.append(float(m + np.log(total / x.shape[0])))
            w = w / total
        mean = w @ x[:, :2]
        r = x[:, :2] - mean
        cov = (r * w[:, None]).T @ r
        self.particles = x[systematic(w, rng)]
        return mean, cov
