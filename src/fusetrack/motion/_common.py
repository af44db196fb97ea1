"""Shared pieces of the motion models: argument checks and the Gaussian transition mechanics.

Every model here is ``x_k = f(x_{k-1}, dt) + w`` with ``w ~ N(0, Q(dt))``;
:class:`GaussianTransition` turns a model's ``mean`` and ``noise_cov`` into ``sample`` and
``log_density`` once, so the concrete models only say what ``f`` and ``Q`` are.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ConfigError, ShapeError, check_positive, invalid

Array = NDArray[np.float64]

_LOG_2PI = math.log(2.0 * math.pi)
# Eigenvalues of Q below this fraction of the largest are treated as zero (as scipy.stats does).
_RANK_RTOL = 1e6 * np.finfo(float).eps
# A residual whose component along the null space of Q exceeds this (relative) size is off-support.
# Not eps-sized: Cholesky succeeds on a numerically singular Q (rounding leaves pivots of
# ~eps ||Q|| where they should be 0), and its factor then reaches ~sqrt(eps s_max) = 1.5e-8
# sqrt(s_max) into the null space, so :meth:`GaussianTransition.sample` puts points up to a few
# times that off the support (2.8e-8 relative seen over 3.6 million draws of the discrete
# CV/CA models). 1e-6 (~70 sqrt(eps)) keeps them on it and is still far below a real departure.
_SUPPORT_RTOL = 1e-6


def check_dt(dt: Any) -> float:
    """``float(dt)`` or :class:`ConfigError` unless it is a finite number of seconds ``>= 0``."""
    try:
        v = float(dt)
    except (TypeError, ValueError):
        raise ConfigError(invalid("dt", dt, "a finite number of seconds >= 0")) from None
    if not (math.isfinite(v) and v >= 0.0):
        raise ConfigError(invalid("dt", dt, "a finite number of seconds >= 0"))
    return v


def check_q(field: str, value: Any) -> float:
    """A noise intensity: a finite number ``>= 0``."""
    return check_positive(field, value, allow_zero=True)


def check_int_range(field: str, value: Any, lo: int, hi: int) -> int:
    """An integer in ``[lo, hi]`` (bools refused), else :class:`ConfigError`."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or not lo <= value <= hi:
        raise ConfigError(invalid(field, value, f"an integer in {lo}..{hi}"))
    return int(value)


def check_rng(rng: Any) -> np.random.Generator:
    """Refuse anything but a :class:`numpy.random.Generator` (seeds must be explicit)."""
    if not isinstance(rng, np.random.Generator):
        raise ConfigError(
            invalid("rng", rng, "a numpy.random.Generator, e.g. np.random.default_rng(0)")
        )
    return rng


def as_state(x: ArrayLike, dim: int, names: tuple[str, ...], field: str = "x") -> Array:
    """``x`` as a float array ``(..., dim)``, or :class:`ShapeError` naming the expected layout."""
    a = np.asarray(x, dtype=float)
    if a.ndim == 0 or a.shape[-1] != dim:
        layout = "[" + ", ".join(names) + "]"
        raise ShapeError(
            invalid(f"{field}.shape", a.shape, f"(..., {dim}): state dimension d={dim}, {layout}")
        )
    return a


def _cache_key(cov: Array) -> tuple[tuple[int, ...], str, bytes]:
    """A covariance's exact identity (shape, dtype, bytes): the key of the per-``cov`` caches."""
    a = np.asarray(cov)
    return a.shape, a.dtype.str, a.tobytes()


def _from_key(key: tuple[tuple[int, ...], str, bytes]) -> Array:
    shape, dtype, data = key
    return np.frombuffer(data, dtype=dtype).reshape(shape)


def psd_factor(cov: Array) -> Array:
    """A matrix ``G`` with ``G @ G.T == cov`` for a symmetric positive semi-definite ``cov``
    (factorised once per distinct ``cov``; a fresh copy each call)."""
    return _psd_factor(_cache_key(cov)).copy()


