"""The rooms and camera layouts of Ercan et al. 2013 (spec §7) and user scenes from YAML files.

The paper shows its layouts only as pictures (Figs. 5, 11, 13b); the coordinates here are the
spec's reconstruction (§7.1-7.3). A :class:`Scene` bundles a room, its cameras, the fixed
camera order of the paper, the occluder diameter and the walking speed and noise, in the scene's
own units (simulation "units" or inches).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from ...core import ConfigError, invalid
from ...evaluation import load_yaml, parse_options
from ...sensors import CameraArray, ring_of_cameras
from ...world import Room, l_shaped_room, rectangle, square_room

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Scene:
    """Everything fixed about one setting."""

    name: str
    room: Room
    cameras: CameraArray
    fixed_order: tuple[int, ...]  # 0-based camera indices, the paper's preselected list
    diameter: float = 3.33
    speed: float = 1.0
    motion_noise: float = 0.33
    prior_q: float = 3.0  # process noise of the occluder-prior Kalman filters (units^2/step)
    prior_q_cv: float = (
        0.03  # white acceleration of the constant-velocity prior filters (calibrated: NEES ~1)
    )
    object_path: Array | None = None  # scripted object positions (lab), or None: a walker

    def __post_init__(self) -> None:
        n = len(self.cameras)
        if sorted(set(self.fixed_order)) != sorted(self.fixed_order) or any(
            not 0 <= i < n for i in self.fixed_order
        ):
            raise ConfigError(
                invalid(
                    "fixed_order",
                    [i + 1 for i in self.fixed_order],
                    f"distinct camera numbers in 1..{n}",
                )
            )
        centres_blocked = ~self.room.free(self.cameras.positions)
        if np.any(centres_blocked):
            bad = [self.cameras.ids[i] for i in np.flatnonzero(centres_blocked)]
            raise ConfigError(
                invalid(
                    "camera position",
                    bad,
                    "cameras inside the room, not in a wall or static occluder",
                )
            )
        probe = self.room.sample_free(np.random.default_rng(12345), 4000)
        sees = self.cameras.in_fov(probe[:, None, :]) & ~self.room.sight_blocked(
            self.cameras.positions[None, :, :], probe[:, None, :]
        )
        blind = ~np.any(sees, axis=0)
        if np.any(blind):
            bad = [self.cameras.ids[i] for i in np.flatnonzero(blind)]
            raise ConfigError(
                invalid(
                    "camera view",
                    bad,
                    "cameras whose field of view contains part of the free floor",
                )
            )


SIM_NOISE = {"sigma_theta": 0.01, "sigma_pos": 1.0, "sigma_read": 2.0}
LAB_NOISE = {"sigma_theta": 0.068, "sigma_pos": 1.0, "sigma_read": 2.0}


def square_scene(static_occluder: bool = True) -> Scene:
    """Fig. 5: 100 x 100 room, 8 cameras (corners odd, walls even), 90 deg FOV (spec §7.1)."""
    occ = [rectangle(35, 65, 40, 60)] if static_occluder else []
    room = square_room(100.0, occ, "square" if static_occluder else "square-open")
    pos = [(0, 0), (50, 0), (100, 0), (100, 50), (100, 100), (50, 100), (0, 100), (0, 50)]
    yaws = [45, 90, 135, 180, 225, 270, 315, 0]
    cams = ring_of_cameras(pos, yaws, 90.0, **SIM_NOISE)
    order = tuple(i - 1 for i in (1, 7, 5, 3, 2, 4, 6, 8))
    return Scene(room.name, room, cams, order)


def l_scene() -> Scene:
    """Fig. 11: the L-shaped room with 12 cameras (spec §7.2)."""
    room = l_shaped_room(200.0)
    pos = [
        (0, 0), (100, 0), (200, 0), (200, 50), (200, 100), (150, 100),
        (100, 100), (100, 150), (100, 200), (50, 200), (0, 200), (0, 100),
    ]  # fmt: skip
    yaws = [45, 90, 135, 180, 225, 270, 225, 180, 225, 270, 315, 0]
    cams = ring_of_cameras(pos, yaws, 90.0, **SIM_NOISE)
    order = tuple(i - 1 for i in (1, 4, 7, 10, 8, 12, 3, 5, 2, 6, 11, 9))
    return Scene("L-shaped", room, cams, order)


LAB_SIZE = (264.0, 228.0)  # 22 ft x 19 ft in inches


def lab_path(steps: int = 200, a: float = 120.0, b: float = 98.0) -> Array:
    """The object's closed path in the lab replica: an ellipse about the room centre, one lap in
    ``steps`` steps; ``a^2 + b^2 = 4 * 77.5^2`` gives the paper's RMSE_max = 77.5 in (spec §7.3)."""
    t = 2 * math.pi * np.arange(steps + 1) / steps
    cx, cy = LAB_SIZE[0] / 2, LAB_SIZE[1] / 2
    return np.column_stack([cx + a * np.cos(t), cy + b * np.sin(t)])


