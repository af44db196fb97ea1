"""Multi-model, multi-measurement particle filter for one object among several (Lee 2009, Sec. 3.2.1).

One filter per tracked object, ``L`` particles ``[x, y, vx, vy]``. Each step (Lee 2009,
Eqs. 3.3-3.11, Fig. 3-1):

1. every particle is propagated through each of the ``J`` models (constant velocity, clockwise
   and anticlockwise turns driven by a centripetal acceleration ``alpha``), giving ``J L``
   predicted particles;
2. every predicted particle is weighted against every one of the ``N`` *unlabelled* bearings of
   the step, ``w = exp(-wrap(z_i - h(x))^2 / (2 sigma^2))``, and the ``J L N`` weights are
   normalised jointly;
3. ``L`` particles are resampled (systematic) from the ``J L N`` weighted copies -- the same as
   resampling the ``J L`` predictions with weights summed over the bearings;
4. the estimate is the JPDA-style average. The printed chain (3.7)-(3.11) is not a convex
   combination (it uses jointly normalised weights inside per-bearing averages and shrinks the
   estimate towards the origin); the default ``estimator="consistent"`` is the convex version,
   ``x = sum_{i,m,l} w x``, with per-model means and probabilities ``mu_m`` for diagnostics;
   ``estimator="literal"`` keeps the printed chain.

With no bearing at a step the filter only predicts (equal weights over the ``J L`` predictions).
If every weight underflows the step is counted as degenerate and also only predicts; weights
are handled as logarithms, never NaN.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..core.angles import wrap_angle_inplace
from ..core.errors import ConfigError, MeasurementError, invalid
from ..core.resampling import inverse_cdf
from ..motion.accel_turn import AccelTurn

Array = np.ndarray

ESTIMATORS = ("consistent", "literal")


def resample_l(w: Array, n: int, rng: np.random.Generator) -> Array:
    """Systematic draw of ``n`` ancestors from the flattened ``(..., J, L)`` weights (Fig. 3-1:
    ``L`` of the ``J L N`` weighted copies); leading axes are independent filters."""
    flat = w.reshape(*w.shape[:-2], -1)
    u = (np.arange(n) + rng.random((*flat.shape[:-1], 1))) / n
    return inverse_cdf(flat, u)


def turn_models(alpha: float, sigma_a: float) -> tuple[AccelTurn, AccelTurn, AccelTurn]:
    """CV, CT (clockwise, ``omega = -alpha/speed``) and ACT (anticlockwise, ``+alpha/speed``), Eqs. 3.12-3.13.

    The text labels the ``+alpha`` model "clockwise"; with the standard turn matrix a positive
    rate turns anticlockwise, and the text's room scenario only stays in the room that way.
    """
    return (
        AccelTurn(2, (0.0, 0.0), None, 0.0, sigma_a),
        AccelTurn(2, (0.0, 0.0), (0, 1), -abs(alpha), sigma_a),
        AccelTurn(2, (0.0, 0.0), (0, 1), abs(alpha), sigma_a),
    )


@dataclass
class MultiModelStep:
    """A step's output: the estimate, the per-model predictions and diagnostics."""

    estimate: Array  # (4,)
    predictions: Array  # (J, L, 4) predicted particles per model (for the ellipse trigger)
    model_means: Array  # (J, 4) x_m
    model_probs: Array  # (J,) mu_m
    degenerate: bool


