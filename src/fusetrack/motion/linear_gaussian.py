"""A user's own linear-Gaussian motion model ``x_k = F(dt) x_{k-1} + w``, ``w ~ N(0, Q(dt))``."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..core import ConfigError, invalid
from ._common import Array, LinearGaussian, check_dt

MatrixOfDt = ArrayLike | Callable[[float], ArrayLike]


def _matrix(name: str, value: Any, dt: float, d: int | None) -> Array:
    """``value(dt)`` or ``value`` as a finite ``(d, d)`` float matrix, else :class:`ConfigError`."""
    raw = value(dt) if callable(value) else value
    try:
        m = np.array(raw, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(invalid(name, raw, "a square matrix of numbers")) from None
    n = m.shape[0] if m.ndim == 2 else -1
    if m.ndim != 2 or m.shape != (n, n) or n == 0 or (d is not None and n != d):
        want = f"({d}, {d})" if d is not None else "(d, d), d >= 1"
        raise ConfigError(invalid(f"{name} shape", m.shape, f"a square matrix {want}"))
    if not np.all(np.isfinite(m)):
        raise ConfigError(invalid(name, raw, "finite entries"))
    return m


@dataclass(frozen=True, eq=False)
class LinearGaussianMotion(LinearGaussian):
    """``x_k = F x_{k-1} + w``, ``w ~ N(0, Q)``, with the user's own ``F`` and ``Q``.

    Each is a ``(d, d)`` matrix (the same every step: ``dt`` is ignored) or a function of ``dt``
    returning one. ``Q`` must be symmetric positive semi-definite.

    >>> m = LinearGaussianMotion(F=[[1.0, 1.0], [0.0, 1.0]], Q=0.1 * np.eye(2))
    >>> m.mean(np.array([1.0, 2.0]), dt=1.0)
    array([3., 2.])
    """

    F: MatrixOfDt
    Q: MatrixOfDt
    names: tuple[str, ...] = ()
    dim: int = field(init=False)
    position_index: tuple[int, ...] = field(init=False, repr=False)
    velocity_index: tuple[int, ...] | None = field(init=False, repr=False, default=None)

    def __post_init__(self) -> None:
        d = _matrix("F", self.F, 1.0, None).shape[0]
        q = _matrix("Q", self.Q, 1.0, d)
        if not np.allclose(q, q.T) or np.linalg.eigvalsh(0.5 * (q + q.T)).min() < -1e-9 * max(
            1.0, float(np.abs(q).max())
        ):
            raise ConfigError(invalid("Q", q.tolist(), "a symmetric positive semi-definite matrix"))
        if self.names and len(self.names) != d:
            raise ConfigError(invalid("names", self.names, f"{d} state names (or none)"))
        object.__setattr__(self, "dim", d)
        object.__setattr__(self, "position_index", tuple(range(d)))

    @property
    def state_names(self) -> tuple[str, ...]:
        return self.names or tuple(f"x{i}" for i in range(self.dim))

    def transition_matrix(self, dt: float) -> Array:
        """``F(dt)``, ``(d, d)``."""
        return _matrix("F", self.F, check_dt(dt), self.dim)

    def noise_cov(self, dt: float) -> Array:
        """``Q(dt)``, ``(d, d)``."""
        return _matrix("Q", self.Q, check_dt(dt), self.dim)
