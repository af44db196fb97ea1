"""The noisy perspective camera of Ercan et al. 2013 (Sec. 3.1, Eqs. 1-4, Appendix B).

A camera on the ground plane at ``c`` with optical axis at angle ``yaw`` reduces a frame to one
number: the horizontal image coordinate of the object,

    z = f h(x) / d(x) + v,                                      # Ercan et al. 2013, Eq. 1
    d(x) = e . (x - c),  e = [cos yaw, sin yaw]   (depth along the optical axis)
    h(x) = n . (x - c),  n = [-sin yaw, cos yaw]  (lateral offset, positive anticlockwise)

(the paper writes these with theta = pi + yaw, Appendix B). The noise collects the camera's
yaw error (sigma_theta), its position error (sigma_pos per axis) and read noise (sigma_read, px):

    var(v | x) = f^2 (1 + h^2/d^2)^2 s_th^2 + f^2 (h^2 + d^2)/d^4 s_pos^2 + s_read^2   # Eq. 2

(Appendix B's last line prints (1 + h^2/d^2) without the square; the derivatives it lists give
the square, as Eq. 2 has it.) The object is in the field of view when ``d > 0`` and
``|h/d| <= tan(fov/2)``; an unseen object gives ``NaN`` (Eq. 4).

:class:`CameraArray` holds N cameras as arrays so that the tracker and the camera selection work
on every camera and every particle at once; :class:`PerspectiveCamera` is one camera with the
usual sensor-model methods.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ConfigError, ShapeError, check_positive, invalid

Array = NDArray[np.float64]

MIN_DEPTH = 1e-6
"""Depths below this (behind or beside the camera) are clamped when a formula divides by ``d``;
such points are outside every field of view, so the clamp only keeps arithmetic finite."""

DEFAULT_IMAGE_WIDTH = 640.0
"""Image width (px) used for the focal length when none is given: f = (W/2) / tan(fov/2)."""


@numba.njit(cache=True, nogil=True)
def _depth_lateral_kernel(
    x: np.ndarray, positions: np.ndarray, c: np.ndarray, s: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - jit
    """``d, h`` ``(L, N)`` of points ``x (L, 2)``: :meth:`CameraArray.depth_lateral`'s arithmetic
    in one pass (NumPy strides over the ``(L, N, 2)`` differences several times)."""
    L, N = x.shape[0], positions.shape[0]
    d, h = np.empty((L, N)), np.empty((L, N))
    for l in range(L):
        for i in range(N):
            r0 = x[l, 0] - positions[i, 0]
            r1 = x[l, 1] - positions[i, 1]
            d[l, i] = c[i] * r0 + s[i] * r1
            h[l, i] = -s[i] * r0 + c[i] * r1
    return d, h


@numba.njit(cache=True, nogil=True)
def _noise_var_kernel(
    d: np.ndarray, h: np.ndarray, f2: np.ndarray, st2: np.ndarray, sp2: np.ndarray, sr2: np.ndarray
) -> np.ndarray:  # pragma: no cover - jit
    """Eq. 2 for ``d, h`` ``(L, N)``: :meth:`CameraArray.noise_var_of`'s arithmetic, term by term
    in its order, in one pass."""
    L, N = d.shape
    out = np.empty((L, N))
    for l in range(L):
        for i in range(N):
            dd = d[l, i]
            dd = dd if (dd >= MIN_DEPTH or dd != dd) else MIN_DEPTH  # np.maximum keeps NaN
            q = h[l, i] / dd
            a = 1.0 + q * q
            out[l, i] = f2[i] * (a * a) * st2[i] + f2[i] * a / (dd * dd) * sp2[i] + sr2[i]
    return out


def focal_for(fov: float, image_width: float = DEFAULT_IMAGE_WIDTH) -> float:
    """Focal length in pixels that maps the field of view onto the image width (spec §7.4)."""
    return float(image_width / 2 / math.tan(fov / 2))


@dataclass(frozen=True)
class PerspectiveCamera:
    """One calibrated camera: position (2,), yaw (rad), fov (rad), focal (px), noise parameters."""

    sensor_id: str
    position: Array
    yaw: float
    fov: float = math.pi / 2
    focal: float | None = None
    sigma_theta: float = 0.01
    sigma_pos: float = 1.0
    sigma_read: float = 2.0
    dim: int = field(default=1, init=False)
    angular: tuple[bool, ...] = field(default=(False,), init=False)

    def __post_init__(self) -> None:
        pos = np.asarray(self.position, dtype=float)
        if pos.shape != (2,) or not np.all(np.isfinite(pos)):
            raise ShapeError(
                f"camera {self.sensor_id!r}: "
                + invalid("position", self.position, "two finite numbers [x, y]")
            )
        if not (0 < float(self.fov) < math.pi):
            raise ConfigError(
                f"camera {self.sensor_id!r}: "
                + invalid("fov", self.fov, "an angle in (0, pi) rad (a perspective camera)")
            )
        if not math.isfinite(float(self.yaw)):
            raise ConfigError(f"camera {self.sensor_id!r}: " + invalid("yaw", self.yaw, "finite"))
        for name in ("sigma_theta", "sigma_pos", "sigma_read"):
            check_positive(
                f"camera {self.sensor_id!r}.{name}", getattr(self, name), allow_zero=True
            )
        f = focal_for(self.fov) if self.focal is None else self.focal
        check_positive(f"camera {self.sensor_id!r}.focal", f)
        object.__setattr__(self, "position", pos)
        object.__setattr__(self, "focal", float(f))
        object.__setattr__(self, "yaw", float(self.yaw))
        object.__setattr__(self, "fov", float(self.fov))

    def as_array(self) -> CameraArray:
        return CameraArray.from_cameras([self])

    def predict(self, x: ArrayLike) -> Array:
        """``f h/d`` (Eq. 1), shape ``(..., 1)``; ``x`` is ``(..., >=2)`` with position first."""
        return self.as_array().image_coordinate(np.asarray(x, float)[..., None, :2])

    def noise_cov(self, x: ArrayLike | None = None) -> Array:
        """``var(v | x)`` of Eq. 2 as ``(..., 1, 1)``; needs ``x`` (the noise depends on it)."""
        if x is None:
            raise ConfigError(
                invalid("x", None, "a position: the perspective camera's noise depends on it")
            )
        var = self.as_array().noise_var(np.asarray(x, float)[..., None, :2])
        return var[..., None]

    def in_fov(self, x: ArrayLike) -> NDArray[np.bool_]:
        return self.as_array().in_fov(np.asarray(x, float)[..., None, :2])[..., 0]

    def log_likelihood(self, z: ArrayLike, x: ArrayLike) -> Array:
        """Gaussian log-density of ``z`` ``(..., 1)`` given ``x`` (Eqs. 1-2)."""
        zz = np.asarray(z, float)
        mean = self.predict(x)
        var = self.noise_cov(x)[..., 0]
        r = zz - mean
        return np.asarray(-0.5 * np.sum(r * r / var + np.log(2 * np.pi * var), axis=-1))

    def simulate(self, x: ArrayLike, rng: np.random.Generator) -> Array:
        """A noisy reading ``(..., 1)``; NaN outside the field of view (occlusions are the world's)."""
        xx = np.asarray(x, float)
        mean = self.predict(xx)
        sd = np.sqrt(self.noise_cov(xx)[..., 0])
        z = mean + sd * rng.standard_normal(mean.shape)
        return np.where(self.in_fov(xx)[..., None], z, np.nan)


@dataclass(frozen=True)
class CameraArray:
    """N cameras as arrays: ``positions (N, 2)``, ``yaws``, ``fovs``, ``focals``, noise ``(N,)``.

    Every method takes positions ``(..., N, 2)`` or ``(..., 1, 2)`` (broadcast against the N
    cameras) and returns ``(..., N)``.
    """

    positions: Array
    yaws: Array
    fovs: Array
    focals: Array
    sigma_theta: Array
    sigma_pos: Array
    sigma_read: Array
    ids: tuple[str, ...]

    @classmethod
    def from_cameras(cls, cameras: Sequence[PerspectiveCamera]) -> CameraArray:
        if len(cameras) == 0:
            raise ConfigError(invalid("cameras", [], "at least one camera"))
        ids = tuple(c.sensor_id for c in cameras)
        if len(set(ids)) != len(ids):
            raise ConfigError(invalid("cameras", ids, "distinct sensor ids"))
        return cls(
            positions=np.array([c.position for c in cameras]),
            yaws=np.array([c.yaw for c in cameras]),
            fovs=np.array([c.fov for c in cameras]),
            focals=np.array([c.focal for c in cameras], dtype=float),
            sigma_theta=np.array([c.sigma_theta for c in cameras]),
            sigma_pos=np.array([c.sigma_pos for c in cameras]),
            sigma_read=np.array([c.sigma_read for c in cameras]),
            ids=ids,
        )

    def __len__(self) -> int:
        return len(self.ids)

    def camera(self, i: int) -> PerspectiveCamera:
        return PerspectiveCamera(
            self.ids[i],
            self.positions[i],
            float(self.yaws[i]),
            float(self.fovs[i]),
            float(self.focals[i]),
            float(self.sigma_theta[i]),
            float(self.sigma_pos[i]),
            float(self.sigma_read[i]),
        )

    def subset(self, index: Sequence[int] | NDArray[np.intp]) -> CameraArray:
        idx = np.asarray(index, dtype=np.intp)
        if idx.size and (idx.min() < 0 or idx.max() >= len(self)):
            raise ConfigError(invalid("camera index", idx.tolist(), f"indices in [0, {len(self)})"))
        return CameraArray(
            self.positions[idx],
            self.yaws[idx],
            self.fovs[idx],
            self.focals[idx],
            self.sigma_theta[idx],
            self.sigma_pos[idx],
            self.sigma_read[idx],
            tuple(self.ids[i] for i in idx),
        )

    @property
    def axes(self) -> Array:
        """Optical axes ``e_i`` ``(N, 2)``."""
        return np.column_stack([np.cos(self.yaws), np.sin(self.yaws)])

    @property
    def normals(self) -> Array:
        """``a_i = n_i = [sin theta_i, -cos theta_i]`` with theta = pi + yaw, ``(N, 2)`` (Eq. 14)."""
        return np.column_stack([-np.sin(self.yaws), np.cos(self.yaws)])

    def depth_lateral(self, x: ArrayLike) -> tuple[Array, Array]:
        """``d_i(x)`` and ``h_i(x)`` (Appendix B), each ``(..., N)``."""
        p = np.asarray(x, float)
        c, s = np.cos(self.yaws), np.sin(self.yaws)
        if p.ndim == 3 and p.shape[1:] == (1, 2):  # points (L, 1, 2): one Numba pass, same bits
            pts = np.ascontiguousarray(p[:, 0, :])
            return _depth_lateral_kernel(pts, np.ascontiguousarray(self.positions, float), c, s)
        rel = p - self.positions
        d = c * rel[..., 0] + s * rel[..., 1]
        h = -s * rel[..., 0] + c * rel[..., 1]
        return d, h

    def in_fov(self, x: ArrayLike) -> NDArray[np.bool_]:
        return self.in_fov_of(*self.depth_lateral(x))

    def in_fov_of(self, d: Array, h: Array) -> NDArray[np.bool_]:
        """:meth:`in_fov` from :meth:`depth_lateral`'s ``d, h`` (computed once, used thrice)."""
        return np.asarray((d > 0) & (np.abs(h) <= np.tan(self.fovs / 2) * d))

    def image_coordinate(self, x: ArrayLike) -> Array:
        """``f_i h_i(x) / d_i(x)`` (Eq. 1) with the depth clamped at :data:`MIN_DEPTH`."""
        d, h = self.depth_lateral(x)
        return np.asarray(self.focals * h / np.maximum(d, MIN_DEPTH))

    def noise_var(self, x: ArrayLike) -> Array:
        """``var(v_i | x)`` (Ercan et al. 2013, Eq. 2), depth clamped at :data:`MIN_DEPTH`."""
        return self.noise_var_of(*self.depth_lateral(x))

    def noise_var_of(self, d: Array, h: Array) -> Array:
        """:meth:`noise_var` from :meth:`depth_lateral`'s ``d, h``."""
        n = len(self.positions)
        if np.ndim(d) == 2 and np.shape(d) == np.shape(h) and np.shape(d)[1] == n:
            per_camera = (
                self.focals**2,
                self.sigma_theta**2,
                self.sigma_pos**2,
                self.sigma_read**2,
            )
            f2, st2, sp2, sr2 = (
                np.ascontiguousarray(np.broadcast_to(v, (n,)), float) for v in per_camera
            )
            return _noise_var_kernel(
                np.ascontiguousarray(d, float), np.ascontiguousarray(h, float), f2, st2, sp2, sr2
            )
        d = np.maximum(d, MIN_DEPTH)
        r2 = (h / d) ** 2
        f2 = self.focals**2
        return np.asarray(
            f2 * (1 + r2) ** 2 * self.sigma_theta**2
            + f2 * (1 + r2) / d**2 * self.sigma_pos**2
            + self.sigma_read**2
        )


def ring_of_cameras(
    positions: ArrayLike,
    yaws_deg: ArrayLike,
    fov_deg: float,
    *,
    sigma_theta: float,
    sigma_pos: float,
    sigma_read: float,
    focal: float | None = None,
    inset: float = 0.01,
) -> CameraArray:
    """Cameras numbered 1..N from positions and yaws in degrees, moved ``inset`` along their axes.

    The inset keeps a camera standing on a wall or in a corner strictly inside the room, so that
    the wall it stands on never counts as blocking its view.
    """
    pos = np.asarray(positions, float)
    yaws = np.deg2rad(np.asarray(yaws_deg, float))
    if pos.ndim != 2 or pos.shape[1] != 2 or len(yaws) != len(pos):
        raise ShapeError(
            invalid("camera positions/yaws", (pos.shape, yaws.shape), "(N, 2) and (N,)")
        )
    cams = [
        PerspectiveCamera(
            f"cam{i + 1}",
            pos[i] + inset * np.array([np.cos(yaws[i]), np.sin(yaws[i])]),
            float(yaws[i]),
            math.radians(fov_deg),
            focal,
            sigma_theta,
            sigma_pos,
            sigma_read,
        )
        for i in range(len(pos))
    ]
    return CameraArray.from_cameras(cams)