@functools.lru_cache(maxsize=256)
def _psd_factor(key: tuple[tuple[int, ...], str, bytes]) -> Array:
    cov = _from_key(key)
    try:
        return np.asarray(np.linalg.cholesky(cov), dtype=np.float64)
    except np.linalg.LinAlgError:  # singular Q (dt = 0, q = 0, Wiener-sequence noise)
        s, v = np.linalg.eigh(cov)
        s = np.where(s > _RANK_RTOL * s.max(initial=0.0), s, 0.0)  # rounding noise is not noise
        return np.asarray(v * np.sqrt(s), dtype=np.float64)


@functools.lru_cache(maxsize=256)
def _full_rank_plan(key: tuple[tuple[int, ...], str, bytes]) -> tuple[Array, Array, float] | None:
    """:func:`gaussian_logpdf`'s ``cov``-only work on its full-rank route: the standard
    deviations, ``inv(chol(corr)).T`` and the log-determinant; None when ``cov`` takes the
    eigen route (a zero variance, rank below ``d``, or a failed Cholesky)."""
    cov = _from_key(key)
    d = cov.shape[-1]
    var = np.diag(cov)
    pos = var > 0.0
    if not pos.all():
        return None
    sd = np.sqrt(var[pos])
    corr = cov[np.ix_(pos, pos)] / np.outer(sd, sd)
    s_corr = np.linalg.eigvalsh(corr)
    if int(np.sum(s_corr > _RANK_RTOL * s_corr.max())) != d:
        return None
    try:
        chol = np.linalg.cholesky(corr)
    except np.linalg.LinAlgError:  # borderline: the eigen route
        return None
    logdet = 2.0 * float(np.sum(np.log(np.diag(chol))) + np.sum(np.log(sd)))
    inv_t = np.linalg.inv(chol).T
    sd.flags.writeable = inv_t.flags.writeable = False
    return sd, inv_t, logdet


def gaussian_logpdf(resid: Array, cov: Array, scale: Array | float = 0.0) -> Array:
    """``log N(resid; 0, cov)`` over the leading axes of ``resid`` ``(..., d)``.

    The rank of ``cov`` is judged on its correlation matrix, so a positive definite ``Q`` that is
    badly scaled (constant acceleration at small ``dt``: ``dt^5/20`` beside ``dt``) stays full
    rank. A singular ``cov`` gives the degenerate Gaussian: the density with respect to Lebesgue
    measure on its support (pseudo-determinant, pseudo-inverse), ``-inf`` off the support; this
    matches ``scipy.stats.multivariate_normal.logpdf(..., allow_singular=True)``. ``scale``
    (broadcast against ``resid[..., 0]``) is the size of the vectors whose difference ``resid``
    is, so that rounding does not push a point off the support. A zero ``cov`` (a point mass)
    raises :class:`ConfigError`.
    """
    d = cov.shape[-1]
    plan = _full_rank_plan(_cache_key(cov))
    if plan is not None:  # the full-rank route, its cov-only work done once per cov
        sd_all, inv_t, logdet = plan
        z = (resid / sd_all) @ inv_t
        out = -0.5 * (d * _LOG_2PI + logdet + np.sum(np.square(z), axis=-1))
        return np.asarray(out, dtype=np.float64)
    var = np.diag(cov)
    pos = var > 0.0
    if not pos.any():
        raise ConfigError(
            invalid("noise_cov", "a zero matrix", "a covariance with a nonzero variance")
        )
    sd = np.sqrt(var[pos])
    corr = cov[np.ix_(pos, pos)] / np.outer(sd, sd)
    s_corr = np.linalg.eigvalsh(corr)
    rank = int(np.sum(s_corr > _RANK_RTOL * s_corr.max()))
    s, v = np.linalg.eigh(cov)  # ascending: the last `rank` span the support
    s_keep, v_keep, v_null = s[d - rank :], v[:, d - rank :], v[:, : d - rank]
    maha = np.sum(np.square(resid @ (v_keep / np.sqrt(s_keep))), axis=-1)
    out = -0.5 * (rank * _LOG_2PI + float(np.sum(np.log(s_keep))) + maha)
    if rank < d:
        off = np.linalg.norm(resid @ v_null, axis=-1)
        tol = _SUPPORT_RTOL * (math.sqrt(float(s[-1])) + np.asarray(scale, dtype=float))
        out = np.where(off > tol, -np.inf, out)
    return np.asarray(out, dtype=np.float64)


