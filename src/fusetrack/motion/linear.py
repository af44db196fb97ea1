"""Linear kinematic models: random walk, constant velocity, constant acceleration.

All three are one idea (Bar-Shalom, Li & Kirubarajan 2001, Ch. 6): every axis carries a chain of
``p`` derivatives — position (p = 1), position and velocity (p = 2), position, velocity and
acceleration (p = 3) — and white noise drives the chain. For one axis::

    F_ij = dt^(j-i) / (j-i)!                                       (j >= i, else 0)

    continuous white noise on the p-th derivative, power spectral density q
    (Sec. 6.2.2 for p = 2, Sec. 6.2.3 for p = 3; p = 1 is Brownian motion):
    Q_ij = q dt^(2p-1-i-j) / ((p-1-i)! (p-1-j)! (2p-1-i-j))

    discrete (Wiener-sequence) noise, one acceleration value per step with variance q
    (Sec. 6.3.2 for p = 2: the piecewise-constant acceleration;
     Sec. 6.3.3 for p = 3: the acceleration increment):
    Q = q g g^T,  g_i = dt^(2-i) / (2-i)!,  i.e. g = [dt^2/2, dt] or [dt^2/2, dt, 1]

The axes are independent and stacked by derivative (positions first, then velocities, then
accelerations), so the full matrices are ``kron(F_axis, I_ndim)`` and ``kron(Q_axis, I_ndim)``.
``dt = 0`` gives ``F = I`` and ``Q = 0``: ``mean`` and ``sample`` return ``x``, ``log_density``
raises. Discrete noise has rank ``ndim`` (< d), so its ``log_density`` is the degenerate density
on that subspace (``-inf`` off it) — use ``noise="continuous"`` when a full-rank transition
density is needed (importance weights with a proposal other than the prior).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import ClassVar, Literal

import numpy as np

from ..core import ConfigError, invalid
from ._common import Array, LinearGaussian, check_dt, check_int_range, check_q

NoiseKind = Literal["continuous", "discrete"]
_AXES = ("x", "y", "z")
_PREFIX = ("", "v", "a")


def kinematic_transition(order: int, dt: float) -> Array:
    """Per-axis transition of a chain of ``order`` derivatives: ``F_ij = dt^(j-i)/(j-i)!``."""
    dt = check_dt(dt)
    f = np.zeros((order, order))
    for i in range(order):
        for j in range(i, order):
            f[i, j] = dt ** (j - i) / math.factorial(j - i)
    return f


def kinematic_noise(order: int, dt: float, noise: NoiseKind = "continuous") -> Array:
    """Per-axis process noise for unit intensity (multiply by ``q``); see the module docstring."""
    dt = check_dt(dt)
    if noise == "continuous":
        p = order
        q = np.empty((p, p))
        for i in range(p):
            for j in range(p):
                k = 2 * p - 1 - i - j  # Bar-Shalom et al. 2001, Sec. 6.2.2-6.2.3
                q[i, j] = dt**k / (math.factorial(p - 1 - i) * math.factorial(p - 1 - j) * k)
        return q
    if noise == "discrete":
        if order not in (2, 3):
            raise ConfigError(invalid("noise", noise, "'continuous' for a random walk"))
        g = np.array([dt ** (2 - i) / math.factorial(2 - i) for i in range(order)])
        return np.outer(g, g)  # Bar-Shalom et al. 2001, Sec. 6.3.2-6.3.3
    raise ConfigError(invalid("noise", noise, "'continuous' or 'discrete'"))


@functools.lru_cache(maxsize=512)
def _kron_cached(order: int, ndim: int, dt: float, noise: str | None) -> Array:
    """``kron(F_axis(dt), I)`` (``noise`` None) or ``kron(Q_axis(dt), I)`` for unit intensity,
    read-only; cached because ``np.kron`` costs more than a whole batched filter step's algebra
    on small matrices, and a filter asks for the same ``dt`` every step."""
    if noise is None:
        axis = kinematic_transition(order, dt)
    else:
        axis = kinematic_noise(order, dt, noise)  # type: ignore[arg-type]
    out = np.asarray(np.kron(axis, np.eye(ndim)), dtype=np.float64)
    out.flags.writeable = False
    return out


def _state_names(order: int, ndim: int) -> tuple[str, ...]:
    return tuple(_PREFIX[k] + _AXES[a] for k in range(order) for a in range(ndim))


class _Kinematic(LinearGaussian):
    """Shared body of the three kinematic models (order ``_order`` per axis, ``_axes`` axes)."""

    _order: ClassVar[int]
    q: float
    noise: NoiseKind

    @property
    def _axes(self) -> int:
        return self.dim // self._order

    def _derive(self, ndim: int) -> None:
        """Validate and fill the derived attributes (dataclass ``__post_init__`` helper)."""
        check_q("q", self.q)
        if self.noise not in ("continuous", "discrete") or (
            self._order == 1 and self.noise != "continuous"
        ):
            valid = "'continuous'" if self._order == 1 else "'continuous' or 'discrete'"
            raise ConfigError(invalid("noise", self.noise, valid))
        object.__setattr__(self, "dim", self._order * ndim)
        object.__setattr__(self, "position_index", tuple(range(ndim)))
        vel = tuple(range(ndim, 2 * ndim)) if self._order >= 2 else None
        object.__setattr__(self, "velocity_index", vel)

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the state components, e.g. ``('x', 'y', 'vx', 'vy')``."""
        return _state_names(self._order, self._axes)

    def transition_matrix(self, dt: float) -> Array:
        """``F(dt) = kron(F_axis(dt), I_ndim)``, ``(d, d)``."""
        f = _kron_cached(self._order, self._axes, check_dt(dt), None)
        return np.array(f, dtype=np.float64)  # a copy: callers may write to it

    def noise_cov(self, dt: float) -> Array:
        """``Q(dt) = q kron(Q_axis(dt), I_ndim)``, ``(d, d)``."""
        qa = _kron_cached(self._order, self._axes, check_dt(dt), self.noise)
        return np.asarray(float(self.q) * qa, dtype=np.float64)


