"""Estimates and tracks: time series of states and covariances."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .errors import ShapeError, invalid


@dataclass(frozen=True, eq=False)
class Estimate:
    """A filter's point estimate at one time: ``mean`` ``(..., d)`` and ``covariance`` ``(..., d, d)``."""

    time: float
    mean: NDArray[np.float64]
    covariance: NDArray[np.float64] | None = None
    metadata: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True, eq=False)
class Track:
    """A time series of estimates.

    ``times`` ``(T,)``, ``means`` ``(T, ..., d)``, ``covariances`` ``(T, ..., d, d)`` or None.
    Leading axes after T are batched runs when a filter ran several at once.
    """

    times: NDArray[np.float64]
    means: NDArray[np.float64]
    covariances: NDArray[np.float64] | None = None
    label: str = ""
    info: Mapping[str, Any] = field(default_factory=dict)
    id: int | None = None  # a multi-target tracker's persistent track identity

    def __post_init__(self) -> None:
        t = np.asarray(self.times, dtype=float)
        m = np.asarray(self.means, dtype=float)
        if m.ndim < 2 or m.shape[0] != t.shape[0]:
            raise ShapeError(invalid("means.shape", m.shape, f"(T={t.shape[0]}, ..., d)"))
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "means", m)
        if self.covariances is not None:
            c = np.asarray(self.covariances, dtype=float)
            if c.shape != (*m.shape, m.shape[-1]):
                raise ShapeError(
                    invalid("covariances.shape", c.shape, f"{(*m.shape, m.shape[-1])}")
                )
            object.__setattr__(self, "covariances", c)

    def __len__(self) -> int:
        return int(self.times.shape[0])

    @property
    def dim(self) -> int:
        return int(self.means.shape[-1])

    @classmethod
    def from_estimates(cls, estimates: Iterable[Estimate], label: str = "", **info: Any) -> Track:
        est = list(estimates)
        if not est:
            raise ShapeError("a Track needs at least one estimate (got none)")
        covs = None
        if all(e.covariance is not None for e in est):
            covs = np.stack([np.asarray(e.covariance) for e in est])
        return cls(
            np.array([e.time for e in est]),
            np.stack([np.asarray(e.mean) for e in est]),
            covs,
            label,
            info,
        )

    def __getitem__(self, k: int) -> Estimate:
        cov = None if self.covariances is None else self.covariances[k]
        return Estimate(float(self.times[k]), self.means[k], cov)