class GaussianTransition:
    """``sample`` and ``log_density`` from a model's ``mean`` and ``noise_cov``.

    Subclasses provide ``dim``, ``state_names``, ``mean(x, dt)``, ``noise_cov(dt)``.
    """

    dim: int

    @property
    def state_names(self) -> tuple[str, ...]:
        raise NotImplementedError

    def mean(self, x: ArrayLike, dt: float) -> Array:
        raise NotImplementedError

    def noise_cov(self, dt: float) -> Array:
        raise NotImplementedError

    def sample(self, x: ArrayLike, dt: float, rng: np.random.Generator) -> Array:
        """A draw ``f(x, dt) + w``, ``w ~ N(0, Q(dt))``, for every row of ``x``; ``(..., d)``."""
        check_rng(rng)
        m = self.mean(x, dt)
        g = psd_factor(self.noise_cov(dt))
        return m + rng.standard_normal(m.shape) @ g.T

    def log_density(self, x_next: ArrayLike, x: ArrayLike, dt: float) -> Array:
        """``log N(x_next; f(x, dt), Q(dt))`` broadcast over leading axes; ``(...)``.

        Raises :class:`ConfigError` when ``Q(dt) = 0`` (``dt = 0`` or ``q = 0``). A singular
        ``Q`` (Wiener-sequence noise) gives the degenerate density on its support, ``-inf`` off it.
        """
        m = self.mean(x, dt)
        xn = as_state(x_next, self.dim, self.state_names, field="x_next")
        cov = self.noise_cov(dt)
        if not np.any(cov):
            raise ConfigError(
                f"log_density is undefined for dt={dt!r}: Q(dt) is zero, so the next state is a "
                "point mass (dt = 0 gives the identity transition, q = 0 removes the noise); "
                "expected dt > 0 and q > 0"
            )
        scale = np.maximum(np.abs(xn).max(axis=-1), np.abs(m).max(axis=-1))
        return gaussian_logpdf(xn - m, cov, scale)


class LinearGaussian(GaussianTransition):
    """A linear model ``f(x, dt) = F(dt) x``; subclasses provide ``transition_matrix(dt)``."""

    def transition_matrix(self, dt: float) -> Array:
        raise NotImplementedError

    def mean(self, x: ArrayLike, dt: float) -> Array:
        """``F(dt) x`` for every row of ``x``; ``(..., d)``."""
        f = self.transition_matrix(dt)
        return as_state(x, self.dim, self.state_names) @ f.T

    def fused_transition(self, dt: float) -> tuple[Array, Array] | None:
        """``(F(dt), G)`` with ``G G^T = Q(dt)``: what the particle filters' fused step needs
        (:mod:`fusetrack.filters.fused`, ``x' = F x + G eps`` with ``eps`` drawn as
        :meth:`sample` draws it). None when a subclass changes ``mean`` or ``sample``."""
        cls = type(self)
        if cls.mean is not LinearGaussian.mean or cls.sample is not GaussianTransition.sample:
            return None
        return self.transition_matrix(dt), psd_factor(self.noise_cov(dt))

    def jacobian(self, x: ArrayLike, dt: float) -> Array:
        """``F(dt)`` broadcast to ``(..., d, d)`` (a read-only view: no copy per particle)."""
        f = self.transition_matrix(dt)
        a = as_state(x, self.dim, self.state_names)
        return np.broadcast_to(f, (*a.shape[:-1], self.dim, self.dim))
