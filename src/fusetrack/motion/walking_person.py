"""A walking person seen by a camera: foot position and velocity, height and width (Nott 2009).

State ``s = [x_f, y_f, h, w, vx, vy]`` (Nott 2009, Eq. 3.7; the thesis leaves ``x_f1, y_f1``
undefined -- they are the foot velocity here, as its constant-velocity motion model needs).
Positions first (``x_f, y_f``), then the two body sizes, then the velocities.

Dynamics (Nott 2009, Eq. 3.8 / 3.12), ``s_{k+1} = A(dt) s_k + w``::

    A = [[1,0,0,0,dt,0], [0,1,0,0,0,dt], [0,0,1,0,0,0], [0,0,0,1,0,0], [0,0,0,0,1,0], [0,0,0,0,0,1]]
    Q = G diag(q_a^2, q_a^2) G^T + diag(0, 0, q_h^2, q_w^2, 0, 0) * dt / step
    G = [[dt^2/2, 0], [0, dt^2/2], [0, 0], [0, 0], [dt, 0], [0, dt]]

The foot moves with piecewise-constant white acceleration of standard deviation ``q_a``
(m/s^2); the height is nearly constant (``q_h`` m per ``step`` seconds, a random walk) and the
width changes with gait and posture, which the thesis models "with a high noise variance"
(``q_w`` m per ``step``). The thesis gives none of these numbers; the defaults are the spec's.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..core import check_positive
from ._common import Array, LinearGaussian, check_dt, check_q

STATE_NAMES = ("x", "y", "h", "w", "vx", "vy")


@dataclass(frozen=True)
class WalkingPerson(LinearGaussian):
    """Constant-velocity foot, nearly constant height, noisy width; state ``[x, y, h, w, vx, vy]``.

    >>> m = WalkingPerson()
    >>> m.mean(np.array([1.0, 2.0, 1.75, 0.5, 1.0, -1.0]), 0.5).tolist()
    [1.5, 1.5, 1.75, 0.5, 1.0, -1.0]
    """

    q_a: float = 0.5
    q_h: float = 1e-3
    q_w: float = 0.05
    step: float = 0.2
    dim: int = field(default=6, init=False, repr=False, compare=False)
    position_index: tuple[int, ...] = field(default=(0, 1), init=False, repr=False, compare=False)
    velocity_index: tuple[int, ...] | None = field(
        default=(4, 5), init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        for name in ("q_a", "q_h", "q_w"):
            object.__setattr__(self, name, check_q(name, getattr(self, name)))
        object.__setattr__(self, "step", check_positive("step", self.step))

    @property
    def state_names(self) -> tuple[str, ...]:
        return STATE_NAMES

    def transition_matrix(self, dt: float) -> Array:
        """``A(dt)`` (Nott 2009, Eq. 3.8 with the spec's constant-velocity A)."""
        dt = check_dt(dt)
        a = np.eye(6)
        a[0, 4] = a[1, 5] = dt
        return a

    def noise_cov(self, dt: float) -> Array:
        """``Q(dt) = G diag(q_a^2) G^T + diag(0, 0, q_h^2, q_w^2, 0, 0) dt / step``."""
        dt = check_dt(dt)
        g = np.zeros((6, 2))
        g[0, 0] = g[1, 1] = 0.5 * dt * dt
        g[4, 0] = g[5, 1] = dt
        q = self.q_a**2 * (g @ g.T)
        q[2, 2] = self.q_h**2 * dt / self.step
        q[3, 3] = self.q_w**2 * dt / self.step
        return q


STATE_NAMES_CA = ("x", "y", "h", "w", "vx", "vy", "ax", "ay")


@dataclass(frozen=True)
class WalkingPersonCA(LinearGaussian):
    """The spec's optional 8-D variant (Nott 2009 simulates constant-acceleration walks but its
    6-D state cannot hold an acceleration): ``[x, y, h, w, vx, vy, ax, ay]``, nearly constant
    acceleration of the foot (Wiener-sequence: a white acceleration increment of standard
    deviation ``q_j`` per ``step`` seconds), height and width as in :class:`WalkingPerson`."""

    q_j: float = 0.1
    q_h: float = 1e-3
    q_w: float = 0.05
    step: float = 0.2
    dim: int = field(default=8, init=False, repr=False, compare=False)
    position_index: tuple[int, ...] = field(default=(0, 1), init=False, repr=False, compare=False)
    velocity_index: tuple[int, ...] | None = field(
        default=(4, 5), init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        for name in ("q_j", "q_h", "q_w"):
            object.__setattr__(self, name, check_q(name, getattr(self, name)))
        object.__setattr__(self, "step", check_positive("step", self.step))

    @property
    def state_names(self) -> tuple[str, ...]:
        return STATE_NAMES_CA

    def transition_matrix(self, dt: float) -> Array:
        dt = check_dt(dt)
        a = np.eye(8)
        a[0, 4] = a[1, 5] = a[4, 6] = a[5, 7] = dt
        a[0, 6] = a[1, 7] = 0.5 * dt * dt
        return a

    def noise_cov(self, dt: float) -> Array:
        """Bar-Shalom et al. 2001, Sec. 6.3.3 per axis, ``g = [dt^2/2, dt, 1]``, variance
        ``q_j^2 dt / step``; height and width random walks as in :class:`WalkingPerson`."""
        dt = check_dt(dt)
        g = np.zeros((8, 2))
        g[0, 0] = g[1, 1] = 0.5 * dt * dt
        g[4, 0] = g[5, 1] = dt
        g[6, 0] = g[7, 1] = 1.0
        q = self.q_j**2 * dt / self.step * (g @ g.T)
        q[2, 2] = self.q_h**2 * dt / self.step
        q[3, 3] = self.q_w**2 * dt / self.step
        return q


__all__ = ["STATE_NAMES", "STATE_NAMES_CA", "WalkingPerson", "WalkingPersonCA"]
