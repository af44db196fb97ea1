"""Position fixes: a radio tag (or GPS, or any localiser) that reports the position directly."""

from __future__ import annotations

import math
from dataclasses import KW_ONLY, dataclass, field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from .base import TWO_PI, Array, SensorBase, _default_index


@dataclass(frozen=True, eq=False)
class PositionFix(SensorBase):
    """A linear position measurement with full covariance and an optional known bias.

    With ``p = x[..., position_index]`` (``k`` entries)::

        z = p + bias + v,   v ~ N(0, cov),   m = k
        dz/dx = H = [I_k at the position_index columns, 0 elsewhere]

    ``bias`` is part of the model (the filter subtracts it): to simulate an uncalibrated tag
    seen by a filter that assumes no bias, simulate with one instance and filter with another.

    ``position`` is the reader / anchor position: it matters only for the visibility limits
    (``max_range`` from it, ``fov`` around ``heading``) and is required when those are set;
    otherwise it defaults to the origin. ``position_index`` defaults to the first ``k`` state
    entries, ``k`` being the size of ``cov``.

    Example
    -------
    >>> tag = PositionFix("tag", cov=[[0.2, 0.05], [0.05, 0.1]])
    >>> tag.predict([1.0, 2.0, 0.5, 0.0]).tolist()
    [1.0, 2.0]
    """

    cov: ArrayLike
    _: KW_ONLY
    position: ArrayLike | None = None  # type: ignore[assignment]  # optional here
    bias: ArrayLike | None = None

    _bias: Array = field(init=False, repr=False)
    _k: int = field(init=False, repr=False)
    _slice: slice | None = field(init=False, repr=False)

    _NOISE_FIELD: ClassVar[str] = "cov"

    def __post_init__(self) -> None:
        try:
            cov = np.array(self.cov, dtype=float)
        except (TypeError, ValueError):
            raise self._fail("cov", self.cov, "a (k, k) covariance matrix") from None
        if cov.ndim != 2 or cov.shape[0] != cov.shape[1] or cov.shape[0] == 0:
            raise self._fail("cov", self.cov, "a square (k, k) covariance matrix, k >= 1")
        k = cov.shape[0]
        cov.flags.writeable = False
        self._set("cov", cov)
        self._set("_k", k)
        if not _default_index(self.position_index):
            try:
                n = len(self.position_index)
            except TypeError:
                n = -1
            if n != k:
                raise self._fail(
                    "position_index",
                    self.position_index,
                    f"{k} state indices to match cov of shape {cov.shape}",
                )
        if self.bias is None:
            bias = np.zeros(k)
        else:
            try:
                bias = np.array(self.bias, dtype=float)
            except (TypeError, ValueError):
                raise self._fail("bias", self.bias, f"an array of shape ({k},)") from None
            if bias.shape != (k,) or not np.all(np.isfinite(bias)):
                raise self._fail("bias", self.bias, f"a finite array of shape ({k},)")
        bias.flags.writeable = False
        self._set("bias", bias)
        self._set("_bias", bias)
        if self.position is None:
            try:
                limited = float(self.fov) < TWO_PI or not math.isinf(float(self.max_range))
            except (TypeError, ValueError):
                limited = False  # the base class reports the bad fov / max_range
            if limited:
                raise self._fail(
                    "position",
                    None,
                    f"a reader position of shape ({k},) when fov or max_range is set",
                )
            self._set("position", np.zeros(k))
        super().__post_init__()
        idx = self._idx
        contiguous = idx == tuple(range(idx[0], idx[0] + k))
        self._set("_slice", slice(idx[0], idx[0] + k) if contiguous else None)

    def _position_sizes(self) -> tuple[int, ...]:
        return (self._k,)

    def _angular_components(self) -> tuple[bool, ...]:
        return (False,) * self._k

    def predict(self, x: ArrayLike) -> Array:
        """``p + bias``, shape ``(..., k)``."""
        xa = self._state(x)
        p = xa[..., self._slice] if self._slice is not None else xa[..., list(self._idx)]
        return p + self._bias

    def jacobian(self, x: ArrayLike) -> Array:
        """The selection matrix ``H`` broadcast to ``(..., k, d)``."""
        xa = self._state(x)
        J = np.zeros((*xa.shape[:-1], self._k, xa.shape[-1]))
        J[..., np.arange(self._k), list(self._idx)] = 1.0
        return J

    def noise_cov(self, x: ArrayLike | None = None) -> Array:
        """``cov``, shape ``(k, k)``."""
        return np.asarray(self.cov, dtype=float)

    def fused_likelihood(self) -> tuple[Any, ...] | None:
        """``("position", index, bias, 0.0, (), log_norm, L^-1)`` for the particle filters'
        fused loop (see the base class; ``L`` is the Cholesky factor of ``cov``), or None when a
        subclass changes ``predict``, ``residual`` or ``log_likelihood``."""
        t = type(self)
        if self._k > 3 or not (
            t.predict is PositionFix.predict
            and t.residual is SensorBase.residual
            and t.log_likelihood is SensorBase.log_likelihood
        ):
            return None
        return ("position", self._idx, self._bias, 0.0, (), self._log_norm, self._chol_inv_T.T)


__all__ = ["PositionFix"]
