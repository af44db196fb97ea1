r"""A camera that sees a person as a vertical rectangle on the floor (Nott 2009, Sec. 3.1.1).

The person's state is ``s = [x_f, y_f, h, w, vx, vy]`` (foot position, height, width, foot
velocity; see :mod:`fusetrack.motion.walking_person`). The camera reports pixels of points of
the rectangle that stands on the foot, is ``h`` tall and ``w`` wide along the horizontal unit
direction ``e``. Three measurement variants (Nott 2009, Eq. 3.9, ``y = f(s) + v``):

* ``"corners"`` (V8, the thesis's four corners of the bounding box)::

      BL = p - (w/2) e, BR = p + (w/2) e  at Z = 0;   TL, TR the same at Z = h
      f(s) = [pi(H_f BL), pi(H_f BR), pi(H_h(h) TL), pi(H_h(h) TR)]        (8 values)

  ordered ``(u, v)`` of BL, BR, TL, TR, which is ``(u_min, v_max, u_max, v_max, u_min, v_min,
  u_max, v_min)`` of an axis-aligned blob bounding box for a zero-roll camera;
* ``"head_foot"`` (V4, the thesis's Bottom Point / Top Point): ``[pi(H_f p), pi(H_h(h) p)]``;
* ``"foot"`` (V2, what the thesis's real experiments tracked): ``pi(H_f p)``.

``H_f`` is the ground homography and ``H_h(h) = [P_1, P_2, h P_3 + P_4]`` the head-plane
homography; with only fitted homographies (no ``P``), the fitted head homography is used and
``h`` does not enter ``f`` (it is then unobservable). Noise ``v ~ N(0, sigma_px^2 I)`` (Nott
2009, Sec. 5.1: "1 pixel each along the rows and columns").

The Jacobian is analytic (the thesis only names it ``D = f'``, Eqs. 3.27-3.31): for a world point
with ``c = P_3 [X, Y, Z, 1]``, ``du/dX = (p11 - u p31) / c`` and likewise for ``Y``, ``Z`` and ``v``;
a corner at ``p +- (w/2) e`` has ``d/dw = +-(e_X d/dX + e_Y d/dY) / 2``; the head rows have
``d/dh = d/dZ``; the velocity columns are zero.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from ..core import ConfigError, ShapeError, check_positive, invalid
from .camera_geometry import Array

Variant = Literal["corners", "head_foot", "foot"]
VARIANT_DIMS = {"corners": 8, "head_foot": 4, "foot": 2}
_X, _Y, _H, _W = 0, 1, 2, 3


def _as_projection(H: Array) -> Array:
    """A plane homography written as a 3x4 projection with a zero ``Z`` column."""
    return np.column_stack([H[:, 0], H[:, 1], np.zeros(3), H[:, 2]])


@dataclass(frozen=True, eq=False)
class HomographyCamera:
    """Measurement model of the camera in Nott (2009); see the module docstring.

    Give either ``camera_matrix`` (3x4; the head plane follows the state's height) or
    ``foot_homography`` (3x3) and, for the head rows, ``head_homography`` (3x3, fitted for the
    subject's own head plane). ``width_direction`` is the rectangle's horizontal direction ``e``
    (normalised; default the world x axis, perpendicular to the default camera's view).
    ``image_size = (width, height)`` in pixels: a person whose points leave the image, or lie
    behind the camera, is not detected.
    """

    sensor_id: str
    camera_matrix: ArrayLike | None = None
    foot_homography: ArrayLike | None = None
    head_homography: ArrayLike | None = None
    variant: Variant = "corners"
    sigma_px: float = 1.0
    width_direction: ArrayLike = (1.0, 0.0)
    image_size: tuple[int, int] = (640, 480)
    detection_prob: float = 1.0
    position_index: tuple[int, ...] = (0, 1)

    dim: int = field(init=False, repr=False)
    angular: tuple[bool, ...] = field(init=False, repr=False)
    _foot: Array = field(init=False, repr=False)
    _head: Array | None = field(init=False, repr=False)
    _e: Array = field(init=False, repr=False)

    def __post_init__(self) -> None:
        owner = f"HomographyCamera({self.sensor_id!r})"
        if not isinstance(self.sensor_id, str) or not self.sensor_id:
            raise ConfigError(invalid("sensor_id", self.sensor_id, "a non-empty string"))
        if self.variant not in VARIANT_DIMS:
            raise ConfigError(
                f"{owner}: " + invalid("variant", self.variant, f"one of {list(VARIANT_DIMS)}")
            )
        head: Array | None
        if self.camera_matrix is not None:
            p = np.asarray(self.camera_matrix, float)
            if p.shape != (3, 4) or not np.all(np.isfinite(p)):
                raise ConfigError(
                    f"{owner}: " + invalid("camera_matrix", p.tolist(), "a finite 3x4 matrix")
                )
            foot = p.copy()
            head = p.copy()
        elif self.foot_homography is not None:
            hf = np.asarray(self.foot_homography, float)
            if hf.shape != (3, 3) or not np.all(np.isfinite(hf)):
                raise ConfigError(
                    f"{owner}: " + invalid("foot_homography", hf.tolist(), "a finite 3x3 matrix")
                )
            foot = _as_projection(hf)
            head = None
            if self.head_homography is not None:
                hh = np.asarray(self.head_homography, float)
                if hh.shape != (3, 3) or not np.all(np.isfinite(hh)):
                    raise ConfigError(
                        f"{owner}: "
                        + invalid("head_homography", hh.tolist(), "a finite 3x3 matrix")
                    )
                head = _as_projection(hh)
        else:
            raise ConfigError(
                f"{owner}: "
                + invalid("camera_matrix", None, "a 3x4 camera matrix, or a foot_homography")
            )
        if self.variant != "foot" and head is None:
            raise ConfigError(
                f"{owner}: "
                + invalid(
                    "head_homography",
                    None,
                    f"a 3x3 matrix for variant={self.variant!r} (or use camera_matrix)",
                )
            )
        e = np.asarray(self.width_direction, float)
        if e.shape != (2,) or not np.isfinite(e).all() or np.linalg.norm(e) == 0:
            raise ConfigError(
                f"{owner}: "
                + invalid("width_direction", self.width_direction, "a nonzero 2-vector")
            )
        check_positive("sigma_px", self.sigma_px)
        for a in (foot, head):
            if a is not None:
                a.flags.writeable = False
        object.__setattr__(self, "_foot", foot)
        object.__setattr__(self, "_head", head)
        object.__setattr__(self, "_e", e / np.linalg.norm(e))
        object.__setattr__(self, "dim", VARIANT_DIMS[self.variant])
        object.__setattr__(self, "angular", (False,) * self.dim)
        object.__setattr__(self, "sigma_px", float(self.sigma_px))

    # -- geometry -----------------------------------------------------------------------------

    def _points(self, x: Array) -> list[tuple[Array, float, Array, Array, Array]]:
        """The measured points: ``(P, w_sign, X, Y, Z)`` per point, arrays ``(...)``."""
        px, py = x[..., self.position_index[0]], x[..., self.position_index[1]]
        zero = np.zeros_like(px)
        if self.variant == "foot":
            return [(self._foot, 0.0, px, py, zero)]
        head = self._head
        assert head is not None
        h = x[..., _H]
        if self.variant == "head_foot":
            return [(self._foot, 0.0, px, py, zero), (head, 0.0, px, py, h)]
        hw = 0.5 * x[..., _W]
        ex, ey = self._e
        left = (px - hw * ex, py - hw * ey)
        right = (px + hw * ex, py + hw * ey)
        return [
            (self._foot, -1.0, *left, zero),
            (self._foot, +1.0, *right, zero),
            (head, -1.0, *left, h),
            (head, +1.0, *right, h),
        ]

    def _state(self, x: ArrayLike) -> Array:
        xa = np.asarray(x, float)
        need = 4 if self.variant != "foot" else max(self.position_index) + 1
        if xa.ndim == 0 or xa.shape[-1] < need:
            raise ShapeError(
                invalid("x.shape", xa.shape, f"(..., d) with d >= {need}: [x, y, h, w, ...]")
            )
        return xa

    @staticmethod
    def _project(p: Array, X: Array, Y: Array, Z: Array) -> tuple[Array, Array, Array]:
        c = p[2, 0] * X + p[2, 1] * Y + p[2, 2] * Z + p[2, 3]
        u = (p[0, 0] * X + p[0, 1] * Y + p[0, 2] * Z + p[0, 3]) / c
        v = (p[1, 0] * X + p[1, 1] * Y + p[1, 2] * Z + p[1, 3]) / c
        return u, v, c

    def predict(self, x: ArrayLike) -> Array:
        """``f(s)``, ``(..., m)`` (Nott 2009, Eq. 3.9)."""
        xa = self._state(x)
        out = []
        for p, _, X, Y, Z in self._points(xa):
            u, v, _c = self._project(p, X, Y, Z)
            out += [u, v]
        return np.stack(out, axis=-1)

    def depth(self, x: ArrayLike) -> Array:
        """Smallest projective depth ``c`` over the measured points, ``(...)`` (> 0: in front)."""
        xa = self._state(x)
        return np.min(
            np.stack([self._project(p, X, Y, Z)[2] for p, _, X, Y, Z in self._points(xa)]), axis=0
        )

    def jacobian(self, x: ArrayLike) -> Array:
        """``D = df/ds`` at ``x``, ``(..., m, d)`` (analytic; see the module docstring)."""
        xa = self._state(x)
        J = np.zeros((*xa.shape[:-1], self.dim, xa.shape[-1]))
        ix, iy = self.position_index
        ex, ey = self._e
        for k, (p, sign, X, Y, Z) in enumerate(self._points(xa)):
            u, v, c = self._project(p, X, Y, Z)
            for row, val in ((2 * k, u), (2 * k + 1, v)):
                r = row % 2
                dX = (p[r, 0] - val * p[2, 0]) / c
                dY = (p[r, 1] - val * p[2, 1]) / c
                J[..., row, ix] = dX
                J[..., row, iy] = dY
                if sign != 0.0:
                    J[..., row, _W] = 0.5 * sign * (ex * dX + ey * dY)
                if Z is not None and p is self._head and p[:, 2].any():
                    J[..., row, _H] = (p[r, 2] - val * p[2, 2]) / c
        return J

    def noise_cov(self, x: ArrayLike | None = None) -> Array:
        """``R_y = sigma_px^2 I_m``."""
        return self.sigma_px**2 * np.eye(self.dim)

    def residual(self, z: ArrayLike, z_pred: ArrayLike) -> Array:
        za = np.asarray(z, float)
        if za.ndim == 0 or za.shape[-1] != self.dim:
            raise ShapeError(invalid("z.shape", za.shape, f"(..., {self.dim})"))
        return np.asarray(za - np.asarray(z_pred, float))

    def log_likelihood(self, z: ArrayLike, x: ArrayLike) -> Array:
        r = self.residual(z, self.predict(x))
        return -0.5 * (
            np.sum(r * r, -1) / self.sigma_px**2 + self.dim * np.log(2 * np.pi * self.sigma_px**2)
        )

    def visible(self, x: ArrayLike) -> Array:
        """Every measured point in front of the camera and inside the image, ``(...)`` booleans."""
        xa = self._state(x)
        z = self.predict(xa)
        w, h = self.image_size
        u, v = z[..., 0::2], z[..., 1::2]
        inside = (u >= 0) & (u <= w - 1) & (v >= 0) & (v <= h - 1)
        return np.asarray(inside.all(-1) & (self.depth(xa) > 0))

    def detection_probability(self, x: ArrayLike) -> Array:
        return self.detection_prob * self.visible(x).astype(float)

    def simulate(self, x: ArrayLike, rng: np.random.Generator) -> Array:
        """``f(s) + v``; NaN rows when not seen (outside the image, behind, missed)."""
        xa = self._state(x)
        z = self.predict(xa) + self.sigma_px * rng.standard_normal((*xa.shape[:-1], self.dim))
        seen = rng.random(xa.shape[:-1]) < self.detection_probability(xa)
        z[~seen] = np.nan
        return z

    def fisher_information(self, x: ArrayLike) -> Array:
        H = self.jacobian(x)
        return np.swapaxes(H, -1, -2) @ H / self.sigma_px**2


def bounding_box_measurement(u_min: float, v_min: float, u_max: float, v_max: float) -> Array:
    """The V8 measurement from a blob's bounding box: ``(u_min, v_max, u_max, v_max, u_min, v_min,
    u_max, v_min)`` = BL, BR, TL, TR."""
    return np.array([u_min, v_max, u_max, v_max, u_min, v_min, u_max, v_min], float)


__all__ = ["VARIANT_DIMS", "HomographyCamera", "bounding_box_measurement"]
