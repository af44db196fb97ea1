"""An ellipsoidal target seen by a pinhole camera (Kushwaha 2010, Ch. V, Eqs. 63-72).

The target is the ellipsoid ``{p : (p - c)^T M (p - c) <= 1}`` with ``M = R(q) A R(q)^T`` and
``A = diag(1/l^2, 1/w^2, 1/h^2)`` (Eq. 65; ``l, w, h`` are semi-axes). Its image through
``P = K [R | -R C]`` is the ellipse ``{y : (y - y_c)^T B (y - y_c) <= 1}``, found exactly from
the dual quadric: ``C* = P Q* P^T`` (the region of Eqs. 69 and 75). Quaternions are scalar-last
``[q1, q2, q3, q4]`` as in Eq. 72.

Everything is vectorised over leading axes of the positions and quaternions.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ShapeError, invalid
from .camera_geometry import PinholeCamera

Array = NDArray[np.float64]


def quaternion_to_rotation(q: ArrayLike) -> Array:
    """Rotation matrices ``(..., 3, 3)`` of unit quaternions ``(..., 4)`` (Kushwaha 2010, Eq. 72)."""
    qa = np.asarray(q, float)
    qa = qa / np.linalg.norm(qa, axis=-1, keepdims=True)
    q1, q2, q3, q4 = np.moveaxis(qa, -1, 0)
    rows = [
        [1 - 2 * q2**2 - 2 * q3**2, 2 * q1 * q2 - 2 * q3 * q4, 2 * q1 * q3 + 2 * q2 * q4],
        [2 * q1 * q2 + 2 * q3 * q4, 1 - 2 * q1**2 - 2 * q3**2, 2 * q2 * q3 - 2 * q1 * q4],
        [2 * q1 * q3 - 2 * q2 * q4, 2 * q2 * q3 + 2 * q1 * q4, 1 - 2 * q1**2 - 2 * q2**2],
    ]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def axis_angle_quaternion(axis: ArrayLike, angle: ArrayLike) -> Array:
    """Scalar-last quaternion of a rotation by ``angle`` about ``axis`` (Kushwaha 2010, Eq. 78)."""
    a = np.asarray(axis, float)
    n = np.linalg.norm(a, axis=-1, keepdims=True)
    a = np.where(n > 1e-12, a / np.maximum(n, 1e-12), np.array([0.0, 0.0, 1.0]))
    half = 0.5 * np.asarray(angle, float)[..., None]
    return np.concatenate([a * np.sin(half), np.cos(half)], axis=-1)


def rotation_to_quaternion(R: ArrayLike) -> Array:
    """Scalar-last unit quaternion of a rotation matrix ``(3, 3)`` (inverse of Eq. 72)."""
    m = np.asarray(R, float)
    tr = np.trace(m)
    if tr > 0:
        s = 2.0 * np.sqrt(1.0 + tr)
        q = [(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, 0.25 * s]
    else:
        i = int(np.argmax(np.diag(m)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * np.sqrt(max(1.0 + m[i, i] - m[j, j] - m[k, k], 1e-12))
        q = [0.0, 0.0, 0.0, (m[k, j] - m[j, k]) / s]
        q[i] = 0.25 * s
        q[j] = (m[j, i] + m[i, j]) / s
        q[k] = (m[k, i] + m[i, k]) / s
    out = np.asarray(q, float)
    return out / np.linalg.norm(out)


def quaternion_multiply(p: ArrayLike, q: ArrayLike) -> Array:
    """Hamilton product ``p q`` of scalar-last quaternions (rotation ``q`` first, then ``p``)."""
    p = np.asarray(p, float)
    q = np.asarray(q, float)
    pv, pw = p[..., :3], p[..., 3:]
    qv, qw = q[..., :3], q[..., 3:]
    v = pw * qv + qw * pv + np.cross(pv, qv)
    w = pw * qw - np.sum(pv * qv, axis=-1, keepdims=True)
    return np.concatenate([v, w], axis=-1)


def ellipsoid_matrix(semi_axes: ArrayLike, q: ArrayLike) -> Array:
    """``M = R(q) A R(q)^T`` with ``A = diag(1/l^2, 1/w^2, 1/h^2)`` (Kushwaha 2010, Eq. 65)."""
    s = np.asarray(semi_axes, float)
    if s.shape != (3,) or np.any(s <= 0):
        raise ShapeError(invalid("semi_axes", s.tolist(), "three positive lengths (m)"))
    R = quaternion_to_rotation(q)
    return np.einsum("...ij,j,...kj->...ik", R, 1.0 / s**2, R)


@lru_cache(maxsize=64)
def _shape_matrix_of(semi_axes: tuple[float, ...], q_bytes: bytes) -> Array:
    m = ellipsoid_matrix(semi_axes, np.frombuffer(q_bytes, dtype=np.float64))
    m.setflags(write=False)
    return m


def shape_matrix(semi_axes: ArrayLike, q: ArrayLike) -> Array:
    """:func:`ellipsoid_matrix`, remembered for the last few single orientations ``(4,)``: a
    tracker's step asks for the same ``M`` once per camera and per likelihood (read-only)."""
    qa = np.asarray(q, dtype=np.float64)
    if qa.shape != (4,):
        return ellipsoid_matrix(semi_axes, qa)
    axes = tuple(float(a) for a in np.asarray(semi_axes, dtype=np.float64).ravel())
    return _shape_matrix_of(axes, qa.tobytes())


