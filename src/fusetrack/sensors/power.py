"""A scalar power-law sensor: ``z = scale * x_k^p + v`` (Zhai 2007, Eq. 32: p = 3; Eq. 94: p = 2)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..core import ConfigError, ShapeError, invalid
from .scalar_gaussian import ScalarGaussianSensor

Array = np.ndarray


@dataclass(frozen=True, eq=False)
class Power(ScalarGaussianSensor):
    """``z = scale * x[index]^exponent + v``, ``v ~ N(0, sigma^2)``; ``m = 1``, not angular.

    >>> s = Power("cube", exponent=3, sigma=1.0)
    >>> float(s.predict(np.array([2.0]))[0])
    8.0
    """

    sensor_id: str
    exponent: int = 3
    sigma: float = 1.0
    scale: float = 1.0
    index: int = 0

    def __post_init__(self) -> None:
        if not isinstance(self.exponent, int | np.integer) or self.exponent < 1:
            raise ConfigError(invalid("exponent", self.exponent, "an integer >= 1"))
        if not (math.isfinite(self.sigma) and self.sigma > 0):
            raise ConfigError(invalid("sigma", self.sigma, "a finite number > 0"))
        if not (math.isfinite(self.scale) and self.scale != 0):
            raise ConfigError(invalid("scale", self.scale, "a finite nonzero number"))

    @property
    def noise_sd(self) -> float:
        return self.sigma

    def _x(self, x: ArrayLike) -> Array:
        xa = np.asarray(x, dtype=float)
        if xa.ndim == 0 or xa.shape[-1] <= self.index:
            raise ShapeError(invalid("x.shape", xa.shape, f"(..., d) with d > index={self.index}"))
        return xa[..., self.index]

    def predict(self, x: ArrayLike) -> Array:
        """``scale x^p``, ``(..., 1)`` (overflow of a diverged state gives inf, silently)."""
        with np.errstate(over="ignore", invalid="ignore"):
            return np.asarray(self.scale * self._x(x) ** self.exponent)[..., None]

    def jacobian(self, x: ArrayLike) -> Array:
        """``p scale x^(p-1)`` at column ``index``, ``(..., 1, d)``."""
        xa = np.asarray(x, dtype=float)
        jac = np.zeros((*xa.shape[:-1], 1, xa.shape[-1]))
        jac[..., 0, self.index] = self.exponent * self.scale * self._x(xa) ** (self.exponent - 1)
        return jac
