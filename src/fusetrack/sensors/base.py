"""The shared base of every geometric sensor model.

A sensor model is ``z = h(x) + v`` with ``v ~ N(0, R)`` and ``R`` constant, seen with probability
``P_D(x) = detection_prob * visible(x)``. A subclass supplies only three things:

* ``predict(x)``  -- ``h(x)``, shape ``(..., m)``;
* ``jacobian(x)`` -- ``dh/dx``, shape ``(..., m, d)``;
* ``noise_cov(x=None)`` -- ``R``, shape ``(m, m)``;

and sets the class attribute ``_ANGULAR`` (which components are angles). Everything else --
validation, field of view and range limits, detection, ``residual``, ``log_likelihood``,
``simulate`` and ``fisher_information`` -- lives here, once.

Geometry (SI units, radians):

* the sensor sits at ``s = position`` and faces ``heading`` (anticlockwise from +x in the xy-plane);
* the target position is ``p = x[..., position_index]``; ``d = p - s``;
* ``visible(x)`` is ``|d| <= max_range`` and ``|wrap(atan2(d_y, d_x) - heading)| <= fov / 2``
  (the angular test is skipped when ``fov == 2 pi``);
* ``detection_probability(x) = detection_prob * visible(x)``.

Angles wrap to ``[-pi, pi)``. Residuals of angle components are wrapped differences, so a bearing
measured at ``pi - 0.01`` against a prediction of ``-pi + 0.01`` is a residual of ``-0.02``, not
``2 pi - 0.02``. The likelihood is Gaussian in the wrapped residual; this is the usual
approximation of the wrapped normal and is accurate while the angle sigmas are well below pi.
"""

from __future__ import annotations

import math
from dataclasses import KW_ONLY, dataclass, field
from typing import Any, ClassVar, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import (
    TWO_PI,
    ConfigError,
    ShapeError,
    check_positive,
    check_probability,
    invalid,
    wrap_angle,
    wrap_angle_inplace,
)

Array = NDArray[np.float64]


MIN_RANGE_SQ = 1e-18
"""Floor (m^2) on squared ranges in Jacobians: ``dh/dx`` of an angle is undefined at the sensor
position (zero range), so ``r^2`` is replaced by ``max(r^2, MIN_RANGE_SQ)`` there and the Jacobian
stays finite (it is 0 exactly at the sensor, since the numerator vanishes too)."""


wrap_inplace = wrap_angle_inplace
wrap = wrap_angle


def _symmetric_positive_definite(field_name: str, c: Array, owner: str) -> Array:
    """Lower Cholesky factor of ``c`` or :class:`ConfigError` naming ``field_name``."""
    if not np.all(np.isfinite(c)):
        raise ConfigError(f"{owner}: " + invalid(field_name, c.tolist(), "finite entries"))
    if not np.allclose(c, c.T, rtol=1e-10, atol=1e-12 * max(1.0, float(np.abs(c).max()))):
        raise ConfigError(f"{owner}: " + invalid(field_name, c.tolist(), "a symmetric matrix"))
    try:
        L = cast(Array, np.linalg.cholesky(0.5 * (c + c.T)))
    except np.linalg.LinAlgError:
        raise ConfigError(
            f"{owner}: " + invalid(field_name, c.tolist(), "a symmetric positive definite matrix")
        ) from None
    return L


def _default_index(position_index: Any) -> bool:
    """True for the "use the default" values of ``position_index``: ``()`` or ``None``."""
    return position_index is None or (isinstance(position_index, tuple) and not position_index)


