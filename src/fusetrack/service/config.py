"""The network config of a fusion node (``fusetrack serve --config network.yaml``).

One YAML file says where the sensors are and what they measure, which node owns which sensors
and with which key, how the node fuses (rate, alignment, clock, tracker) and its limits. Angles
may be given in radians (``sigma``, ``heading``, ``fov``) or degrees (``sigma_deg``, ...);
they are converted once here. See ``examples/network.yaml`` for a commented example.

:func:`load_config` raises :class:`~fusetrack.core.ConfigError` naming the field, the value
and what would be valid.
"""

from __future__ import annotations

import hashlib
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, ClassVar, Literal

import numpy as np
import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator
from pydantic_core import PydanticCustomError

from ..core import ConfigError, Gaussian, invalid
from ..motion import ConstantVelocity, CoordinatedTurnRate
from ..sensors import (
    AngularSampling,
    AzimuthPolar,
    Bearing,
    HomographyCamera,
    PositionFix,
    Range,
    RangeBearing,
)
from .auth import MIN_KEY_BYTES, bearer_token
from .schema import _NAME, READING_KINDS

FUSED_KINDS: tuple[str, ...] = READING_KINDS
"""Reading kinds a node may be configured for. ``detection_function`` readings need the grid
tracker (``tracker.filter: grid``); every other kind is fused by every tracker."""

GRID_ONLY_KINDS: tuple[str, ...] = ("detection_function",)

MAX_GRID_CELLS = 250_000
"""The grid tracker keeps one arc-mean matrix (cells x samples) per detection-function sensor:
a bound on the cells keeps a config from asking for gigabytes."""


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    @model_validator(mode="before")
    @classmethod
    def _known_keys(cls, data: Any) -> Any:
        """An unknown key is refused with the section's valid keys (``NAME_deg`` stands for an
        angle ``NAME``)."""
        if isinstance(data, dict):
            valid = list(cls.model_fields)
            for key in data:
                name = key[: -len("_deg")] if isinstance(key, str) and key.endswith("_deg") else key
                if name not in valid:
                    raise PydanticCustomError(
                        "unknown_key",
                        "unknown key {key}: valid keys are {valid}",
                        {"key": key, "valid": ", ".join(valid)},
                    )
        return data


def _degrees(data: Any, names: tuple[str, ...]) -> Any:
    """Replace ``NAME_deg`` entries by ``NAME`` in radians (unit conversion at the edge)."""
    if not isinstance(data, dict):
        return data
    out = dict(data)
    for name in names:
        key = f"{name}_deg"
        if key in out:
            if name in out:
                raise ValueError(f"give {name} (rad) or {key}, not both")
            value = out.pop(key)
            out[name] = math.radians(value) if isinstance(value, int | float) else value
    return out


