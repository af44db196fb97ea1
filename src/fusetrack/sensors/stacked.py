"""Several sensors read at the same instant as one stacked measurement.

``z = [z_1; z_2; ...]``, ``h = [h_1; h_2; ...]``, ``H = [H_1; H_2; ...]``,
``R = blkdiag(R_1, R_2, ...)``. A Kalman update with the stacked sensor equals the sequential
updates with its parts when the models are linear (Nott 2009, Sec. 3.2.1 offers both views of
the joint tracker; the spec's ``--stacked`` option).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import block_diag

from ..core.errors import ConfigError, invalid
from ..core.models import SensorModel
from .camera_geometry import Array


@dataclass(frozen=True, eq=False)
class StackedSensor:
    """The sensors ``parts`` read together (see the module docstring)."""

    sensor_id: str
    parts: Sequence[SensorModel]
    dim: int = field(init=False)
    angular: tuple[bool, ...] = field(init=False)
    _cuts: tuple[int, ...] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not self.parts:
            raise ConfigError(invalid("parts", self.parts, "at least one sensor model"))
        dims = [int(p.dim) for p in self.parts]
        object.__setattr__(self, "dim", sum(dims))
        object.__setattr__(self, "angular", tuple(a for p in self.parts for a in p.angular))
        object.__setattr__(self, "_cuts", tuple(np.cumsum(dims)[:-1].tolist()))

    def _split(self, z: ArrayLike) -> list[Array]:
        return np.split(np.asarray(z, float), self._cuts, axis=-1)

    def predict(self, x: Any) -> Array:
        return np.concatenate([p.predict(x) for p in self.parts], axis=-1)

    def jacobian(self, x: Any) -> Array:
        return np.concatenate([p.jacobian(x) for p in self.parts], axis=-2)

    def noise_cov(self, x: Any = None) -> Array:
        return np.asarray(
            block_diag(*[np.asarray(p.noise_cov(x), dtype=np.float64) for p in self.parts])
        )

    def residual(self, z: ArrayLike, z_pred: ArrayLike) -> Array:
        zs, ps = self._split(z), self._split(z_pred)
        return np.concatenate([p.residual(a, b) for p, a, b in zip(self.parts, zs, ps)], axis=-1)

    def log_likelihood(self, z: ArrayLike, x: Any) -> Array:
        zs = self._split(z)
        return np.sum([p.log_likelihood(a, x) for p, a in zip(self.parts, zs)], axis=0)

    def simulate(self, x: Any, rng: np.random.Generator) -> Array:
        return np.concatenate([p.simulate(x, rng) for p in self.parts], axis=-1)

    def fisher_information(self, x: Any) -> Array:
        return np.sum([p.fisher_information(x) for p in self.parts], axis=0)

    def detection_probability(self, x: Any) -> Array:
        return np.prod([p.detection_probability(x) for p in self.parts], axis=0)


__all__ = ["StackedSensor"]
