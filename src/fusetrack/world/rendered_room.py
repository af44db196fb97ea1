"""A rendered indoor scene with exact ground truth, for the Nott (2009) video experiments.

The thesis's videos are not published; this renders their stand-in from a known camera
(:func:`~fusetrack.sensors.camera_geometry.default_camera`): a 9 m x 15 m room with a tiled floor
and textured walls, smooth lighting, per-frame sensor noise (sigma = 2 grey levels) and a small
lighting flicker; people as billboard silhouettes (head ellipse, torso, arms, two legs swinging
with the gait) of height 1.75 m and width 0.5 m, facing the camera; optional cast shadows
(floor darkened by 0.6 in the silhouette sheared along the light); an optional separate "hand"
blob (Nott 2009, Fig. 5.10a); and a wall. Occluders are drawn far to near (painter's algorithm on
the camera depth). For every frame and person the renderer returns the full and the visible
silhouette, and the true foot and head pixels. The scene's walks (training, one person, two
crossing, behind the wall) are :class:`~fusetrack.world.walkers.Walk` values in floor metres; the
camera sees x in [1, 8] m, y in [1, 14] m.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from ..sensors import PinholeCamera, default_camera
from .walkers import Walk, polyline_walk

Array = NDArray[np.float64]
ROOM = (0.0, 9.0, 0.0, 15.0)  # x0, x1, y0, y1 (m): walls at x = 0, x = 9 and y = 15


# ----------------------------------------------------------- the scene's walks and wall


def straight_training_walk(fps: float = 15.0, speed: float = 1.1) -> Walk:
    """The thesis's training walk: "a single straight line" (Nott 2009, Sec. 5.2.2)."""
    return polyline_walk([[1.5, 2.0], [7.5, 6.0]], speed, fps)


def diverse_training_walk(fps: float = 15.0, speed: float = 1.4) -> Walk:
    """A zig-zag that covers the visible floor (what Sec. 5.2.2 says was missing)."""
    return polyline_walk(
        [[1.5, 1.5], [7.5, 3.0], [1.5, 5.0], [7.5, 7.5], [1.5, 10.0], [7.0, 12.5], [4.5, 13.0]],
        speed,
        fps,
    )


def single_person_walk(fps: float = 15.0, n_frames: int = 90) -> Walk:
    """A curved walk, in view throughout."""
    t = np.arange(n_frames) / fps
    xy = np.column_stack([2.0 + 0.9 * t, 3.0 + 2.5 * np.sin(0.5 * t) + 0.3 * t])
    return Walk(t, xy)


def crossing_walks(fps: float = 15.0, n_frames: int = 90) -> tuple[Walk, Walk]:
    """Two people who cross in the image: the subject nearer the camera walks left to right,
    the other farther away walks right to left (person-person occlusion, Nott 2009, Fig. 5.9)."""
    t = np.arange(n_frames) / fps
    a = np.column_stack([1.6 + 0.95 * t, 4.0 + 0.05 * t])
    b = np.column_stack([7.4 - 0.95 * t, 7.0 + 0.0 * t])
    return Walk(t, a), Walk(t, b)


def behind_wall_walk(fps: float = 15.0, n_frames: int = 90) -> Walk:
    """A walk behind the wall of :data:`WALL` (static occluder, Nott 2009, Sec. 5.2)."""
    t = np.arange(n_frames) / fps
    return Walk(t, np.column_stack([1.8 + 0.95 * t, 6.5 + 0.02 * t]))


WALL = ((3.4, 5.0), (5.0, 5.0))
WALL_HEIGHT = 2.2
"""The artificial wall (1.6 m wide, 2.2 m high: the spec suggests 1.2 x 2.0 m, but a 2.0 m wall
at this distance leaves the top of the head visible, which is not the occlusion the thesis means)."""


@dataclass(frozen=True)
class Person:
    """One person: a walk, body size, clothing colours (RGB), whether to draw a separate hand."""

    walk: Walk
    height: float = 1.75
    width: float = 0.5
    shirt: tuple[int, int, int] = (200, 40, 40)
    trousers: tuple[int, int, int] = (30, 40, 140)
    skin: tuple[int, int, int] = (230, 180, 140)
    separate_hand: bool = False


