"""Range and range-bearing sensors (radar, ultrasound, ranging radios)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from .base import MIN_RANGE_SQ, Array, SensorBase, wrap_inplace


@dataclass(frozen=True, eq=False)
class Range(SensorBase):
    """Distance from the sensor, in 2-D or 3-D (the size of ``position`` decides).

    With ``d = p - s``::

        z = |d| + v,   v ~ N(0, sigma^2),   m = 1
        dz/dp = d^T / |d|

    At the sensor position (``|d| = 0``) the gradient is undefined; ``|d|^2`` is floored at
    :data:`~fusetrack.sensors.base.MIN_RANGE_SQ` there, which returns a finite (zero) row.
    """

    sigma: float

    _ANGULAR: ClassVar[tuple[bool, ...]] = (False,)

    def _check(self) -> None:
        self._check_sigma("sigma")

    def predict(self, x: ArrayLike) -> Array:
        """``|p - s|``, shape ``(..., 1)``."""
        d = self._relative(self._state(x))
        return np.sqrt(sum(di * di for di in d))[..., None]

    def jacobian(self, x: ArrayLike) -> Array:
        """``(p - s)^T / |p - s|`` at ``position_index``, shape ``(..., 1, d)``."""
        xa = self._state(x)
        d = self._relative(xa)
        r = np.sqrt(np.maximum(sum(di * di for di in d), MIN_RANGE_SQ))
        block = np.stack([di / r for di in d], axis=-1)[..., None, :]
        return self._embed(block, xa)

    def noise_cov(self, x: ArrayLike | None = None) -> Array:
        """``[[sigma^2]]``."""
        return np.array([[self.sigma**2]])

    def fused_likelihood(self) -> tuple[Any, ...] | None:
        """``("range", ...)`` for the particle filters' fused loop (see the base class)."""
        return self._fused("range") if self._fusable(Range) else None


@dataclass(frozen=True, eq=False)
class RangeBearing(SensorBase):
    """2-D range and bearing (relative to the heading), e.g. a radar.

    With ``d = p - s`` and ``r = |d|``::

        z = [r, wrap(atan2(d_y, d_x) - heading)] + v,
        v ~ N(0, diag(sigma_range^2, sigma_bearing^2)),   m = 2

        dz/dp = [[ d_x / r,    d_y / r   ],
                 [-d_y / r^2,  d_x / r^2 ]]

    Undefined at the sensor position; ``r^2`` is floored at
    :data:`~fusetrack.sensors.base.MIN_RANGE_SQ` so the Jacobian stays finite (zero) there.
    """

    sigma_range: float
    sigma_bearing: float

    _ANGULAR: ClassVar[tuple[bool, ...]] = (False, True)
    _POSITION_SIZES: ClassVar[tuple[int, ...]] = (2,)

    def _check(self) -> None:
        self._check_sigma("sigma_range")
        self._check_sigma("sigma_bearing")

    def predict(self, x: ArrayLike) -> Array:
        """``[range, bearing]``, shape ``(..., 2)``."""
        dx, dy = self._relative(self._state(x))
        b = np.arctan2(dy, dx)
        if self.heading:
            b -= self.heading
        return np.stack([np.hypot(dx, dy), wrap_inplace(b)], axis=-1)

    def jacobian(self, x: ArrayLike) -> Array:
        """``d[range, bearing]/dx``, shape ``(..., 2, d)`` (see class docstring)."""
        xa = self._state(x)
        dx, dy = self._relative(xa)
        r2 = np.maximum(dx * dx + dy * dy, MIN_RANGE_SQ)
        r = np.sqrt(r2)
        block = np.stack(
            [np.stack([dx / r, dy / r], axis=-1), np.stack([-dy / r2, dx / r2], axis=-1)],
            axis=-2,
        )
        return self._embed(block, xa)

    def noise_cov(self, x: ArrayLike | None = None) -> Array:
        """``diag(sigma_range^2, sigma_bearing^2)``."""
        return np.diag([self.sigma_range**2, self.sigma_bearing**2])

    def fused_likelihood(self) -> tuple[Any, ...] | None:
        """``("range_bearing", ...)`` for the particle filters' fused loop (see the base class)."""
        return self._fused("range_bearing") if self._fusable(RangeBearing) else None


__all__ = ["Range", "RangeBearing"]
