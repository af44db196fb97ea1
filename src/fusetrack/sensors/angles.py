"""Angle-only sensors: 2-D bearing and 3-D azimuth + polar angle (e.g. acoustic DOA arrays)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from .base import MIN_RANGE_SQ, Array, SensorBase, wrap_inplace


@dataclass(frozen=True, eq=False)
class Bearing(SensorBase):
    """2-D bearing (direction of arrival) relative to the sensor heading.

    With ``d = p - s`` (target minus sensor position in the plane)::

        z = wrap(atan2(d_y, d_x) - heading) + v,    v ~ N(0, sigma^2),   m = 1
        dz/dp = [-d_y, d_x] / r^2,                   r^2 = d_x^2 + d_y^2

    The Jacobian is undefined at the sensor position (``r = 0``); there ``r^2`` is floored at
    :data:`~fusetrack.sensors.base.MIN_RANGE_SQ` so the returned value is finite (zero).

    Example
    -------
    >>> s = Bearing("doa", position=[1.0, 2.0], sigma=0.01)
    >>> float(s.predict([4.0, 6.0])[0])  # atan2(4, 3)
    0.9272952180016122
    """

    sigma: float

    _ANGULAR: ClassVar[tuple[bool, ...]] = (True,)
    _POSITION_SIZES: ClassVar[tuple[int, ...]] = (2,)

    def _check(self) -> None:
        self._check_sigma("sigma")

    def predict(self, x: ArrayLike) -> Array:
        """``wrap(atan2(d_y, d_x) - heading)``, shape ``(..., 1)``."""
        dx, dy = self._relative(self._state(x))
        b = np.arctan2(dy, dx)
        if self.heading:
            b -= self.heading
        return wrap_inplace(b)[..., None]

    def jacobian(self, x: ArrayLike) -> Array:
        """``[[-d_y, d_x]] / max(r^2, MIN_RANGE_SQ)`` at ``position_index``, ``(..., 1, d)``."""
        xa = self._state(x)
        dx, dy = self._relative(xa)
        r2 = np.maximum(dx * dx + dy * dy, MIN_RANGE_SQ)
        block = np.stack([-dy / r2, dx / r2], axis=-1)[..., None, :]
        return self._embed(block, xa)

    def noise_cov(self, x: ArrayLike | None = None) -> Array:
        """``[[sigma^2]]``."""
        return np.array([[self.sigma**2]])

    def fused_likelihood(self) -> tuple[Any, ...] | None:
        """``("bearing", ...)`` for the particle filters' fused loop (see the base class)."""
        return self._fused("bearing") if self._fusable(Bearing) else None


@dataclass(frozen=True, eq=False)
class AzimuthPolar(SensorBase):
    """3-D direction: azimuth relative to the heading and polar angle from the +z axis.

    With ``d = p - s`` in 3-D, ``rho^2 = d_x^2 + d_y^2`` and ``r^2 = rho^2 + d_z^2``::

        azimuth = wrap(atan2(d_y, d_x) - heading)      in [-pi, pi)
        polar   = atan2(rho, d_z) = arccos(d_z / r)    in [0, pi]   (0 = straight up, +z)
        z = [azimuth, polar] + v,   v ~ N(0, diag(sigma_azimuth^2, sigma_polar^2)),   m = 2

        d azimuth / dp = [-d_y, d_x, 0] / rho^2
        d polar / dp   = [d_x d_z / rho, d_y d_z / rho, -rho] / r^2

    Only the azimuth is periodic (``angular == (True, False)``); the polar angle lives on
    ``[0, pi]`` and its residual is a plain difference. Simulated polar angles are not folded
    back into ``[0, pi]`` (the noise model is Gaussian). The Jacobian is singular on the
    sensor's vertical axis (``rho = 0``: azimuth undefined) and at the sensor (``r = 0``); there
    ``rho^2`` and ``r^2`` are floored at :data:`~fusetrack.sensors.base.MIN_RANGE_SQ`.
    """

    sigma_azimuth: float
    sigma_polar: float

    _ANGULAR: ClassVar[tuple[bool, ...]] = (True, False)
    _POSITION_SIZES: ClassVar[tuple[int, ...]] = (3,)

    def _check(self) -> None:
        self._check_sigma("sigma_azimuth")
        self._check_sigma("sigma_polar")

    def predict(self, x: ArrayLike) -> Array:
        """``[azimuth, polar]``, shape ``(..., 2)``."""
        dx, dy, dz = self._relative(self._state(x))
        az = np.arctan2(dy, dx)
        if self.heading:
            az -= self.heading
        polar = np.arctan2(np.hypot(dx, dy), dz)
        return np.stack([wrap_inplace(az), polar], axis=-1)

    def jacobian(self, x: ArrayLike) -> Array:
        """``d[azimuth, polar]/dx``, shape ``(..., 2, d)`` (see class docstring)."""
        xa = self._state(x)
        dx, dy, dz = self._relative(xa)
        rho2 = np.maximum(dx * dx + dy * dy, MIN_RANGE_SQ)
        rho = np.sqrt(rho2)
        r2 = np.maximum(rho2 + dz * dz, MIN_RANGE_SQ)
        zero = np.zeros_like(dx)
        k = dz / (rho * r2)
        block = np.stack(
            [
                np.stack([-dy / rho2, dx / rho2, zero], axis=-1),
                np.stack([dx * k, dy * k, -rho / r2], axis=-1),
            ],
            axis=-2,
        )
        return self._embed(block, xa)

    def noise_cov(self, x: ArrayLike | None = None) -> Array:
        """``diag(sigma_azimuth^2, sigma_polar^2)``."""
        return np.diag([self.sigma_azimuth**2, self.sigma_polar**2])


__all__ = ["AzimuthPolar", "Bearing"]