def project_ellipsoid(P: ArrayLike, centre: ArrayLike, M: ArrayLike) -> tuple[Array, Array]:
    """Exact image ``(y_c, B)`` of the ellipsoid ``(p - c)^T M (p - c) <= 1`` through ``P``.

    Dual quadric ``Q* = [[M^-1 - c c^T, -c], [-c^T, -1]]`` (the inverse of the point quadric up to
    scale), dual conic ``C* = P Q* P^T``; the conic ``C = (C*)^-1`` in centre form gives ``y_c``
    and ``B`` (spec Sec. 2.9). ``centre`` ``(..., 3)``, ``M`` ``(..., 3, 3)``; returns
    ``(..., 2)`` and ``(..., 2, 2)``. Points behind the camera give NaN.
    """
    p = np.asarray(P, float)
    c = np.asarray(centre, float)
    m = np.asarray(M, float)
    one_inverse = np.linalg.inv(m) if m.ndim == 2 else None  # one shape for every centre
    c, m = np.broadcast_arrays(c[..., None, :], m)
    c = c[..., 0, :]
    minv = np.linalg.inv(m) if one_inverse is None else np.broadcast_to(one_inverse, m.shape)
    q = np.empty((*c.shape[:-1], 4, 4))
    q[..., :3, :3] = minv - c[..., :, None] * c[..., None, :]
    q[..., :3, 3] = -c
    q[..., 3, :3] = -c
    q[..., 3, 3] = -1.0
    dual = np.einsum("ij,...jk,lk->...il", p, q, p)
    conic = np.linalg.inv(dual)
    # A point conic C and -C are the same conic; pick the sign that makes C_2 positive definite
    sign = np.sign(conic[..., 0, 0])[..., None, None]
    conic = conic * np.where(sign == 0, 1.0, sign)
    c2 = conic[..., :2, :2]
    c1 = conic[..., :2, 2]
    c0 = conic[..., 2, 2]
    yc = -np.linalg.solve(c2, c1[..., None])[..., 0]
    scale = np.einsum("...i,...i->...", c1, -yc) - c0
    B = c2 / scale[..., None, None]
    depth = np.einsum("j,...j->...", p[2, :3], c) + p[2, 3]
    bad = (depth <= 0) | (scale <= 0)
    yc = np.where(bad[..., None], np.nan, yc)
    B = np.where(bad[..., None, None], np.nan, B)
    return yc, B


def ellipse_area(B: ArrayLike) -> Array:
    """Area ``pi / sqrt(det B)`` of the ellipse ``y^T B y <= 1`` (pixels^2); NaN stays NaN."""
    return np.pi / np.sqrt(np.linalg.det(np.asarray(B, float)))