@dataclass(frozen=True)
class _PerAxisKinematic(_Kinematic):
    """Fields of the models with ``ndim`` axes of ``_order`` >= 2 derivatives (CV, CA)."""

    ndim: int = 2
    q: float = 1.0
    noise: NoiseKind = "continuous"
    dim: int = field(init=False, repr=False, compare=False)
    position_index: tuple[int, ...] = field(init=False, repr=False, compare=False)
    velocity_index: tuple[int, ...] | None = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        self._derive(check_int_range("ndim", self.ndim, 1, 3))


@dataclass(frozen=True)
class ConstantVelocity(_PerAxisKinematic):
    """Nearly constant velocity in ``ndim`` = 1, 2 or 3 dimensions; state ``[pos(n), vel(n)]``.

    ``F = [[I, dt I], [0, I]]``. ``noise="continuous"`` (white-noise acceleration with PSD ``q``,
    m^2/s^3): per axis ``Q = q [[dt^3/3, dt^2/2], [dt^2/2, dt]]`` (Bar-Shalom et al. 2001,
    Sec. 6.2.2), positive definite for ``dt > 0``. ``noise="discrete"`` (piecewise-constant
    white acceleration, variance ``q`` in m^2/s^4): ``Q = q [[dt^4/4, dt^3/2], [dt^3/2, dt^2]]``
    (Sec. 6.3.2), rank ``ndim``.

    >>> cv = ConstantVelocity(ndim=2, q=0.5)
    >>> cv.mean(np.array([0.0, 0.0, 1.0, 2.0]), dt=2.0)
    array([2., 4., 1., 2.])
    """

    _order: ClassVar[int] = 2


@dataclass(frozen=True)
class ConstantAcceleration(_PerAxisKinematic):
    """Nearly constant acceleration in 1-3 dimensions; state ``[pos(n), vel(n), acc(n)]``.

    ``F = [[I, dt I, dt^2/2 I], [0, I, dt I], [0, 0, I]]``. ``noise="continuous"`` (white jerk,
    PSD ``q`` in m^2/s^5): per axis ``Q = q [[dt^5/20, dt^4/8, dt^3/6], [dt^4/8, dt^3/3, dt^2/2],
    [dt^3/6, dt^2/2, dt]]`` (Bar-Shalom et al. 2001, Sec. 6.2.3). ``noise="discrete"``
    (Wiener-sequence acceleration: the acceleration changes by a white increment of variance
    ``q`` each step): ``Q = q g g^T``, ``g = [dt^2/2, dt, 1]`` (Sec. 6.3.3), rank ``ndim``.
    """

    _order: ClassVar[int] = 3


@dataclass(frozen=True)
class RandomWalk(_Kinematic):
    """Position random walk in ``dim`` = 1, 2 or 3 dimensions: ``x_k = x_{k-1} + N(0, q dt I)``.

    Brownian motion with diffusion ``q`` (m^2/s), the ``p = 1`` member of the kinematic family;
    ``F = I``. No velocity in the state (``velocity_index`` is None).
    """

    dim: int = 2
    q: float = 1.0
    noise: NoiseKind = field(default="continuous", init=False, repr=False, compare=False)
    position_index: tuple[int, ...] = field(init=False, repr=False, compare=False)
    velocity_index: tuple[int, ...] | None = field(init=False, repr=False, compare=False)
    _order: ClassVar[int] = 1

    def __post_init__(self) -> None:
        self._derive(check_int_range("dim", self.dim, 1, 3))
