"""A multi-coloured ellipsoid moving through a network of cameras (Kushwaha 2010, Ch. V, Sec. 3.7-3.8).

The paper superimposes a synthetic ellipsoid "with correct pixel color values" on pre-recorded
cluttered background video. Here the backgrounds are procedural clutter (fixed per camera, with
per-frame noise), and the target is ray-cast exactly into each camera, so every frame comes with
exact ground truth: the target's pixels, its projected ellipse and the cameras that see it.

* :class:`EllipsoidTarget` -- semi-axes and the surface colours (octants + black/white stripes);
* :class:`Trajectory` -- positions, velocities and scalar-last quaternions per step (Eq. 63);
* :func:`smooth_trajectory` -- the random smooth paths of the experiments (0.2 m/step);
* :func:`corner_cameras`, :func:`perimeter_cameras` -- setups A and B;
* :func:`render_target` / :func:`render_frames` -- the frames; :func:`reference_views` -- the
  target seen from the model's viewpoints by hypothetical cameras (Eqs. 66-68). Both take any
  :class:`PaintedTarget` (also :class:`fusetrack.world.box_target.BoxTarget`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core import ConfigError, invalid
from ..sensors import (
    EllipsoidCamera,
    PinholeCamera,
    axis_angle_quaternion,
    ellipsoid_matrix,
    look_at,
    project_ellipsoid,
    quaternion_multiply,
    quaternion_to_rotation,
)

Array = NDArray[np.float64]
Image = NDArray[np.uint8]


class PaintedTarget(Protocol):
    """A target the cameras can render: ``semi_axes`` (m) of the ellipsoid the trackers model it
    with, and ``paint`` that draws it into an RGB image in place and returns its pixel mask."""

    @property
    def semi_axes(self) -> tuple[float, float, float]: ...

    def paint(
        self, image: Image, cam: EllipsoidCamera, position: ArrayLike, quaternion: ArrayLike
    ) -> NDArray[np.bool_]: ...


#: Octant colours (RGB) of the synthetic target, indexed by the signs of the body coordinates.
OCTANT_COLOURS = np.array(
    [
        [220, 30, 30],  # red
        [30, 190, 40],  # green
        [30, 60, 220],  # blue
        [230, 220, 30],  # yellow
        [210, 40, 210],  # magenta
        [30, 210, 220],  # cyan
        [240, 140, 20],  # orange
        [120, 40, 160],  # purple
    ],
    dtype=float,
)


@dataclass(frozen=True)
class EllipsoidTarget:
    """The synthetic target: semi-axes ``(l, w, h)`` (m) and a band of black/white stripes."""

    semi_axes: tuple[float, float, float] = (0.3, 0.2, 0.4)
    stripe_band: float = 0.18  # |z_body| / h below this is striped (texture for the LBP)
    stripes: int = 12  # black/white stripes around the equator

    def colour(self, body_points: ArrayLike) -> Array:
        """RGB (0-255) of surface points given in the body frame ``(..., 3)``."""
        p = np.asarray(body_points, float)
        octant = (p[..., 0] > 0).astype(int) + 2 * (p[..., 1] > 0) + 4 * (p[..., 2] > 0)
        rgb = OCTANT_COLOURS[octant]
        band = np.abs(p[..., 2]) / self.semi_axes[2] < self.stripe_band
        phase = np.floor(np.arctan2(p[..., 1], p[..., 0]) / (2 * np.pi) * self.stripes) % 2
        bw = np.where(phase[..., None] > 0, 235.0, 20.0) * np.ones(3)
        return np.where(band[..., None], bw, rgb)

    def paint(
        self, image: Image, cam: EllipsoidCamera, position: ArrayLike, quaternion: ArrayLike
    ) -> NDArray[np.bool_]:
        """Draw the ellipsoid into ``image`` (in place): :func:`render_target`."""
        return render_target(image, cam, self, position, quaternion)


@dataclass(frozen=True)
class Trajectory:
    """Ground truth per step: ``positions`` and ``velocities`` ``(T, 3)``, ``quaternions`` ``(T, 4)``."""

    positions: Array
    velocities: Array
    quaternions: Array

    def __len__(self) -> int:
        return int(self.positions.shape[0])


def smooth_trajectory(
    rng: np.random.Generator,
    steps: int,
    low: ArrayLike,
    high: ArrayLike,
    speed: float = 0.2,
    turn_sd: float = 0.25,
    rotation_deg: float = 0.0,
    start: ArrayLike | None = None,
    heading: float | None = None,
) -> Trajectory:
    """A smooth random path in the box ``[low, high]`` at ``speed`` m/step (spec Sec. 3.7).

    The heading turns by ``N(0, turn_sd^2)`` rad per step and is steered back towards the box
    centre near its walls; the height drifts slowly. With ``rotation_deg > 0`` the target turns by
    that angle per step about a random fixed body axis (the "rotating target" runs), otherwise
    it keeps a random initial orientation. ``start`` and ``heading`` (rad) fix the first position
    and direction of travel (default: random).
    """
    lo = np.asarray(low, float)
    hi = np.asarray(high, float)
    if steps < 2 or np.any(hi <= lo):
        raise ConfigError(invalid("(steps, low, high)", (steps, lo, hi), "steps >= 2, high > low"))
    centre = 0.5 * (lo + hi)
    pos = np.empty((steps, 3))
    pos[0] = rng.uniform(lo + 0.2 * (hi - lo), hi - 0.2 * (hi - lo)) if start is None else start
    drawn = rng.uniform(-np.pi, np.pi)
    heading = drawn if heading is None else float(heading)
    climb = 0.0
    margin = 0.15 * (hi - lo)
    for t in range(1, steps):
        to_centre = np.arctan2(centre[1] - pos[t - 1, 1], centre[0] - pos[t - 1, 0])
        near_wall = np.any(pos[t - 1, :2] < lo[:2] + margin[:2]) or np.any(
            pos[t - 1, :2] > hi[:2] - margin[:2]
        )
        turn = rng.normal(0.0, turn_sd)
        if near_wall:
            turn += 0.5 * np.angle(np.exp(1j * (to_centre - heading)))
        heading += turn
        climb = 0.8 * climb + rng.normal(0.0, 0.02)
        step = np.array([np.cos(heading) * speed, np.sin(heading) * speed, climb])
        pos[t] = np.clip(pos[t - 1] + step, lo, hi)
    vel = np.asarray(np.gradient(pos, axis=0), float)
    axis = rng.normal(size=3)
    q0 = axis_angle_quaternion(rng.normal(size=3), rng.uniform(0, np.pi))
    turn_q = axis_angle_quaternion(axis, np.deg2rad(rotation_deg))
    quats = np.empty((steps, 4))
    quats[0] = q0
    for t in range(1, steps):
        quats[t] = quaternion_multiply(turn_q, quats[t - 1])
    return Trajectory(pos, vel, quats)


def _camera(
    name: str, centre: Array, target: Array, focal: float, size: tuple[int, int]
) -> EllipsoidCamera:
    w, h = size
    K = np.array([[focal, 0.0, w / 2.0], [0.0, focal, h / 2.0], [0.0, 0.0, 1.0]])
    return EllipsoidCamera(name, PinholeCamera(K, look_at(centre, target), centre, w, h))


def corner_cameras(
    room: tuple[float, float, float] = (8.0, 8.0, 3.0),
    height: float = 2.8,
    focal: float = 150.0,
    size: tuple[int, int] = (160, 120),
) -> list[EllipsoidCamera]:
    """Setup A (spec Sec. 3.7): four cameras at the upper corners looking at the room centre."""
    lx, ly, _ = room
    look = np.array([lx / 2, ly / 2, 1.0])
    corners = [(0.0, 0.0), (lx, 0.0), (lx, ly), (0.0, ly)]
    return [
        _camera(f"cam{i}", np.array([x, y, height]), look, focal, size)
        for i, (x, y) in enumerate(corners)
    ]


def perimeter_cameras(
    side: float = 30.0,
    n: int = 10,
    height: float = 4.0,
    focal: float = 260.0,
    size: tuple[int, int] = (160, 120),
    reach: float = 12.0,
) -> list[EllipsoidCamera]:
    """Setup B (spec Sec. 3.8): ``n`` cameras spread along the perimeter of a ``side`` x ``side``
    area, ``height`` m high, each looking inwards at a point ``reach`` m away, so that each
    covers a patch of the area and the middle is seen by a few cameras only."""
    cams = []
    for i in range(n):
        s = (i + 0.5) / n * 4.0  # position along the perimeter in units of sides
        k, f = int(s), s - int(s)
        xy, inward = [
            (np.array([f * side, 0.0]), np.array([0.0, 1.0])),
            (np.array([side, f * side]), np.array([-1.0, 0.0])),
            (np.array([side * (1 - f), side]), np.array([0.0, -1.0])),
            (np.array([0.0, side * (1 - f)]), np.array([1.0, 0.0])),
        ][k]
        look_xy = xy + reach * inward
        cams.append(
            _camera(
                f"cam{i}",
                np.array([xy[0], xy[1], height]),
                np.array([look_xy[0], look_xy[1], 1.0]),
                focal,
                size,
            )
        )
    return cams


def clutter_background(rng: np.random.Generator, size: tuple[int, int]) -> Image:
    """A cluttered still background (RGB): smooth shading plus random coloured blobs and bars."""
    w, h = size
    yy, xx = np.mgrid[0:h, 0:w]
    base = 90 + 40 * np.sin(xx / w * rng.uniform(2, 6) + rng.uniform(0, 6))[..., None]
    img = np.clip(base + 25 * np.cos(yy / h * rng.uniform(2, 5))[..., None], 0, 255)
    img = np.repeat(img, 3, axis=2) * rng.uniform(0.7, 1.1, size=3)
    out = np.ascontiguousarray(np.clip(img, 0, 255).astype(np.uint8))
    for _ in range(int(w * h / 600)):
        colour = tuple(int(c) for c in rng.integers(20, 235, size=3))
        cx, cy = int(rng.integers(0, w)), int(rng.integers(0, h))
        if rng.random() < 0.5:
            axes = (int(rng.integers(2, max(3, w // 12))), int(rng.integers(2, max(3, h // 12))))
            cv2.ellipse(out, (cx, cy), axes, float(rng.uniform(0, 180)), 0, 360, colour, -1)
        else:
            dx, dy = int(rng.integers(2, w // 8)), int(rng.integers(2, h // 8))
            cv2.rectangle(out, (cx, cy), (cx + dx, cy + dy), colour, -1)
    return out


def render_target(
    image: Image,
    cam: EllipsoidCamera,
    target: EllipsoidTarget,
    position: ArrayLike,
    quaternion: ArrayLike,
) -> NDArray[np.bool_]:
    """Ray-cast the target into ``image`` (RGB, in place); return its exact pixel mask.

    Every pixel whose centre ray meets the ellipsoid gets the colour of the first surface point,
    shaded by the cosine between the normal and the ray (ambient 0.55).
    """
    w, h = cam.size
    mask = np.zeros((h, w), dtype=bool)
    x = np.asarray(position, float)
    q = np.asarray(quaternion, float)
    yc, B = cam.ellipse(x, q, target.semi_axes)
    if not np.all(np.isfinite(yc)):
        return mask
    half = np.sqrt(np.diag(np.linalg.inv(B))) + 1.0  # bounding box of the ellipse
    x0, x1 = int(max(0, np.floor(yc[0] - half[0]))), int(min(w - 1, np.ceil(yc[0] + half[0])))
    y0, y1 = int(max(0, np.floor(yc[1] - half[1]))), int(min(h - 1, np.ceil(yc[1] + half[1])))
    if x1 < x0 or y1 < y0:
        return mask
    vv, uu = np.mgrid[y0 : y1 + 1, x0 : x1 + 1]
    d = cam.ray(np.stack([uu, vv], axis=-1).astype(float))
    R = quaternion_to_rotation(q)
    s = np.asarray(target.semi_axes, float)
    o = ((cam.centre - x) @ R) / s  # ray in the body frame scaled to the unit sphere
    db = (d @ R) / s
    a = np.sum(db * db, -1)
    b = 2 * db @ o
    c = o @ o - 1.0
    disc = b * b - 4 * a * c
    hit = disc > 0
    t = (-b - np.sqrt(np.where(hit, disc, 0.0))) / (2 * a)
    hit &= t > 0
    if not hit.any():
        return mask
    pb = (o + t[..., None] * db) * s  # body-frame surface points
    normal = pb / s**2
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    shade = 0.55 + 0.45 * np.clip(-np.sum(normal * (d @ R), -1), 0, 1)
    colour = np.clip(target.colour(pb) * shade[..., None], 0, 255)
    sub = image[y0 : y1 + 1, x0 : x1 + 1]
    sub[hit] = colour[hit].astype(np.uint8)
    mask[y0 : y1 + 1, x0 : x1 + 1] = hit
    return mask


@dataclass(frozen=True)
class Frames:
    """Rendered frames ``images[t][n]`` (RGB) and their exact ground truth per step and camera."""

    images: list[list[Image]]
    target_pixels: NDArray[np.int64]  # (T, N) pixels covered by the target
    participating: NDArray[np.bool_]  # (T, N) the camera shows at least ``min_pixels`` of it


def render_frames(
    cams: Sequence[EllipsoidCamera],
    target: PaintedTarget,
    truth: Trajectory,
    rng: np.random.Generator,
    hidden: NDArray[np.bool_] | None = None,
    noise_sd: float = 3.0,
    min_pixels: int = 12,
) -> Frames:
    """Render every camera at every step over its own clutter background with per-frame noise.

    ``hidden[t, n]`` hides the target from camera ``n`` at step ``t`` (an occluder painted with
    the background: the setup-B "one-camera gap").
    """
    backgrounds = [clutter_background(rng, c.size) for c in cams]
    T, N = len(truth), len(cams)
    images: list[list[Image]] = []
    pixels = np.zeros((T, N), dtype=np.int64)
    for t in range(T):
        row = []
        for n, cam in enumerate(cams):
            noise = rng.normal(0.0, noise_sd, size=backgrounds[n].shape)
            img = np.clip(backgrounds[n] + noise, 0, 255).astype(np.uint8)
            if hidden is None or not hidden[t, n]:
                mask = target.paint(img, cam, truth.positions[t], truth.quaternions[t])
                pixels[t, n] = int(mask.sum())
            row.append(img)
        images.append(row)
    return Frames(images, pixels, pixels >= min_pixels)


def cube_viewpoints() -> Array:
    """The 26 unit viewpoints of the reference model: cube faces, edges and corners (spec [C])."""
    g = np.array(np.meshgrid([-1, 0, 1], [-1, 0, 1], [-1, 0, 1], indexing="ij")).reshape(3, -1).T
    g = g[np.any(g != 0, axis=1)].astype(float)
    return g / np.linalg.norm(g, axis=1, keepdims=True)


def reference_views(
    target: PaintedTarget,
    viewpoints: ArrayLike,
    pixels_across: float = 60.0,
    size: tuple[int, int] = (96, 96),
    background: int = 128,
) -> tuple[list[Image], Array, Array]:
    """The target alone seen from each body-frame viewpoint ``e_j`` by a hypothetical camera at
    ``L e_j`` looking along ``-e_j`` (Kushwaha 2010, Eqs. 66-68), with ``L`` chosen so that the
    target is about ``pixels_across`` wide. Returns images and the ellipses ``(y_c, B)`` of the
    regions (the target drawn at the origin with the identity orientation)."""
    e = np.asarray(viewpoints, float)
    focal = 150.0
    L = focal * 2 * max(target.semi_axes) / pixels_across
    ident = np.array([0.0, 0.0, 0.0, 1.0])
    images, centres, shapes = [], [], []
    for ej in e:
        up = (0.0, 0.0, 1.0) if abs(ej[2]) < 0.99 else (0.0, 1.0, 0.0)
        w, h = size
        K = np.array([[focal, 0.0, w / 2.0], [0.0, focal, h / 2.0], [0.0, 0.0, 1.0]])
        c = L * ej
        cam = EllipsoidCamera("ref", PinholeCamera(K, look_at(c, np.zeros(3), up), c, w, h))
        img = np.full((h, w, 3), background, dtype=np.uint8)
        target.paint(img, cam, np.zeros(3), ident)
        yc, B = project_ellipsoid(cam.P, np.zeros(3), ellipsoid_matrix(target.semi_axes, ident))
        images.append(img)
        centres.append(yc)
        shapes.append(B)
    return images, np.array(centres), np.array(shapes)
