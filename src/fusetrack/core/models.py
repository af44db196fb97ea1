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


@runtime_checkable
class Belief(Protocol):
    """What every belief offers a reader: the point estimate ``mean`` ``(..., d)`` and its
    covariance ``cov`` ``(..., d, d)`` (Gaussian, particles, grid, mixture, model-conditioned)."""

    @property
    def mean(self) -> Array: ...

    @property
    def cov(self) -> Array: ...


@runtime_checkable
class Filter(Protocol[B]):
    """A recursive Bayesian filter: pure ``predict`` and ``update`` on immutable beliefs.

    Everything the filter carries from one step to the next lives in the belief it returns; the
    filter object holds only its configuration. Two optional capabilities (duck-typed, see
    :class:`SteppingFilter` and :class:`LikelihoodFilter`) let a filter draw its prediction with
    the new measurements in view and report ``log p(z_k | z_1:k-1)``.
    """

    def predict(self, belief: B, dt: float, rng: np.random.Generator | None = None) -> B: ...

    def update(
        self, belief: B, measurements: Sequence[Measurement], rng: np.random.Generator | None = None
    ) -> B: ...


@runtime_checkable
class SteppingFilter(Filter[B], Protocol[B]):
    """A filter whose prediction looks at the measurements it is about to be updated with (a
    particle filter with a proposal ``q(x_k | x_{k-1}, z_k)``): ``step`` replaces
    ``update(predict(belief, dt), measurements)`` and must equal it in distribution."""

    def step(
        self,
        belief: B,
        dt: float,
        measurements: Sequence[Measurement],
        rng: np.random.Generator | None = None,
    ) -> B: ...


@runtime_checkable
class LikelihoodFilter(Filter[B], Protocol[B]):
    """A filter that also reports the log-likelihood increment ``log p(z_k | z_1:k-1)`` of an
    update, ``(...)`` per batch entry: the sum over a run is the log-likelihood of the model,
    for parameter estimation and model comparison."""

    def update_with_likelihood(
        self, belief: B, measurements: Sequence[Measurement], rng: np.random.Generator | None = None
    ) -> tuple[B, Array]: ...


def step_with_likelihood(
    filt: LikelihoodFilter[B],
    belief: B,
    dt: float,
    measurements: Sequence[Measurement],
    rng: np.random.Generator | None = None,
) -> tuple[B, Array | float]:
    """:func:`filter_step` and its log-likelihood increment: a stepping filter's own
    ``step_with_likelihood`` (its proposal's estimate, the same draws as ``step``) when it has
    one, else predict (when ``dt > 0``) then ``update_with_likelihood``."""
    own = getattr(filt, "step_with_likelihood", None)
    if own is not None and callable(getattr(filt, "step", None)):
        result: tuple[B, Array] = own(belief, dt, measurements, rng)
        return result
    if dt > 0:
        belief = filt.predict(belief, dt, rng)
    if not measurements:
        return belief, 0.0
    return filt.update_with_likelihood(belief, measurements, rng)


def filter_step(
    filt: Filter[B],
    belief: B,
    dt: float,
    measurements: Sequence[Measurement],
    rng: np.random.Generator | None = None,
) -> B:
    """One step of any filter: its own ``step`` when it has one, else predict (when ``dt > 0``)
    then update (when there are measurements)."""
    step = getattr(
        filt, "step", None
    )  # not isinstance(SteppingFilter): that check is slow per step
    if callable(step):
        result: B = step(belief, dt, measurements, rng)
        return result
    if dt > 0:
        belief = filt.predict(belief, dt, rng)
    return filt.update(belief, measurements, rng) if measurements else belief


SensorMap = Mapping[str, SensorModel]
