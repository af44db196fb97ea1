"""A textured box (cuboid) target, ray-cast into a camera (Kushwaha 2010, Ch. V, LCR experiment).

The dissertation's real LCR run tracks "a typical box" with trackers that model every target as
an ellipsoid (Eq. 64). Spec 003 A-V-18 replaces the unrecorded footage by a rendered box, so the
trackers meet a target whose silhouette and shading are not those of their model. Each face has
its own colour with a checkerboard of light and dark squares (texture for the LBP histograms).

Rays are intersected with the box by the slab method (Kay & Kajiya 1986; Williams et al. 2005):
in the body frame the ray ``o + t d`` enters the box at ``t_near = max_i min(t_i-, t_i+)`` and
leaves at ``t_far = min_i max(t_i-, t_i+)``, ``t_i± = (±h_i - o_i) / d_i``; it hits when
``0 < t_near <= t_far``, on the face normal to the axis that attains ``t_near``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ConfigError, invalid
from ..sensors import EllipsoidCamera, quaternion_to_rotation

Array = NDArray[np.float64]
Image = NDArray[np.uint8]

#: Face colours (RGB), indexed by ``2 * axis + (outward normal > 0)``: -x, +x, -y, +y, -z, +z.
FACE_COLOURS = np.array(
    [
        [200, 40, 40],  # red
        [40, 170, 60],  # green
        [40, 70, 210],  # blue
        [225, 205, 40],  # yellow
        [200, 60, 200],  # magenta
        [40, 200, 210],  # cyan
    ],
    dtype=float,
)
DARK_SQUARE = 0.45  # brightness of the checkerboard's dark squares
AMBIENT = 0.55  # shading: AMBIENT + (1 - AMBIENT) cos(normal, ray), as the ellipsoid's


@dataclass(frozen=True)
class BoxTarget:
    """A box with half-sizes ``half_sizes`` (m, body x, y, z) and checker squares of side
    ``checker`` (m).

    ``semi_axes`` is the ellipsoid the trackers model it with: the box's half-sizes scaled by
    ``(6 / pi)^(1/3)``, the ellipsoid of the box's volume (``4/3 pi abc = 8 h_x h_y h_z``).
    """

    half_sizes: tuple[float, float, float] = (0.3, 0.22, 0.18)
    checker: float = 0.1

    def __post_init__(self) -> None:
        if len(self.half_sizes) != 3 or min(self.half_sizes) <= 0 or self.checker <= 0:
            raise ConfigError(
                invalid(
                    "(half_sizes, checker)",
                    (self.half_sizes, self.checker),
                    "three positive half-sizes (m) and a positive checker side (m)",
                )
            )

    @property
    def semi_axes(self) -> tuple[float, float, float]:
        k = (6.0 / np.pi) ** (1.0 / 3.0)
        a, b, c = self.half_sizes
        return (k * a, k * b, k * c)

    def corners(self) -> Array:
        """The eight corners ``(8, 3)`` in the body frame."""
        signs = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1], indexing="ij")).reshape(3, -1).T
        return signs * np.asarray(self.half_sizes, float)

    def colour(self, body_points: ArrayLike, face: ArrayLike) -> Array:
        """RGB (0-255) of surface points ``(..., 3)`` (body frame) on faces ``face`` (0-5, see
        :data:`FACE_COLOURS`): the face colour, dark on every other checker square."""
        p = np.asarray(body_points, float)
        f = np.asarray(face, int)
        cells = np.floor(p / self.checker).astype(int)
        # the checker runs over the two coordinates in the face: all three minus the normal's
        normal_cell = np.take_along_axis(cells, (f // 2)[..., None], axis=-1)[..., 0]
        parity = (cells.sum(axis=-1) - normal_cell) % 2
        light = np.where(parity == 0, 1.0, DARK_SQUARE)
        return FACE_COLOURS[f] * light[..., None]

    def paint(
        self, image: Image, cam: EllipsoidCamera, position: ArrayLike, quaternion: ArrayLike
    ) -> NDArray[np.bool_]:
        """Draw the box into ``image`` (in place): :func:`render_box`."""
        return render_box(image, cam, self, position, quaternion)


def _pixel_window(cam: EllipsoidCamera, corners_world: Array) -> tuple[int, int, int, int] | None:
    """Pixel bounds ``(x0, x1, y0, y1)`` (inclusive) that hold the box's image; the whole image
    when a corner is behind the camera, None when all are."""
    w, h = cam.size
    depth = cam.depth(corners_world)
    if np.all(depth <= 0):
        return None
    if np.any(depth <= 0):
        return 0, w - 1, 0, h - 1
    uv = cam.project(corners_world)
    x0, y0 = np.floor(uv.min(axis=0)).astype(int) - 1
    x1, y1 = np.ceil(uv.max(axis=0)).astype(int) + 1
    x0, x1, y0, y1 = max(0, x0), min(w - 1, x1), max(0, y0), min(h - 1, y1)
    if x1 < x0 or y1 < y0:
        return None
    return int(x0), int(x1), int(y0), int(y1)


def render_box(
    image: Image,
    cam: EllipsoidCamera,
    box: BoxTarget,
    position: ArrayLike,
    quaternion: ArrayLike,
) -> NDArray[np.bool_]:
    """Ray-cast ``box`` at ``position`` with orientation ``quaternion`` (scalar-last, body to
    world) into ``image`` (RGB, in place); return its exact pixel mask.

    Every pixel whose centre ray meets the box gets the colour of the face it enters, shaded by
    the cosine between that face's normal and the ray (ambient 0.55).
    """
    w, h = cam.size
    mask = np.zeros((h, w), dtype=bool)
    x = np.asarray(position, float)
    R = quaternion_to_rotation(np.asarray(quaternion, float))
    window = _pixel_window(cam, x + box.corners() @ R.T)
    if window is None:
        return mask
    x0, x1, y0, y1 = window
    vv, uu = np.mgrid[y0 : y1 + 1, x0 : x1 + 1]
    d = cam.ray(np.stack([uu, vv], axis=-1).astype(float)) @ R  # body-frame unit rays
    o = (cam.centre - x) @ R
    d = np.where(np.abs(d) < 1e-12, 1e-12, d)  # a ray parallel to a slab never crosses it
    half = np.asarray(box.half_sizes, float)
    t_lo, t_hi = (-half - o) / d, (half - o) / d
    t_in, t_out = np.minimum(t_lo, t_hi), np.maximum(t_lo, t_hi)
    t_near = t_in.max(axis=-1)
    hit = (t_near > 0) & (t_near <= t_out.min(axis=-1))
    if not hit.any():
        return mask
    axis = t_in.argmax(axis=-1)
    d_axis = np.take_along_axis(d, axis[..., None], axis=-1)[..., 0]
    face = 2 * axis + (d_axis < 0)  # the ray enters against the outward normal
    surface = o + t_near[..., None] * d
    shade = AMBIENT + (1.0 - AMBIENT) * np.abs(d_axis)
    colour = np.clip(box.colour(surface, face) * shade[..., None], 0, 255)
    sub = image[y0 : y1 + 1, x0 : x1 + 1]
    sub[hit] = colour[hit].astype(np.uint8)
    mask[y0 : y1 + 1, x0 : x1 + 1] = hit
    return mask


__all__ = ["FACE_COLOURS", "BoxTarget", "render_box"]
