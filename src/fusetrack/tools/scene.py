"""The scene YAML of ``fusetrack track --config scene.yaml`` (docs/track.md).

A scene is the live node's network config (:mod:`fusetrack.service.config`) without nodes or
keys, where every sensor also names its *recording*: the sensor entries, ``tracker`` and
``area`` are the node's own models (:class:`~fusetrack.service.config.SensorConfig`,
:class:`~fusetrack.service.config.TrackerConfig`), so a scene that tracks offline runs unchanged
as ``fusetrack serve``'s sensors and tracker. Recordings:

* ``wav``: a multichannel WAV of a microphone array (``microphones``: one ``[x, y]`` per channel,
  metres in the sensor frame) -> delay-and-sum beam energies -> bearings (``kind: bearing``);
* ``video``: a video and its camera YAML (``fusetrack track-video``'s calibration) ->
  background subtraction -> the foot point of the largest blob (``kind: image_position``);
* ``csv``, ``jsonl``, ``parquet``: a table of readings (``time`` and the kind's columns);
* ``sqlite``: the durable log of a fusion node (``fusetrack serve``), this sensor's messages.

:func:`load_scene` checks everything it can before any work and raises
:class:`~fusetrack.core.ConfigError` naming the field, the value and what is valid.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from ..core import ConfigError, invalid
from ..service import NetworkConfig, SensorConfig, TrackerConfig, parse_config

SUFFIXES = {
    ".wav": "wav",
    ".mp4": "video",
    ".avi": "video",
    ".mkv": "video",
    ".mov": "video",
    ".csv": "csv",
    ".jsonl": "jsonl",
    ".parquet": "parquet",
    ".sqlite": "sqlite",
    ".db": "sqlite",
}
"""File suffix -> recording format, when ``format`` is not given."""

OFFLINE_NODE_KEY = "offline-scene-key-not-a-secret"  # the node config needs one; never used


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class _Recording(_Strict):
    path: str = Field(description="the file, relative to the scene YAML")
    offset: float = Field(
        default=0.0,
        description="seconds added to the recording's times to put them on the scene clock",
    )


class WavRecording(_Recording):
    """A microphone array's channels -> bearings, one every ``hop`` seconds (Kushwaha 2010, Eq. 33)."""

    format: Literal["wav"]
    microphones: list[Annotated[list[float], Field(min_length=2, max_length=2)]] = Field(
        min_length=2, description="[x, y] of each channel's microphone, sensor frame (m)"
    )
    hop: float = Field(default=0.1, gt=0.0, description="seconds between two bearings")
    window: int = Field(default=2048, ge=64, description="samples per beamforming window")
    beams: int = Field(default=72, ge=8, le=3600, description="beams over the full circle")
    band: tuple[float, float] = Field(default=(300.0, 3400.0), description="band-pass (Hz)")
    upsample: int = Field(default=4, ge=1, le=16, description="finer integer delays")
    speed_of_sound: float = Field(default=343.0, gt=0.0)
    min_snr_db: float = Field(
        default=3.0, description="skip windows this far (dB) or less above the quietest ones"
    )


class VideoRecording(_Recording):
    """A camera's video -> background subtraction -> image positions (Nott 2009, Sec. 4.1)."""

    format: Literal["video"]
    calibration: str = Field(description="camera YAML of fusetrack track-video")


class TableRecording(_Recording):
    """A table of readings: ``time`` (s) and the kind's columns (docs/track.md)."""

    format: Literal["csv", "jsonl", "parquet"]
    columns: dict[str, str] = Field(
        default_factory=dict, description="rename: the kind's column -> the file's column"
    )
    where: dict[str, str | int | float] = Field(
        default_factory=dict, description="keep only rows with these column values"
    )
    degrees: bool = Field(default=False, description="angles in the file are in degrees")


class NodeLogRecording(_Recording):
    """The durable log of a fusion node: the messages of ``sensor`` (default: this sensor)."""

    format: Literal["sqlite"]
    sensor: str | None = None