class SensorConfig(_Section):
    """One sensor: its id, kind, geometry and noise (SI units, radians)."""

    id: str = Field(pattern=_NAME)
    kind: Literal[
        "bearing",
        "doa",
        "range",
        "range_bearing",
        "position_fix",
        "image_position",
        "detection_function",
    ]
    position: list[float] | None = Field(default=None, min_length=2, max_length=3)
    heading: float = 0.0
    fov: float = Field(default=2 * math.pi, gt=0.0, le=2 * math.pi)
    max_range: float = Field(default=math.inf, gt=0.0, allow_inf_nan=True)
    sigma: float | None = Field(default=None, gt=0.0, description="bearing / range noise std")
    sigma_range: float | None = Field(default=None, gt=0.0)
    sigma_bearing: float | None = Field(default=None, gt=0.0)
    sigma_azimuth: float | None = Field(default=None, gt=0.0)
    sigma_polar: float | None = Field(default=None, gt=0.0)
    cov: list[list[float]] | None = None
    homography: list[list[float]] | None = Field(
        default=None, description="image_position: 3x3 ground plane (m) -> image (px)"
    )
    sigma_px: float | None = Field(default=None, gt=0.0, description="image_position noise")
    image_size: list[int] = Field(default=[640, 480], min_length=2, max_length=2)
    cells: int | None = Field(
        default=None,
        ge=2,
        le=4096,
        description="detection_function: samples per reading, over the full circle when fov "
        "is 2 pi (microphone beams, the first at the heading) or else over the field of view "
        "(camera column bins, centred)",
    )

    @model_validator(mode="before")
    @classmethod
    def _angles_in_degrees(cls, data: Any) -> Any:
        names = ("heading", "fov", "sigma", "sigma_bearing", "sigma_azimuth", "sigma_polar")
        return _degrees(data, names)

    @model_validator(mode="after")
    def _needs(self) -> SensorConfig:
        need = {
            "bearing": ("position", "sigma"),
            "doa": ("position", "sigma_azimuth", "sigma_polar"),
            "range": ("position", "sigma"),
            "range_bearing": ("position", "sigma_range", "sigma_bearing"),
            "position_fix": ("cov",),
            "image_position": ("homography", "sigma_px"),
            "detection_function": ("position", "cells"),
        }[self.kind]
        missing = [n for n in need if getattr(self, n) is None]
        if missing:
            raise ValueError(f"a {self.kind} sensor needs {', '.join(missing)}")
        return self

    def model(self) -> Any:
        """The fusetrack sensor model this entry describes."""
        s: Any = self  # the validator above guarantees the fields this kind needs
        geometry: dict[str, Any] = {
            "heading": s.heading,
            "fov": s.fov,
            "max_range": s.max_range,
        }
        match s.kind:
            case "bearing":
                return Bearing(s.id, position=s.position, sigma=s.sigma, **geometry)
            case "doa":
                return AzimuthPolar(
                    s.id,
                    position=s.position,
                    sigma_azimuth=s.sigma_azimuth,
                    sigma_polar=s.sigma_polar,
                    **geometry,
                )
            case "range":
                return Range(s.id, position=s.position, sigma=s.sigma, **geometry)
            case "range_bearing":
                return RangeBearing(
                    s.id,
                    position=s.position,
                    sigma_range=s.sigma_range,
                    sigma_bearing=s.sigma_bearing,
                    **geometry,
                )
            case "image_position":
                return HomographyCamera(
                    s.id,
                    foot_homography=np.array(s.homography),
                    variant="foot",
                    sigma_px=s.sigma_px,
                    image_size=(s.image_size[0], s.image_size[1]),
                )
            case "detection_function":
                return DetectionFunctionSensor(s.id, s.position, s.heading, self.sampling())
            case _:
                return PositionFix(s.id, cov=np.array(s.cov), position=s.position)

    def sampling(self) -> AngularSampling:
        """Where a detection function's samples lie, in the sensor's frame."""
        if self.cells is None:
            raise ConfigError(invalid(f"sensors[{self.id}].cells", None, "a number of samples"))
        if self.fov >= 2 * math.pi - 1e-9:
            return AngularSampling.beams(self.cells)
        return AngularSampling.camera_bins(self.fov, self.cells)


@dataclass(frozen=True)
class DetectionFunctionSensor:
    """A sensor that reports a detection function (Kushwaha 2010, Ch. III): beam energies of a
    microphone array or per-column foreground scores of a camera, ``dim`` = its samples. Only the
    grid tracker fuses it (:mod:`fusetrack.service.grid_cells`)."""

    sensor_id: str
    position: list[float]
    heading: float
    sampling: AngularSampling

    @property
    def dim(self) -> int:
        return self.sampling.size

    @property
    def position_index(self) -> tuple[int, int]:
        return (0, 1)


class _KeyHolder(_Section):
    """An id with a key, inline or the name of an environment variable holding it."""

    id: str = Field(pattern=_NAME)
    key: str | None = None
    key_env: str | None = None

    _section: ClassVar[str] = "nodes"

    def secret(self) -> bytes:
        """The key as bytes (at least 16)."""
        where = f"{self._section}[{self.id}]"
        if (self.key is None) == (self.key_env is None):
            raise ConfigError(invalid(f"{where}.key", self.key, "key or key_env, one"))
        raw = self.key if self.key is not None else os.environ.get(str(self.key_env))
        if raw is None:
            raise ConfigError(
                invalid(f"{where}.key_env", self.key_env, "a set environment variable")
            )
        key = raw.encode()
        if len(key) < MIN_KEY_BYTES:
            raise ConfigError(
                invalid(f"{where}.key", "<hidden>", f"at least {MIN_KEY_BYTES} bytes")
            )
        return key


class NodeConfig(_KeyHolder):
    """A sensor node: its id, its key (``key`` or ``key_env``) and the sensors it may report
    for. Its bearer token (:func:`.auth.bearer_token`) may post readings and read."""

    sensors: list[str] = Field(min_length=1)


class ReaderConfig(_KeyHolder):
    """A reader (a dashboard, a client of ``/tracks``): its bearer token may read and subscribe
    but never post readings. Once any reader is configured, reading needs a token."""

    _section: ClassVar[str] = "readers"


class MotionConfig(_Section):
    model: Literal["constant_velocity", "coordinated_turn_rate"] = "constant_velocity"
    q: float = Field(default=1.0, gt=0.0)
    q_omega: float = Field(default=0.01, gt=0.0)
    ndim: Literal[2, 3] = 2

    def build(self) -> Any:
        if self.model == "coordinated_turn_rate":
            return CoordinatedTurnRate(q=self.q, q_omega=self.q_omega)
        return ConstantVelocity(ndim=self.ndim, q=self.q)


