"""Multi-model, multi-measurement particle filter for one object among several (Lee 2009, Sec. 3.2.1).

One filter per tracked object, ``L`` particles ``[x, y, vx, vy]`` in a :class:`MultiModelBelief`.
A step (Lee 2009, Eqs. 3.3-3.11, Fig. 3-1) is :meth:`MultiModelBearingPF.predict` then
:meth:`MultiModelBearingPF.update`:

1. every particle is propagated through each of the ``J`` models (constant velocity, clockwise
   and anticlockwise turns driven by a centripetal acceleration ``alpha``), giving ``J L``
   predicted particles;
2. every predicted particle is weighted against every one of the ``N`` *unlabelled* bearings of
   the step (one :class:`~fusetrack.core.Measurement` each),
   ``w = exp(-wrap(z_i - h(x))^2 / (2 sigma^2))``, and the ``J L N`` weights are normalised jointly;
3. ``L`` particles are resampled (systematic) from the ``J L N`` weighted copies -- the same as
   resampling the ``J L`` predictions with weights summed over the bearings;
4. the estimate is the JPDA-style average. The printed chain (3.7)-(3.11) is not a convex
   combination (it uses jointly normalised weights inside per-bearing averages and shrinks the
   estimate towards the origin); the default ``estimator="consistent"`` is the convex version,
   ``x = sum_{i,m,l} w x``, with per-model means and probabilities ``mu_m`` for diagnostics;
   ``estimator="literal"`` keeps the printed chain.

With no bearing at a step the filter only predicts (equal weights over the ``J L`` predictions).
If every weight underflows the step is marked degenerate and also only predicts; weights are
handled as logarithms, never NaN. :meth:`MultiModelBearingPF.step` fuses the two halves in one
Numba kernel (:mod:`.multi_model_kernel`) for the usual bank, with the same random draws.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..core import (
    ConfigError,
    Measurement,
    MeasurementError,
    invalid,
    inverse_cdf,
    wrap_angle_inplace,
)
from ..motion import AccelTurn
from .multi_model_kernel import gather_particles, kernel_bank, predict_weigh_kernel

Array = np.ndarray

ESTIMATORS = ("consistent", "literal")
MULTI_MODEL_ESTIMATORS = ESTIMATORS  # the public name (fusetrack.filters)
ENGINES = ("numba", "numpy")


def resample_l(w: Array, n: int, rng: np.random.Generator) -> Array:
    """Systematic draw of ``n`` ancestors from the flattened ``(..., J, L)`` weights (Fig. 3-1:
    ``L`` of the ``J L N`` weighted copies); leading axes are independent filters."""
    flat = w.reshape(*w.shape[:-2], -1)
    u = (np.arange(n) + rng.random((*flat.shape[:-1], 1))) / n
    return inverse_cdf(flat, u)


def take_resampled(pred: Array, idx: Array) -> Array:
    """The resampled particles of a batch: ``pred (B, O, J, L, 4)`` and ancestors ``idx (B, O, M)``
    into the flattened ``J L`` predictions -> ``(B, O, M, 4)`` (what
    ``np.take_along_axis(pred.reshape(B, O, -1, 4), idx[..., None], axis=2)`` gives)."""
    return gather_particles(np.ascontiguousarray(pred), np.ascontiguousarray(idx))


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


@dataclass(frozen=True)
class MultiModelBelief:
    """Particles ``states (M, 4)`` with the index of the model that last moved each one
    (``model (M,)``, -1 before the first prediction) and ``log_weights (M,)``.

    After :meth:`~MultiModelBearingPF.predict` ``M = J L`` (model-major); after an update
    ``M = L``, equally weighted, and the step's outputs ride along: ``estimate (4,)`` (Eq. 3.10),
    ``predictions (J, L, 4)`` (for the ellipse trigger, Eq. 3.16), ``model_means (J, 4)``,
    ``model_probs (J,)`` and whether the weights were ``degenerate``.
    """

    states: Array
    model: Array
    log_weights: Array
    estimate: Array | None = None
    predictions: Array | None = None
    model_means: Array | None = None
    model_probs: Array | None = None
    degenerate: bool = False

    @classmethod
    def uniform(cls, states: Array) -> MultiModelBelief:
        """Equally weighted particles not yet moved by any model."""
        n = len(states)
        return cls(states, np.full(n, -1), np.full(n, -math.log(n)))

    @property
    def uniform_weights(self) -> bool:
        lw = self.log_weights  # np.ptp(lw) == 0, without its wrapper
        return bool(lw.max() - lw.min() == 0)

    def weights(self) -> Array:
        w = np.exp(self.log_weights - self.log_weights.max())
        return w / w.sum()

    @property
    def mean(self) -> Array:
        """The step's estimate, or the particles' weighted mean before any update."""
        return self.estimate if self.estimate is not None else self.weights() @ self.states

    @property
    def cov(self) -> Array:
        d = self.states - self.weights() @ self.states
        return np.einsum("n,ni,nj->ij", self.weights(), d, d)


def reset_to_fix(
    belief: MultiModelBelief, position: Array, sigma_r: float, rng: np.random.Generator
) -> MultiModelBelief:
    """A camera fix: particles' positions redrawn around it, velocities kept (spec Sec. 5.3
    choice); the fix (with the old velocity estimate) becomes the estimate."""
    states = belief.states.copy()
    states[:, :2] = np.asarray(position, float) + sigma_r * rng.standard_normal((len(states), 2))
    estimate = np.concatenate([np.asarray(position, float), belief.mean[2:]])
    return MultiModelBelief(states, belief.model, belief.log_weights, estimate)


def bearings_of(measurements: Sequence[Measurement]) -> Array:
    """The step's unlabelled bearings (rad), in order; each measurement carries one or more."""
    if not measurements:
        return np.empty(0)
    return finite_bearings(
        np.concatenate([np.ravel(np.asarray(m.value, dtype=float)) for m in measurements])
    )


