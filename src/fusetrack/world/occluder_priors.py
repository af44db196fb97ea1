"""Gaussian priors of moving occluders from noisy "virtual" positions (Ercan et al. 2013, Sec. 6.1).

The paper obtains the priors ``N(mu_j(t), Sigma_j(t))`` with a Kalman filter per occluder fed with
virtual measurements ``y_j(t) = x_j(t) + psi_j(t)``, ``psi ~ N(0, sigma_psi^2 I)``, and measures
their accuracy as RMSE_occ. It does not give the filter's motion model; this one is a random walk
per coordinate (spec §8 item 3): ``Q = q I`` with ``q = 0.5 units^2`` (about ``s^2 / 2`` for a unit
speed in a random direction), ``R = sigma_psi^2 I``, started at the room centre with a large
variance. The filter is isotropic, so the priors have ``alpha_j = 1`` and Eq. 7 is exact up to the
rectangle shape. ``sigma_psi = 0`` gives perfect priors, ``sigma_psi = inf`` no information (the
prior stays at the centre; the tracker then uses the no-prior likelihood of Sec. 6.1 instead).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.errors import ConfigError, invalid
from .geometry import Array
from .occlusion import OccluderPriors


@dataclass(frozen=True)
class RandomWalkPriorFilter:
    """A bank of isotropic random-walk Kalman filters, one per occluder (vectorised)."""

    sigma_psi: float
    q: float = 0.5
    initial_var: float = 1e4

    def __post_init__(self) -> None:
        if not (self.sigma_psi >= 0):
            raise ConfigError(
                invalid("sigma_psi", self.sigma_psi, "a number >= 0 (inf: no information)")
            )
        if not (self.q > 0 and math.isfinite(self.q)):
            raise ConfigError(invalid("q", self.q, "a finite number > 0"))

    def run(self, truth: Array, center: Array, rng: np.random.Generator) -> tuple[Array, Array]:
        """Means ``(T, M, 2)`` and scalar variances ``(T,)`` for occluder positions ``truth (T, M, 2)``.

        The covariance of every occluder at step t is ``var[t] * I`` (all filters start alike and
        see the same noise level, so they share it).
        """
        steps, m = truth.shape[0], truth.shape[1]
        means = np.empty_like(truth)
        var = np.empty(steps)
        if self.sigma_psi == 0:
            means[:] = truth
            var[:] = 0.0
            return means, var
        mu = np.broadcast_to(np.asarray(center, float), (m, 2)).copy()
        p = self.initial_var
        r = self.sigma_psi**2
        for t in range(steps):
            p = p + self.q
            if math.isfinite(r):
                y = truth[t] + self.sigma_psi * rng.standard_normal((m, 2))
                gain = p / (p + r)
                mu = mu + gain * (y - mu)
                p = (1 - gain) * p
            means[t] = mu
            var[t] = p
        return means, var

    @staticmethod
    def priors(means: Array, var: float) -> OccluderPriors:
        """The priors at one step as :class:`OccluderPriors`."""
        m = len(means)
        return OccluderPriors(means, np.broadcast_to(var * np.eye(2), (m, 2, 2)).copy())


def rmse_per_coordinate(estimates: Array, truth: Array) -> float:
    """``sqrt(mean over everything of (estimate - truth)^2)``: the paper's RMSE (spec §8 item 1)."""
    e = np.asarray(estimates, float) - np.asarray(truth, float)
    return float(np.sqrt(np.mean(e * e))) if e.size else float("nan")