@dataclass(frozen=True, eq=False)
class SensorBase:
    """Common fields and behaviour of the fusetrack sensor models (see module docstring).

    Parameters
    ----------
    sensor_id:
        Name the filters use to route measurements to this model.
    position:
        Sensor position ``s``, shape ``(2,)`` or ``(3,)`` (metres).
    heading:
        Orientation in the xy-plane (rad, anticlockwise from +x). Angle measurements are relative
        to it and the field of view is centred on it.
    fov:
        Full angular width of the field of view in the xy-plane, in ``(0, 2 pi]``.
    max_range:
        Targets farther than this (metres) are not seen; ``inf`` for no limit.
    detection_prob:
        Probability of a report for a visible target, in ``[0, 1]``.
    position_index:
        Which state entries are the target position; empty (the default) or None means the
        first ``len(position)`` entries.
    """

    sensor_id: str
    position: ArrayLike
    _: KW_ONLY
    heading: float = 0.0
    fov: float = TWO_PI
    max_range: float = math.inf
    detection_prob: float = 1.0
    position_index: tuple[int, ...] = ()

    dim: int = field(init=False, repr=False)
    angular: tuple[bool, ...] = field(init=False, repr=False)

    # Precomputed once from the constant R (the particle filter's hot path must not factorise R).
    _pos: Array = field(init=False, repr=False)
    _idx: tuple[int, ...] = field(init=False, repr=False)
    _ang: tuple[int, ...] = field(init=False, repr=False)
    _R: Array = field(init=False, repr=False)
    _R_inv: Array = field(init=False, repr=False)
    _chol: Array = field(init=False, repr=False)
    _chol_inv_T: Array = field(init=False, repr=False)
    _inv_var: Array | None = field(init=False, repr=False)
    _sd: Array | None = field(init=False, repr=False)
    _log_norm: float = field(init=False, repr=False)

    _ANGULAR: ClassVar[tuple[bool, ...]] = ()
    _POSITION_SIZES: ClassVar[tuple[int, ...]] = (2, 3)
    _NOISE_FIELD: ClassVar[str] = "sigma"

    # ----------------------------------------------------------------------------------------
    # construction and validation

    def _set(self, name: str, value: Any) -> None:
        object.__setattr__(self, name, value)

    def _fail(self, field_name: str, value: Any, valid: str) -> ConfigError:
        return ConfigError(f"{self._owner}: " + invalid(field_name, value, valid))

    @property
    def _owner(self) -> str:
        return f"{type(self).__name__}({self.sensor_id!r})"

    def __post_init__(self) -> None:
        if not isinstance(self.sensor_id, str) or not self.sensor_id:
            raise ConfigError(
                f"{type(self).__name__}: "
                + invalid("sensor_id", self.sensor_id, "a non-empty string")
            )
        try:
            pos = np.array(self.position, dtype=float)
        except (TypeError, ValueError):
            raise self._fail("position", self.position, "an array of numbers") from None
        allowed = self._position_sizes()
        sizes = " or ".join(f"({n},)" for n in allowed)
        if pos.ndim != 1 or pos.size not in allowed:
            raise self._fail("position", self.position, f"an array of shape {sizes}")
        if not np.all(np.isfinite(pos)):
            raise self._fail("position", self.position, "finite coordinates")
        pos.flags.writeable = False
        self._set("position", pos)
        self._set("_pos", pos)

        try:
            heading = float(self.heading)
        except (TypeError, ValueError):
            raise self._fail("heading", self.heading, "a finite angle in radians") from None
        if not math.isfinite(heading):
            raise self._fail("heading", self.heading, "a finite angle in radians")
        self._set("heading", heading)
        try:
            fov = float(self.fov)
        except (TypeError, ValueError):
            raise self._fail("fov", self.fov, "an angle in (0, 2*pi] radians") from None
        if not 0.0 < fov <= TWO_PI + 1e-12:
            raise self._fail("fov", self.fov, "an angle in (0, 2*pi] radians")
        self._set("fov", min(fov, TWO_PI))
        try:
            max_range = float(self.max_range)
        except (TypeError, ValueError):
            raise self._fail("max_range", self.max_range, "a number > 0 (or inf)") from None
        if not max_range > 0.0:  # also rejects NaN
            raise self._fail("max_range", self.max_range, "a number > 0 (or inf)")
        self._set("max_range", max_range)
        try:
            self._set("detection_prob", check_probability("detection_prob", self.detection_prob))
        except ConfigError as e:
            raise ConfigError(f"{self._owner}: {e}") from None
        if self.fov < TWO_PI and pos.size < 2:
            raise self._fail("fov", self.fov, "2*pi for a sensor without an xy-plane")

        if _default_index(self.position_index):
            idx = tuple(range(pos.size))
        else:
            try:
                idx = tuple(int(i) for i in self.position_index)
                ok = all(i == j and i >= 0 for i, j in zip(idx, self.position_index))
            except (TypeError, ValueError):
                ok = False
            if not ok:
                raise self._fail(
                    "position_index", self.position_index, "a tuple of non-negative integers"
                )
            if len(set(idx)) != len(idx):
                raise self._fail("position_index", self.position_index, "distinct state indices")
            if len(idx) != pos.size:
                raise self._fail(
                    "position_index",
                    self.position_index,
                    f"{pos.size} indices, one per coordinate of position={pos.tolist()}",
                )
        self._set("position_index", idx)
        self._set("_idx", idx)

        self._check()

        angular = self._angular_components()
        self._set("angular", angular)
        self._set("dim", len(angular))
        self._set("_ang", tuple(i for i, a in enumerate(angular) if a))

        R = np.array(self.noise_cov(), dtype=float)
        if R.shape != (self.dim, self.dim):
            raise self._fail(
                self._NOISE_FIELD, R.tolist(), f"a ({self.dim}, {self.dim}) covariance"
            )
        L = _symmetric_positive_definite(self._NOISE_FIELD, R, self._owner)
        R = 0.5 * (R + R.T)
        L_inv = np.linalg.inv(L)
        R_inv = L_inv.T @ L_inv
        diagonal = not np.any(R - np.diag(np.diag(R)))
        for name, a in (("_R", R), ("_R_inv", R_inv), ("_chol", L), ("_chol_inv_T", L_inv.T)):
            a.flags.writeable = False
            self._set(name, a)
        self._set("_inv_var", 1.0 / np.diag(R) if diagonal else None)
        self._set("_sd", np.sqrt(np.diag(R)) if diagonal else None)
        logdet = 2.0 * float(np.sum(np.log(np.diag(L))))
        self._set("_log_norm", -0.5 * (logdet + self.dim * math.log(TWO_PI)))

    def _check(self) -> None:
        """Validate subclass parameters (raise :class:`ConfigError` naming the field)."""

    def _check_sigma(self, name: str) -> None:
        """Coerce ``self.<name>`` to a finite float > 0 or raise naming ``name``."""
        try:
            self._set(name, check_positive(name, getattr(self, name)))
        except ConfigError as e:
            raise ConfigError(f"{self._owner}: {e}") from None

    def _angular_components(self) -> tuple[bool, ...]:
        return self._ANGULAR

    def _position_sizes(self) -> tuple[int, ...]:
        return self._POSITION_SIZES

    # ----------------------------------------------------------------------------------------
    # geometry helpers for subclasses

    def _state(self, x: ArrayLike) -> Array:
        xa = np.asarray(x, dtype=float)
        need = max(self._idx) + 1
        if xa.ndim == 0 or xa.shape[-1] < need:
            raise ShapeError(
                f"{self._owner}: "
                + invalid(
                    "x.shape", xa.shape, f"(..., d) with d >= {need} (position_index={self._idx})"
                )
            )
        return xa

    def _relative(self, x: Array) -> list[Array]:
        """Target minus sensor position, one array ``(...)`` per coordinate: ``d = p - s``."""
        return [x[..., i] - s for i, s in zip(self._idx, self._pos.tolist())]

    def _embed(self, block: Array, x: Array) -> Array:
        """Place ``dh/dp`` ``(..., m, k)`` at the ``position_index`` columns of ``(..., m, d)``."""
        J = np.zeros((*x.shape[:-1], self.dim, x.shape[-1]))
        J[..., list(self._idx)] = block
        return J

    # ----------------------------------------------------------------------------------------
    # the three model-specific methods

    def predict(self, x: ArrayLike) -> Array:
        """``h(x)``: the noiseless measurement, shape ``(..., m)``."""
        raise NotImplementedError

    def jacobian(self, x: ArrayLike) -> Array:
        """``dh/dx`` at ``x``, shape ``(..., m, d)`` (nonzero only at ``position_index``)."""
        raise NotImplementedError

    def noise_cov(self, x: ArrayLike | None = None) -> Array:
        """``R``, shape ``(m, m)`` (constant: ``x`` is accepted for the interface and ignored)."""
        raise NotImplementedError

    # ----------------------------------------------------------------------------------------
    # shared behaviour

    def visible(self, x: ArrayLike) -> NDArray[np.bool_]:
        """Boolean ``(...)``: target inside the field of view and within ``max_range``.

        ``|d| <= max_range`` and ``|wrap(atan2(d_y, d_x) - heading)| <= fov / 2``.
        """
        xa = self._state(x)
        vis = np.ones(xa.shape[:-1], dtype=bool)
        if math.isinf(self.max_range) and self.fov >= TWO_PI:
            return vis
        d = self._relative(xa)
        if not math.isinf(self.max_range):
            r2 = sum(di * di for di in d)
            vis &= np.asarray(r2 <= self.max_range**2)
        if self.fov < TWO_PI:
            off = wrap_inplace(np.arctan2(d[1], d[0]) - self.heading)
            vis &= np.abs(off) <= 0.5 * self.fov
        return vis

    def detection_probability(self, x: ArrayLike) -> Array:
        """``P_D(x) = detection_prob * visible(x)``, shape ``(...)``."""
        return self.detection_prob * self.visible(x).astype(float)

    def residual(self, z: ArrayLike, z_pred: ArrayLike) -> Array:
        """``z - z_pred`` (broadcast), angle components wrapped to ``[-pi, pi)``."""
        za = np.asarray(z, dtype=float)
        if za.ndim == 0:
            za = za[None]
        if za.shape[-1] != self.dim:
            raise ShapeError(
                f"{self._owner}: " + invalid("z.shape", za.shape, f"(..., {self.dim})")
            )
        r = np.subtract(za, z_pred)
        if len(self._ang) == self.dim:
            wrap_inplace(r)
        else:
            for k in self._ang:
                r[..., k] = wrap_inplace(r[..., k])
        return r

    def log_likelihood(self, z: ArrayLike, x: ArrayLike) -> Array:
        """``log N(r; 0, R)`` with ``r = residual(z, h(x))``, shape ``(...)``.

        ``log p(z | x) = -1/2 r^T R^-1 r - 1/2 log det(2 pi R)``. ``z`` is ``(m,)`` or
        ``(..., 1, m)`` / ``(..., N, m)`` and broadcasts against ``predict(x)``. ``R`` is
        constant, so its inverse Cholesky factor and log-determinant are computed once at
        construction; for a diagonal ``R`` the quadratic form is a direct weighted sum.
        NaN in ``z`` gives NaN (filters skip such values before calling this).
        """
        r = self.residual(z, self.predict(x))
        if self._inv_var is not None:
            if self.dim == 1:
                q = r[..., 0]
                q = q * q * float(self._inv_var[0])
            else:
                q = (r * r) @ self._inv_var
        else:
            u = r @ self._chol_inv_T  # u = L^-1 r, so |u|^2 = r^T R^-1 r
            q = np.einsum("...i,...i->...", u, u)
        return self._log_norm - 0.5 * q

    def fused_likelihood(self) -> tuple[Any, ...] | None:
        """What the particle filters' fused likelihood loop needs to evaluate
        :meth:`log_likelihood` per particle (:mod:`fusetrack.filters.fused`):
        ``(kind, position_index, position, heading, 1 / diag(R), log_norm)``, or None when this
        model has no fused form (the filters then call :meth:`log_likelihood`)."""
        return None

    def _fusable(self, cls: type[SensorBase]) -> bool:
        """True when ``predict``, ``residual`` and ``log_likelihood`` are ``cls``'s own and ``R``
        is diagonal (a subclass that changes any of them loses the fused form)."""
        t = type(self)
        return (
            t.predict is cls.predict
            and t.residual is SensorBase.residual
            and t.log_likelihood is SensorBase.log_likelihood
            and self._inv_var is not None
        )

    def _fused(self, kind: str) -> tuple[Any, ...]:
        assert self._inv_var is not None
        inv_var = tuple(float(v) for v in self._inv_var)
        return (kind, self._idx, self._pos, self.heading, inv_var, self._log_norm)

    def simulate(self, x: ArrayLike, rng: np.random.Generator) -> Array:
        """Noisy measurements ``h(x) + v``, ``v ~ N(0, R)``, shape ``(..., m)``.

        Angle components are wrapped to ``[-pi, pi)``. A row is NaN when the target is not
        detected: outside the field of view, beyond ``max_range``, or (independently) with
        probability ``1 - detection_prob``. Draws, in order: ``standard_normal(x.shape[:-1] +
        (m,))`` then ``random(x.shape[:-1])``.
        """
        xa = self._state(x)
        z = self.predict(xa)
        e = rng.standard_normal(z.shape)
        z = z + (e * self._sd if self._sd is not None else e @ self._chol.T)
        for k in self._ang:
            z[..., k] = wrap_inplace(z[..., k])
        detected = rng.random(z.shape[:-1]) < self.detection_probability(xa)
        z[~detected] = np.nan
        return z

    def fisher_information(self, x: ArrayLike) -> Array:
        """``J(x) = H^T R^-1 H`` with ``H = jacobian(x)``, shape ``(..., d, d)``."""
        H = self.jacobian(x)
        return np.swapaxes(H, -1, -2) @ (self._R_inv @ H)
