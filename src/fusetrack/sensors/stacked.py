"""Several sensors read at the same instant as one stacked measurement.

``z = [z_1; z_2; ...]``, ``h = [h_1; h_2; ...]``, ``H = [H_1; H_2; ...]``,
``R = blkdiag(R_1, R_2, ...)``. A Kalman update with the stacked sensor equals the sequential
updates with its parts when the models are linear (Nott 2009, Sec. 3.2.1 offers both views of
the joint tracker; the spec's ``--stacked`` option); an extended Kalman filter built with
``joint=True`` fuses all the readings of one time through one stacked sensor.

Many plain :class:`~fusetrack.sensors.Bearing` parts (a microphone ring, say) are evaluated
together: ``h``, ``H`` and the residual of all of them are a few array operations on the
``(n, 2)`` sensor positions, not ``n`` Python calls (the other parts are asked one by one).
``tests/sensors/test_stacked_bank.py`` checks the fast path against the parts' own methods.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import block_diag

from ..core import ConfigError, SensorModel, invalid, wrap_angle_inplace
from .angles import Bearing
from .base import MIN_RANGE_SQ, SensorBase
from .camera_geometry import Array


@dataclass(frozen=True, eq=False)
class _BearingBank:
    """The plain :class:`Bearing` parts of a stacked sensor that read the same state entries,
    evaluated at once: ``z_i = wrap(atan2(d_iy, d_ix) - heading_i)``,
    ``dz_i/dp = [-d_iy, d_ix] / max(r_i^2, MIN_RANGE_SQ)`` (the Bearing model's own equations)."""

    rows: np.ndarray  # (n,) rows of the stacked measurement
    idx: tuple[int, int]  # the state's x and y entries
    positions: np.ndarray  # (n, 2)
    headings: np.ndarray  # (n,)
    variances: np.ndarray  # (n,) sigma_i^2, the bearings' constant noise

    def relative(self, x: Array) -> tuple[Array, Array]:
        return (
            x[..., self.idx[0], None] - self.positions[:, 0],
            x[..., self.idx[1], None] - self.positions[:, 1],
        )

    def predict(self, x: Array) -> Array:
        dx, dy = self.relative(x)
        return wrap_angle_inplace(np.arctan2(dy, dx) - self.headings)

    def jacobian(self, x: Array) -> Array:
        dx, dy = self.relative(x)
        r2 = np.maximum(dx * dx + dy * dy, MIN_RANGE_SQ)
        j = np.zeros((*dx.shape, x.shape[-1]))
        j[..., self.idx[0]] = -dy / r2
        j[..., self.idx[1]] = dx / r2
        return j


def _bearing_banks(parts: Sequence[SensorModel], rows: list[int]) -> list[_BearingBank]:
    """Group the plain Bearing parts by the state entries they read (two or more per group)."""
    groups: dict[tuple[int, ...], list[tuple[int, Bearing]]] = {}
    for i, p in enumerate(parts):
        if type(p) is Bearing:
            groups.setdefault(tuple(p.position_index), []).append((i, p))
    return [
        _BearingBank(
            np.array([rows[i] for i, _ in members]),
            (idx[0], idx[1]),
            np.array([np.asarray(b.position, dtype=np.float64) for _, b in members]),
            np.array([float(b.heading) for _, b in members]),
            np.array([float(np.asarray(b.noise_cov())[0, 0]) for _, b in members]),
        )
        for idx, members in groups.items()
        if len(members) > 1
    ]


@dataclass(frozen=True, eq=False)
class StackedSensor:
    """The sensors ``parts`` read together (see the module docstring)."""

    sensor_id: str
    parts: Sequence[SensorModel]
    dim: int = field(init=False)
    angular: tuple[bool, ...] = field(init=False)
    _cuts: tuple[int, ...] = field(init=False, repr=False)
    _banks: list[_BearingBank] = field(init=False, repr=False)
    _others: list[tuple[SensorModel, slice]] = field(init=False, repr=False)
    _wrapped: np.ndarray | None = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not self.parts:
            raise ConfigError(invalid("parts", self.parts, "at least one sensor model"))
        dims = [int(p.dim) for p in self.parts]
        starts = np.concatenate([[0], np.cumsum(dims)]).astype(int).tolist()
        object.__setattr__(self, "dim", sum(dims))
        object.__setattr__(self, "angular", tuple(a for p in self.parts for a in p.angular))
        object.__setattr__(self, "_cuts", tuple(starts[1:-1]))
        banks = _bearing_banks(self.parts, starts[:-1])
        in_bank = {int(r) for b in banks for r in b.rows}
        others = [
            (p, slice(starts[i], starts[i + 1]))
            for i, p in enumerate(self.parts)
            if starts[i] not in in_bank
        ]
        object.__setattr__(self, "_banks", banks)
        object.__setattr__(self, "_others", others)
        # the residual is one wrapped subtraction when no part has its own residual
        plain = all(
            isinstance(p, SensorBase) and type(p).residual is SensorBase.residual
            for p in self.parts
        )
        wrapped = np.flatnonzero(self.angular) if plain else None
        object.__setattr__(self, "_wrapped", wrapped)

    def _split(self, z: ArrayLike) -> list[Array]:
        return np.split(np.asarray(z, float), self._cuts, axis=-1)

    def predict(self, x: Any) -> Array:
        if not self._banks:
            return np.concatenate([p.predict(x) for p in self.parts], axis=-1)
        xa = np.asarray(x, dtype=float)
        out = np.empty((*xa.shape[:-1], self.dim))
        for b in self._banks:
            out[..., b.rows] = b.predict(xa)
        for p, rows in self._others:
            out[..., rows] = p.predict(xa)
        return out

    def jacobian(self, x: Any) -> Array:
        if not self._banks:
            return np.concatenate([p.jacobian(x) for p in self.parts], axis=-2)
        xa = np.asarray(x, dtype=float)
        out = np.empty((*xa.shape[:-1], self.dim, xa.shape[-1]))
        for b in self._banks:
            out[..., b.rows, :] = b.jacobian(xa)
        for p, rows in self._others:
            out[..., rows, :] = p.jacobian(xa)
        return out

    def noise_cov(self, x: Any = None) -> Array:
        blocks = [np.asarray(p.noise_cov(x), dtype=np.float64) for p in self.parts]
        if all(b.shape == (1, 1) for b in blocks):
            return np.diag(np.concatenate([b[0] for b in blocks]))
        return np.asarray(block_diag(*blocks))

    def noise_diagonal(self, x: Any = None) -> Array | None:
        """The diagonal of :meth:`noise_cov` ``(m,)`` without the ``m x m`` matrix, or None when
        a part's noise is not diagonal (the banked bearings' variances are kept once)."""
        out = np.empty(self.dim)
        for b in self._banks:
            out[b.rows] = b.variances
        for p, rows in self._others:
            block = np.asarray(p.noise_cov(x), dtype=np.float64)
            if block.shape != (rows.stop - rows.start,) * 2:
                return None
            diag = np.diagonal(block)
            if np.count_nonzero(block) != np.count_nonzero(diag):
                return None
            out[rows] = diag
        return out

    def residual(self, z: ArrayLike, z_pred: ArrayLike) -> Array:
        if self._wrapped is not None:
            r = np.subtract(np.asarray(z, dtype=float), z_pred)
            if self._wrapped.size:
                r[..., self._wrapped] = wrap_angle_inplace(r[..., self._wrapped])
            return r
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
