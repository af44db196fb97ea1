"""Synthetic video of elliptical head-like sprites with exact ground truth (the substitute for
Zhai 2007's private visual-tracking sequences, spec 001 Sec. 7).

A sequence is built in two pure steps:

1. :func:`keyframe_trajectory` turns a manoeuvre timeline (velocity keyframes, linearly
   interpolated: piecewise-constant acceleration) into a truth ``[x, y, vx, vy]`` per frame, in
   pixels and pixels/frame, ``x`` = column, ``y`` = row, with optional random acceleration jitter.
2. :func:`render` draws every frame: a textured, cluttered background (smoothed colour noise plus
   random rectangles, bars and small ellipse outlines that make Canny edges -- none head-sized,
   so clutter is never a second head), the target and any
   distractor sprites (a filled ellipse with texture and an optional dark "hair" cap), partial
   occluders, camera ego-motion (the background canvas shifts), a global illumination gain and
   sensor noise. Frames are RGB ``uint8`` ``(T, H, W, 3)``.

Everything is generated at run time from a numpy Generator; nothing is downloaded.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import cv2
import numpy as np
from numpy.typing import NDArray

from ..core import ConfigError, invalid

Array = NDArray[np.float64]
_PAD = 32  # noise-bank margin (px)
_SHIFT = 4  # cv2 sub-pixel drawing: coordinates in 1/16 px


def keyframe_trajectory(
    start: Sequence[float],
    keyframes: Sequence[tuple[int, float, float]],
    n_frames: int,
    rng: np.random.Generator | None = None,
    jitter: float = 0.0,
) -> Array:
    """Truth ``(n_frames, 4)`` ``[x, y, vx, vy]`` from velocity keyframes ``(frame, vx, vy)``.

    The velocity is linear between keyframes (constant acceleration per segment) and constant
    before the first and after the last; ``jitter`` (px/frame^2) adds white acceleration noise.
    Frame 0 is at ``start[:2]``; ``x_{k+1} = x_k + (v_k + v_{k+1}) / 2`` (exact for linear v).
    """
    if n_frames < 2:
        raise ConfigError(invalid("n_frames", n_frames, "an integer >= 2"))
    frames = np.array([k[0] for k in keyframes], float)
    if len(frames) and np.any(np.diff(frames) <= 0):
        raise ConfigError(invalid("keyframes", list(frames), "strictly increasing frame numbers"))
    t = np.arange(n_frames, dtype=float)
    if len(keyframes):
        vx = np.interp(t, frames, [k[1] for k in keyframes])
        vy = np.interp(t, frames, [k[2] for k in keyframes])
    else:
        vx = np.full(n_frames, float(start[2]))
        vy = np.full(n_frames, float(start[3]))
    v = np.stack([vx, vy], axis=-1)
    if jitter > 0:
        if rng is None:
            raise ConfigError(invalid("rng", rng, "a numpy Generator when jitter > 0"))
        v = v + np.cumsum(jitter * rng.standard_normal(v.shape), axis=0)
    pos = np.empty_like(v)
    pos[0] = np.asarray(start[:2], float)
    pos[1:] = pos[0] + np.cumsum(0.5 * (v[1:] + v[:-1]), axis=0)
    return np.concatenate([pos, v], axis=-1)


@dataclass(frozen=True)
class Sprite:
    """An elliptical sprite: semi-axes ``(a, b)`` = (horizontal, vertical) px at scale 1, a body
    colour and a darker cap (``hair``, the top ``hair_fraction`` of the ellipse) in RGB 0-255,
    and a texture amplitude (grey-level speckle inside the ellipse)."""

    axes: tuple[float, float] = (14.0, 18.0)
    colour: tuple[int, int, int] = (224, 172, 140)
    hair: tuple[int, int, int] | None = (60, 40, 30)
    hair_fraction: float = 0.35
    texture: float = 18.0


@dataclass(frozen=True)
class Actor:
    """A sprite on a trajectory ``(T, >=2)`` with a per-frame scale ``(T,)``; ``in_front``
    actors are drawn after the target (they occlude it)."""

    sprite: Sprite
    trajectory: Array
    scale: Array | None = None
    in_front: bool = False


@dataclass(frozen=True)
class Scene:
    """Background and camera of a sequence.

    ``clutter``: number of random edge-making shapes; ``clutter_box`` (x0, y0, x1, y1) puts
    ``clutter_local`` more of them in one region (e.g. around the head's path, E9);
    ``ego_motion`` ``(T, 2)`` the camera's pan (px, the background moves by minus it);
    ``gain`` ``(T,)`` the illumination; ``occluders``: ``(first, last, x0, y0, x1, y1)`` grey
    bars drawn over everything in frames ``first..last``; ``noise``: sensor noise std (grey levels).
    """

    height: int = 240
    width: int = 320
    clutter: int = 40
    clutter_box: tuple[float, float, float, float] | None = None
    clutter_local: int = 0
    contrast: float = 1.0
    ego_motion: Array | None = None
    gain: Array | None = None
    occluders: tuple[tuple[int, int, float, float, float, float], ...] = field(default=())
    noise: float = 4.0
    margin: int = 80


def _background(scene: Scene, rng: np.random.Generator) -> NDArray[np.uint8]:
    """A textured canvas ``margin`` px larger than the frame on every side."""
    h, w = scene.height + 2 * scene.margin, scene.width + 2 * scene.margin
    base = rng.uniform(70, 170, size=3)
    noise = rng.standard_normal((h // 8 + 1, w // 8 + 1, 3)).astype(np.float32)
    smooth = cv2.resize(noise, (w, h), interpolation=cv2.INTER_CUBIC)
    img = base + 25.0 * scene.contrast * smooth
    img = np.clip(img, 0, 255).astype(np.uint8)
    img = np.ascontiguousarray(img)

    def shape(x0: float, y0: float, x1: float, y1: float) -> None:
        col = tuple(int(c) for c in np.clip(base + scene.contrast * rng.normal(0, 55, 3), 0, 255))
        cx, cy = rng.uniform(x0, x1), rng.uniform(y0, y1)
        kind = rng.integers(3)
        if kind == 0:
            sx, sy = rng.uniform(4, 30, 2)
            cv2.rectangle(img, (int(cx - sx), int(cy - sy)), (int(cx + sx), int(cy + sy)), col, -1)
        elif kind == 1:
            ang = rng.uniform(0, np.pi)
            ln = rng.uniform(15, 60)
            p0 = (int(cx - ln * np.cos(ang)), int(cy - ln * np.sin(ang)))
            p1 = (int(cx + ln * np.cos(ang)), int(cy + ln * np.sin(ang)))
            cv2.line(img, p0, p1, col, int(rng.integers(1, 4)))
        else:
            ax = (int(rng.uniform(3, 9)), int(rng.uniform(3, 9)))  # smaller than a head
            cv2.ellipse(img, (int(cx), int(cy)), ax, rng.uniform(0, 180), 0, 360, col, 2)

    for _ in range(scene.clutter):
        shape(0, 0, w, h)
    if scene.clutter_box is not None:
        x0, y0, x1, y1 = scene.clutter_box
        m = scene.margin
        for _ in range(scene.clutter_local):
            shape(x0 + m, y0 + m, x1 + m, y1 + m)
    return img


def _draw_sprite(
    img: NDArray[np.uint8],
    sprite: Sprite,
    centre: Array,
    scale: float,
    speckle: NDArray[np.float32],
    gain: float,
) -> None:
    """Alpha-blend the sprite into ``img`` in place, inside its bounding box only."""
    a, b = sprite.axes[0] * scale, sprite.axes[1] * scale
    H, W = img.shape[:2]
    x0, x1 = max(int(centre[0] - a) - 2, 0), min(int(centre[0] + a) + 3, W)
    y0, y1 = max(int(centre[1] - b) - 2, 0), min(int(centre[1] + b) + 3, H)
    if x1 <= x0 or y1 <= y0:
        return
    cx, cy = float(centre[0]) - x0, float(centre[1]) - y0
    roi = img[y0:y1, x0:x1]
    one = 1 << _SHIFT
    mask = np.zeros(roi.shape[:2], np.uint8)
    cv2.ellipse(
        mask,
        (round(cx * one), round(cy * one)),
        (round(float(a) * one), round(float(b) * one)),
        0,
        0,
        360,
        255,
        -1,
        cv2.LINE_AA,
        _SHIFT,
    )
    colour = np.empty(roi.shape, np.float32)
    colour[:] = sprite.colour
    if sprite.hair is not None:
        top = cy - b + 2 * b * sprite.hair_fraction
        colour[: max(int(np.ceil(top)), 0)] = sprite.hair
    ps = speckle.shape[0]  # the texture moves and scales with the sprite
    k = scale * 2.2 * max(sprite.axes) / ps
    warp = np.array([[k, 0, cx - k * ps / 2], [0, k, cy - k * ps / 2]], np.float32)
    tex = cv2.warpAffine(speckle, warp, (roi.shape[1], roi.shape[0]), flags=cv2.INTER_LINEAR)
    colour += sprite.texture * tex[..., None]
    alpha = mask.astype(np.float32)[..., None] / 255.0
    out = roi.astype(np.float32) * (1 - alpha) + np.clip(colour * gain, 0, 255) * alpha
    roi[:] = np.clip(out, 0, 255).astype(np.uint8)


@dataclass(frozen=True)
class RenderedSequence:
    """Rendered frames ``(T, H, W, 3)`` uint8 RGB, the target's truth ``(T, 4)`` and its
    scale ``(T,)`` (the target's semi-axes at frame k are ``sprite.axes * scale[k]``)."""

    frames: NDArray[np.uint8]
    truth: Array
    scale: Array
    sprite: Sprite

    @property
    def half_size(self) -> Array:
        """The target's smaller semi-axis per frame (px): the track-loss radius of spec C17."""
        return np.asarray(min(self.sprite.axes) * self.scale, dtype=np.float64)


def render(
    scene: Scene,
    target: Actor,
    rng: np.random.Generator,
    others: Sequence[Actor] = (),
) -> RenderedSequence:
    """Render every frame of ``target`` (and ``others``) over ``scene``; see the module docstring."""
    truth = np.asarray(target.trajectory, float)
    n = len(truth)
    scale = np.ones(n) if target.scale is None else np.asarray(target.scale, float)
    if scale.shape != (n,):
        raise ConfigError(invalid("target.scale.shape", scale.shape, f"({n},)"))
    ego = np.zeros((n, 2)) if scene.ego_motion is None else np.asarray(scene.ego_motion, float)
    gain = np.ones(n) if scene.gain is None else np.asarray(scene.gain, float)
    if ego.shape != (n, 2) or gain.shape != (n,):
        raise ConfigError(
            invalid("scene.ego_motion/gain", (ego.shape, gain.shape), f"({n}, 2)/({n},)")
        )
    if np.any(np.abs(ego) > scene.margin - 1):
        raise ConfigError(
            invalid(
                "scene.ego_motion", float(np.abs(ego).max()), f"< {scene.margin - 1} px (margin)"
            )
        )
    canvas = _background(scene, rng)
    m, H, W = scene.margin, scene.height, scene.width
    frames = np.empty((n, H, W, 3), np.uint8)
    speckles = {
        id(a): cv2.GaussianBlur(rng.standard_normal((64, 64)).astype(np.float32), (0, 0), 2.0) * 3.0
        for a in (target, *others)
    }
    bank = np.round(
        scene.noise * rng.standard_normal((4, H + _PAD, W + _PAD, 3), dtype=np.float32)
    ).astype(np.int16)
    back = [a for a in others if not a.in_front]
    front = [a for a in others if a.in_front]
    for k in range(n):
        ox, oy = m + ego[k, 0], m + ego[k, 1]
        ix, iy = int(np.floor(ox)), int(np.floor(oy))
        img = canvas[iy : iy + H + 1, ix : ix + W + 1]
        if ox != ix or oy != iy:  # sub-pixel pan
            shift = np.array([[1.0, 0.0, ix - ox], [0.0, 1.0, iy - oy]], np.float32)
            img = np.asarray(cv2.warpAffine(img, shift, (W + 1, H + 1)), dtype=np.uint8)
        img = np.asarray(
            cv2.convertScaleAbs(img[:H, :W], alpha=float(gain[k])), dtype=np.uint8
        )  # illumination, saturating
        for actor in (*back, target, *front):
            traj = np.asarray(actor.trajectory, float)
            if k >= len(traj):
                continue
            s = 1.0 if actor.scale is None else float(np.asarray(actor.scale)[k])
            _draw_sprite(img, actor.sprite, traj[k, :2], s, speckles[id(actor)], float(gain[k]))
        for first, last, x0, y0, x1, y1 in scene.occluders:
            if first <= k <= last:
                cv2.rectangle(img, (int(x0), int(y0)), (int(x1), int(y1)), (128, 128, 128), -1)
        # sensor noise: a random window of a pre-drawn noise bank (cheap, still seeded)
        b, dy, dx = rng.integers(len(bank)), rng.integers(_PAD), rng.integers(_PAD)
        noisy = cv2.add(img.astype(np.int16), bank[b, dy : dy + H, dx : dx + W])
        frames[k] = np.clip(noisy, 0, 255).astype(np.uint8)
    return RenderedSequence(frames, truth, scale, target.sprite)
