"""Coordinated turn: constant speed on a circle, turn rate known or in the state.

Li & Jilkov 2003 (Survey of maneuvering target tracking, Part I, Sec. V): with ``a = omega dt``::

    x'  = x + sin(a)/omega vx - (1 - cos a)/omega vy
    y'  = y + (1 - cos a)/omega vx + sin(a)/omega vy
    vx' = cos(a) vx - sin(a) vy
    vy' = sin(a) vx + cos(a) vy

Positive ``omega`` turns anticlockwise. The two ratios are evaluated as ``dt sinc(a)`` and
``dt (a/2) sinc(a/2)^2`` (``sinc(u) = sin(u)/u``), exact and smooth through ``omega = 0``, where the
model is constant velocity; their derivatives in ``omega`` use a Taylor series for ``|a| < 0.1``.

Noise (a modelling choice, stated here): the continuous white-noise-acceleration noise of the 2-D
constant-velocity model on ``[x, y, vx, vy]`` (PSD ``q``, Bar-Shalom et al. 2001, Sec. 6.2.2), and
for :class:`CoordinatedTurnRate` an independent random walk ``q_omega dt`` (rad^2/s^3 times s)
on ``omega``. It is not the exact discretisation of white acceleration through the turn.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ..core import ConfigError, invalid
from ._common import Array, GaussianTransition, LinearGaussian, as_state, check_dt, check_q
from .linear import kinematic_noise

_SERIES_BELOW = 0.1
_SERIES_TERMS = 7


def _sinc(a: Array) -> Array:
    """``sin(a)/a``, 1 at 0."""
    return np.sinc(a / np.pi)


def turn_factors(a: ArrayLike) -> tuple[Array, Array]:
    """``f1(a) = sin(a)/a`` and ``f2(a) = (1 - cos a)/a``, so ``sin(a)/omega = dt f1(omega dt)``."""
    a = np.asarray(a, dtype=float)
    return _sinc(a), 0.5 * a * _sinc(0.5 * a) ** 2  # 1 - cos a = 2 sin^2(a/2)


def turn_factor_derivatives(a: ArrayLike) -> tuple[Array, Array]:
    """``f1'(a) = (a cos a - sin a)/a^2`` and ``f2'(a) = (a sin a - 1 + cos a)/a^2``.

    Both are evaluated from their Taylor series when ``|a| < 0.1`` (the closed forms cancel
    there): ``f1' = sum_{k>=1} (-1)^k 2k a^(2k-1)/(2k+1)!``,
    ``f2' = sum_{k>=1} (-1)^(k+1) (2k-1) a^(2k-2)/(2k)!``.
    """
    a = np.asarray(a, dtype=float)
    small = np.abs(a) < _SERIES_BELOW
    a_s = np.where(small, a, 0.0)
    d1s = np.zeros_like(a)
    d2s = np.zeros_like(a)
    for k in range(1, _SERIES_TERMS + 1):
        sign = (-1.0) ** k
        d1s = d1s + sign * 2 * k * a_s ** (2 * k - 1) / math.factorial(2 * k + 1)
        d2s = d2s - sign * (2 * k - 1) * a_s ** (2 * k - 2) / math.factorial(2 * k)
    a_b = np.where(small, 1.0, a)
    s, c = np.sin(a_b), np.cos(a_b)
    d1b = (a_b * c - s) / a_b**2
    d2b = (a_b * s - 1.0 + c) / a_b**2
    return np.where(small, d1s, d1b), np.where(small, d2s, d2b)


def _check_finite(field_name: str, value: float) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ConfigError(invalid(field_name, value, "a finite number (rad/s)")) from None
    if not math.isfinite(v):
        raise ConfigError(invalid(field_name, value, "a finite number (rad/s)"))
    return v


def _cv_noise(q: float, dt: float) -> Array:
    """2-D constant-velocity white-noise-acceleration ``Q`` on ``[x, y, vx, vy]``."""
    return np.asarray(
        q * np.kron(kinematic_noise(2, dt, "continuous"), np.eye(2)), dtype=np.float64
    )


@dataclass(frozen=True)
class CoordinatedTurn(LinearGaussian):
    """Coordinated turn with a known turn rate ``omega`` (rad/s); state ``[x, y, vx, vy]``.

    Linear: ``F(dt) = [[1, 0, S, -C], [0, 1, C, S], [0, 0, cos a, -sin a], [0, 0, sin a, cos a]]``
    with ``a = omega dt``, ``S = sin(a)/omega``, ``C = (1 - cos a)/omega`` (Li & Jilkov 2003,
    Sec. V); ``omega = 0`` is constant velocity. ``Q``: the 2-D CV continuous noise, PSD ``q``.
    """

    omega: float
    q: float = 1.0
    dim: int = field(default=4, init=False, repr=False, compare=False)
    position_index: tuple[int, ...] = field(default=(0, 1), init=False, repr=False, compare=False)
    velocity_index: tuple[int, ...] | None = field(
        default=(2, 3), init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        _check_finite("omega", self.omega)
        check_q("q", self.q)

    @property
    def state_names(self) -> tuple[str, ...]:
        return ("x", "y", "vx", "vy")

    def transition_matrix(self, dt: float) -> Array:
        """``F(dt)``, ``(4, 4)``."""
        dt = check_dt(dt)
        a = float(self.omega) * dt
        f1, f2 = turn_factors(a)
        s, c = dt * float(f1), dt * float(f2)
        co, si = math.cos(a), math.sin(a)
        return np.array(
            [[1.0, 0.0, s, -c], [0.0, 1.0, c, s], [0.0, 0.0, co, -si], [0.0, 0.0, si, co]]
        )  # Li & Jilkov 2003, Sec. V (CT model, known turn rate)

    def noise_cov(self, dt: float) -> Array:
        """2-D CV continuous white-noise-acceleration ``Q(dt)``, ``(4, 4)``."""
        return _cv_noise(self.q, check_dt(dt))


@dataclass(frozen=True)
class CoordinatedTurnRate(GaussianTransition):
    """Coordinated turn with the turn rate in the state: ``[x, y, vx, vy, omega]``.

    ``f`` is the coordinated turn with each row's own ``omega`` (kept constant by ``f``;
    Li & Jilkov 2003, Sec. V); nonlinear, so :meth:`jacobian` depends on ``x``.
    ``Q = blockdiag(Q_CV(q, dt), q_omega dt)``: CV white-noise acceleration with PSD ``q``
    on ``[x, y, vx, vy]`` and a random walk of intensity ``q_omega`` (rad^2/s^3) on ``omega``.
    """

    q: float = 1.0
    q_omega: float = 0.01
    dim: int = field(default=5, init=False, repr=False, compare=False)
    position_index: tuple[int, ...] = field(default=(0, 1), init=False, repr=False, compare=False)
    velocity_index: tuple[int, ...] | None = field(
        default=(2, 3), init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        check_q("q", self.q)
        check_q("q_omega", self.q_omega)

    @property
    def state_names(self) -> tuple[str, ...]:
        return ("x", "y", "vx", "vy", "omega")

    def mean(self, x: ArrayLike, dt: float) -> Array:
        """The turn for every row, each with its own ``omega``; ``(..., 5)``."""
        dt = check_dt(dt)
        xa = as_state(x, 5, self.state_names)
        px, py, vx, vy, w = np.moveaxis(xa, -1, 0)
        a = w * dt
        f1, f2 = turn_factors(a)
        s, c = dt * f1, dt * f2
        co, si = np.cos(a), np.sin(a)
        return np.stack(  # Li & Jilkov 2003, Sec. V (CT model, turn rate in the state)
            [px + s * vx - c * vy, py + c * vx + s * vy, co * vx - si * vy, si * vx + co * vy, w],
            axis=-1,
        )

    def jacobian(self, x: ArrayLike, dt: float) -> Array:
        """``df/dx`` at every row, ``(..., 5, 5)``; exact through ``omega = 0``."""
        dt = check_dt(dt)
        xa = as_state(x, 5, self.state_names)
        _, _, vx, vy, w = np.moveaxis(xa, -1, 0)
        a = w * dt
        f1, f2 = turn_factors(a)
        d1, d2 = turn_factor_derivatives(a)
        s, c = dt * f1, dt * f2
        co, si = np.cos(a), np.sin(a)
        j = np.zeros((*xa.shape[:-1], 5, 5))
        j[..., 0, 0] = j[..., 1, 1] = j[..., 4, 4] = 1.0
        j[..., 0, 2], j[..., 0, 3] = s, -c
        j[..., 1, 2], j[..., 1, 3] = c, s
        j[..., 2, 2], j[..., 2, 3] = co, -si
        j[..., 3, 2], j[..., 3, 3] = si, co
        # d/d omega: d(dt f(omega dt))/d omega = dt^2 f'(a)
        j[..., 0, 4] = dt * dt * (d1 * vx - d2 * vy)
        j[..., 1, 4] = dt * dt * (d2 * vx + d1 * vy)
        j[..., 2, 4] = -dt * (si * vx + co * vy)
        j[..., 3, 4] = dt * (co * vx - si * vy)
        return j

    def noise_cov(self, dt: float) -> Array:
        """``blockdiag(Q_CV(dt), q_omega dt)``, ``(5, 5)``."""
        dt = check_dt(dt)
        out = np.zeros((5, 5))
        out[:4, :4] = _cv_noise(self.q, dt)
        out[4, 4] = float(self.q_omega) * dt
        return out