def look_at(centre: ArrayLike, target: ArrayLike, up: ArrayLike = (0.0, 0.0, 1.0)) -> Array:
    """World-to-camera rotation (rows: right, down, forward) of a camera at ``centre`` looking at
    ``target`` with zero roll (spec Sec. 2.9, the look-at form of ``R_x R_y R_0``)."""
    f = np.asarray(target, float) - np.asarray(centre, float)
    f = f / np.linalg.norm(f)
    right = np.cross(f, np.asarray(up, float))
    if np.linalg.norm(right) < 1e-9:  # looking straight up or down
        right = np.cross(f, np.array([0.0, 1.0, 0.0]))
    right = right / np.linalg.norm(right)
    down = np.cross(f, right)
    return np.vstack([right, down, f])


@dataclass(frozen=True)
class EllipsoidCamera:
    """A smart camera of the network: a pinhole camera and the rule that decides when it takes part.

    A camera *participates* for a hypothesised target when the projected centre is inside the
    image, the target is in front of it, and the projected ellipse covers at least ``min_area``
    pixels (spec Sec. 2.9: otherwise its factor in the network similarity is 1).
    """

    sensor_id: str
    camera: PinholeCamera
    min_area: float = 12.0

    @cached_property
    def P(self) -> Array:
        """The camera matrix, computed once (the camera does not move; read-only)."""
        p = self.camera.P
        p.setflags(write=False)
        return p

    @property
    def centre(self) -> Array:
        return self.camera.centre

    @property
    def focal(self) -> float:
        return float(self.camera.K[0, 0])

    @property
    def size(self) -> tuple[int, int]:
        return self.camera.width, self.camera.height

    def project(self, x: ArrayLike) -> Array:
        """Pixels ``(..., 2)`` of 3-D points ``(..., 3)``."""
        return self.camera.project(x)

    def ellipse(self, x: ArrayLike, q: ArrayLike, semi_axes: ArrayLike) -> tuple[Array, Array]:
        """``(y_c, B)`` of the target at ``x`` ``(..., 3)`` with orientation ``q``."""
        return project_ellipsoid(self.P, x, shape_matrix(semi_axes, q))

    def participates(self, yc: ArrayLike, B: ArrayLike) -> NDArray[np.bool_]:
        """Whether a projected ellipse ``(y_c, B)`` is usable in this camera."""
        yc = np.asarray(yc, float)
        w, h = self.size
        with np.errstate(invalid="ignore"):
            area = ellipse_area(B)
            inside = (yc[..., 0] >= 0) & (yc[..., 0] < w) & (yc[..., 1] >= 0) & (yc[..., 1] < h)
            return inside & (area >= self.min_area) & np.isfinite(area)

    def ray(self, pixels: ArrayLike) -> Array:
        """Unit world directions ``(..., 3)`` of the rays through ``pixels`` ``(..., 2)``."""
        uv = np.asarray(pixels, float)
        k = self.camera.K
        xn = (uv[..., 0] - k[0, 2]) / k[0, 0]
        yn = (uv[..., 1] - k[1, 2]) / k[1, 1]
        d = np.stack([xn, yn, np.ones_like(xn)], axis=-1) @ self.camera.R
        return d / np.linalg.norm(d, axis=-1, keepdims=True)

    def depth(self, x: ArrayLike) -> Array:
        """Depth along the optical axis of points ``(..., 3)``."""
        return self.camera.depth(x)


def intersect_rays(origins: ArrayLike, directions: ArrayLike) -> Array:
    """Least-squares point closest to rays ``o_n + t d_n`` (the baseline P's 3-D position).

    Solves ``sum_n (I - d_n d_n^T) x = sum_n (I - d_n d_n^T) o_n``; needs two non-parallel rays.
    """
    o = np.asarray(origins, float)
    d = np.asarray(directions, float)
    d = d / np.linalg.norm(d, axis=-1, keepdims=True)
    proj = np.eye(3) - d[:, :, None] * d[:, None, :]
    A = proj.sum(0)
    b = np.einsum("nij,nj->i", proj, o)
    return np.linalg.lstsq(A, b, rcond=None)[0]
