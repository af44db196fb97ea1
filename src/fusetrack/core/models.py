"""The small interfaces every motion model, sensor model and filter follows.

Shapes: a state array is ``(..., d)``; leading axes are particles, runs or targets and every
method is vectorised over them. A measurement array is ``(..., m)``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Protocol, TypeVar, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from .measurement import Measurement

Array = NDArray[np.float64]


@runtime_checkable
class MotionModel(Protocol):
    """``x_k = f(x_{k-1}, dt) + w``, ``w ~ N(0, Q(dt))``."""

    @property
    def dim(self) -> int:
        """State dimension d."""
        ...

    def mean(self, x: Array, dt: float) -> Array:
        """``f(x, dt)``: the noiseless next state, ``(..., d)``."""
        ...

    def sample(self, x: Array, dt: float, rng: np.random.Generator) -> Array:
        """A draw of the next state for every row of ``x``."""
        ...

    def jacobian(self, x: Array, dt: float) -> Array:
        """``df/dx`` at ``x``: ``(..., d, d)`` (or ``(d, d)`` for a linear model)."""
        ...

    def noise_cov(self, dt: float) -> Array:
        """Process noise covariance ``Q(dt)``, ``(d, d)``."""
        ...

    def log_density(self, x_next: Array, x: Array, dt: float) -> Array:
        """``log p(x_next | x)``, broadcast over leading axes."""
        ...


@runtime_checkable
class SensorModel(Protocol):
    """``z = h(x) + v``, ``v ~ N(0, R(x))``, seen with probability ``detection_probability(x)``."""

    @property
    def sensor_id(self) -> str: ...

    @property
    def dim(self) -> int:
        """Measurement dimension m."""
        ...

    @property
    def angular(self) -> tuple[bool, ...]:
        """Which measurement components are angles (wrapped in residuals)."""
        ...

    def predict(self, x: Array) -> Array:
        """``h(x)``, ``(..., m)``."""
        ...

    def residual(self, z: Array, z_pred: Array) -> Array:
        """``z - z_pred`` with angle components wrapped to [-pi, pi)."""
        ...

    def jacobian(self, x: Array) -> Array:
        """``dh/dx`` at ``x``: ``(..., m, d)``."""
        ...

    def noise_cov(self, x: Array | None = None) -> Array:
        """``R(x)``: ``(m, m)`` or ``(..., m, m)``."""
        ...

    def log_likelihood(self, z: Array, x: Array) -> Array:
        """``log p(z | x)``; ``z`` broadcasts against ``predict(x)``; returns ``(...)``."""
        ...

    def simulate(self, x: Array, rng: np.random.Generator) -> Array:
        """Noisy measurements of ``x``; rows the sensor does not detect are NaN."""
        ...

    def fisher_information(self, x: Array) -> Array:
        """``H^T R^-1 H`` at ``x``: ``(..., d, d)``."""
        ...

    def detection_probability(self, x: Array) -> Array:
        """Probability that the sensor reports ``x`` (field of view, range, P_D), ``(...)``."""
        ...


B = TypeVar("B")


class Filter(Protocol[B]):
    """A recursive Bayesian filter: pure ``predict`` and ``update`` on immutable beliefs."""

    def predict(self, belief: B, dt: float, rng: np.random.Generator | None = None) -> B: ...

    def update(
        self, belief: B, measurements: Sequence[Measurement], rng: np.random.Generator | None = None
    ) -> B: ...


SensorMap = Mapping[str, SensorModel]
