"""A sensor that reports a detection function over its own bearings (Kushwaha 2010, Ch. II).

An acoustic node reports its beam energies sampled at fixed bearings (the piecewise-linear
detection function of Eq. 34); a camera reports a Gaussian mixture over the bearings in its field
of view (Eq. 35). As a sensor model: a :class:`~fusetrack.core.measurement.Measurement` from
this sensor carries the step's detection function, and :meth:`DetectionFunctionSensor.log_likelihood`
weighs particles ``x (..., >= 2)`` by the normalised detection function at their bearing,
``log λ̃(θ(x))`` (one factor of the product over sensors, Eq. 30).

The measurement value is the ``sampling.n`` sampled values (beams) or, for a camera (``sampling``
None), the mixture's weights, means and standard deviations concatenated ``(3k,)``; use
:meth:`DetectionFunctionSensor.mixture_value` to build it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import MeasurementError, invalid
from .detection_function import AngularSampling, interpolate
from .detection_kernel import log_sampled_detection

Array = NDArray[np.float64]


@dataclass(frozen=True)
class DetectionFunctionSensor:
    """One sensor's pose and how its detection function is given.

    ``sampling`` set: the function is sampled at ``sampling``'s bearings (beams, interpolated);
    None: a Gaussian mixture over bearings within the field of view ``fov`` (bearings outside it
    get the neutral value ``1 / fov``). ``floor`` keeps every bearing possible.
    """

    sensor_id: str
    position: tuple[float, float]
    heading: float
    sampling: AngularSampling | None = None
    fov: float = 2 * np.pi
    floor: float = 1e-3

    @staticmethod
    def mixture_value(weights: ArrayLike, means: ArrayLike, sigmas: ArrayLike) -> Array:
        """A camera's measurement value: weights, means and sigmas concatenated."""
        return np.concatenate([np.asarray(v, float).reshape(-1) for v in (weights, means, sigmas)])

    def bearing(self, xy: ArrayLike) -> Array:
        """Bearing of positions ``(..., >= 2)`` relative to the heading, in ``[-pi, pi)``."""
        p = np.asarray(xy, float)
        theta = (
            np.arctan2(p[..., 1] - self.position[1], p[..., 0] - self.position[0]) - self.heading
        )
        return np.asarray(np.mod(theta + np.pi, 2 * np.pi) - np.pi)

    def likelihood(self, z: ArrayLike, xy: ArrayLike) -> Array:
        """The normalised detection function ``λ̃(θ(x))`` (plus the floor) at positions ``xy``."""
        theta = self.bearing(xy)
        v = np.asarray(z, float)
        if self.sampling is None:
            if v.ndim != 1 or v.size % 3:
                raise MeasurementError(
                    invalid("value", v.shape, "(3k,): mixture weights, means, sigmas")
                )
            a, mu, sd = np.split(v, 3)
            zz = (theta[..., None] - mu) / sd
            dens = (a * np.exp(-0.5 * zz * zz) / (np.sqrt(2 * np.pi) * sd)).sum(-1)
            neutral = 1.0 / self.fov
            dens = np.where(np.abs(theta) <= self.fov / 2, dens, neutral)
            return np.asarray(dens + self.floor * neutral)
        v = v - v.min()
        total = v.sum()
        if not total > 0:
            return np.ones(theta.shape)
        density = v / (total * self.sampling.step)  # a density over the sensor's bearings
        return np.asarray(interpolate(self.sampling, density, theta) + self.floor / (2 * np.pi))

    def log_likelihood(self, z: ArrayLike, x: ArrayLike) -> Array:
        """``log λ̃(θ(x))`` for particles ``x (..., >= 2)`` (Kushwaha 2010, Eq. 30 factor).

        A sampled function (beams) takes one pass of :func:`.detection_kernel.log_sampled_detection`
        (the same numbers as ``log(likelihood(z, x))``)."""
        xy = np.asarray(x, float)[..., :2]
        v = np.asarray(z, float)
        if self.sampling is None or v.ndim != 1 or xy.ndim < 1 or xy.shape[-1] != 2:
            return np.log(np.maximum(self.likelihood(v, xy), 1e-300))
        self.sampling.check(v)
        v = v - v.min()
        total = v.sum()
        if not total > 0:
            return np.zeros(xy.shape[:-1])
        s = self.sampling
        flat = np.ascontiguousarray(xy.reshape(-1, 2))
        out = log_sampled_detection(
            flat,
            float(self.position[0]),
            float(self.position[1]),
            float(self.heading),
            float(s.start),
            float(s.step),
            v / (total * s.step),
            bool(s.periodic),
            float(self.floor / (2 * np.pi)),
        )
        return out.reshape(xy.shape[:-1])
