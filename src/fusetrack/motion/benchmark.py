"""The scalar nonlinear benchmark of Zhai 2007 (Eqs. 31 and 93).

``x_t = a exp(-2 x_{t-1}^2) + b g(x_{t-1}) + w``, ``w ~ N(0, q)``, with ``g = sin`` (Zhai 2007,
Eq. 31: a = 1.7, b = 5, q = 1) or ``g = cos`` (Zhai 2007, Eq. 93: q = 8). ``dt`` is ignored: the
model is a discrete-time map (one step per measurement).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from ..core import ConfigError, invalid
from ._common import Array, GaussianTransition, check_q


@dataclass(frozen=True)
class ScalarBenchmark(GaussianTransition):
    """``x' = a exp(-2 x^2) + b g(x) + w``, ``g`` in {sin, cos}, ``w ~ N(0, q)``; state ``[x]``.

    >>> m = ScalarBenchmark()
    >>> float(m.mean(np.array([0.0]), 1.0)[0])  # 1.7 exp(0) + 5 sin(0)
    1.7
    """

    a: float = 1.7
    b: float = 5.0
    trig: Literal["sin", "cos"] = "sin"
    q: float = 1.0
    dim: int = field(default=1, init=False, repr=False, compare=False)
    position_index: tuple[int, ...] = field(default=(0,), init=False, repr=False, compare=False)
    velocity_index: tuple[int, ...] | None = field(
        default=None, init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        if self.trig not in ("sin", "cos"):
            raise ConfigError(invalid("trig", self.trig, "'sin' (Eq. 31) or 'cos' (Eq. 93)"))
        check_q("q", self.q)

    @property
    def state_names(self) -> tuple[str, ...]:
        return ("x",)

    def mean(self, x: ArrayLike, dt: float = 1.0) -> Array:
        """``a exp(-2 x^2) + b g(x)`` (Zhai 2007, Eq. 31 / Eq. 93), ``(..., 1)``."""
        xa = np.asarray(x, dtype=float)
        g = np.sin(xa) if self.trig == "sin" else np.cos(xa)
        return np.asarray(self.a * np.exp(-2.0 * xa * xa) + self.b * g, dtype=np.float64)

    def jacobian(self, x: ArrayLike, dt: float = 1.0) -> Array:
        """``-4 a x exp(-2x^2) + b g'(x)`` as ``(..., 1, 1)`` (Zhai 2007, Sec. 3.1.3: F(x))."""
        xa = np.asarray(x, dtype=float)
        dg = np.cos(xa) if self.trig == "sin" else -np.sin(xa)
        return np.asarray((-4.0 * self.a * xa * np.exp(-2.0 * xa * xa) + self.b * dg)[..., None])

    def noise_cov(self, dt: float = 1.0) -> Array:
        """``[[q]]``."""
        return np.array([[float(self.q)]])
