"""A smart camera's appearance likelihood: how well a frame's features match a target hypothesis.

The measurement of camera ``n`` is a :class:`~fusetrack.sensors.appearance.FeatureImage`; the
hypotheses are arrays of particles. :class:`AppearanceCamera` gives, for the ellipsoidal target
of Kushwaha 2010 (Ch. V):

* ``log_likelihood(z, x, q)``: ``log rho_n(x_i)`` of 3-D positions ``x`` ``(M, 3)`` -- the
  target's ellipse projected at each position, compared with the view it shows the camera
  (Eqs. 71, 74-76, 81);
* ``log_likelihood_pixels(z, y, x0, q)``: ``log rho`` of image-plane particles ``y`` ``(M, 2)``
  -- the ellipse predicted at ``x0`` moved to each pixel (Alg. 3, Eqs. 94-98);
* ``view_similarities(z, x, q)``: ``rho_j`` of one position against every reference view
  ``j``, the evidence on the orientation (input of Eq. 77).

``rho`` is floored at ``RHO_FLOOR`` so that a region outside the image is unlikely, not
impossible. :func:`colour_log_likelihood` is Perez et al.'s colour likelihood
``-lambda (1 - rho_HS)`` of pixel particles against a reference histogram (the baseline P).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .appearance import N_HS, AppearanceModel, FeatureImage, bhattacharyya, region_histograms
from .ellipsoid_camera import EllipsoidCamera, quaternion_to_rotation

Array = NDArray[np.float64]

RHO_FLOOR = 1e-3


@dataclass(frozen=True)
class AppearanceCamera:
    """One camera of the network, the target's multi-view appearance and its semi-axes (m)."""

    camera: EllipsoidCamera
    model: AppearanceModel
    semi_axes: tuple[float, float, float]

    @property
    def sensor_id(self) -> str:
        return self.camera.sensor_id

    def participates(self, x: ArrayLike, q: ArrayLike) -> bool:
        """Whether the target at ``x`` ``(3,)`` with orientation ``q`` is usable in the image."""
        yc, B = self.camera.ellipse(x, q, self.semi_axes)
        return bool(self.camera.participates(yc, B))

    def log_likelihood(self, z: FeatureImage, x: Array, q: Array) -> Array:
        """``log max(rho_n(x_i), RHO_FLOOR)`` for positions ``x`` ``(M, 3)`` (Eqs. 71, 74-76, 81)."""
        cam = self.camera
        yc, B = cam.ellipse(x, q, self.semi_axes)
        view = self.model.view_index(cam.centre, x, quaternion_to_rotation(q))
        rho = self.model.similarity(z, yc, B, view)
        return np.asarray(np.log(np.maximum(rho, RHO_FLOOR)), dtype=np.float64)

    def log_likelihood_pixels(self, z: FeatureImage, pixels: Array, x0: Array, q: Array) -> Array:
        """``log max(rho, RHO_FLOOR)`` of image-plane particles ``pixels`` ``(M, 2)``: the
        ellipse and view predicted at ``x0`` ``(3,)``, centred on each pixel (Eqs. 94-98)."""
        cam = self.camera
        _, B = cam.ellipse(x0, q, self.semi_axes)
        view = self.model.view_index(cam.centre, x0, quaternion_to_rotation(q))
        shapes = np.broadcast_to(B, (len(pixels), 2, 2))
        rho = self.model.similarity(z, pixels, shapes, view)
        return np.asarray(np.log(np.maximum(rho, RHO_FLOOR)), dtype=np.float64)

    def view_similarities(self, z: FeatureImage, x: Array, q: Array) -> Array:
        """``rho_j`` ``(J,)`` of the target's region at ``x`` ``(3,)`` against every reference
        view ``j`` (input of Eq. 77)."""
        yc, B = self.camera.ellipse(x, q, self.semi_axes)
        return self.model.all_views(z, yc, B)

    def predicted_region(self, x: Array, q: Array) -> tuple[Array, Array]:
        """``(y_c, B)``: the target's ellipse in the image."""
        return self.camera.ellipse(x, q, self.semi_axes)


def colour_log_likelihood(
    z: FeatureImage, pixels: Array, shape: Array, reference: Array, lam: float = 20.0
) -> Array:
    """Perez et al.'s colour likelihood ``-lambda (1 - rho_HS)`` of the fixed ellipse ``shape``
    ``(2, 2)`` centred on each pixel ``(M, 2)`` against the ``reference`` HS histogram."""
    B = np.broadcast_to(shape, (len(pixels), 2, 2))
    p = region_histograms(z.hs, pixels, B, N_HS)
    return np.asarray(-lam * (1.0 - bhattacharyya(p, reference)), dtype=np.float64)


def reference_histogram(z: FeatureImage, centre: Array, shape: Array) -> Array:
    """The HS histogram of one region, a colour tracker's reference (Perez et al.)."""
    return region_histograms(z.hs, centre, shape, N_HS)[0]