class GridConfig(_Section):
    """The grid tracker (``filter: grid``; Kushwaha 2010, Ch. III): cells over ``area``, the
    directional motion's box half-width ``delta`` (m per tick) and the fusion rule of the
    sensors' per-cell likelihoods (``product``, Eq. 30, or quality-weighted ``sum``, Eq. 31)."""

    cell: float = Field(default=1.0, gt=0.0)
    delta: float = Field(default=1.5, ge=0.0)
    fusion: Literal["product", "sum"] = "product"
    max_speed: float = Field(default=20.0, gt=0.0, description="m/s, clips the grid's velocity")


class SingleTarget(_Section):
    """One target (``method: none``, the default): the configured filter is a one-track tracker
    that publishes its estimate every tick."""

    method: Literal["none"] = "none"


PerSensor = float | dict[str, float]
"""One number for every sensor, or ``sensor id -> number`` naming every sensor."""


class ScanTrackerAssociation(_Section):
    """What every scan-by-scan multi-target tracker (``gnn``, ``jpda``, ``mht``) shares: the
    :class:`~fusetrack.tracking.MultiTargetTracker` on the configured filter and sensors, one
    scan per tick (every reading of the tick, at the tick time). A reading of a position fix or
    a range-bearing plot that no track takes starts a tentative track (its position from the
    reading, the rest from ``prior_mean``/``prior_std``); bearings, ranges, DOAs and image
    positions update tracks but start none."""

    p_detect: PerSensor = Field(
        default=0.9, description="P_D in (0, 1] of a target in a tick; or per sensor id"
    )
    clutter_density: PerSensor = Field(
        default=1e-4,
        description="false readings per tick per unit of a sensor's measurement space (m^2 "
        "for a 2-D position fix, m rad for a range-bearing plot, rad for a bearing); or per "
        "sensor id",
    )
    gate_probability: float = Field(
        default=0.999, gt=0.0, le=1.0, description="P_G: the share of a target's readings gated"
    )
    survival_probability: float = Field(
        default=0.99, gt=0.0, le=1.0, description="P_S from one tick to the next (existence)"
    )
    confirm_m: int = Field(default=2, ge=1, description="confirm a track detected in M ...")
    confirm_n: int = Field(default=3, ge=1, description="... of its first N ticks (M-of-N)")
    delete_misses: int = Field(
        default=5, ge=1, description="end a confirmed track after this many missed ticks in a row"
    )

    @model_validator(mode="after")
    def _m_of_n(self) -> ScanTrackerAssociation:
        if self.confirm_m > self.confirm_n:
            raise ValueError(
                f"confirm_m={self.confirm_m} must be at most confirm_n={self.confirm_n}"
            )
        for name in ("p_detect", "clutter_density"):
            values = getattr(self, name)
            values = values.values() if isinstance(values, dict) else [values]
            hi = 1.0 if name == "p_detect" else math.inf
            if not all(0.0 < v <= hi and math.isfinite(v) for v in values):
                raise ValueError(f"{name} must be in (0, {hi:g}] (per sensor too)")
        return self


class GNNAssociation(ScanTrackerAssociation):
    """Global nearest neighbour: the most likely joint assignment of each tick's readings
    (Blackman & Popoli 1999, Ch. 6; :class:`~fusetrack.association.GlobalNearestNeighbour`)."""

    method: Literal["gnn"]


class JPDAAssociation(ScanTrackerAssociation):
    """Joint probabilistic data association (Fortmann, Bar-Shalom & Scheffe 1983;
    :class:`~fusetrack.association.JointProbabilisticDataAssociation`): each track updated with
    the probability-weighted mix of its gated readings; exact up to ``max_exact_events`` joint
    events per cluster, loopy belief propagation above."""

    method: Literal["jpda"]
    max_exact_events: int = Field(default=10_000, ge=0)
    unassociated_below: float = Field(
        default=0.5,
        gt=0.0,
        le=1.0,
        description="a reading less likely than this to be any track's may start a track",
    )


class MHTAssociation(ScanTrackerAssociation):
    """Track-oriented MHT (Blackman 2004; :class:`~fusetrack.association.TrackOrientedMHT`) as
    the tracker's per-tick associator: each track keeps its ``max_hypotheses`` best children of
    the tick, weighted."""

    method: Literal["mht"]
    max_hypotheses: int = Field(default=20, ge=1)


