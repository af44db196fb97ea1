"""Langevin (Ornstein-Uhlenbeck velocity) model of an image centroid (Zhai 2007, Sec. 3.5.2).

State ``[x, y, vx, vy]`` in pixels and pixels per frame; ``dt`` counts frames. Per axis::

    x_t = x_{t-1} + dt v_{t-1} + e,   v_t = a v_{t-1} + b m,   m ~ N(0, 1)
    a = exp(-beta frame_period dt),   b = v_mean sqrt(1 - a^2)

The thesis prints ``a = exp(beta dT)``, which needs ``beta < 0`` to keep ``|a| < 1``; this uses
the standard Langevin sign (spec 001 Sec. 6, item 13). ``v_mean`` is the stationary speed std.
The thesis puts no noise on the position; ``position_var`` (``e ~ N(0, position_var dt)``) keeps
the transition density proper for the proposals whose weights need it (spec Sec. 2.5, choice 6).
Defaults (spec choices): ``beta = 10 /s``, 30 frames/s (``a = 0.7165``), ``v_mean = 5 px/frame``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._common import Array, LinearGaussian, check_dt, check_q


@dataclass(frozen=True)
class Langevin(LinearGaussian):
    """>>> m = Langevin()
    >>> round(float(m.transition_matrix(1.0)[2, 2]), 4)
    0.7165
    """

    beta: float = 10.0
    frame_period: float = 1.0 / 30.0
    v_mean: float = 5.0
    position_var: float = 0.25
    dim: int = field(default=4, init=False, repr=False, compare=False)
    position_index: tuple[int, ...] = field(default=(0, 1), init=False, repr=False, compare=False)
    velocity_index: tuple[int, ...] | None = field(
        default=(2, 3), init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        check_q("beta", self.beta)
        check_q("frame_period", self.frame_period)
        check_q("v_mean", self.v_mean)
        check_q("position_var", self.position_var)

    @property
    def state_names(self) -> tuple[str, ...]:
        return ("x", "y", "vx", "vy")

    def decay(self, dt: float) -> float:
        """``a = exp(-beta frame_period dt)``."""
        return float(np.exp(-self.beta * self.frame_period * check_dt(dt)))

    def transition_matrix(self, dt: float) -> Array:
        a = self.decay(dt)
        f = np.eye(4)
        f[0, 2] = f[1, 3] = dt
        f[2, 2] = f[3, 3] = a
        return f

    def noise_cov(self, dt: float) -> Array:
        a = self.decay(dt)
        b2 = self.v_mean**2 * (1.0 - a * a)
        return np.diag([self.position_var * dt, self.position_var * dt, b2, b2])
