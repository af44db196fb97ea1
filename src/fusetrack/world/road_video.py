"""Rendered camera frames of vehicles on a road (the video substitute of spec 003 §3.2).

A :class:`~fusetrack.sensors.camera_geometry.PinholeCamera` at a pose
(:meth:`~fusetrack.sensors.camera_geometry.PinholeCamera.from_pose`: position, height, yaw,
downward pitch) renders 320×240
grey-level frames: a fixed textured background with sensor noise and a slow illumination drift,
each vehicle as the convex hull of its projected 3-D box with its ground shadow, and the urban
clutter the paper names — a swaying tree (random foreground blobs in one image region) and
glints (single-column bright spikes). Perception then sees only pixels.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import cv2
import numpy as np
from numpy.typing import NDArray

from ..sensors import PinholeCamera


@dataclass(frozen=True)
class Vehicle:
    """A box vehicle: centre of mass ``xy``, ``heading`` (rad), size, grey level."""

    xy: tuple[float, float]
    heading: float
    length: float = 4.5
    width: float = 1.8
    height: float = 1.5
    grey: float = 40.0

    def corners(self, z0: float = 0.0, z1: float | None = None) -> NDArray[np.float64]:
        c, s = np.cos(self.heading), np.sin(self.heading)
        hl, hw = self.length / 2, self.width / 2
        base = np.array([[hl, hw], [-hl, hw], [-hl, -hw], [hl, -hw]]) @ np.array([[c, s], [-s, c]])
        base = base + np.asarray(self.xy)
        top = self.height if z1 is None else z1
        return np.concatenate(
            [np.column_stack([base, np.full(4, z0)]), np.column_stack([base, np.full(4, top)])]
        )


@dataclass
class RoadRenderer:
    """Frames of one camera. ``clutter`` scales the tree and glint rates (0 = clean)."""

    camera: PinholeCamera
    rng: np.random.Generator
    clutter: float = 1.0
    noise_sigma: float = 2.0
    shadow_offset: tuple[float, float] = (0.9, -0.6)
    tree_box: tuple[int, int, int, int] | None = None  # (u0, u1, v0, v1)
    background: NDArray[np.float64] = field(init=False)
    frame_index: int = 0

    def __post_init__(self) -> None:
        h, w = self.camera.height, self.camera.width
        tex = cv2.GaussianBlur(self.rng.normal(0, 1, (h, w)), (0, 0), 6)
        tex = 110 + 35 * tex / max(tex.std(), 1e-9)
        self.background = np.clip(tex + np.linspace(30, -10, h)[:, None], 0, 255)
        if self.tree_box is None:
            u0 = int(self.rng.integers(20, w - 80))
            self.tree_box = (u0, u0 + 40, 20, 110)

    def render(self, vehicles: Sequence[Vehicle]) -> NDArray[np.uint8]:
        cam = self.camera
        self.frame_index += 1
        drift = 1.0 + 0.03 * np.sin(2 * np.pi * self.frame_index / 400)
        img = self.background * drift
        order = sorted(vehicles, key=lambda v: -np.linalg.norm(np.asarray(v.xy) - cam.centre[:2]))
        for v in order:
            shadow = Vehicle(
                (v.xy[0] + self.shadow_offset[0], v.xy[1] + self.shadow_offset[1]),
                v.heading,
                v.length,
                v.width,
                0.0,
            )
            self._fill(img, shadow.corners(0.0, 0.0)[:4], None, 0.6)
            self._fill(img, v.corners(0.3), v.grey, None)
        if self.clutter > 0:
            u0, u1, v0, v1 = self.tree_box  # type: ignore[misc]
            for _ in range(self.rng.poisson(2.0 * self.clutter)):
                centre = (int(self.rng.integers(u0, u1)), int(self.rng.integers(v0, v1)))
                axes = (int(self.rng.integers(2, 7)), int(self.rng.integers(2, 7)))
                cv2.ellipse(img, centre, axes, 0, 0, 360, float(self.rng.uniform(30, 90)), -1)
            if self.rng.random() < 0.15 * self.clutter:
                col = int(self.rng.integers(0, cam.width))
                r0 = int(self.rng.integers(0, cam.height - 60))
                img[r0 : r0 + int(self.rng.integers(20, 60)), col] = 255.0
        img = img + self.rng.normal(0, self.noise_sigma, img.shape)
        return np.clip(img, 0, 255).astype(np.uint8)

    def _fill(
        self,
        img: NDArray[np.float64],
        corners: NDArray[np.float64],
        grey: float | None,
        scale: float | None,
    ) -> None:
        if np.any(self.camera.depth(corners) < 0.5):
            return  # (partly) behind the camera: not drawn
        uv = self.camera.project(corners)
        if np.all(uv[:, 0] < -50) or np.all(uv[:, 0] > self.camera.width + 50):
            return
        hull = cv2.convexHull(np.round(uv).astype(np.int32))
        if scale is None:
            cv2.fillConvexPoly(img, hull, float(grey))  # type: ignore[arg-type]
        else:
            mask = np.zeros(img.shape, np.uint8)
            cv2.fillConvexPoly(mask, hull, 1)
            img[mask > 0] *= scale
