"""The test model of tests/estimation: a scalar AR(1) state seen in Gaussian noise,

``x_0 ~ N(0, q / (1 - rho^2))``, ``x_t = rho x_{t-1} + N(0, q)``, ``y_t = x_t + N(0, r)``,

with ``theta = (log q, log r)``; its likelihood is exact under the Kalman filter."""

from __future__ import annotations

import math

import numpy as np

from fusetrack.core import Gaussian, Measurement
from fusetrack.filters import BootstrapFilter, KalmanFilter
from fusetrack.motion import LinearGaussianMotion
from fusetrack.sensors import LinearGaussianSensor

RHO = 0.9
Q, R = 1.0, 0.5
THETA = np.log([Q, R])


def simulate(T: int, seed: int, q: float = Q, r: float = R) -> list[Measurement]:
    rng = np.random.default_rng(seed)
    x = rng.normal() * math.sqrt(q / (1 - RHO**2))
    out = []
    for t in range(T):
        if t:
            x = RHO * x + math.sqrt(q) * rng.normal()
        out.append(Measurement(float(t), "y", [x + math.sqrt(r) * rng.normal()]))
    return out


def parts(theta: np.ndarray) -> tuple[LinearGaussianMotion, LinearGaussianSensor, Gaussian]:
    q, r = np.exp(theta)
    return (
        LinearGaussianMotion(F=[[RHO]], Q=[[q]]),
        LinearGaussianSensor("y", H=[[1.0]], R=[[r]]),
        Gaussian(np.zeros(1), np.array([[q / (1 - RHO**2)]])),
    )


def kalman_model(theta: np.ndarray) -> tuple[KalmanFilter, Gaussian]:
    motion, sensor, prior = parts(theta)
    return KalmanFilter(motion, [sensor]), prior


def particle_model(n: int):  # type: ignore[no-untyped-def]
    def model(theta: np.ndarray) -> tuple[BootstrapFilter, Gaussian]:
        motion, sensor, prior = parts(theta)
        return BootstrapFilter(motion, [sensor], n_particles=n), prior

    return model


def log_prior(theta: np.ndarray) -> float:
    """Independent ``N(0, 2^2)`` on ``log q`` and ``log r``."""
    return float(-0.125 * np.sum(np.asarray(theta) ** 2))
