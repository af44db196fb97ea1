"""A user's own linear-Gaussian sensor model ``z = H x + v``, ``v ~ N(0, R)``."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ..core import ConfigError, ShapeError, check_probability, invalid
from .base import Array


@dataclass(frozen=True, eq=False)
class LinearGaussianSensor:
    """``z = H x + v``, ``v ~ N(0, R)``, reported with probability ``detection_prob``.

    ``H`` is ``(m, d)`` and ``R`` a symmetric positive definite ``(m, m)``; no component is an
    angle. Works in every filter (Kalman family: exact; particle filters: the Gaussian
    likelihood) and in the CRLB through :meth:`fisher_information`.

    >>> s = LinearGaussianSensor("gps", H=[[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]], R=np.eye(2))
    >>> s.predict(np.array([3.0, 4.0, 1.0, 0.0])).tolist()
    [3.0, 4.0]
    """

    sensor_id: str
    H: ArrayLike
    R: ArrayLike
    detection_prob: float = 1.0
    dim: int = field(init=False)
    angular: tuple[bool, ...] = field(init=False, repr=False)
    _chol: Array = field(init=False, repr=False)
    _log_norm: float = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.sensor_id, str) or not self.sensor_id:
            raise ConfigError(invalid("sensor_id", self.sensor_id, "a non-empty string"))
        h = np.array(self.H, dtype=float)
        r = np.array(self.R, dtype=float)
        if h.ndim != 2 or 0 in h.shape or not np.all(np.isfinite(h)):
            raise ConfigError(invalid("H", self.H, "a finite (m, d) matrix"))
        m = h.shape[0]
        if r.shape != (m, m) or not np.allclose(r, r.T):
            raise ConfigError(invalid("R", self.R, f"a symmetric ({m}, {m}) matrix"))
        try:
            chol = np.linalg.cholesky(r)
        except np.linalg.LinAlgError:
            raise ConfigError(invalid("R", self.R, "a positive definite matrix")) from None
        check_probability("detection_prob", self.detection_prob)
        for name, value in (("H", h), ("R", r), ("_chol", chol)):
            value.flags.writeable = False
            object.__setattr__(self, name, value)
        object.__setattr__(self, "dim", m)
        object.__setattr__(self, "angular", (False,) * m)
        log_det = 2.0 * float(np.log(np.diag(chol)).sum())
        object.__setattr__(self, "_log_norm", -0.5 * (m * math.log(2 * math.pi) + log_det))

    def _state(self, x: ArrayLike) -> Array:
        a = np.asarray(x, dtype=float)
        d = self.H.shape[1]  # type: ignore[union-attr]
        if a.ndim == 0 or a.shape[-1] != d:
            raise ShapeError(invalid("x.shape", a.shape, f"(..., {d}) to match H"))
        return a

    def predict(self, x: ArrayLike) -> Array:
        """``H x``, ``(..., m)``."""
        return self._state(x) @ np.asarray(self.H).T

    def residual(self, z: ArrayLike, z_pred: ArrayLike) -> Array:
        """``z - z_pred`` (no angles to wrap)."""
        return np.asarray(z, dtype=float) - np.asarray(z_pred, dtype=float)

    def jacobian(self, x: ArrayLike) -> Array:
        """``H`` broadcast to ``(..., m, d)``."""
        a = self._state(x)
        return np.broadcast_to(np.asarray(self.H), (*a.shape[:-1], *np.shape(self.H)))

    def noise_cov(self, x: ArrayLike | None = None) -> Array:
        """``R``, ``(m, m)``."""
        return np.asarray(self.R)

    def log_likelihood(self, z: ArrayLike, x: ArrayLike) -> Array:
        """``log N(z; H x, R)``, ``(...)``."""
        r = self.residual(z, self.predict(x))
        white = np.linalg.solve(self._chol, r[..., None])[..., 0]
        return self._log_norm - 0.5 * np.sum(white * white, axis=-1)

    def simulate(self, x: ArrayLike, rng: np.random.Generator) -> Array:
        """``H x + v``; rows not detected (probability ``1 - detection_prob``) are NaN."""
        zp = self.predict(x)
        z = zp + rng.standard_normal(zp.shape) @ self._chol.T
        if self.detection_prob < 1.0:
            missed = rng.random(zp.shape[:-1]) >= self.detection_prob
            z[missed] = np.nan
        return z

    def fisher_information(self, x: ArrayLike) -> Array:
        """``H^T R^-1 H`` broadcast to ``(..., d, d)``."""
        h = np.asarray(self.H)
        info = h.T @ np.linalg.solve(np.asarray(self.R), h)
        a = self._state(x)
        return np.broadcast_to(info, (*a.shape[:-1], *info.shape))

    def detection_probability(self, x: ArrayLike) -> Array:
        """``detection_prob`` for every row of ``x``."""
        return np.full(self._state(x).shape[:-1], float(self.detection_prob))
