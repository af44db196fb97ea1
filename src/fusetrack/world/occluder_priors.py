"""Gaussian priors of moving occluders from noisy "virtual" positions (Ercan et al. 2013, Sec. 6.1).

The paper obtains the priors ``N(mu_j(t), Sigma_j(t))`` with a Kalman filter per occluder fed with
virtual measurements ``y_j(t) = x_j(t) + psi_j(t)``, ``psi ~ N(0, sigma_psi^2 I)``, and measures
their accuracy as RMSE_occ. It does not give the filter's motion model; this one is a random walk
per coordinate (spec §8 item 3): ``Q = q I`` with ``q = 0.5 units^2`` (about ``s^2 / 2`` for a unit
speed in a random direction), ``R = sigma_psi^2 I``, started at the room centre with a large
variance. The filter is isotropic, so the priors have ``alpha_j = 1`` and Eq. 7 is exact up to the
rectangle shape. ``sigma_psi = 0`` gives perfect priors, ``sigma_psi = inf`` no information (the
prior stays at the centre; the tracker then uses the no-prior likelihood of Sec. 6.1 instead).

A random walk lags a walker that keeps its heading, so its priors claim less variance than their
error has (they are overconfident). :class:`ConstantVelocityPriorFilter` (the spec's alternative)
follows the heading. :func:`prior_track` also builds two *oracle* priors that use the truth and
exist only to find out why priors help or hurt the tracker: the random-walk priors with their
covariance scaled until squared error and claimed variance agree ("calibrated-random-walk"), and
priors whose errors are white in time with the random walk's accuracy ("white").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core import ConfigError, invalid
from ..motion import ConstantVelocity
from .geometry import Array
from .occlusion import OccluderPriors


def _outputs(truth: Array, sigma_psi: float) -> tuple[Array, Array]:
    """Arrays for a filter bank's means ``(T, M, 2)`` and variances ``(T,)``; filled with the
    truth and zero variance when ``sigma_psi = 0`` (perfect priors)."""
    means = np.empty_like(truth)
    var = np.empty(truth.shape[0])
    if sigma_psi == 0:
        means[:] = truth
        var[:] = 0.0
    return means, var


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
        means, var = _outputs(truth, self.sigma_psi)
        if self.sigma_psi == 0:
            return means, var
        steps, m = truth.shape[0], truth.shape[1]
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
        return OccluderPriors.isotropic(means, var)


@dataclass(frozen=True)
class ConstantVelocityPriorFilter:
    """A bank of isotropic constant-velocity Kalman filters, one per occluder (vectorised).

    State per coordinate ``[position, velocity]``; piecewise-constant white acceleration of variance
    ``q`` per step (:class:`~fusetrack.motion.ConstantVelocity`, ``noise="discrete"``),
    ``R = sigma_psi^2``; started at the room centre at rest
    with large variances. Same interface as :class:`RandomWalkPriorFilter`.
    """

    sigma_psi: float
    q: float = 0.03
    initial_var: float = 1e4
    initial_speed_var: float = 1.0

    def __post_init__(self) -> None:
        RandomWalkPriorFilter(self.sigma_psi, self.q)  # same checks

    def run(self, truth: Array, center: Array, rng: np.random.Generator) -> tuple[Array, Array]:
        """Means ``(T, M, 2)`` and scalar position variances ``(T,)`` (one per step, shared)."""
        means, var = _outputs(truth, self.sigma_psi)
        if self.sigma_psi == 0:
            return means, var
        steps, m = truth.shape[0], truth.shape[1]
        axis = ConstantVelocity(ndim=1, q=self.q, noise="discrete")
        F, Q = axis.transition_matrix(1.0), axis.noise_cov(1.0)
        pos = np.broadcast_to(np.asarray(center, float), (m, 2)).copy()
        vel = np.zeros((m, 2))
        P = np.diag([self.initial_var, self.initial_speed_var])
        r = self.sigma_psi**2
        for t in range(steps):
            pos = pos + vel
            P = F @ P @ F.T + Q
            if math.isfinite(r):
                y = truth[t] + self.sigma_psi * rng.standard_normal((m, 2))
                s = P[0, 0] + r
                k_pos, k_vel = P[0, 0] / s, P[1, 0] / s
                innov = y - pos
                pos = pos + k_pos * innov
                vel = vel + k_vel * innov
                P = P - np.outer([k_pos, k_vel], P[0])
            means[t] = pos
            var[t] = P[0, 0]
        return means, var


PRIOR_FILTERS = ("random-walk", "constant-velocity", "calibrated-random-walk", "white")
"""Kinds of :func:`prior_track`; the last two are oracles (they use the truth): diagnosis only."""


def prior_nees(means: Array, var: Array, truth: Array) -> float:
    """Squared error over the variance the priors claim, per coordinate (1 = calibrated)."""
    if truth.shape[1] == 0 or not np.all(var > 0):
        return float("nan")
    return float(np.mean(np.sum((means - truth) ** 2, axis=-1) / (2 * var[:, None])))


def prior_track(
    kind: str,
    sigma_psi: float,
    q: float,
    truth: Array,
    center: Array,
    rng: np.random.Generator,
    q_cv: float = 0.03,
) -> tuple[Array, Array]:
    """Occluder priors ``(means (T, M, 2), variances (T,))`` of one of :data:`PRIOR_FILTERS`.

    ``q``: the random walk's process noise, ``q_cv``: the constant-velocity filter's. The oracles
    start from the random walk's track (same virtual readings): "calibrated-random-walk" scales its
    variances by its own squared error / claimed variance; "white" replaces its errors by fresh
    ``N(0, s^2 I)`` draws each step with ``s`` its RMSE per coordinate, and claims ``s^2``.
    """
    if kind not in PRIOR_FILTERS:
        raise ConfigError(invalid("prior_filter", kind, f"one of {PRIOR_FILTERS}"))
    if kind == "constant-velocity":
        return ConstantVelocityPriorFilter(sigma_psi, q_cv).run(truth, center, rng)
    means, var = RandomWalkPriorFilter(sigma_psi, q).run(truth, center, rng)
    if kind == "random-walk" or sigma_psi == 0 or truth.shape[1] == 0:
        return means, var
    if kind == "calibrated-random-walk":
        return means, var * prior_nees(means, var, truth)
    s = rmse_per_coordinate(means, truth)
    return truth + s * rng.standard_normal(truth.shape), np.full(len(truth), s * s)


def rmse_per_coordinate(estimates: Array, truth: Array) -> float:
    """``sqrt(mean over everything of (estimate - truth)^2)``: the paper's RMSE (spec §8 item 1)."""
    e = np.asarray(estimates, float) - np.asarray(truth, float)
    return float(np.sqrt(np.mean(e * e))) if e.size else float("nan")