class PHDAssociation(_Section):
    """The Gaussian-mixture PHD filter (Vo & Ma 2006; :class:`~fusetrack.filters.GMPHDFilter`,
    extended-Kalman form on the configured motion and sensors), one scan per tick. New targets
    are born anywhere in ``area``: ``birth_cells`` x ``birth_cells`` Gaussian components of
    total weight ``birth_weight`` (expected births per tick), velocities (and any other state
    entry) from ``prior_mean``/``prior_std``. Tracks are the components of weight above
    ``extract_threshold``, with their labels as ids (Panta, Clark & Vo 2009)."""

    method: Literal["phd"]
    p_detect: float = Field(default=0.9, gt=0.0, le=1.0)
    clutter_density: PerSensor = Field(
        default=1e-4, description="false readings per tick per unit measurement space"
    )
    survival_probability: float = Field(default=0.99, ge=0.0, le=1.0)
    birth_weight: float = Field(default=0.1, gt=0.0, description="expected births per tick")
    birth_cells: int = Field(default=4, ge=1, le=50)
    extract_threshold: float = Field(default=0.5, ge=0.0)
    truncation_threshold: float = Field(default=1e-5, ge=0.0)
    merge_threshold: float = Field(default=4.0, ge=0.0)
    max_components: int = Field(default=100, ge=1)

    @model_validator(mode="after")
    def _clutter(self) -> PHDAssociation:
        c = self.clutter_density
        if not all(
            v > 0 and math.isfinite(v) for v in (c.values() if isinstance(c, dict) else [c])
        ):
            raise ValueError("clutter_density must be > 0 (per sensor too)")
        return self


class MCMCDAAssociation(_Section):
    """Online MCMCDA (Oh et al. 2009, as Kushwaha 2010 uses it) on each tick's position
    detections: position fixes, range-bearing plots converted to positions, and with the grid
    tracker the peaks of the tick's fused likelihood; ``tracker.filter`` is used only for
    ``grid``."""

    method: Literal["mcmcda"]
    n_mc: int = Field(default=300, ge=1, le=100_000)
    window: int = Field(default=8, ge=2, le=1000)
    max_gap: int = Field(default=3, ge=1)
    max_speed: float = Field(default=20.0, gt=0.0)
    p_detect: float = Field(default=0.8, gt=0.0, lt=1.0)
    p_terminate: float = Field(default=0.05, gt=0.0, lt=1.0)
    birth_rate: float = Field(default=0.05, gt=0.0, description="per tick, whole area")
    false_alarm_rate: float = Field(default=0.1, gt=0.0, description="per tick, whole area")
    obs_std: float = Field(default=1.0, gt=0.0, description="m")
    accel_std: float = Field(default=2.0, gt=0.0, description="m/s^2")


AssociationConfig = Annotated[
    SingleTarget
    | GNNAssociation
    | JPDAAssociation
    | MHTAssociation
    | PHDAssociation
    | MCMCDAAssociation,
    Field(discriminator="method"),
]
"""``tracker.association``: one target (``none``) or several (``gnn``, ``jpda``, ``mht``,
``phd``, ``mcmcda``), each method with its own fields."""

ASSOCIATION_METHODS: tuple[str, ...] = ("none", "gnn", "jpda", "mht", "phd", "mcmcda")
MULTI_TARGET_METHODS: tuple[str, ...] = ASSOCIATION_METHODS[1:]


class TrackerConfig(_Section):
    """Which filter fuses the readings, with which motion model and prior."""

    filter: Literal["ekf", "ukf", "pf", "grid"] = "ekf"
    update: Literal["joint", "sequential"] = Field(
        default="joint",
        description="ekf/ukf: fuse the readings of one time as one stacked measurement (one "
        "gain) or one after the other",
    )
    particles: int = Field(default=1000, ge=10, le=1_000_000)
    seed: int = Field(default=0, ge=0)
    motion: MotionConfig = MotionConfig()
    prior_mean: list[float]
    prior_std: list[float]
    grid: GridConfig = GridConfig()
    association: AssociationConfig = SingleTarget()

    @model_validator(mode="before")
    @classmethod
    def _single_by_default(cls, data: Any) -> Any:
        """An ``association`` section without ``method`` is the single-target one."""
        if isinstance(data, dict) and isinstance(data.get("association"), dict):
            if "method" not in data["association"]:
                data = {**data, "association": {"method": "none", **data["association"]}}
        return data

    @model_validator(mode="after")
    def _prior(self) -> TrackerConfig:
        if len(self.prior_mean) != len(self.prior_std) or any(s <= 0 for s in self.prior_std):
            raise ValueError("prior_mean and prior_std need the same length and std > 0")
        return self

    def prior(self) -> Gaussian:
        return Gaussian(np.array(self.prior_mean), np.diag(np.square(self.prior_std)))


