"""Likelihoods of a 3-D azimuth/polar-angle measurement over particle arrays (Lee 2009, Ch. 2).

Two ways a particle filter can read one ``z = (theta, phi)`` of a :class:`DoaSensor3D`:

* :class:`ProjectedPlaneBearing` -- on one plane (xy, yz or zx): the measurement projected on
  the plane, compared with the particle's plane bearing under the projected variance at the
  measured angles, the unnormalised kernel ``exp(-r^2 / (2 sigma_P^2))`` (Lee 2009, Eq. 2.16;
  unnormalised so that the weight sums of different planes compare, Sec. 2.2.2);
* :class:`DoaCone` -- in 3-D: ``exp(-dtheta^2/(2 s^2)) exp(-dphi^2/(2 s^2))`` with the azimuth
  residual wrapped (the "cone" likelihood of the direct 3-D filter, Sec. 2.2.2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import wrap_angle_inplace
from .doa_projection import PLANES, DoaSensor3D, check_plane, projected_angles, projected_variance

Array = NDArray[np.float64]


@dataclass(frozen=True)
class ProjectedPlaneBearing:
    """A :class:`DoaSensor3D` seen on ``plane``; particles are the plane's ``[p_a, p_b, v_a, v_b]``."""

    sensor: DoaSensor3D
    plane: str

    def __post_init__(self) -> None:
        check_plane(self.plane)

    def variance(self, z: ArrayLike) -> float:
        """Projected variance ``sigma_P^2`` of the plane bearing at the measured angles."""
        v = np.asarray(z, float)
        var = projected_variance(v[..., 0], v[..., 1], self.sensor.sigma**2)
        return float(np.asarray(var)[..., PLANES.index(self.plane)])

    def log_likelihood(self, z: ArrayLike, x: ArrayLike, variance: float | None = None) -> Array:
        """``-r^2 / (2 sigma_P^2)`` per particle ``x (N, >=2)`` (Lee 2009, Eq. 2.16); ``variance``
        overrides :meth:`variance` (a caller that has the projected variances of all pairs)."""
        v = np.asarray(z, float)
        zp = projected_angles(v[0], v[1])[PLANES.index(self.plane)]
        parts = np.asarray(x, float)
        r = self.sensor.plane_bearing_2d(parts[:, 0], parts[:, 1], self.plane) - zp
        wrap_angle_inplace(r)
        var = self.variance(v) if variance is None else variance
        return np.asarray(-0.5 * r * r / var)


@dataclass(frozen=True)
class DoaCone:
    """Both angles of a :class:`DoaSensor3D` against 3-D particles ``x (N, >=3)``."""

    sensor: DoaSensor3D

    def log_likelihood(self, z: ArrayLike, x: ArrayLike) -> Array:
        v = np.asarray(z, float)
        theta, phi = self.sensor.angles(np.asarray(x, float)[:, :3])
        dth = wrap_angle_inplace(theta - v[0])
        dph = phi - v[1]
        return np.asarray(-0.5 * (dth * dth + dph * dph) / self.sensor.sigma**2)
