"""Pinhole camera geometry for a camera watching people on a floor (Nott 2009, Sec. 3.1).

A world point ``(X, Y, Z)`` (metres, ``Z`` up, ``Z = 0`` the floor) projects to the pixel
``(u, v)`` (column, row; ``v`` grows downwards) through the 3x4 camera matrix ``P``::

    [a, b, c]^T = P [X, Y, Z, 1]^T,   (u, v) = (a / c, b / c)      (Nott 2009, Eqs. 3.2-3.3)

On a horizontal plane ``Z = h`` this is a homography of the plane's ``(X, Y)``::

    H(h) = [P_1, P_2, h P_3 + P_4]          (columns of P; Nott 2009, Eqs. 3.4-3.6 for h = 0)

``H(0)`` is the ground-plane (foot) homography, ``H(h)`` at the person's height the head-plane
homography (the thesis only says "a different homography"; this is its form in terms of P).

:class:`PinholeCamera` is fusetrack's one camera model: built from ``K, R, C`` (Nott 2009) or from
a pose (position, yaw, downward pitch, field of view; :meth:`PinholeCamera.from_pose`, the road
cameras of Kushwaha 2010), it renders the simulated scenes in :mod:`fusetrack.world`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ConfigError, ShapeError, invalid

Array = NDArray[np.float64]


def camera_matrix(K: ArrayLike, R: ArrayLike, centre: ArrayLike) -> Array:
    """``P = K [R | -R C]`` for intrinsics ``K`` (3x3), rotation ``R`` (world to camera), centre ``C``."""
    k = np.asarray(K, float)
    r = np.asarray(R, float)
    c = np.asarray(centre, float)
    if k.shape != (3, 3) or r.shape != (3, 3) or c.shape != (3,):
        raise ShapeError(
            invalid("(K, R, centre) shapes", (k.shape, r.shape, c.shape), "(3,3), (3,3), (3,)")
        )
    return k @ np.hstack([r, (-r @ c)[:, None]])


def look_rotation(tilt_deg: float, pan_deg: float = 0.0) -> Array:
    """World-to-camera rotation of a zero-roll camera looking along ``+Y`` turned by ``pan``
    (anticlockwise, degrees) and tilted down by ``tilt``: rows = right, down, forward."""
    t, p = np.deg2rad(tilt_deg), np.deg2rad(pan_deg)
    return _zero_roll(-np.sin(p), np.cos(p), np.cos(t), np.sin(t))


def yaw_pitch_rotation(yaw: float, pitch: float) -> Array:
    """World-to-camera rotation of a zero-roll camera looking along ``yaw`` (rad, CCW from ``+X``)
    and tilted down by ``pitch`` (rad): rows = right, down, forward."""
    return _zero_roll(np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch))


def _zero_roll(cos_h: float, sin_h: float, cos_t: float, sin_t: float) -> Array:
    """Rows right, down, forward for the horizontal viewing direction ``(cos_h, sin_h)`` tilted
    down by the angle whose cosine and sine are ``cos_t, sin_t``."""
    fwd = np.array([cos_h * cos_t, sin_h * cos_t, -sin_t])
    right = np.array([sin_h, -cos_h, 0.0])
    down = np.cross(fwd, right)
    return np.vstack([right, down, fwd])


@dataclass(frozen=True)
class PinholeCamera:
    """A calibrated camera: intrinsics ``K``, rotation ``R``, centre ``C`` and the image size."""

    K: Array
    R: Array
    centre: Array
    width: int = 640
    height: int = 480

    @classmethod
    def from_pose(
        cls,
        position: ArrayLike,
        yaw: float,
        pitch: float = np.deg2rad(8.0),
        hfov: float = np.deg2rad(60.0),
        width: int = 320,
        height: int = 240,
    ) -> PinholeCamera:
        """A camera at ``position (x, y, z)`` looking along ``yaw`` (rad, CCW from ``+X``), tilted
        down by ``pitch``, with horizontal field of view ``hfov``, square pixels and the principal
        point at the image centre."""
        focal = (width / 2) / np.tan(hfov / 2)
        K = np.array([[focal, 0.0, width / 2], [0.0, focal, height / 2], [0.0, 0.0, 1.0]])
        centre = np.asarray(position, float)
        return cls(K, yaw_pitch_rotation(yaw, pitch), centre, width, height)

    @property
    def P(self) -> Array:
        return camera_matrix(self.K, self.R, self.centre)

    @property
    def focal(self) -> float:
        """Horizontal focal length in pixels."""
        return float(self.K[0, 0])

    @property
    def hfov(self) -> float:
        """Horizontal field of view (rad)."""
        return float(2 * np.arctan((self.width / 2) / self.K[0, 0]))

    def project(self, points: ArrayLike) -> Array:
        """Pixels ``(..., 2)`` of world points ``(..., 3)`` (Nott 2009, Eqs. 3.2-3.3)."""
        return project_points(self.P, points)

    def depth(self, points: ArrayLike) -> Array:
        """Distance along the optical axis ``(...)`` (positive in front of the camera)."""
        x = np.asarray(points, float)
        return (x - self.centre) @ self.R[2]

    def column_angles(self) -> Array:
        """Bearing of each pixel column relative to the optical axis (CCW positive):
        ``atan((c_x - j - 1/2) / f)`` (spec 003 §2.3 step 5; exact for zero pitch, within a
        fraction of a degree at 8 degrees)."""
        j = np.arange(self.width)
        return np.asarray(np.arctan((self.K[0, 2] - (j + 0.5)) / self.K[0, 0]))


def default_camera() -> PinholeCamera:
    """The spec's reproduction camera (Nott 2009 gives none): 640x480, f = 500 px, centre
    (4.5, -5, 3.5) m, looking along +Y, tilted 15 degrees down, zero roll."""
    K = np.array([[500.0, 0.0, 320.0], [0.0, 500.0, 240.0], [0.0, 0.0, 1.0]])
    return PinholeCamera(K, look_rotation(15.0), np.array([4.5, -5.0, 3.5]))


def project_points(P: ArrayLike, points: ArrayLike) -> Array:
    """``pi(P [X, Y, Z, 1]^T)`` for world points ``(..., 3)``; returns ``(..., 2)``."""
    p = np.asarray(P, float)
    x = np.asarray(points, float)
    h = x @ p[:, :3].T + p[:, 3]
    return h[..., :2] / h[..., 2:3]


def plane_homography(P: ArrayLike, height: float = 0.0) -> Array:
    """``H(h) = [P_1, P_2, h P_3 + P_4]``: the homography of the plane ``Z = h`` into the image."""
    p = np.asarray(P, float)
    if p.shape != (3, 4):
        raise ShapeError(invalid("P.shape", p.shape, "(3, 4)"))
    return np.column_stack([p[:, 0], p[:, 1], height * p[:, 2] + p[:, 3]])


def ground_homography(P: ArrayLike) -> Array:
    """The foot homography ``H_f = [P_1, P_2, P_4]`` (Nott 2009, Eqs. 3.4-3.6)."""
    return plane_homography(P, 0.0)


def apply_homography(H: ArrayLike, xy: ArrayLike) -> Array:
    """``pi(H [x, y, 1]^T)`` for points ``(..., 2)``; returns ``(..., 2)``."""
    h = np.asarray(H, float)
    p = np.asarray(xy, float)
    q = p @ h[:, :2].T + h[:, 2]
    return q[..., :2] / q[..., 2:3]


def invert_homography(H: ArrayLike) -> Array:
    """``H^-1`` normalised to ``[2, 2] = 1``, or :class:`ConfigError` when ``H`` is singular."""
    h = np.asarray(H, float)
    if h.shape != (3, 3) or not np.all(np.isfinite(h)):
        raise ConfigError(invalid("homography", h.tolist(), "a finite 3x3 matrix"))
    s = np.linalg.svd(h, compute_uv=False)
    if s[-1] <= 1e-12 * s[0]:
        raise ConfigError(
            invalid("homography", np.round(h, 6).tolist(), "a non-singular 3x3 matrix (rank 3)")
        )
    inv = np.linalg.inv(h)
    return inv / inv[2, 2] if abs(inv[2, 2]) > 1e-15 else inv


def back_project(H: ArrayLike, uv: ArrayLike) -> Array:
    """Floor points ``(..., 2)`` seen at pixels ``uv`` ``(..., 2)`` through the plane homography ``H``."""
    return apply_homography(invert_homography(H), uv)


__all__ = [
    "PinholeCamera",
    "apply_homography",
    "back_project",
    "camera_matrix",
    "default_camera",
    "ground_homography",
    "invert_homography",
    "look_rotation",
    "plane_homography",
    "project_points",
    "yaw_pitch_rotation",
]