class FusionConfig(_Section):
    """When and how readings are fused.

    ``rate_hz``: fusion ticks per second. ``alignment``: ``all`` fuses every reading in time
    order (each at its own time, then predicts to the tick); ``closest`` fuses, per sensor, the
    one reading closest to the tick time (within half a period each side), as if taken at the
    tick. ``clock``: ``wall`` ticks on the node's clock (readings stamped in Unix seconds);
    ``data`` ticks as the readings' own times advance (replays at any speed, simulations): the
    ``clock_quorum``-th latest of the nodes' latest reading times, so that one node stamping
    ahead cannot move everyone's clock (with fewer nodes heard, the heard ones set it).
    ``lag``: seconds the fusion waits behind the clock for late readings. ``start``: the time of
    the prior and of tick 0 (``data`` clock; the ``wall`` clock starts at the node's start).
    ``idle_flush``: with the ``data`` clock, the last ``lag`` seconds of a stream are fused once
    no reading has come for this many wall seconds (the end of a replay).
    """

    rate_hz: float = Field(default=4.0, gt=0.0, le=1000.0)
    alignment: Literal["all", "closest"] = "all"
    clock: Literal["wall", "data"] = "wall"
    lag: float = Field(default=0.5, ge=0.0, le=3600.0)
    start: float = 0.0
    max_future: float = Field(default=10.0, gt=0.0, description="s ahead of the clock allowed")
    clock_quorum: int = Field(
        default=2,
        ge=1,
        le=1000,
        description="data clock: the clock is the clock_quorum-th latest of the nodes' latest "
        "reading times (nodes heard within silent_after wall seconds), so no single node drags "
        "it; 1: the latest reading's time",
    )
    silent_after: float = Field(default=5.0, gt=0.0, description="s without readings: silent")
    idle_flush: float | None = Field(
        default=2.0,
        gt=0.0,
        description="data clock: after this many wall seconds without a "
        "reading, fuse up to the latest reading without waiting for the lag (None: never)",
    )

    @property
    def period(self) -> float:
        return 1.0 / self.rate_hz


class LimitsConfig(_Section):
    max_message_bytes: int = Field(default=65536, ge=256, le=16 * 2**20)
    buffer_size: int = Field(default=256, ge=1, le=1_000_000)
    max_pending: int = Field(default=100_000, ge=1)
    history: int = Field(default=600, ge=1, le=1_000_000)
    max_subscribers: int = Field(
        default=64, ge=1, le=100_000, description="open /ws/tracks connections at most"
    )
    auth_failure_burst: int = Field(
        default=100,
        ge=1,
        le=1_000_000,
        description="authentication failures one source address may make before its messages "
        "are dropped unchecked (UDP) or answered 429 (HTTP)",
    )
    auth_failures_per_second: float = Field(
        default=10.0, gt=0.0, le=1e6, description="refill rate of a source's failures"
    )
    max_frame_age: float = Field(
        default=30.0,
        gt=0.0,
        le=86400.0,
        description="UDP frames sent longer ago than this (seconds, by the node's wall clock) "
        "are refused as stale: a captured frame is replayable for this long at most",
    )
    max_clock_skew: float = Field(
        default=2.0,
        ge=0.0,
        le=3600.0,
        description="how far (seconds) a sender's clock may be off the node's: frames sent "
        "further ahead are refused (clock_skew); without a log, frames sent before the node "
        "started, less this, are refused (stale)",
    )

    @model_validator(mode="after")
    def _age_covers_skew(self) -> LimitsConfig:
        """A sender whose clock runs ``max_clock_skew`` behind must still have frames fresh."""
        if self.max_frame_age <= self.max_clock_skew:
            raise ValueError(
                f"limits.max_frame_age={self.max_frame_age:g} is invalid: expected more than "
                f"limits.max_clock_skew={self.max_clock_skew:g} (a sender whose clock runs "
                "behind by the skew would have every frame refused as stale)"
            )
        return self


class LogConfig(_Section):
    """The durable log (:mod:`.log`): ``path``, a SQLite file (relative to the config file), and
    ``durability``: ``normal`` (SQLite ``synchronous=NORMAL`` in WAL mode: a killed process
    loses no committed message, a power cut or OS crash may lose the last commits) or ``full``
    (``synchronous=FULL``: every commit is on disk before it is acknowledged; slower writes).
    ``log: PATH`` is short for ``log: {path: PATH}``."""

    path: str | None = None
    durability: Literal["normal", "full"] = "normal"


