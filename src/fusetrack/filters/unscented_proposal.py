"""Unscented-proposal particle filter (after van der Merwe et al. 2000), a "beyond the paper"
comparator for the Zhai 2007 proposals.

Each particle ``x_{t-1}^i`` is the mean of a Gaussian ``N(x_{t-1}^i, P)`` whose covariance ``P``
is the particle set's covariance after the previous step (shared by all particles: a common
simplification of the UPF, which carries one covariance per particle); one UKF predict + update
of that Gaussian with the step's measurements gives the particle's own proposal
``N(m_i, S_i)``. The proposal depends on the particle's own past, so the paired weight of Eq. 13,
``p(z | x) p(x | x_{t-1}^i) / N(x; m_i, S_i)``, is the right one.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..core import Gaussian, Measurement
from .kalman import UnscentedKalmanFilter
from .proposals import Array, Zs

_LOG_2PI = float(np.log(2 * np.pi))


@dataclass
class UnscentedProposal:
    """Per-particle UKF proposal; ``floor`` (relative) keeps the shared covariance positive."""

    floor: float = 1e-6

    def initialize(self, prior: Gaussian, particles: Array, rng: np.random.Generator) -> Array:
        return np.broadcast_to(
            np.asarray(prior.cov, float), (*particles.shape[:-2], *prior.cov.shape)
        ).copy()

    def draw(
        self, state: Array, prev: Array, zs: Zs, dt: float, rng: np.random.Generator, filt: Any
    ) -> tuple[Array, Array, Array]:
        ukf = getattr(self, "_ukf", None)
        if ukf is None or ukf.motion is not filt.motion:
            ukf = UnscentedKalmanFilter(filt.motion, filt.sensors)
            self._ukf = ukf
        n, d = prev.shape[-2], prev.shape[-1]
        cov = np.broadcast_to(state[..., None, :, :], (*prev.shape[:-1], d, d))
        belief = ukf.predict(Gaussian(prev, cov), dt)
        ms = [
            Measurement(0.0, s.sensor_id, np.atleast_1d(np.asarray(z, float)))
            for s, z in zip(filt.sensors, zs)
            if z is not None and np.all(np.isfinite(z)) and np.ndim(z) <= 1
        ]
        if ms:
            belief = ukf.update(belief, ms)
        m = np.asarray(belief.mean, float)
        S = np.asarray(belief.cov, float)
        S = 0.5 * (S + np.swapaxes(S, -1, -2))
        scale = np.maximum(np.trace(S, axis1=-2, axis2=-1) / d, 1e-300)
        S = S + (self.floor * scale)[..., None, None] * np.eye(d)
        L = np.linalg.cholesky(S)
        e = rng.standard_normal(m.shape)
        x = m + np.einsum("...ij,...j->...i", L, e)
        logdet = 2.0 * np.sum(np.log(np.diagonal(L, axis1=-2, axis2=-1)), axis=-1)
        log_q = -0.5 * (np.sum(e * e, axis=-1) + logdet + d * _LOG_2PI)
        del n
        return x, log_q, state

    def feedback(self, state: Array, particles: Array, estimate: Array, filt: Any) -> Array:
        dev = particles - estimate[..., None, :]
        cov = np.einsum("...ni,...nj->...ij", dev, dev) / max(particles.shape[-2] - 1, 1)
        q = np.asarray(filt.motion.noise_cov(1.0), float)
        return np.asarray(cov + self.floor * q)