Recording = Annotated[
    WavRecording | VideoRecording | TableRecording | NodeLogRecording,
    Field(discriminator="format"),
]

RECORDING_KINDS: dict[str, tuple[str, ...]] = {
    "wav": ("bearing",),
    "video": ("image_position",),
    "csv": ("bearing", "doa", "range", "range_bearing", "position_fix", "image_position"),
    "jsonl": ("bearing", "doa", "range", "range_bearing", "position_fix", "image_position"),
    "parquet": ("bearing", "doa", "range", "range_bearing", "position_fix", "image_position"),
    "sqlite": ("bearing", "doa", "range", "range_bearing", "position_fix", "image_position"),
}
"""Which sensor kinds each recording format can give."""


class SceneSensor(SensorConfig):
    """A node sensor (:class:`~fusetrack.service.config.SensorConfig`) and its recording."""

    recording: Recording

    @model_validator(mode="before")
    @classmethod
    def _format_from_suffix(cls, data: Any) -> Any:
        """``recording.format`` from the file's suffix when not given."""
        rec = data.get("recording") if isinstance(data, dict) else None
        if isinstance(rec, dict) and "format" not in rec and isinstance(rec.get("path"), str):
            fmt = _format_of(rec)
            if fmt is None:
                raise ValueError(
                    f"recording.path={rec['path']!r} does not say its format: give "
                    f"recording.format, or a file ending in {', '.join(SUFFIXES)}"
                )
            data = {**data, "recording": {**rec, "format": fmt}}
        return data

    @model_validator(mode="after")
    def _recording_fits(self) -> SceneSensor:
        fmt = self.recording.format
        if self.kind not in RECORDING_KINDS[fmt]:
            raise ValueError(
                f"a {fmt} recording gives {' or '.join(RECORDING_KINDS[fmt])} readings, "
                f"not {self.kind}"
            )
        return self


class Fusion(_Strict):
    """Fusion ticks (the node's ``fusion`` section, offline): ``rate_hz`` ticks per second from
    ``start`` (default: the earliest reading), readings aligned ``all`` or ``closest``."""

    rate_hz: float = Field(default=4.0, gt=0.0, le=1000.0)
    alignment: Literal["all", "closest"] = "all"
    start: float | None = None


class Animation(_Strict):
    fps: int = Field(default=10, ge=1, le=60, description="frames per second")
    max_frames: int = Field(default=120, ge=2, le=2000)
    format: Literal["gif", "mp4"] = "gif"


class Scene(_Strict):
    """The whole scene (module docstring)."""

    version: Literal[1] = 1
    name: str = "scene"
    area: list[float] = Field(default=[0.0, 100.0, 0.0, 100.0], min_length=4, max_length=4)
    sensors: list[SceneSensor] = Field(min_length=1)
    fusion: Fusion = Fusion()
    tracker: TrackerConfig
    truth: str | None = Field(default=None, description="CSV: time, x, y (and target)")
    clock_tolerance: float = Field(
        default=1.0, ge=0.0, description="s a recording may lie outside the others' time span"
    )
    animation: Animation = Animation()


def _format_of(rec: dict[str, Any]) -> Any:
    """``rec``'s ``format``, or the one its file's suffix implies (None if neither)."""
    if "format" in rec or not isinstance(rec.get("path"), str):
        return rec.get("format")
    return SUFFIXES.get(Path(rec["path"]).suffix.lower())


def _with_calibration(data: Any, base: Path) -> Any:
    """An image_position sensor with a video recording takes ``homography`` from its camera YAML."""
    from .track_video import read_calibration

    if not isinstance(data, dict) or not isinstance(data.get("sensors"), list):
        return data
    sensors = []
    for i, s in enumerate(data["sensors"]):
        rec = s.get("recording") if isinstance(s, dict) else None
        if (
            isinstance(rec, dict)
            and _format_of(rec) == "video"
            and isinstance(rec.get("calibration"), str)
            and s.get("homography") is None
        ):
            path = resolve(base, rec["calibration"], f"sensors[{i}].recording.calibration")
            s = {**s, "homography": read_calibration(path)["foot_homography"]}
        sensors.append(s)
    return {**data, "sensors": sensors}