def _topic_problem(topic: str, wildcards: bool) -> str | None:
    """Why ``topic`` is not a valid MQTT topic (a filter when ``wildcards``), or None
    (MQTT 3.1.1 §4.7: ``+`` a whole level, ``#`` the last level; no NUL; at most 65535 bytes)."""
    if not topic or len(topic.encode()) > 65535 or "\0" in topic:
        return "1 to 65535 UTF-8 bytes without NUL"
    levels = topic.split("/")
    if not wildcards:
        return "a topic without + or # wildcards" if {"+", "#"} & set(topic) else None
    for i, level in enumerate(levels):
        if ("+" in level and level != "+") or ("#" in level and level != "#"):
            return "wildcards + and # filling a whole level"
        if level == "#" and i != len(levels) - 1:
            return "# only as the last level"
    return None


class MqttTlsConfig(_Section):
    """TLS to the broker: ``ca_file`` (PEM; the system's CAs when absent) and, for brokers that
    authenticate clients by certificate, ``cert_file`` and ``key_file`` (relative paths are
    relative to the config file)."""

    ca_file: str | None = None
    cert_file: str | None = None
    key_file: str | None = None

    @model_validator(mode="after")
    def _pair(self) -> MqttTlsConfig:
        if (self.cert_file is None) != (self.key_file is None):
            raise ValueError("give cert_file and key_file together, or neither")
        return self


class MqttConfig(_Section):
    """The MQTT bridge (:mod:`.mqtt`): the node subscribes to ``subscribe`` (topic filters) and
    ingests each message's payload as a sealed frame (:func:`.auth.seal`, the UDP frame format:
    per-node HMAC, JSON or MessagePack inside); it publishes each tick's tracks (the
    ``/ws/tracks`` JSON) to ``publish_tracks``. ``qos`` is used for both; with QoS 1 or 2 a
    message is acknowledged to the broker only once the node has ingested and logged it.
    ``clean_session: false`` keeps the session (subscriptions, QoS 1/2 messages queued while
    the node is away) on the broker under ``client_id``. MQTT 3.1.1."""

    host: str = Field(default="127.0.0.1", min_length=1)
    port: int = Field(default=1883, ge=1, le=65535)
    subscribe: list[str] = Field(default=[], max_length=100)
    publish_tracks: str | None = None
    qos: Literal[0, 1, 2] = 1
    retain_tracks: bool = False
    client_id: str = Field(default="fusetrack-node", pattern=r"^[A-Za-z0-9_.\-]{1,64}$")
    clean_session: bool = False
    keepalive: int = Field(default=30, ge=5, le=3600, description="seconds")
    username: str | None = None
    password: str | None = None
    password_env: str | None = None
    tls: MqttTlsConfig | None = None
    reconnect_min: float = Field(default=0.5, gt=0.0, le=60.0, description="s, first retry")
    reconnect_max: float = Field(default=30.0, gt=0.0, le=3600.0, description="s, doubling cap")
    max_queued: int = Field(
        default=1000, ge=1, le=1_000_000, description="track messages queued while disconnected"
    )

    @model_validator(mode="after")
    def _valid(self) -> MqttConfig:
        if not self.subscribe and self.publish_tracks is None:
            raise ValueError("give subscribe (topics to ingest) or publish_tracks, or both")
        for topic in self.subscribe:
            problem = _topic_problem(topic, wildcards=True)
            if problem:
                raise ValueError(f"subscribe topic {topic!r} is invalid: expected {problem}")
        if self.publish_tracks is not None:
            problem = _topic_problem(self.publish_tracks, wildcards=False)
            if problem:
                raise ValueError(
                    f"publish_tracks={self.publish_tracks!r} is invalid: expected {problem}"
                )
        if self.password is not None and self.password_env is not None:
            raise ValueError("give password or password_env, not both")
        if (self.password is not None or self.password_env is not None) and not self.username:
            raise ValueError("a password needs a username")
        if self.reconnect_min > self.reconnect_max:
            raise ValueError("reconnect_min must be at most reconnect_max")
        return self

    def secret(self) -> str | None:
        """The broker password (inline or from the environment variable ``password_env``)."""
        if self.password_env is None:
            return self.password
        value = os.environ.get(self.password_env)
        if value is None:
            raise ConfigError(
                invalid("mqtt.password_env", self.password_env, "a set environment variable")
            )
        return value


