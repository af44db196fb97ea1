"""RFID reader coverages as virtual sensors, refined by two cameras (Lee 2009, Sec. 5.2.3).

A reader detects a tag inside its coverage disk (with a detection probability). The set of
readers that detect a tag names a region of the floor: every distinct region formed by the
overlapping coverages is a *virtual sensor* with a reference point at its centre, and the coarse
position of a tag is the reference point of the region its detecting set names (Lee 2009,
Figs. 5-31, 5-32). With ``k`` readers and at most ``p``-fold overlaps there are at most
``sum_{i=1..p} C(k, i)`` virtual sensors (12 readers, p = 2: 78).

Refinement (Eqs. 5.39-5.40): camera 1 on the middle of the left wall looks along +x and sees the
y offset of the tag from the reference point, camera 2 on the middle of the bottom wall looks
along +y and sees the x offset. In a pinhole camera an image offset ``du`` at depth ``Z`` is a
floor offset ``du Z / f``; Eq. 5.39 uses the reference point's depth, Eq. 5.40 corrects for the
tag's own depth, which the other camera provides (here: the fixed point of that correction,
solved exactly -- the two cameras' rays intersected).

Regions are found on a grid (``resolution`` m), which handles any reader layout without a
geometry library; a region smaller than one cell is not found.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core import ConfigError, invalid

Array = np.ndarray


def max_virtual_sensors(k: int, p: int) -> int:
    """``sum_{i=1..p} C(k, i)``: the bound on the number of virtual sensors."""
    if k < 0 or p < 0:
        raise ConfigError(invalid("k, p", (k, p), "non-negative integers"))
    return sum(math.comb(k, i) for i in range(1, min(p, k) + 1))


@dataclass(frozen=True)
class RfidReader:
    """A reader with a disk coverage of ``radius`` metres around ``position``."""

    reader_id: str
    position: tuple[float, float]
    radius: float
    detection_prob: float = 1.0

    def __post_init__(self) -> None:
        if not (self.radius > 0 and math.isfinite(self.radius)):
            raise ConfigError(
                invalid(
                    f"radius of reader {self.reader_id!r}", self.radius, "a coverage radius > 0 (m)"
                )
            )
        if not 0 < self.detection_prob <= 1:
            raise ConfigError(invalid("detection_prob", self.detection_prob, "in (0, 1]"))

    def covers(self, p: Array) -> Array:
        d = np.asarray(p, float) - np.asarray(self.position)
        return np.hypot(d[..., 0], d[..., 1]) <= self.radius

    def detect(self, p: Array, rng: np.random.Generator) -> bool:
        return bool(self.covers(p)) and rng.random() < self.detection_prob


@dataclass(frozen=True)
class VirtualSensor:
    readers: frozenset[str]
    reference: tuple[float, float]
    area: float


def virtual_sensors(
    readers: list[RfidReader], area: tuple[float, float], resolution: float = 0.05
) -> dict[frozenset[str], VirtualSensor]:
    """Every non-empty region of distinct covering-reader sets inside ``[0, W] x [0, H]``."""
    w, h = area
    xs = np.arange(resolution / 2, w, resolution)
    ys = np.arange(resolution / 2, h, resolution)
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    pts = np.stack([gx.ravel(), gy.ravel()], axis=-1)
    cover = np.stack([r.covers(pts) for r in readers], axis=1)  # (cells, k)
    keys = cover @ (1 << np.arange(len(readers), dtype=np.int64))
    out: dict[frozenset[str], VirtualSensor] = {}
    for key in np.unique(keys):
        if key == 0:
            continue
        cells = pts[keys == key]
        sig = frozenset(r.reader_id for i, r in enumerate(readers) if (int(key) >> i) & 1)
        c = cells.mean(axis=0)
        out[sig] = VirtualSensor(sig, (float(c[0]), float(c[1])), float(len(cells) * resolution**2))
    return out


def coarse_position(
    detected: frozenset[str], regions: dict[frozenset[str], VirtualSensor]
) -> Array | None:
    """The reference point of the region the detecting readers name.

    No detection: ``None`` (the tag is outside every coverage, or every reader missed it).
    A set that names no region (a reader missed the tag inside an overlap) falls back to the
    region of the largest subset of it.
    """
    if not detected:
        return None
    if detected in regions:
        return np.array(regions[detected].reference)
    best = max((s for s in regions if s <= detected), key=len, default=None)
    return None if best is None else np.array(regions[best].reference)


@dataclass(frozen=True)
class WallCameraPair:
    """Two pinhole cameras on the middle of the left and bottom walls (focal length ``f`` px)."""

    room: tuple[float, float]
    f: float = 800.0
    pixel_sigma: float = 1.0

    @property
    def cam1(self) -> Array:
        return np.array([0.0, self.room[1] / 2])  # looks along +x, image coordinate ~ y

    @property
    def cam2(self) -> Array:
        return np.array([self.room[0] / 2, 0.0])  # looks along +y, image coordinate ~ x

    def image(self, p: Array, rng: np.random.Generator | None = None) -> Array:
        """Image coordinates ``(u1, u2)`` of a floor point in the two cameras."""
        p = np.asarray(p, float)
        u1 = self.f * (p[1] - self.cam1[1]) / max(p[0] - self.cam1[0], 1e-6)
        u2 = self.f * (p[0] - self.cam2[0]) / max(p[1] - self.cam2[1], 1e-6)
        u = np.array([u1, u2])
        if rng is not None and self.pixel_sigma > 0:
            u = u + self.pixel_sigma * rng.standard_normal(2)
        return u

    def jacobian(self, p: Array) -> Array:
        """``d(u1, u2)/d(x, y)`` at floor points ``p`` ``(..., 2)``: ``(..., 2, 2)``, with
        ``u1 = f (y - c1y) / (x - c1x)`` and ``u2 = f (x - c2x) / (y - c2y)``."""
        p = np.asarray(p, float)
        d1 = p[..., 0] - self.cam1[0]  # camera 1's depth
        o1 = p[..., 1] - self.cam1[1]
        d2 = p[..., 1] - self.cam2[1]  # camera 2's depth
        o2 = p[..., 0] - self.cam2[0]
        if np.any(d1 <= 0) or np.any(d2 <= 0):
            raise ConfigError(invalid("p", "a point behind a camera", "points inside the room"))
        row1 = np.stack([-self.f * o1 / d1**2, self.f / d1], axis=-1)
        row2 = np.stack([self.f / d2, -self.f * o2 / d2**2], axis=-1)
        return np.stack([row1, row2], axis=-2)

    def fisher_information(self, p: Array) -> Array:
        """``H^T H / pixel_sigma^2`` (1/m^2) at floor points ``p`` ``(..., 2)``: the Fisher
        information of the two image coordinates (independent Gaussian pixel noise)."""
        if not self.pixel_sigma > 0:
            raise ConfigError(invalid("pixel_sigma", self.pixel_sigma, "> 0 for a finite bound"))
        H = self.jacobian(p)
        return np.asarray(np.swapaxes(H, -1, -2) @ H / self.pixel_sigma**2)

    def refine(self, coarse: Array, u_obj: Array, *, depth_corrected: bool = True) -> Array:
        """Refined position from the coarse reference point and the tag's image coordinates.

        Eq. 5.39 (``depth_corrected=False``): offsets scaled by the reference point's depth.
        Eq. 5.40: scaled by the tag's depth, taken from the other camera's refined coordinate.
        """
        ref = np.asarray(coarse, float)
        u_ref = self.image(ref)
        a, b = u_obj[0] / self.f, u_obj[1] / self.f
        c1, c2 = self.cam1, self.cam2
        det = 1.0 - a * b
        if depth_corrected and abs(det) > 1e-6:
            # The fixed point of "each camera's offset at the depth the other camera gives":
            # y - c1y = a (x - c1x) and x - c2x = b (y - c2y), solved at once.
            x = (c2[0] + b * (c1[1] - a * c1[0] - c2[1])) / det
            return np.array([x, c1[1] + a * (x - c1[0])])
        depth1, depth2 = ref[0] - c1[0], ref[1] - c2[1]  # Eq. 5.39: the reference's depths
        return np.array(
            [
                ref[0] + (u_obj[1] - u_ref[1]) * depth2 / self.f,
                ref[1] + (u_obj[0] - u_ref[0]) * depth1 / self.f,
            ]
        )