def finite_bearings(z: Array) -> Array:
    """``z`` as a flat float array of bearings (rad), or :class:`MeasurementError` unless every
    one is finite (what :meth:`MultiModelBearingPF.step_bearings` expects)."""
    z = np.asarray(z, dtype=float).reshape(-1)
    if not np.all(np.isfinite(z)):
        raise MeasurementError(invalid("bearings", z.tolist(), "finite angles (rad)"))
    return z


def weigh_every_model(
    filt: MultiModelBearingPF, parts: Array, z: Array, dt: float, rng: np.random.Generator
) -> tuple[Array, Array, Array, int]:
    """Predict through every model and weigh against every bearing, for ``B x O`` independent
    filters at once (Eqs. 3.3-3.6, the consistent estimator): ``parts (B, O, L, 4)`` equally
    weighted, ``z (B, nz)`` each run's bearings. Returns the predictions ``(B, O, J, L, 4)``,
    their normalised weights summed over the bearings ``(B, O, J, L)``, the estimates
    ``(B, O, 4)`` and the number of degenerate filters (weights kept equal). Engine "numba"
    fuses it all in one kernel when it implements the bank; "numpy" is the reference (same
    draws, results equal to rounding)."""
    B, O, L = parts.shape[:3]
    J = len(filt.models)
    alphas = filt.bank
    if filt.engine == "numba" and alphas is not None:
        sigma_a = float(filt.models[0].sigma_a)
        shape = (J, B, O, L, 2)  # the draw of propagate_every_model, scaled by sigma_a inside
        eta = rng.standard_normal(shape) if sigma_a > 0 else np.zeros(shape)
        pred = np.empty((B, O, J, L, 4))
        w_ml = np.empty((B, O, J, L))
        est = np.empty((B, O, 4))
        degenerate = predict_weigh_kernel(
            parts, eta, sigma_a, alphas, dt, filt.sensor_array, z,
            1.0 / filt.sigma**2, pred, w_ml, est,
        )  # fmt: skip
        return pred, w_ml, est, int(degenerate)
    pred = np.moveaxis(filt.propagate_every_model(parts, dt, rng), 0, 2)  # (B, O, J, L, 4)
    r = filt.bearing(pred)[..., None] - z[:, None, None, None, :]  # Eqs. 3.4-3.5
    wrap_angle_inplace(r)
    logw = -0.5 * (1.0 / filt.sigma**2) * r * r
    top = logw.max(axis=(2, 3, 4), keepdims=True)
    w_ml = np.exp(logw - top).sum(axis=-1)  # Eq. 3.6, summed over the bearings
    total = w_ml.sum(axis=(2, 3), keepdims=True)
    bad = ~(np.isfinite(top[..., 0]) & (total > 0))
    w_ml = np.where(bad, 1.0, w_ml) / np.where(bad, J * L, total)
    est = np.einsum("bojl,bojld->bod", w_ml, pred)  # consistent estimator
    return pred, w_ml, est, int(bad.sum())


