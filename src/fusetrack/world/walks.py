"""Walks of people on the floor for the Nott (2009) reproductions: smooth paths sampled at a
frame rate, in floor metres (the camera of :func:`~fusetrack.sensors.camera_geometry.default_camera`
sees x in [1, 8] m, y in [1, 14] m)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core.errors import ConfigError, invalid

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Walk:
    """Foot positions ``xy`` ``(T, 2)`` at ``times`` ``(T,)`` (s) of one person."""

    times: Array
    xy: Array

    @property
    def velocity(self) -> Array:
        return (
            np.gradient(self.xy, self.times, axis=0)
            if len(self.times) > 1
            else np.zeros_like(self.xy)
        )


def polyline_walk(waypoints: ArrayLike, speed: float, fps: float, t0: float = 0.0) -> Walk:
    """Constant-speed walk through ``waypoints`` ``(K, 2)``, sampled at ``fps``."""
    w = np.asarray(waypoints, float)
    if w.ndim != 2 or w.shape[1] != 2 or len(w) < 2:
        raise ConfigError(invalid("waypoints", w.tolist(), "(K >= 2, 2) floor points"))
    seg = np.linalg.norm(np.diff(w, axis=0), axis=1)
    s_way = np.concatenate([[0.0], np.cumsum(seg)])
    n = int(np.floor(s_way[-1] / speed * fps)) + 1
    s = np.arange(n) * speed / fps
    xy = np.column_stack([np.interp(s, s_way, w[:, 0]), np.interp(s, s_way, w[:, 1])])
    return Walk(t0 + np.arange(n) / fps, xy)


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


__all__ = [
    "WALL",
    "WALL_HEIGHT",
    "Walk",
    "behind_wall_walk",
    "crossing_walks",
    "diverse_training_walk",
    "polyline_walk",
    "single_person_walk",
    "straight_training_walk",
]
