"""A camera detection mapped to the ground plane, weighted by its distance (Lee 2009, Ch. 4).

Camera ``j`` reports the object's image position ``l^j``; its homography ``G_j`` (the text's
"perspective model") maps it to the ground plane, ``g^j = G_j l^j``. The detection's quality for
a ground position ``x`` -- the predicted position in Lee 2009 -- is the Gaussian kernel

    W^j(x) = exp(-|g^j - x|^2 / (2 sigma^2))                                   (Eq. 4.20)

and as a sensor model ``log_likelihood(z, x) = log W`` over particle arrays ``x (..., >= 2)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .camera_geometry import apply_homography

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class GroundPlaneDetection:
    """Camera ``sensor_id`` with image-to-ground homography ``homography`` (3x3); ``sigma2`` the
    kernel's ``sigma^2`` (ground units squared)."""

    sensor_id: str
    homography: Array
    sigma2: float = 1.0

    def ground(self, z: ArrayLike) -> Array:
        """Image position(s) ``(..., 2)`` on the ground plane: ``g = G l``."""
        return apply_homography(self.homography, z)

    def image(self, ground: ArrayLike) -> Array:
        """Ground point(s) back in the image: ``G^-1 g``."""
        return apply_homography(np.linalg.inv(np.asarray(self.homography, float)), ground)

    def log_likelihood(self, z: ArrayLike, x: ArrayLike) -> Array:
        """``log W = -|G z - x|^2 / (2 sigma^2)`` for positions ``x (..., >= 2)``."""
        d = self.ground(z) - np.asarray(x, float)[..., :2]
        return np.asarray(-np.sum(d * d, axis=-1) / (2.0 * self.sigma2))

    def quality(self, z: ArrayLike, x: ArrayLike) -> Array:
        """``W`` in ``[0, 1]`` (Lee 2009, Eq. 4.20)."""
        return np.asarray(np.exp(self.log_likelihood(z, x)))