def resolve(base: Path, name: str, field: str) -> Path:
    """``name`` relative to the scene's folder; a ConfigError naming ``field`` if it is no file."""
    path = Path(name) if Path(name).is_absolute() else base / name
    if not path.is_file():
        raise ConfigError(invalid(field, name, f"an existing file (looked for {path})"))
    return path


def network_config(scene: Scene, source: str) -> NetworkConfig:
    """The node config of the scene's sensors and tracker (one offline node owns them all), so
    the node's checks and its engine apply unchanged."""
    sensors = [s.model_dump(exclude={"recording"}, exclude_none=True) for s in scene.sensors]
    for s in sensors:
        if s.get("max_range") == math.inf:
            del s["max_range"]
    data = {
        "area": scene.area,
        "sensors": sensors,
        "nodes": [
            {"id": "offline", "key": OFFLINE_NODE_KEY, "sensors": [s["id"] for s in sensors]}
        ],
        "fusion": {
            "rate_hz": scene.fusion.rate_hz,
            "alignment": scene.fusion.alignment,
            "clock": "data",
            "lag": 0.0,
        },
        "tracker": scene.tracker.model_dump(),
    }
    return parse_config(data, source)


def _first_error(err: ValidationError) -> str:
    """The first problem as ``field=value is invalid: expected ...`` (``sensors[0].kind``)."""
    first = err.errors()[0]
    where = ""
    for part in first["loc"]:
        if isinstance(part, int):
            where += f"[{part}]"
        elif part not in ("wav", "video", "csv", "jsonl", "parquet", "sqlite"):  # union tags
            where += f".{part}" if where else str(part)
    shown = first.get("input")
    expected = first["msg"].removeprefix("Value error, ").removeprefix("Input should be ")
    ctx = first.get("ctx") or {}
    if first["type"] == "unknown_key":
        where = f"{where}.{ctx['key']}" if where else str(ctx["key"])
        shown = shown[ctx["key"]] if isinstance(shown, dict) else shown
        expected = f"one of the keys {ctx['valid']} (unknown key)"
    elif first["type"] == "extra_forbidden":
        expected = "no such key (docs/track.md lists the valid ones)"
    elif first["type"] in ("union_tag_invalid", "union_tag_not_found"):
        where, shown = f"{where}.format", ctx.get("tag")
        expected = "one of wav, video, csv, jsonl, parquet, sqlite"
    elif first["type"] == "missing":
        shown, expected = None, "a value (required)"
    if isinstance(shown, dict | list) and len(repr(shown)) > 120:
        shown = f"{repr(shown)[:117]}..."
    return invalid(where or "scene", shown, expected)


def load_scene(path: str | Path) -> tuple[Scene, NetworkConfig, Path]:
    """Read and check a scene YAML: the scene, its node config and the folder its paths are
    relative to. Every recording file must exist."""
    import yaml

    p = Path(path)
    if not p.is_file():
        raise ConfigError(invalid("--config", str(p), "an existing scene YAML file"))
    try:
        data = yaml.safe_load(p.read_text())
    except yaml.YAMLError as err:
        raise ConfigError(invalid("--config", str(p), f"valid YAML ({err})")) from None
    if not isinstance(data, dict):
        raise ConfigError(invalid("--config", str(p), "a YAML mapping (docs/track.md)"))
    base = p.parent
    data = _with_calibration(data, base)
    try:
        scene = Scene.model_validate(data)
    except ValidationError as err:
        raise ConfigError(f"{p}: {_first_error(err)}") from None
    for i, s in enumerate(scene.sensors):
        resolve(base, s.recording.path, f"sensors[{i}].recording.path")
    if scene.truth is not None:
        resolve(base, scene.truth, "truth")
    return scene, network_config(scene, str(p)), base


__all__ = ["Scene", "SceneSensor", "load_scene", "resolve"]