@dataclass(frozen=True)
class Frame:
    """One rendered frame: ``image`` (H, W, 3) uint8 RGB, and per person (in the order given):
    ``full`` and ``visible`` silhouettes (H, W) bool, ``foot`` and ``head`` true pixels, ``xy``."""

    index: int
    time: float
    image: NDArray[np.uint8]
    full: list[NDArray[np.bool_]]
    visible: list[NDArray[np.bool_]]
    foot: Array
    head: Array
    xy: Array


def _hash_noise(ix: NDArray[np.int64], iy: NDArray[np.int64], salt: int) -> Array:
    """Deterministic per-cell values in [0, 1)."""
    h = (ix * 73856093) ^ (iy * 19349663) ^ (salt * 83492791)
    return ((h % 1000003) / 1000003.0).astype(float)


@dataclass
class RoomRenderer:
    """Renders frames of people walking in the room seen by ``camera``."""

    camera: PinholeCamera = field(default_factory=default_camera)
    noise_sigma: float = 2.0
    flicker: float = 0.005
    shadows: bool = True
    light: tuple[float, float] = (0.35, 0.25)  # floor shift (m) per metre of height
    wall: tuple[tuple[float, float], tuple[float, float]] | None = None
    wall_height: float = WALL_HEIGHT
    background: NDArray[np.float32] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.background = self._render_background()

    # -- the empty room -----------------------------------------------------------------------

    def _render_background(self) -> NDArray[np.float32]:
        cam = self.camera
        w, h = cam.width, cam.height
        u, v = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
        rays = np.stack([u, v, np.ones_like(u)], -1) @ np.linalg.inv(cam.K).T @ cam.R  # world dirs
        c = cam.centre
        x0, x1, _y0, y1 = ROOM
        best = np.full(u.shape, np.inf)
        img = np.zeros((h, w, 3), np.float32)
        with np.errstate(divide="ignore", invalid="ignore"):
            t_floor = np.where(rays[..., 2] < 0, -c[2] / rays[..., 2], np.inf)
            t_back = np.where(rays[..., 1] > 0, (y1 - c[1]) / rays[..., 1], np.inf)
            t_left = np.where(rays[..., 0] < 0, (x0 - c[0]) / rays[..., 0], np.inf)
            t_right = np.where(rays[..., 0] > 0, (x1 - c[0]) / rays[..., 0], np.inf)
        for t, kind in ((t_floor, "floor"), (t_back, "back"), (t_left, "side"), (t_right, "side")):
            p = c + t[..., None] * rays
            if kind == "floor":
                ok = (p[..., 0] >= x0) & (p[..., 0] <= x1) & (p[..., 1] <= y1)
            elif kind == "back":
                ok = (p[..., 0] >= x0) & (p[..., 0] <= x1) & (p[..., 2] >= 0)
            else:
                ok = (p[..., 1] <= y1) & (p[..., 2] >= 0)
            take = ok & np.isfinite(t) & (t < best)
            best = np.where(take, t, best)
            colour = self._texture(p, kind)
            img[take] = colour[take]
        outside = ~np.isfinite(best)
        img[outside] = (90, 90, 100)
        # smooth lighting: brighter in the middle of the room
        dist = np.where(np.isfinite(best), best, 25.0)
        img *= (1.05 - 0.25 * np.clip(dist / 25.0, 0, 1))[..., None]
        return np.clip(img, 20, 235).astype(np.float32)

    @staticmethod
    def _texture(p: Array, kind: str) -> NDArray[np.float32]:
        if kind == "floor":
            a, b = p[..., 0], p[..., 1]
            base = np.array([150.0, 130.0, 100.0])
        else:
            a, b = (p[..., 0] if kind == "back" else p[..., 1]), p[..., 2]
            base = np.array([180.0, 175.0, 150.0])
        a = np.clip(np.nan_to_num(a), -1e4, 1e4)
        b = np.clip(np.nan_to_num(b), -1e4, 1e4)
        with np.errstate(invalid="ignore"):
            ia = np.floor(np.nan_to_num(a) / 0.5).astype(np.int64)
            ib = np.floor(np.nan_to_num(b) / 0.5).astype(np.int64)
            tile = 0.85 + 0.3 * _hash_noise(ia, ib, 1 if kind == "floor" else 2)
            fa, fb = np.nan_to_num(a) / 0.5 - ia, np.nan_to_num(b) / 0.5 - ib
            grout = (np.minimum(fa, fb) < 0.04) & (kind == "floor")
            fine = 0.93 + 0.14 * _hash_noise(
                np.floor(np.nan_to_num(a) / 0.05).astype(np.int64),
                np.floor(np.nan_to_num(b) / 0.05).astype(np.int64),
                3,
            )
        col = base * (tile * fine)[..., None]
        col = np.where(grout[..., None], col * 0.6, col)
        return col.astype(np.float32)

    # -- people ---------------------------------------------------------------------------------

    def _body_polygons(
        self, person: Person, k: int
    ) -> list[tuple[Array, tuple[int, int, int], bool]]:
        """World polygons (n, 3) of the person's parts at frame ``k`` with colours; the flag marks
        the separate hand (part of the person's silhouette, but a blob of its own)."""
        x, y = person.walk.xy[k]
        t = person.walk.times[k]
        H, W = person.height, person.width
        speed = float(np.linalg.norm(person.walk.velocity[k]))
        swing = 0.18 * np.sin(2 * np.pi * 0.9 * t) * min(speed / 1.0, 1.0)  # gait (m)
        leg_top, hip_w, leg_w = 0.47 * H, 0.36 * W, 0.26 * W

        def quad(
            s0: float,
            s1: float,
            z0: float,
            z1: float,
            s0_top: float | None = None,
            s1_top: float | None = None,
        ) -> Array:
            a, b = (s0 if s0_top is None else s0_top), (s1 if s1_top is None else s1_top)
            return np.array([[s0, z0], [s1, z0], [b, z1], [a, z1]])

        parts: list[tuple[Array, tuple[int, int, int], bool]] = []
        for side, sw in ((-1, swing), (1, -swing)):
            centre_top = side * hip_w / 2
            foot_c = centre_top + sw
            parts.append(
                (
                    quad(
                        foot_c - leg_w / 2,
                        foot_c + leg_w / 2,
                        0.0,
                        leg_top,
                        centre_top - leg_w / 2,
                        centre_top + leg_w / 2,
                    ),
                    person.trousers,
                    False,
                )
            )
        parts.append(
            (
                quad(-0.38 * W, 0.38 * W, leg_top - 0.02, 0.82 * H, -0.5 * W, 0.5 * W),
                person.shirt,
                False,
            )
        )
        for side in (-1, 1):
            arm_s = side * 0.47 * W
            parts.append(
                (quad(arm_s - 0.05, arm_s + 0.05, 0.50 * H, 0.80 * H), person.shirt, False)
            )
        ang = np.linspace(0, 2 * np.pi, 20, endpoint=False)
        head_r, head_c = 0.065 * H, 0.935 * H
        parts.append(
            (
                np.column_stack([0.13 * W * np.cos(ang) * 1.1, head_c + head_r * np.sin(ang)]),
                person.skin,
                False,
            )
        )
        parts.append((quad(-0.05, 0.05, 0.82 * H, 0.88 * H), person.skin, False))  # neck
        if person.separate_hand:
            hs = 1.15 * W  # far enough that the 7x7 closing does not reattach it
            parts.append(
                (
                    np.column_stack([hs + 0.09 * np.cos(ang), 0.55 * H + 0.12 * np.sin(ang)]),
                    person.skin,
                    True,
                )
            )
        out = []
        for poly, colour, hand in parts:
            world = np.column_stack([x + poly[:, 0], np.full(len(poly), y), poly[:, 1]])
            out.append((world, colour, hand))
        return out

    def _fill(self, img: NDArray[Any], world: Array, value: Any) -> None:
        pix = self.camera.project(world)
        pts = np.round(pix * 16).astype(np.int32).reshape(-1, 1, 2)
        cv2.fillPoly(img, [pts], value, lineType=cv2.LINE_8, shift=4)

    def render(self, people: Sequence[Person], k: int, rng: np.random.Generator) -> Frame:
        """Frame ``k`` of the walks of ``people`` (all walks share their frame times)."""
        cam = self.camera
        h, w = cam.height, cam.width
        img = self.background * np.float32(1.0 + self.flicker * rng.standard_normal())
        if self.shadows:
            shade = np.zeros((h, w), np.uint8)
            lx, ly = self.light
            for person in people:
                for world, _, _hand in self._body_polygons(person, k):
                    flat = world.copy()
                    flat[:, 0] += lx * world[:, 2]
                    flat[:, 1] += ly * world[:, 2]
                    flat[:, 2] = 0.0
                    self._fill(shade, flat, 1)
            img[shade.astype(bool)] *= np.float32(0.6)
        full = []
        drawables: list[tuple[float, int]] = []
        for i, person in enumerate(people):
            m = np.zeros((h, w), np.uint8)
            for world, _, _hand in self._body_polygons(person, k):
                self._fill(m, world, 1)
            full.append(m.astype(bool))
            x, y = person.walk.xy[k]
            drawables.append((float(cam.depth(np.array([x, y, 0.0]))), i))
        if self.wall is not None:
            (ax, ay), (bx, by) = self.wall
            drawables.append((float(cam.depth(np.array([(ax + bx) / 2, (ay + by) / 2, 0.0]))), -1))
        label = np.full((h, w), -2, np.int16)
        for _, i in sorted(drawables, reverse=True):  # far to near
            if i == -1:
                (ax, ay), (bx, by) = self.wall  # type: ignore[misc]
                world = np.array(
                    [
                        [ax, ay, 0.0],
                        [bx, by, 0.0],
                        [bx, by, self.wall_height],
                        [ax, ay, self.wall_height],
                    ]
                )
                self._fill(img, world, (110.0, 150.0, 110.0))
                self._fill(label, world, -1)
                continue
            for world, colour, _hand in self._body_polygons(people[i], k):
                self._fill(img, world, tuple(float(c) for c in colour))
                self._fill(label, world, i)
        noisy = img + np.float32(self.noise_sigma) * rng.standard_normal(
            img.shape, dtype=np.float32
        )
        image = np.clip(np.rint(noisy), 0, 255).astype(np.uint8)
        xy = np.array([p.walk.xy[k] for p in people]).reshape(-1, 2)
        heights = np.array([p.height for p in people], float)
        foot = cam.project(np.column_stack([xy, np.zeros(len(people))]))
        head = cam.project(np.column_stack([xy, heights]))
        visible = [full[i] & (label == i) for i in range(len(people))]
        t = float(people[0].walk.times[k]) if people else float(k)
        return Frame(k, t, image, full, visible, foot, head, xy)

    def empty_frames(self, n: int, rng: np.random.Generator) -> NDArray[np.uint8]:
        """``n`` frames of the empty room (with the wall, if any): background training."""
        frames = []
        for _ in range(n):
            f = self.render([], 0, rng)
            frames.append(f.image)
        return np.stack(frames)

    def frames(self, people: Sequence[Person], rng: np.random.Generator) -> Iterator[Frame]:
        n = min(len(p.walk.times) for p in people)
        for k in range(n):
            yield self.render(people, k, rng)


def write_video(
    path: str, images: Sequence[NDArray[np.uint8]] | Iterator[NDArray[np.uint8]], fps: float
) -> int:
    """Write RGB frames to a video file (``.avi``: lossless FFV1; ``.mp4``: MPEG-4); returns the count."""
    writer = None
    n = 0
    for im in images:
        if writer is None:
            fourcc = cv2.VideoWriter.fourcc(*("FFV1" if str(path).endswith(".avi") else "mp4v"))
            writer = cv2.VideoWriter(str(path), fourcc, fps, (im.shape[1], im.shape[0]))
            if not writer.isOpened():
                raise OSError(f"cannot open a video writer for {path}")
        writer.write(cv2.cvtColor(im, cv2.COLOR_RGB2BGR))
        n += 1
    if writer is not None:
        writer.release()
    return n


__all__ = [
    "ROOM",
    "WALL",
    "WALL_HEIGHT",
    "Frame",
    "Person",
    "RoomRenderer",
    "behind_wall_walk",
    "crossing_walks",
    "diverse_training_walk",
    "single_person_walk",
    "straight_training_walk",
    "write_video",
]