@dataclass
class MultiModelBearingPF:
    """Lee 2009's IMM-PF for one object, bearings from a sensor at ``sensor_position``."""

    models: tuple[AccelTurn, ...]
    sensor_position: tuple[float, float]
    sigma: float  # bearing noise std (rad)
    n_particles: int = 500
    estimator: str = "consistent"
    degenerate_steps: int = field(default=0, init=False)

    def __post_init__(self) -> None:
        if not self.models:
            raise ConfigError(invalid("models", self.models, "at least one motion model"))
        if not (self.sigma > 0 and math.isfinite(self.sigma)):
            raise ConfigError(invalid("sigma", self.sigma, "a bearing std > 0 (rad)"))
        if self.estimator not in ESTIMATORS:
            raise ConfigError(invalid("estimator", self.estimator, f"one of {ESTIMATORS}"))
        if self.n_particles < 1:
            raise ConfigError(invalid("n_particles", self.n_particles, "an integer >= 1"))

    def initialize(self, mean: Array, std: Array, rng: np.random.Generator) -> Array:
        return np.asarray(mean, float) + np.asarray(std, float) * rng.standard_normal(
            (self.n_particles, 4)
        )

    def bearing(self, x: Array) -> Array:
        s = self.sensor_position
        return np.arctan2(x[..., 1] - s[1], x[..., 0] - s[0])

    def step(
        self, particles: Array, bearings: Array, dt: float, rng: np.random.Generator
    ) -> tuple[Array, MultiModelStep]:
        """Predict with every model, weight against every bearing, resample ``L``; return the new particles."""
        z = np.asarray(bearings, dtype=float).reshape(-1)
        if not np.all(np.isfinite(z)):
            raise MeasurementError(invalid("bearings", z.tolist(), "finite angles (rad)"))
        pred = self._propagate(particles, dt, rng)  # (J, L, 4)  Eq. 3.3
        J, L = pred.shape[:2]
        degenerate = False
        if z.size:
            r = self.bearing(pred)[None] - z[:, None, None]  # (N, J, L)  Eqs. 3.4-3.5
            wrap_angle_inplace(r)
            logw = -0.5 * r * r / self.sigma**2
            top = float(logw.max())
            total = top + math.log(float(np.exp(logw - top).sum())) if np.isfinite(top) else -np.inf
            if np.isfinite(total):
                w = np.exp(logw - total)  # Eq. 3.6: joint normalisation over (i, m, l)
            else:
                degenerate = True
        if not z.size or degenerate:
            w = np.full((1, J, L), 1.0 / (J * L))
        self.degenerate_steps += degenerate
        w_ml = w.sum(axis=0)  # (J, L): weight of each prediction summed over bearings
        est, means, probs = self._estimate(pred, w, w_ml)
        new = pred.reshape(J * L, 4)[resample_l(w_ml, self.n_particles, rng)]
        return new, MultiModelStep(est, pred, means, probs, degenerate)

    def _propagate(self, particles: Array, dt: float, rng: np.random.Generator) -> Array:
        """Every particle through every model: ``(..., L, 4)`` -> ``(J, ..., L, 4)``.

        Fast path for the usual bank (2-D, no known acceleration, turns on axes (0, 1) or none):
        one vectorised coordinated-turn map with ``omega_j = alpha_j / speed`` (0 for CV),
        identical in law to calling each model's ``sample``.
        """
        fast = all(
            m.ndim == 2
            and not np.any(m.accel)
            and m.turn_axes in (None, (0, 1))
            and m.sigma_a == self.models[0].sigma_a
            for m in self.models
        )
        if not fast:
            return np.stack([m.sample(particles, dt, rng) for m in self.models])
        lead = particles.shape[:-1]
        alphas = np.array([m.turn_alpha if m.turn_axes else 0.0 for m in self.models])
        alphas = alphas.reshape(-1, *([1] * len(lead)))
        x, y, vx, vy = (particles[..., i] for i in range(4))
        speed = np.hypot(vx, vy)
        omega = np.where(speed > 1e-9, alphas / np.maximum(speed, 1e-9), 0.0)  # (J, L)
        wt = omega * dt
        small = np.abs(wt) < 1e-9
        safe = np.where(small, 1.0, omega)
        s_, c_ = np.sin(wt), np.cos(wt)
        a1 = np.where(small, dt, s_ / safe)  # sin(wT)/w
        a2 = np.where(small, 0.0, (1.0 - c_) / safe)  # (1 - cos wT)/w
        out = np.empty((len(self.models), *lead, 4))
        out[..., 0] = x + a1 * vx - a2 * vy
        out[..., 1] = y + a2 * vx + a1 * vy
        out[..., 2] = c_ * vx - s_ * vy
        out[..., 3] = s_ * vx + c_ * vy
        sa = self.models[0].sigma_a
        if sa > 0:
            eta = sa * rng.standard_normal((len(self.models), *lead, 2))
            out[..., :2] += 0.5 * dt * dt * eta
            out[..., 2:] += dt * eta
        return out

    def _estimate(self, pred: Array, w: Array, w_ml: Array) -> tuple[Array, Array, Array]:
        p_m = w_ml.sum(axis=1)  # (J,)
        if self.estimator == "consistent":
            safe = np.where(p_m > 0, p_m, 1.0)
            means = np.einsum("jl,jld->jd", w_ml, pred) / safe[:, None]
            return np.einsum("jl,jld->d", w_ml, pred), means, p_m
        # Literal chain (Eqs. 3.7-3.11) with the jointly normalised weights.
        xbar_mi = np.einsum("ijl,jld->ijd", w, pred)  # Eq. 3.7
        mu_mi = w.sum(axis=2) / np.maximum(w.sum(axis=(1, 2))[:, None], 1e-300)  # Eq. 3.9 (i, m)
        xbar_m = np.einsum("ijd,ij->jd", xbar_mi, mu_mi)  # Eq. 3.8
        mu_m = mu_mi.sum(axis=0) / max(mu_mi.sum(), 1e-300)  # Eq. 3.11
        return mu_m @ xbar_m, xbar_m, mu_m  # Eq. 3.10

    def reset_to_fix(
        self, particles: Array, position: Array, sigma_r: float, rng: np.random.Generator
    ) -> Array:
        """A camera fix: particles' positions redrawn around it, velocities kept (spec Sec. 5.3 choice)."""
        out = particles.copy()
        out[:, :2] = np.asarray(position, float) + sigma_r * rng.standard_normal((len(out), 2))
        return out