class NetworkConfig(_Section):
    """The whole node: sensors, nodes and their keys, fusion, tracker, limits, durable log."""

    version: Literal[1] = 1
    area: list[float] = Field(default=[0.0, 100.0, 0.0, 100.0], min_length=4, max_length=4)
    sensors: list[SensorConfig] = Field(min_length=1)
    nodes: list[NodeConfig] = Field(min_length=1)
    readers: list[ReaderConfig] = Field(
        default=[], description="read-only tokens; when given, reading needs a token"
    )
    fusion: FusionConfig = FusionConfig()
    tracker: TrackerConfig
    limits: LimitsConfig = LimitsConfig()
    log: LogConfig = LogConfig()
    mqtt: MqttConfig | None = Field(
        default=None, description="the MQTT bridge (subscribe to readings, publish tracks)"
    )

    @model_validator(mode="before")
    @classmethod
    def _log_path(cls, data: Any) -> Any:
        """``log: PATH`` (or null) is the log section with that path."""
        if isinstance(data, dict) and (data.get("log") is None or isinstance(data["log"], str)):
            data = {**data, "log": {"path": data.get("log")}}
        return data

    @model_validator(mode="after")
    def _consistent(self) -> NetworkConfig:
        ids = [s.id for s in self.sensors]
        if len(set(ids)) != len(ids):
            raise ValueError(f"sensor ids must be unique, got {ids}")
        nodes = [n.id for n in self.nodes]
        if len(set(nodes)) != len(nodes):
            raise ValueError(f"node ids must be unique, got {nodes}")
        owners: dict[str, str] = {}
        for n in self.nodes:
            for s in n.sensors:
                if s not in ids:
                    raise ValueError(f"node {n.id!r} names sensor {s!r}, not one of {ids}")
                if s in owners:
                    raise ValueError(f"sensor {s!r} belongs to nodes {owners[s]!r} and {n.id!r}")
                owners[s] = n.id
        return self

    # -- what the node is built from ---------------------------------------------------------
    def sensor_models(self) -> dict[str, Any]:
        return {s.id: s.model() for s in self.sensors}

    def sensor(self, sensor_id: str) -> SensorConfig:
        return next(s for s in self.sensors if s.id == sensor_id)

    def keys(self) -> dict[str, bytes]:
        return {n.id: n.secret() for n in self.nodes}

    def fingerprint(self) -> str:
        """SHA-256 of everything that decides the tracks (all but ``log``, ``limits``,
        ``readers`` and ``mqtt``): a durable log records it and refuses to resume under another
        config."""
        body = self.model_dump_json(exclude={"log", "limits", "readers", "mqtt"})
        return hashlib.sha256(body.encode()).hexdigest()

    def tokens(self) -> dict[str, str]:
        return {node: bearer_token(key) for node, key in self.keys().items()}

    def read_tokens(self) -> dict[str, str]:
        """reader id -> its bearer token (read only)."""
        return {r.id: bearer_token(r.secret()) for r in self.readers}

    def owner(self) -> dict[str, str]:
        """sensor id -> the node allowed to report it."""
        return {s: n.id for n in self.nodes for s in n.sensors}


def parse_config(data: Mapping[str, Any], source: str = "config") -> NetworkConfig:
    """Validate a config mapping; :class:`ConfigError` names the first bad field."""
    try:
        cfg = NetworkConfig.model_validate(data)
    except ValidationError as err:
        raise ConfigError(f"{source}: " + _first_error(err)) from None
    keys = cfg.keys()  # keys are checked now, not at the first message
    shared = [r.id for r in cfg.readers if r.secret() in keys.values() or r.id in keys]
    readers = [r.id for r in cfg.readers]
    if shared or len(set(readers)) != len(readers):
        raise ConfigError(
            f"{source}: "
            + invalid("readers", readers, "ids and keys of their own (not a node's, unique)")
        )
    if cfg.mqtt is not None:
        try:
            cfg.mqtt.secret()  # an unset password_env is reported now, not at connection
        except ConfigError as err:
            raise ConfigError(f"{source}: {err}") from None
    try:
        models = cfg.sensor_models()
    except ConfigError as err:
        raise ConfigError(f"{source}: {err}") from None
    dim = len(cfg.tracker.prior_mean)
    expect = cfg.tracker.motion.build().dim
    if dim != expect:
        raise ConfigError(
            f"{source}: "
            + invalid("tracker.prior_mean", cfg.tracker.prior_mean, f"{expect} entries")
        )
    if cfg.tracker.filter == "grid" or cfg.tracker.association.method != "none":
        x0, x1, y0, y1 = cfg.area
        cell = cfg.tracker.grid.cell
        cells = round((x1 - x0) / cell) * round((y1 - y0) / cell)
        if cfg.tracker.filter == "grid" and not 4 <= cells <= MAX_GRID_CELLS:
            raise ConfigError(
                f"{source}: "
                + invalid(
                    "tracker.grid.cell",
                    cell,
                    f"a cell size giving 4..{MAX_GRID_CELLS} cells over area {cfg.area} "
                    f"(this gives {cells})",
                )
            )
        if not (x1 > x0 and y1 > y0):
            raise ConfigError(f"{source}: " + invalid("area", cfg.area, "x0 < x1 and y0 < y1"))
    grid_only = [s.id for s in cfg.sensors if s.kind in GRID_ONLY_KINDS]
    if grid_only and cfg.tracker.filter != "grid":
        raise ConfigError(
            f"{source}: "
            + invalid(
                "tracker.filter",
                cfg.tracker.filter,
                f"'grid': sensors {grid_only} report detection functions, which only the "
                "grid tracker fuses",
            )
        )
    problem = _association_problem(cfg)
    if problem is not None:
        raise ConfigError(f"{source}: " + invalid(*problem))
    motion = cfg.tracker.motion.build()
    for sid, model in models.items():  # each sensor must read positions of the tracker's state
        idx = tuple(getattr(model, "_idx", ()) or model.position_index)
        if not set(idx) <= set(motion.position_index):
            raise ConfigError(
                f"{source}: sensor {sid!r} ({cfg.sensor(sid).kind}) reads state entries "
                f"{list(idx)}, but the tracker's positions are {list(motion.position_index)} "
                f"({cfg.tracker.motion.model}, {expect} entries)"
            )
    return cfg