def lab_scene() -> Scene:
    """Fig. 13(b) replica: 22' x 19' room, 16 cameras (4 a wall) aimed at the centre, 47 deg FOV,
    one 24 x 24 in virtual static occluder (spec §7.3). Units: inches."""
    w, h = LAB_SIZE
    occ = rectangle(78, 102, 138, 162)
    room = Room(rectangle(0, w, 0, h), (occ,), "lab")
    fr = (1 / 8, 3 / 8, 5 / 8, 7 / 8)
    inset = 3.0
    pos = (
        [(w * f, inset) for f in fr]
        + [(w - inset, h * f) for f in fr]
        + [(w * (1 - f), h - inset) for f in fr]
        + [(inset, h * (1 - f)) for f in fr]
    )
    c = np.array([w / 2, h / 2])
    yaws = [math.degrees(math.atan2(c[1] - y, c[0] - x)) for x, y in pos]
    cams = ring_of_cameras(pos, yaws, 47.0, **LAB_NOISE)
    order = tuple(i - 1 for i in (1, 13, 9, 5, 3, 8, 11, 16, 6))
    return Scene(
        "lab",
        room,
        cams,
        order,
        diameter=12.0,
        speed=3.6,
        motion_noise=1.2,
        prior_q=39.0,
        prior_q_cv=0.03 * 3.6**2,  # the sim's, scaled by the lab's 3.6 inches per unit
        object_path=lab_path(),
    )


SCENES = {
    "square": lambda: square_scene(True),
    "square-open": lambda: square_scene(False),
    "L": l_scene,
    "lab": lab_scene,
}


def get_scene(name: str) -> Scene:
    try:
        return SCENES[name]()
    except KeyError:
        raise ConfigError(
            invalid("scene", name, f"one of {sorted(SCENES)} or a YAML file")
        ) from None


class CameraConfig(BaseModel):
    """One camera of a ``--config`` room: position, yaw (degrees, anticlockwise from +x), fov."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    position: tuple[float, float]
    yaw: float
    fov: float | None = Field(None, gt=0, le=360, description="degrees (default: the room's)")


class NoiseConfig(BaseModel):
    """Reading noise of every camera (Ercan et al. 2013, Eq. 3)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    sigma_theta: float = Field(default=SIM_NOISE["sigma_theta"], ge=0)
    sigma_pos: float = Field(default=SIM_NOISE["sigma_pos"], ge=0)
    sigma_read: float = Field(default=SIM_NOISE["sigma_read"], ge=0)


class RoomConfig(BaseModel):
    """The YAML format of ``fusetrack run ercan2013-selection --config`` (examples/ercan2013_room.yaml)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    room: list[tuple[float, float]] = Field(description="floor polygon")
    static_occluders: list[list[tuple[float, float]]] = []
    cameras: list[CameraConfig] = Field(min_length=1)
    fov: float = Field(90.0, gt=0, le=360, description="default field of view (degrees)")
    noise: NoiseConfig = NoiseConfig()
    fixed_order: list[int] | None = Field(None, description="1-based camera order (default 1..N)")
    occluder_diameter: float = Field(3.33, gt=0)
    speed: float = Field(1.0, gt=0)
    motion_noise: float = Field(0.33, ge=0)
    prior_q: float = Field(3.0, gt=0)
    prior_q_cv: float = Field(0.03, gt=0)


def scene_from_mapping(spec: Mapping[str, Any], name: str = "custom") -> Scene:
    """A scene from a mapping (the YAML format of ``--config``, :class:`RoomConfig`)::

    room: [[0, 0], [120, 0], [120, 80], [0, 80]]     # floor polygon
    static_occluders: [[[50, 30], [70, 30], [70, 50], [50, 50]]]
    cameras:                                          # position, yaw (deg), optional fov (deg)
      - {position: [0, 0], yaw: 30}
      - {position: [120, 80], yaw: 210, fov: 60}
    fov: 90                                           # default field of view (deg)
    noise: {sigma_theta: 0.01, sigma_pos: 1.0, sigma_read: 2.0}
    fixed_order: [1, 2]                               # 1-based, default 1..N
    occluder_diameter: 3.33
    speed: 1.0
    motion_noise: 0.33
    """
    return scene_from_config(parse_options(RoomConfig, spec, "config"), name)


def scene_from_config(cfg: RoomConfig, name: str = "custom") -> Scene:
    """The :class:`Scene` a validated :class:`RoomConfig` describes."""
    room = Room(
        np.asarray(cfg.room, float), tuple(np.asarray(o, float) for o in cfg.static_occluders), name
    )
    noise = cfg.noise.model_dump()
    arrays = [
        ring_of_cameras(
            [c.position], [c.yaw], cfg.fov if c.fov is None else c.fov, **noise, inset=0.0
        )
        for c in cfg.cameras
    ]
    cams = CameraArray(
        np.concatenate([a.positions for a in arrays]),
        np.concatenate([a.yaws for a in arrays]),
        np.concatenate([a.fovs for a in arrays]),
        np.concatenate([a.focals for a in arrays]),
        np.concatenate([a.sigma_theta for a in arrays]),
        np.concatenate([a.sigma_pos for a in arrays]),
        np.concatenate([a.sigma_read for a in arrays]),
        tuple(f"cam{i + 1}" for i in range(len(arrays))),
    )
    order = list(range(1, len(arrays) + 1)) if cfg.fixed_order is None else cfg.fixed_order
    return Scene(
        name,
        room,
        cams,
        tuple(i - 1 for i in order),
        diameter=cfg.occluder_diameter,
        speed=cfg.speed,
        motion_noise=cfg.motion_noise,
        prior_q=cfg.prior_q,
        prior_q_cv=cfg.prior_q_cv,
    )


def load_scene(path: str | Path) -> Scene:
    """A scene from a YAML file (:class:`RoomConfig`, see :func:`scene_from_mapping`)."""
    return scene_from_config(load_yaml(RoomConfig, path, "config"), Path(path).stem)