@dataclass(frozen=True)
class MultiModelBearingPF:
    """Lee 2009's IMM-PF for one object, bearings from a sensor at ``sensor_position``.

    ``engine`` "numba": :meth:`step` runs the fused kernel when it implements the bank, "numpy":
    always ``update(predict(...))`` (same draws, results equal to rounding).
    """

    models: tuple[AccelTurn, ...]
    sensor_position: tuple[float, float]
    sigma: float  # bearing noise std (rad)
    n_particles: int = 500
    estimator: str = "consistent"
    engine: str = "numba"

    def __post_init__(self) -> None:
        if not self.models:
            raise ConfigError(invalid("models", self.models, "at least one motion model"))
        if not (self.sigma > 0 and math.isfinite(self.sigma)):
            raise ConfigError(invalid("sigma", self.sigma, "a bearing std > 0 (rad)"))
        if self.estimator not in ESTIMATORS:
            raise ConfigError(invalid("estimator", self.estimator, f"one of {ESTIMATORS}"))
        if self.n_particles < 1:
            raise ConfigError(invalid("n_particles", self.n_particles, "an integer >= 1"))
        if self.engine not in ENGINES:
            raise ConfigError(invalid("engine", self.engine, f"one of {ENGINES}"))

    @cached_property
    def bank(self) -> Array | None:
        """The models' turn accelerations when the fused kernel implements the bank, else None
        (:func:`~.multi_model_kernel.kernel_bank`, computed once per filter; read-only)."""
        alphas = kernel_bank(self.models)
        if alphas is not None:
            alphas.flags.writeable = False
        return alphas

    @cached_property
    def sensor_array(self) -> Array:
        """``sensor_position`` as a read-only float array (the kernel's argument)."""
        s = np.asarray(self.sensor_position, float)
        s.flags.writeable = False
        return s

    def initial_belief(self, mean: Array, std: Array, rng: np.random.Generator) -> MultiModelBelief:
        """``n_particles`` draws from ``N(mean, diag(std^2))``."""
        draws = np.asarray(mean, float) + np.asarray(std, float) * rng.standard_normal(
            (self.n_particles, 4)
        )
        return MultiModelBelief.uniform(draws)

    def bearing(self, x: Array) -> Array:
        s = self.sensor_position
        return np.arctan2(x[..., 1] - s[1], x[..., 0] - s[0])

    def predict(
        self, belief: MultiModelBelief, dt: float, rng: np.random.Generator | None = None
    ) -> MultiModelBelief:
        """Every particle through every model (Eq. 3.3): ``M`` particles become ``J M``."""
        rng = rng if rng is not None else np.random.default_rng()
        pred = self.propagate_every_model(belief.states, dt, rng)  # (J, M, 4)
        J, M = pred.shape[:2]
        return MultiModelBelief(
            pred.reshape(J * M, 4), np.repeat(np.arange(J), M), np.tile(belief.log_weights, J)
        )

    def update(
        self,
        belief: MultiModelBelief,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> MultiModelBelief:
        """Weight every prediction against every bearing (Eqs. 3.4-3.6), estimate (Eqs.
        3.7-3.11) and resample ``L`` (Fig. 3-1)."""
        return self.update_bearings(belief, bearings_of(measurements), rng)

    def update_bearings(
        self, belief: MultiModelBelief, z: Array, rng: np.random.Generator | None = None
    ) -> MultiModelBelief:
        """:meth:`update` with the step's bearings ``z`` (rad, finite) as one array."""
        rng = rng if rng is not None else np.random.default_rng()
        J = len(self.models)
        pred = belief.states.reshape(J, -1, 4)
        w, degenerate = self._joint_weights(pred, z)
        if not belief.uniform_weights:  # prior weights of a belief predicted twice
            w = w * belief.weights().reshape(1, *pred.shape[:2])
            w = w / w.sum()
        w_ml = w.sum(axis=0)  # (J, L): weight of each prediction summed over bearings
        est, means, probs = self._estimate(pred, w, w_ml)
        idx = resample_l(w_ml, self.n_particles, rng)
        return self._resampled(belief, pred, idx, est, means, probs, degenerate)

    def step(
        self,
        belief: MultiModelBelief,
        dt: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> MultiModelBelief:
        """``update(predict(...))``, through the fused kernel when it implements the bank."""
        return self.step_bearings(belief, dt, bearings_of(measurements), rng)

    def step_bearings(
        self,
        belief: MultiModelBelief,
        dt: float,
        z: Array,
        rng: np.random.Generator | None = None,
    ) -> MultiModelBelief:
        """:meth:`step` with the step's bearings ``z`` (rad, finite; what :func:`bearings_of`
        makes of the measurements) as one array: no measurement objects per step."""
        rng = rng if rng is not None else np.random.default_rng()
        alphas = self.bank
        if (
            self.engine == "numpy"
            or alphas is None
            or z.size == 0
            or self.estimator != "consistent"
            or not belief.uniform_weights
        ):
            return self.update_bearings(self.predict(belief, dt, rng), z, rng)
        J, L = len(alphas), len(belief.states)
        pred, w_ml, est, deg = weigh_every_model(
            self, belief.states[None, None], z.reshape(1, -1), dt, rng
        )
        w, p = w_ml[0, 0], pred[0, 0]
        p_m = w.sum(axis=1)
        means = np.einsum("jl,jld->jd", w, p) / np.where(p_m > 0, p_m, 1.0)[:, None]
        idx = resample_l(w, self.n_particles, rng)
        predicted = MultiModelBelief(
            p.reshape(J * L, 4), np.repeat(np.arange(J), L), belief.log_weights
        )
        return self._resampled(predicted, p, idx, est[0, 0], means, p_m, bool(deg))

    def _resampled(
        self,
        predicted: MultiModelBelief,
        pred: Array,
        idx: Array,
        est: Array,
        means: Array,
        probs: Array,
        degenerate: bool,
    ) -> MultiModelBelief:
        J, L = pred.shape[:2]
        n = self.n_particles
        return MultiModelBelief(
            pred.reshape(J * L, 4)[idx],
            predicted.model[idx],
            np.full(n, -math.log(n)),
            est,
            pred,
            means,
            probs,
            degenerate,
        )

    def _joint_weights(self, pred: Array, z: Array) -> tuple[Array, bool]:
        """Jointly normalised weights ``(N, J, L)`` (Eq. 3.6); equal ``(1, J, L)`` weights when
        there is no bearing or every weight underflows (degenerate)."""
        J, L = pred.shape[:2]
        if z.size:
            r = self.bearing(pred)[None] - z[:, None, None]  # (N, J, L)  Eqs. 3.4-3.5
            wrap_angle_inplace(r)
            logw = -0.5 * r * r / self.sigma**2
            top = float(logw.max())
            total = top + math.log(float(np.exp(logw - top).sum())) if np.isfinite(top) else -np.inf
            if np.isfinite(total):
                return np.exp(logw - total), False
        return np.full((1, J, L), 1.0 / (J * L)), bool(z.size)

    def propagate_every_model(self, particles: Array, dt: float, rng: np.random.Generator) -> Array:
        """Every particle through every model: ``(..., L, 4)`` -> ``(J, ..., L, 4)``.

        Fast path for the usual bank (2-D, no known acceleration, turns on axes (0, 1) or none):
        one vectorised coordinated-turn map with ``omega_j = alpha_j / speed`` (0 for CV),
        identical in law to calling each model's ``sample``.
        """
        alphas = self.bank
        if alphas is None:
            return np.stack([m.sample(particles, dt, rng) for m in self.models])
        lead = particles.shape[:-1]
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
