"""Received acoustic intensity of a source (Zhai 2007, Eq. 37), on the decibel scale.

``P = S / ||x - r||^(alpha/2)`` (Eq. 37 as printed; ``alpha = 2`` gives ``P = S/d``, the spec's
default, ``alpha = 4`` the inverse-square law). Measured as a level ``L = 10 log10 P + e``,
``e ~ N(0, sigma_db^2)`` (spec choice: noise in dB), so ``z = [L]`` with
``h(x) = source_db - 5 alpha log10 d`` (the source level ``source_db`` is ``10 log10 S`` at 1 m).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ..core import ConfigError, invalid
from .scalar_gaussian import ScalarGaussianSensor

Array = np.ndarray
_MIN_D = 1e-3


@dataclass(frozen=True, eq=False)
class AcousticIntensity(ScalarGaussianSensor):
    """Sound level (dB) received by a sensor at ``position`` from a source at the target position.

    >>> s = AcousticIntensity("mic", position=[0.0, 0.0], source_db=70.0)
    >>> float(s.predict(np.array([10.0, 0.0, 0.0, 0.0]))[0])  # 70 - 10 log10(10)
    60.0
    """

    sensor_id: str
    position: ArrayLike
    source_db: float = 70.0
    alpha: float = 2.0
    sigma_db: float = 1.0
    position_index: tuple[int, ...] = (0, 1)
    _pos: Array = field(init=False, repr=False)

    def __post_init__(self) -> None:
        pos = np.asarray(self.position, dtype=float)
        if pos.shape != (2,):
            raise ConfigError(invalid("position", self.position, "a 2-D point [x, y]"))
        object.__setattr__(self, "_pos", pos)
        for name in ("alpha", "sigma_db"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ConfigError(invalid(name, v, "a finite number > 0"))

    @property
    def noise_sd(self) -> float:
        return self.sigma_db

    def distance(self, x: ArrayLike) -> Array:
        xa = np.asarray(x, dtype=float)
        d = np.hypot(
            xa[..., self.position_index[0]] - self._pos[0],
            xa[..., self.position_index[1]] - self._pos[1],
        )
        return np.maximum(d, _MIN_D)

    def predict(self, x: ArrayLike) -> Array:
        """``source_db - 5 alpha log10 d`` (Eq. 37 in dB), ``(..., 1)``."""
        return np.asarray(self.source_db - 5.0 * self.alpha * np.log10(self.distance(x)))[..., None]

    def linear(self, level_db: ArrayLike) -> Array:
        """Intensity on the linear scale, ``10^(L/10)``."""
        return np.asarray(10.0 ** (np.asarray(level_db, float) / 10.0))

    def jacobian(self, x: ArrayLike) -> Array:
        xa = np.asarray(x, dtype=float)
        d = self.distance(xa)
        c = -5.0 * self.alpha / (np.log(10.0) * d * d)
        jac = np.zeros((*xa.shape[:-1], 1, xa.shape[-1]))
        for k, i in enumerate(self.position_index):
            jac[..., 0, i] = c * (xa[..., i] - self._pos[k])
        return jac
