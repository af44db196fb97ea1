"""The shared scenario of ``pf_bearing.py``: one target, three bearing sensors, plain NumPy.

Nothing here imports fusetrack or a peer library, so every implementation in the benchmark
filters the very same truth and the very same measurements.

State ``[x, y, vx, vy]`` (fusetrack's layout: positions first, then velocities). Motion:
constant velocity driven by continuous white-noise acceleration of PSD ``q`` (m^2/s^3), i.e.
per axis ``Q = q [[dt^3/3, dt^2/2], [dt^2/2, dt]]`` (Bar-Shalom et al. 2001, Sec. 6.2.2).
Measurements: ``z_i = wrap(atan2(y - s_iy, x - s_ix) + v_i)``, ``v_i ~ N(0, sigma^2)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

DT = 1.0  # s between steps
Q_PSD = 0.05  # m^2/s^3, continuous white-noise acceleration
SIGMA_BEARING = 0.02  # rad (about 1.15 degrees)
SENSORS = np.array([[0.0, 0.0], [400.0, 0.0], [200.0, 350.0]])  # m, fixed and known
SENSOR_IDS = ("s0", "s1", "s2")
X0_TRUE = np.array([150.0, 100.0, 1.5, 1.0])  # m, m/s
PRIOR_STD = np.array([20.0, 20.0, 1.0, 1.0])  # m, m/s


def wrap(a: Array) -> Array:
    """Angles to [-pi, pi)."""
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def cv_matrices(dt: float = DT, q: float = Q_PSD) -> tuple[Array, Array]:
    """``F`` and ``Q`` of the 2-D constant-velocity model in the layout ``[x, y, vx, vy]``."""
    i2 = np.eye(2)
    F = np.block([[i2, dt * i2], [np.zeros((2, 2)), i2]])
    Q = q * np.block([[dt**3 / 3 * i2, dt**2 / 2 * i2], [dt**2 / 2 * i2, dt * i2]])
    return F, Q


@dataclass(frozen=True)
class Scenario:
    """Truth ``(steps + 1, 4)`` (row 0: time 0), bearings ``z`` ``(steps, 3)`` at times 1..steps."""

    steps: int
    dt: float
    q: float
    sigma: float
    sensors: Array  # (3, 2)
    sensor_ids: tuple[str, ...]
    prior_mean: Array  # (4,)
    prior_cov: Array  # (4, 4)
    truth: Array
    z: Array


def make_scenario(steps: int = 100, seed: int = 2024) -> Scenario:
    """Simulate the truth and the measurements once, from ``seed`` (the same for every library)."""
    rng = np.random.default_rng(seed)
    F, Q = cv_matrices(DT, Q_PSD)
    LQ = np.linalg.cholesky(Q)
    truth = np.empty((steps + 1, 4))
    truth[0] = X0_TRUE
    for k in range(1, steps + 1):
        truth[k] = F @ truth[k - 1] + LQ @ rng.standard_normal(4)
    d = truth[1:, None, :2] - SENSORS[None, :, :]
    z = wrap(
        np.arctan2(d[..., 1], d[..., 0])
        + SIGMA_BEARING * rng.standard_normal((steps, len(SENSORS)))
    )
    prior_cov = np.diag(PRIOR_STD**2)
    prior_mean = X0_TRUE + PRIOR_STD * rng.standard_normal(
        4
    )  # an honest prior: truth is a draw from it
    return Scenario(
        steps, DT, Q_PSD, SIGMA_BEARING, SENSORS.copy(), SENSOR_IDS, prior_mean, prior_cov, truth, z
    )


def position_rmse(estimates: Array, truth: Array) -> float:
    """``sqrt(mean_k |p_hat_k - p_k|^2)``; ``estimates`` and ``truth`` ``(K, 2)`` positions."""
    e = np.asarray(estimates, float) - np.asarray(truth, float)
    return float(np.sqrt(np.mean(np.sum(e * e, axis=-1))))


def with_sensors(base: Scenario, count: int) -> Scenario:
    """``base``'s truth and prior seen by ``count`` bearing sensors evenly on a circle of radius
    400 m around (200, 100) m, bearings drawn from seed ``count`` (the sensors sweep)."""
    ang = np.linspace(0.0, 2.0 * np.pi, count, endpoint=False)
    sensors = np.stack([200 + 400 * np.cos(ang), 100 + 400 * np.sin(ang)], axis=-1)
    d = base.truth[1:, None, :2] - sensors[None]
    rng = np.random.default_rng(count)
    z = wrap(np.arctan2(d[..., 1], d[..., 0]) + base.sigma * rng.standard_normal(d.shape[:2]))
    ids = tuple(f"s{i}" for i in range(count))
    return Scenario(
        base.steps, base.dt, base.q, base.sigma, sensors, ids,
        base.prior_mean, base.prior_cov, base.truth, z,
    )  # fmt: skip
