"""Zhai 2007's manoeuvre models: a coordinated turn driven by a manoeuvre acceleration.

The turn rate is not in the state: it follows from the speed, ``Omega = +-a_m / |v|`` (Zhai 2007,
Eqs. 42-43; ``direction=+1`` anticlockwise, model r = 2; ``-1`` clockwise, r = 3), so the map is
nonlinear in the velocity. State ``[x, y, vx, vy]``. With ``a = Omega T``::

    x'  = x + sin(a)/Omega vx - (1 - cos a)/Omega vy        vx' = cos(a) vx - sin(a) vy
    y'  = y + (1 - cos a)/Omega vx + sin(a)/Omega vy        vy' = sin(a) vx + cos(a) vy

The Jacobian (Zhai 2007, Eqs. 55-63) is ``dF/dv = (dF/dv)|_Omega + g dOmega/dv`` with
``g = df/dOmega``. The thesis prints three slips there: the last term of g1 has the wrong sign,
g2's second term has vy for vx, and g3/g4 write ``y_{x_t}`` for vy. This module uses the correct
derivative (checked against finite differences in the tests).

Noise (Zhai 2007, Eq. 34): ``Gamma m``, ``Gamma = [[T^2/2, 0], [0, T^2/2], [T, 0], [0, T]]``,
``m ~ N(0, q I)``: ``noise="discrete"`` (rank 2, the thesis's model, for simulating truths) or
``"continuous"`` (full rank, ``q [[T^3/3, T^2/2], [T^2/2, T]]`` per axis, for filters whose weights
need a transition density).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from ..core import ConfigError, invalid
from ._common import Array, GaussianTransition, check_q
from .linear import kinematic_noise
from .turn import turn_factor_derivatives, turn_factors

_MIN_SPEED = 1e-6


@dataclass(frozen=True)
class ManeuverTurn(GaussianTransition):
    """Coordinated turn at manoeuvre acceleration ``a_m`` (turn rate ``direction a_m / speed``).

    >>> m = ManeuverTurn(a_m=1.0, direction=1)
    >>> np.round(m.mean(np.array([0.0, 0.0, 1.0, 0.0]), np.pi / 2), 6)  # quarter circle, radius 1
    array([1., 1., 0., 1.])
    """

    a_m: float
    direction: int = 1
    q: float = 1.0
    noise: Literal["discrete", "continuous"] = "continuous"
    dim: int = field(default=4, init=False, repr=False, compare=False)
    position_index: tuple[int, ...] = field(default=(0, 1), init=False, repr=False, compare=False)
    velocity_index: tuple[int, ...] | None = field(
        default=(2, 3), init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        check_q("a_m", self.a_m)
        check_q("q", self.q)
        if self.direction not in (1, -1):
            raise ConfigError(invalid("direction", self.direction, "+1 (anticlockwise) or -1"))
        if self.noise not in ("discrete", "continuous"):
            raise ConfigError(invalid("noise", self.noise, "'discrete' or 'continuous'"))

    @property
    def state_names(self) -> tuple[str, ...]:
        return ("x", "y", "vx", "vy")

    def turn_rate(self, x: ArrayLike) -> Array:
        """``Omega = direction a_m / |v|`` (Zhai 2007, Eq. 43); 0 below a speed of 1e-6."""
        xa = np.asarray(x, dtype=float)
        speed = np.hypot(xa[..., 2], xa[..., 3])
        return np.where(
            speed > _MIN_SPEED, self.direction * self.a_m / np.maximum(speed, _MIN_SPEED), 0.0
        )

    def mean(self, x: ArrayLike, dt: float) -> Array:
        """``F(x) x`` (Zhai 2007, Eq. 42), ``(..., 4)``."""
        xa = np.asarray(x, dtype=float)
        a = self.turn_rate(xa) * dt
        f1, f2 = turn_factors(a)
        s, c = dt * f1, dt * f2
        co, si = np.cos(a), np.sin(a)
        px, py, vx, vy = xa[..., 0], xa[..., 1], xa[..., 2], xa[..., 3]
        return np.stack(
            [
                px + s * vx - c * vy,
                py + c * vx + s * vy,
                co * vx - si * vy,
                si * vx + co * vy,
            ],
            axis=-1,
        )

    def jacobian(self, x: ArrayLike, dt: float) -> Array:
        """``df/dx`` (Zhai 2007, Eqs. 55-63, corrected), ``(..., 4, 4)``."""
        xa = np.asarray(x, dtype=float)
        vx, vy = xa[..., 2], xa[..., 3]
        omega = self.turn_rate(xa)
        a = omega * dt
        f1, f2 = turn_factors(a)
        d1, d2 = turn_factor_derivatives(a)
        co, si = np.cos(a), np.sin(a)
        s, c = dt * f1, dt * f2
        # g = df/dOmega (corrected Eqs. 56-59)
        g = np.stack(
            [
                dt * dt * (d1 * vx - d2 * vy),
                dt * dt * (d2 * vx + d1 * vy),
                -dt * (si * vx + co * vy),
                dt * (co * vx - si * vy),
            ],
            axis=-1,
        )
        speed2 = vx * vx + vy * vy
        moving = speed2 > _MIN_SPEED**2
        k = np.where(
            moving, -self.direction * self.a_m / np.maximum(speed2, _MIN_SPEED**2) ** 1.5, 0.0
        )
        domega = np.stack([k * vx, k * vy], axis=-1)  # dOmega/d[vx, vy]  (Eqs. 60-63)
        jac = np.zeros((*xa.shape[:-1], 4, 4))
        jac[..., 0, 0] = jac[..., 1, 1] = 1.0
        jac[..., 0, 2], jac[..., 0, 3] = s, -c
        jac[..., 1, 2], jac[..., 1, 3] = c, s
        jac[..., 2, 2], jac[..., 2, 3] = co, -si
        jac[..., 3, 2], jac[..., 3, 3] = si, co
        jac[..., :, 2:] += g[..., :, None] * domega[..., None, :]
        return jac

    def noise_cov(self, dt: float) -> Array:
        """``Gamma (q I) Gamma^T`` (discrete, Eq. 34) or the continuous-noise CV ``Q``, ``(4, 4)``."""
        return np.asarray(
            self.q * np.kron(kinematic_noise(2, dt, self.noise), np.eye(2)), dtype=np.float64
        )
