"""A 3-D acoustic direction-of-arrival sensor seen on the xy, yz and zx planes (Lee 2009, Ch. 2).

The sensor reports an azimuth ``theta = atan2(y, x)`` and a *polar* angle ``phi`` measured from +z
(the dissertation calls it "elevation", but every number it prints uses the polar angle), each
with independent noise of the same variance ``sigma^2``. Projected Planes Selection (PPS) turns
the pair into three plane bearings:

* ``theta_xy = atan2(u_y, u_x)``, ``theta_yz = atan2(u_z, u_y)``, ``theta_zx = atan2(u_x, u_z)``
  with ``u = (sin phi cos theta, sin phi sin theta, cos phi)``.

Lee 2009, Eqs. 2.1-2.2 print ``arctan(|sec theta| / (tan theta tan phi)) + beta`` and
``arctan(tan phi / |sec theta|) + gamma``; for ``x > 0`` they equal these atan2 forms, but the
``|sec theta|`` makes them wrong for ``x < 0`` and the printed gamma cases are contradictory, so
the atan2 forms are used for measurements and predictions alike.

The projected noise variances (Eq. 2.3) have no closed form in the text (it plots Monte Carlo
estimates, Figs. 2-2/2-3); :func:`projected_variance` is the first-order (delta-method) variance,
which matches Monte Carlo to about 1 % at ``sigma^2 = 1 deg^2``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ConfigError, ShapeError, invalid

Array = NDArray[np.float64]

PLANES: tuple[str, str, str] = ("xy", "yz", "zx")
# Plane -> (first axis, second axis); the plane bearing is atan2(second, first).
PLANE_AXES: dict[str, tuple[int, int]] = {"xy": (0, 1), "yz": (1, 2), "zx": (2, 0)}
LITERAL_PHI_RANGE = (math.radians(45.0), math.radians(135.0))


def check_plane(plane: str) -> str:
    if plane not in PLANE_AXES:
        raise ConfigError(invalid("plane", plane, f"one of {PLANES}"))
    return plane


def direction_angles(rel: ArrayLike) -> tuple[Array, Array]:
    """Azimuth in ``[0, 2 pi)`` and polar angle in ``[0, pi]`` of relative positions ``(..., 3)``."""
    r = np.asarray(rel, dtype=float)
    if r.shape[-1] != 3:
        raise ShapeError(invalid("rel.shape", r.shape, "(..., 3) relative positions"))
    theta = np.mod(np.arctan2(r[..., 1], r[..., 0]), 2 * np.pi)
    phi = np.arctan2(np.hypot(r[..., 0], r[..., 1]), r[..., 2])
    return theta, phi


def unit_vector(theta: ArrayLike, phi: ArrayLike) -> Array:
    """``(sin phi cos theta, sin phi sin theta, cos phi)``, shape ``(..., 3)``."""
    t, p = np.asarray(theta, dtype=float), np.asarray(phi, dtype=float)
    sp = np.sin(p)
    return np.stack(np.broadcast_arrays(sp * np.cos(t), sp * np.sin(t), np.cos(p)), axis=-1)


def plane_bearing(rel: ArrayLike, plane: str) -> Array:
    """Bearing of relative positions ``(..., 3)`` (or unit vectors) on ``plane``, in ``[-pi, pi)``."""
    a, b = PLANE_AXES[check_plane(plane)]
    r = np.asarray(rel, dtype=float)
    return np.arctan2(r[..., b], r[..., a])


def projected_angles(theta: ArrayLike, phi: ArrayLike) -> Array:
    """``(theta_xy, theta_yz, theta_zx)`` of measured angles, ``(..., 3)`` (Lee 2009, Eqs. 2.1-2.2, atan2 form)."""
    u = unit_vector(theta, phi)
    return np.stack([plane_bearing(u, p) for p in PLANES], axis=-1)


def projected_variance(theta: ArrayLike, phi: ArrayLike, sigma2: ArrayLike = 1.0) -> Array:
    """Variances of the three plane bearings, ``(..., 3)`` in the units of ``sigma2``.

    Delta method on ``theta_yz = atan2(cos phi, sin phi sin theta)`` and
    ``theta_zx = atan2(sin phi cos theta, cos phi)`` (Lee 2009, Eq. 2.3 -- the text only plots
    Monte Carlo estimates)::

        var_xy / s2 = 1
        var_yz / s2 = (sin^2 t + sin^2 p cos^2 p cos^2 t) / (sin^2 p sin^2 t + cos^2 p)^2
        var_zx / s2 = (cos^2 t + sin^2 p cos^2 p sin^2 t) / (sin^2 p cos^2 t + cos^2 p)^2

    On the z axis (``phi = 0`` and ``sin theta = 0`` ...) a denominator vanishes: the plane bearing
    is undefined there and the variance is ``inf``.
    """
    t, p = np.asarray(theta, dtype=float), np.asarray(phi, dtype=float)
    s2 = np.asarray(sigma2, dtype=float)
    st2, ct2 = np.sin(t) ** 2, np.cos(t) ** 2
    sp2, cp2 = np.sin(p) ** 2, np.cos(p) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        yz = (st2 + sp2 * cp2 * ct2) / (sp2 * st2 + cp2) ** 2
        zx = (ct2 + sp2 * cp2 * st2) / (sp2 * ct2 + cp2) ** 2
    yz = np.where(np.isfinite(yz), yz, np.inf)
    zx = np.where(np.isfinite(zx), zx, np.inf)
    xy = np.ones_like(yz)
    return np.stack(np.broadcast_arrays(xy * s2, yz * s2, zx * s2), axis=-1)


def monte_carlo_projected_variance(
    theta: float, phi: float, sigma: float, n: int, rng: np.random.Generator
) -> Array:
    """Sample variances of the three plane bearings under ``N(0, sigma^2)`` noise on both angles.

    This is how the text obtains Figs. 2-2/2-3; residuals are wrapped about the noiseless
    plane bearings, so the estimate is valid across the ``+-pi`` cut.
    """
    th = theta + sigma * rng.standard_normal(n)
    ph = phi + sigma * rng.standard_normal(n)
    clean = projected_angles(theta, phi)
    noisy = projected_angles(th, ph)
    d = np.mod(noisy - clean + np.pi, 2 * np.pi) - np.pi
    return np.mean(d**2, axis=0)


def literal_second_plane(phi: ArrayLike) -> NDArray[np.str_]:
    """PPS as published (Lee 2009, Algorithm 1): yz when ``45 deg <= phi <= 135 deg``, else zx.

    The text motivates the rule by "yz has the smaller variance there"; with the polar angle it is
    the other way round (see :func:`minvar_second_plane`), but this is the rule that reproduces the
    plane selections the text reports for Scenarios 1-4 and Table 2.1.
    """
    p = np.asarray(phi, dtype=float)
    lo, hi = LITERAL_PHI_RANGE
    return np.where((p >= lo) & (p <= hi), "yz", "zx")


def minvar_second_plane(theta: ArrayLike, phi: ArrayLike) -> NDArray[np.str_]:
    """The second plane that the method intends: the one of yz, zx with the smaller projected variance."""
    v = projected_variance(theta, phi)
    return np.where(v[..., 1] <= v[..., 2], "yz", "zx")


def _pm_one(values: ArrayLike, field_name: str) -> Array:
    v = np.asarray(values, dtype=float)
    if v.shape != (3,) or not np.all(np.isin(v, (-1.0, 1.0))):
        raise ConfigError(invalid(field_name, values, "three axis polarities, each +1 or -1"))
    return v


class DoaSensor3D:
    """An azimuth/polar-angle acoustic sensor with its own axis polarities (Lee 2009, Sec. 2.2.3).

    ``polarity[c] = u_c^k . u_c^0`` says whether the sensor's axis ``c`` points like the primary
    sensor's (+1) or the other way (-1). A global position ``p`` is ``polarity * (p - position)``
    in the sensor's frame (Lee 2009, Eqs. 2.22-2.24 print a state-dependent shift with the wrong
    sign; ``global = position + polarity * local`` is the transform they describe).
    ``sigma`` is the noise standard deviation of each angle (radians).
    """

    def __init__(
        self,
        sensor_id: str,
        position: ArrayLike = (0.0, 0.0, 0.0),
        sigma: float = math.radians(math.sqrt(3.0)),
        polarity: ArrayLike = (1.0, 1.0, 1.0),
    ) -> None:
        self.sensor_id = str(sensor_id)
        pos = np.asarray(position, dtype=float)
        if pos.shape != (3,) or not np.all(np.isfinite(pos)):
            raise ConfigError(invalid("position", position, "a finite 3-D position (m)"))
        if not (math.isfinite(sigma) and sigma >= 0):
            raise ConfigError(invalid("sigma", sigma, "a finite angle std >= 0 (rad)"))
        self.position = pos
        self.sigma = float(sigma)
        self.polarity = _pm_one(polarity, "polarity")

    def local(self, p: ArrayLike) -> Array:
        """Positions ``(..., 3)`` in the sensor's frame."""
        return self.polarity * (np.asarray(p, dtype=float) - self.position)

    def angles(self, p: ArrayLike) -> tuple[Array, Array]:
        """Noiseless azimuth and polar angle of global positions ``(..., 3)``."""
        return direction_angles(self.local(p))

    def simulate(self, p: ArrayLike, rng: np.random.Generator) -> Array:
        """Noisy ``(theta, phi)`` of global positions ``(..., 3)``: ``(..., 2)``."""
        theta, phi = self.angles(p)
        z = np.stack([theta, phi], axis=-1)
        return z + self.sigma * rng.standard_normal(z.shape)

    def plane_bearing(self, p: ArrayLike, plane: str) -> Array:
        """Predicted plane bearing of global positions ``(..., 3)``."""
        return plane_bearing(self.local(p), plane)

    def plane_bearing_2d(self, pa: Array, pb: Array, plane: str) -> Array:
        """Plane bearing from the plane's two global coordinates (a plane filter's particles)."""
        a, b = PLANE_AXES[check_plane(plane)]
        la = self.polarity[a] * (pa - self.position[a])
        lb = self.polarity[b] * (pb - self.position[b])
        return np.arctan2(lb, la)


def check_angles(z: ArrayLike) -> Array:
    """Validate one ``(theta, phi)`` measurement (radians); raises on non-finite or polar outside [0, pi]."""
    from ..core import MeasurementError

    v = np.asarray(z, dtype=float)
    if v.shape != (2,):
        raise MeasurementError(invalid("z.shape", v.shape, "(2,): azimuth and polar angle"))
    if not np.all(np.isfinite(v)):
        raise MeasurementError(invalid("z", v.tolist(), "finite azimuth and polar angle (rad)"))
    slack = 0.5  # noisy polar angles may leave [0, pi] slightly; far outside is a unit error
    if not (-slack <= v[1] <= math.pi + slack):
        raise MeasurementError(
            invalid("z[1] (polar angle)", float(v[1]), "within [0, pi] rad (+-0.5 rad of noise)")
        )
    return v