def _first_error(err: ValidationError) -> str:
    """The first validation error as ``field=value is invalid: expected ...``; an unknown key or
    association method lists the valid ones."""
    first = err.errors()[0]
    where = ".".join(str(p) for p in first["loc"]) or "config"
    shown, expected = first.get("input"), first["msg"]
    ctx = first.get("ctx") or {}
    if first["type"] == "unknown_key":
        key = ctx["key"]
        where = f"{where}.{key}" if first["loc"] else str(key)
        shown = shown[key] if isinstance(shown, dict) else shown
        expected = f"one of the keys {ctx['valid']} (unknown key)"
    elif first["type"] in ("union_tag_invalid", "union_tag_not_found") and where.endswith(
        "association"
    ):
        where, shown = f"{where}.method", ctx.get("tag")
        expected = f"one of {', '.join(ASSOCIATION_METHODS)}"
    return invalid(where, shown, expected)


def _association_problem(cfg: NetworkConfig) -> tuple[str, Any, str] | None:
    """``(field, value, what is valid)`` when ``tracker.association`` does not fit the rest of
    the network, else None."""
    a, filt = cfg.tracker.association, cfg.tracker.filter
    if a.method == "none":
        return None
    if cfg.fusion.alignment == "closest":
        return (
            "fusion.alignment",
            "closest",
            f"'all' with association {a.method!r} (closest keeps one reading per sensor per "
            "tick: one target's)",
        )
    ids = [s.id for s in cfg.sensors]
    for name in ("p_detect", "clutter_density"):
        value = getattr(a, name, None)
        if isinstance(value, dict) and sorted(value) != sorted(ids):
            return f"tracker.association.{name}", value, f"one entry per sensor {ids}"
    localising = [s.id for s in cfg.sensors if s.kind in ("position_fix", "range_bearing")]
    if a.method == "mcmcda":
        if localising or filt == "grid":
            return None
        return (
            "tracker.association.method",
            "mcmcda",
            "position detections: position_fix or range_bearing sensors, or the grid "
            "tracker (whose fused likelihood gives them)",
        )
    if filt == "grid" or (a.method == "phd" and filt != "ekf"):
        valid = "ekf (phd runs its own Gaussian mixture)" if a.method == "phd" else "ekf, ukf or pf"
        return "tracker.filter", filt, f"{valid} with association {a.method!r}"
    if not localising and a.method != "phd":
        return (
            "tracker.association.method",
            a.method,
            "sensors that start tracks (position_fix or range_bearing): bearings, ranges and "
            "image positions only update them",
        )
    return None


def load_config(path: str | Path) -> NetworkConfig:
    """Read and validate a network YAML file."""
    p = Path(path)
    try:
        data = yaml.safe_load(p.read_text())
    except OSError as err:
        raise ConfigError(invalid("config", str(p), f"a readable YAML file ({err})")) from None
    except yaml.YAMLError as err:
        raise ConfigError(invalid("config", str(p), f"valid YAML ({err})")) from None
    if not isinstance(data, dict):
        raise ConfigError(invalid("config", str(p), "a YAML mapping"))
    cfg = parse_config(data, str(p))
    if cfg.log.path is not None and not Path(cfg.log.path).is_absolute():
        log = cfg.log.model_copy(update={"path": str(p.parent / cfg.log.path)})
        cfg = cfg.model_copy(update={"log": log})
    if cfg.mqtt is not None and cfg.mqtt.tls is not None:
        tls = cfg.mqtt.tls
        files = {
            name: str(p.parent / value)
            for name in ("ca_file", "cert_file", "key_file")
            if (value := getattr(tls, name)) is not None and not Path(value).is_absolute()
        }
        mqtt = cfg.mqtt.model_copy(update={"tls": tls.model_copy(update=files)})
        cfg = cfg.model_copy(update={"mqtt": mqtt})
    return cfg
