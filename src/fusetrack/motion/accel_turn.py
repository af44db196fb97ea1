"""Known per-axis accelerations and a turn driven by a constant centripetal acceleration (Lee 2009).

State ``[pos(n), vel(n)]``. Every axis moves as ``p <- p + v T + A T^2/2``, ``v <- v + A T``
(Lee 2009, Eq. 2.15; the printed state-dependent matrix divides by the previous velocity, this
additive form is the same map without the division by ``V ~ 0``; ``A = 0`` is constant velocity,
Eq. 2.12). Optionally one pair of axes ``(a, b)`` turns at rate ``omega = alpha / |(v_a, v_b)|``
(Lee 2009, Eqs. 2.13-2.14 and 3.12-3.13): the coordinated-turn map on that pair. A positive
``alpha`` turns anticlockwise (from ``a`` towards ``b``); the dissertation labels the ``+alpha``
model "clockwise", but its own scenarios (the Table 2.1 angle ranges, the Sec. 3.4 room) are only
reproduced with ``+alpha`` = anticlockwise, so ``CT = -alpha``, ``ACT = +alpha`` here.
The printed CT matrix (2.13) also has rows 2 and 3 swapped; the map below is the correct one.

Process noise (not given in the text): discrete white acceleration per axis,
``[dp, dv] = [T^2/2, T] eta``, ``eta ~ N(0, sigma_a^2)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..core import ConfigError, ShapeError, check_positive, invalid
from .turn import turn_factors

Array = np.ndarray

MIN_TURN_SPEED = 1e-9


@dataclass(frozen=True)
class AccelTurn:
    """``ndim`` axes with known accelerations, an optional alpha-driven turn on ``turn_axes``."""

    ndim: int = 3
    accel: tuple[float, ...] = ()
    turn_axes: tuple[int, int] | None = None
    turn_alpha: float = 0.0
    sigma_a: float = 0.0
    _accel: Array = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.ndim < 1:
            raise ConfigError(invalid("ndim", self.ndim, "an integer >= 1"))
        acc = np.zeros(self.ndim) if len(self.accel) == 0 else np.asarray(self.accel, float)
        if acc.shape != (self.ndim,):
            raise ConfigError(invalid("accel", self.accel, f"{self.ndim} accelerations (m/s^2)"))
        if self.turn_axes is not None:
            a, b = self.turn_axes
            if not (0 <= a < self.ndim and 0 <= b < self.ndim and a != b):
                raise ConfigError(
                    invalid("turn_axes", self.turn_axes, f"two distinct axes in 0..{self.ndim - 1}")
                )
        check_positive("sigma_a", self.sigma_a, allow_zero=True)
        object.__setattr__(self, "_accel", acc)

    @property
    def dim(self) -> int:
        return 2 * self.ndim

    @property
    def position_index(self) -> tuple[int, ...]:
        return tuple(range(self.ndim))

    @property
    def velocity_index(self) -> tuple[int, ...]:
        return tuple(range(self.ndim, 2 * self.ndim))

    def restrict(self, axes: tuple[int, ...], state: Array | None = None) -> AccelTurn:
        """The model of a subset of axes (a plane filter's model).

        The turn survives only when both its axes are kept. An axis that turns with an axis that
        is dropped cannot be modelled on its own: without ``state`` it becomes constant velocity
        (plus noise); with a full state estimate ``state`` (e.g. the fused estimate of the last
        step) it gets the turn's current acceleration on that axis as a known acceleration,
        ``dv_a/dt = -omega v_b``, ``dv_b/dt = omega v_a``.
        """
        keep_turn = self.turn_axes is not None and all(a in axes for a in self.turn_axes)
        turning = set(self.turn_axes or ())
        coupled = np.zeros(self.ndim)
        if self.turn_axes is not None and not keep_turn and state is not None:
            ta, tb = self.turn_axes
            st = np.asarray(state, dtype=float)
            va, vb = st[self.ndim + ta], st[self.ndim + tb]
            speed = math.hypot(va, vb)
            if speed > MIN_TURN_SPEED:
                omega = self.turn_alpha / speed
                coupled[ta], coupled[tb] = -omega * vb, omega * va
        accel = tuple(
            coupled[a] if (a in turning and not keep_turn) else self._accel[a] for a in axes
        )
        turn = None
        if keep_turn and self.turn_axes is not None:
            turn = (axes.index(self.turn_axes[0]), axes.index(self.turn_axes[1]))
        return AccelTurn(len(axes), accel, turn, self.turn_alpha if turn else 0.0, self.sigma_a)

    def mean(self, x: Array, dt: float) -> Array:
        """Noiseless next state, ``(..., 2 n)``."""
        x = np.asarray(x, dtype=float)
        if x.shape[-1] != self.dim:
            raise ShapeError(invalid("x.shape", x.shape, f"(..., {self.dim})"))
        n = self.ndim
        p, v = x[..., :n], x[..., n:]
        p_new = p + v * dt + 0.5 * self._accel * dt * dt
        v_new = v + self._accel * dt
        if self.turn_axes is not None and self.turn_alpha != 0.0:
            a, b = self.turn_axes
            va, vb = v[..., a], v[..., b]
            speed = np.hypot(va, vb)
            omega = np.where(
                speed > MIN_TURN_SPEED, self.turn_alpha / np.maximum(speed, MIN_TURN_SPEED), 0.0
            )
            f1, f2 = turn_factors(omega * dt)  # sin(wT)/(wT), (1 - cos wT)/(wT)
            c, s = np.cos(omega * dt), np.sin(omega * dt)
            p_new[..., a] = p[..., a] + dt * (f1 * va - f2 * vb)  # Lee 2009, Eq. 2.13 (corrected)
            p_new[..., b] = p[..., b] + dt * (f2 * va + f1 * vb)
            v_new[..., a] = c * va - s * vb
            v_new[..., b] = s * va + c * vb
        return np.concatenate([p_new, v_new], axis=-1)

    def sample(self, x: Array, dt: float, rng: np.random.Generator) -> Array:
        out = self.mean(x, dt)
        if self.sigma_a > 0:
            eta = self.sigma_a * rng.standard_normal((*out.shape[:-1], self.ndim))
            out[..., : self.ndim] += 0.5 * dt * dt * eta
            out[..., self.ndim :] += dt * eta
        return out

    def noise_cov(self, dt: float) -> Array:
        """``sigma_a^2 [T^2/2, T]^T [T^2/2, T]`` per axis, in ``[pos, vel]`` layout."""
        g = np.concatenate([np.full(self.ndim, 0.5 * dt * dt), np.full(self.ndim, dt)])
        same_axis = np.equal.outer(np.arange(self.dim) % self.ndim, np.arange(self.dim) % self.ndim)
        return self.sigma_a**2 * np.outer(g, g) * same_axis

    def trajectory(self, x0: Array, dt: float, steps: int) -> Array:
        """Noiseless states at steps ``0..steps-1``, ``(steps, 2 n)``."""
        out = [np.asarray(x0, dtype=float)]
        for _ in range(steps - 1):
            out.append(self.mean(out[-1], dt))
        return np.array(out)
