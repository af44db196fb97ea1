"""The versioned wire schema of the fusion node: what a sensor node sends and what the node publishes.

A sensor node sends :class:`SensorMessage` values (one, or a :class:`MessageBatch`) encoded as
JSON or MessagePack. Each message carries the sending node's id, a sequence number (strictly
new per node: replays are rejected, see :mod:`.auth`), the sensor's id, the reading's time
(seconds, on the node's clock: see the network config's ``fusion.clock``) and one reading whose
``kind`` says what it is. Units are SI and radians on the wire; every number must be finite.

The node publishes :class:`TrackState` values (REST ``/tracks``, WebSocket ``/ws/tracks``).
:func:`message_json_schema` gives the JSON Schema (also served at ``/schema``; the node's
OpenAPI document at ``/openapi.json`` references the same models).

>>> m = SensorMessage(node="west", seq=1, sensor="mic_west", time=0.5,
...                   reading=BearingReading(bearing=0.3))
>>> decode_messages(encode_message(m, "msgpack"), "msgpack")[0] == m
True
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from typing import Annotated, Any, Literal

import msgpack
import numpy as np
from pydantic import BaseModel, ConfigDict, Field, TypeAdapter, ValidationError

from ..core import MeasurementError, invalid

SCHEMA_VERSION = 1
Encoding = Literal["json", "msgpack"]
ENCODINGS: tuple[str, ...] = ("json", "msgpack")

_NAME = r"^[A-Za-z0-9_.\-]{1,64}$"
_ANGLE = Field(ge=-2 * math.pi, le=2 * math.pi, description="radians")
MAX_BATCH = 1000
MAX_DETECTION_CELLS = 4096


class _Strict(BaseModel):
    """Frozen, no unknown fields, no NaN or infinity anywhere, and strict types: a number must
    be a JSON number, not a string of digits (``"seq": "123"`` and ``"bearing": "0.3"`` were
    accepted although ``/schema`` says integer / number, issue 18); an integer field takes no
    ``2.0``."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False, strict=True)


class BearingReading(_Strict):
    """A bearing in the xy-plane, anticlockwise, relative to the sensor's heading (rad)."""

    kind: Literal["bearing"] = "bearing"
    bearing: float = _ANGLE

    def vector(self) -> list[float]:
        return [self.bearing]


class DoaReading(_Strict):
    """A two-angle direction of arrival: azimuth relative to the heading, polar angle from +z."""

    kind: Literal["doa"] = "doa"
    azimuth: float = _ANGLE
    polar: float = Field(ge=0.0, le=math.pi, description="radians from +z")

    def vector(self) -> list[float]:
        return [self.azimuth, self.polar]


class RangeReading(_Strict):
    """A distance to the target (m)."""

    kind: Literal["range"] = "range"
    range: float = Field(ge=0.0, le=1e7, description="metres")

    def vector(self) -> list[float]:
        return [self.range]


class RangeBearingReading(_Strict):
    """A 2-D range (m) and bearing relative to the heading (rad): a radar plot."""

    kind: Literal["range_bearing"] = "range_bearing"
    range: float = Field(ge=0.0, le=1e7, description="metres")
    bearing: float = _ANGLE

    def vector(self) -> list[float]:
        return [self.range, self.bearing]


class PositionFixReading(_Strict):
    """A position fix (m), e.g. a radio tag localised by its readers."""

    kind: Literal["position_fix"] = "position_fix"
    position: list[Annotated[float, Field(ge=-1e7, le=1e7)]] = Field(min_length=2, max_length=3)

    def vector(self) -> list[float]:
        return list(self.position)


class ImagePositionReading(_Strict):
    """A target's position in a camera image (pixels, origin top left)."""

    kind: Literal["image_position"] = "image_position"
    u: float = Field(ge=-1e5, le=1e5, description="pixels")
    v: float = Field(ge=-1e5, le=1e5, description="pixels")

    def vector(self) -> list[float]:
        return [self.u, self.v]


class DetectionFunctionReading(_Strict):
    """A detection function over the sensor's cells: beam energies of a microphone array, or the
    per-column foreground score of a camera (non-negative; the sensor's config says the cells)."""

    kind: Literal["detection_function"] = "detection_function"
    values: list[Annotated[float, Field(ge=0.0, le=1e12)]] = Field(
        min_length=1, max_length=MAX_DETECTION_CELLS
    )

    def vector(self) -> list[float]:
        return list(self.values)


Reading = Annotated[
    BearingReading
    | DoaReading
    | RangeReading
    | RangeBearingReading
    | PositionFixReading
    | ImagePositionReading
    | DetectionFunctionReading,
    Field(discriminator="kind"),
]
READING_KINDS: tuple[str, ...] = (
    "bearing",
    "doa",
    "range",
    "range_bearing",
    "position_fix",
    "image_position",
    "detection_function",
)


class SensorMessage(_Strict):
    """One reading of one sensor, as a sensor node sends it."""

    version: Literal[1] = 1
    node: str = Field(pattern=_NAME, description="the sending node's id (its key signs this)")
    seq: int = Field(ge=0, le=2**63 - 1, description="per-node sequence number, never reused")
    sensor: str = Field(pattern=_NAME, description="the sensor's id in the network config")
    time: float = Field(ge=-1e12, le=1e12, description="seconds on the fusion clock")
    reading: Reading
    covariance: list[list[float]] | None = Field(
        default=None, description="optional noise covariance (m x m) overriding the sensor's own"
    )

    def value(self) -> np.ndarray:
        """The reading as the measurement vector ``z`` the sensor models use."""
        return np.asarray(self.reading.vector(), dtype=float)


class MessageBatch(_Strict):
    """Several messages in one HTTP request or WebSocket frame (applied in order)."""

    version: Literal[1] = 1
    messages: list[SensorMessage] = Field(min_length=1, max_length=MAX_BATCH)


class TrackState(_Strict):
    """The fused estimate published after one fusion tick."""

    version: Literal[1] = 1
    track: int = Field(description="track id (1 for the single-target tracker)")
    tick: int
    time: float
    state: list[float]
    covariance: list[list[float]]
    position: list[float]
    position_covariance: list[list[float]]
    sensors: list[str] = Field(description="sensors whose readings this tick fused")
    readings: int = Field(description="how many readings this tick fused")


def reading_from_vector(kind: str, z: Sequence[float]) -> Any:
    """Build the reading of ``kind`` from a measurement vector (the inverse of ``.vector()``)."""
    z = [float(v) for v in np.atleast_1d(np.asarray(z, dtype=float))]
    fields: dict[str, Any]
    match kind:
        case "bearing":
            fields = {"bearing": z[0]}
        case "doa":
            fields = {"azimuth": z[0], "polar": z[1]}
        case "range":
            fields = {"range": z[0]}
        case "range_bearing":
            fields = {"range": z[0], "bearing": z[1]}
        case "position_fix":
            fields = {"position": z}
        case "image_position":
            fields = {"u": z[0], "v": z[1]}
        case "detection_function":
            fields = {"values": z}
        case _:
            raise MeasurementError(invalid("kind", kind, f"one of {list(READING_KINDS)}"))
    return TypeAdapter(Reading).validate_python({"kind": kind, **fields})


def encode_message(message: SensorMessage | MessageBatch, encoding: Encoding = "json") -> bytes:
    """Serialise a message or a batch as JSON (UTF-8) or MessagePack."""
    data = message.model_dump(mode="json", exclude_none=True)
    if encoding == "json":
        return json.dumps(data, separators=(",", ":")).encode()
    if encoding == "msgpack":
        return bytes(msgpack.packb(data, use_bin_type=True))
    raise MeasurementError(invalid("encoding", encoding, "'json' or 'msgpack'"))


class SchemaRejection(Exception):
    """A payload that is not a valid message; ``reason`` is ``malformed`` or ``schema``."""

    def __init__(self, reason: str, detail: str) -> None:
        super().__init__(detail)
        self.reason = reason
        self.detail = detail


def decode_messages(payload: bytes, encoding: str) -> list[SensorMessage]:
    """Parse a message or a batch; raise :class:`SchemaRejection` for anything else.

    ``malformed``: the bytes are not JSON / MessagePack; ``schema``: they are, but not a valid
    message (the detail names the first field that failed and why).
    """
    try:
        if encoding == "json":
            data = json.loads(payload)
        elif encoding == "msgpack":
            data = msgpack.unpackb(payload, raw=False, strict_map_key=True)
        else:
            raise SchemaRejection("malformed", invalid("encoding", encoding, "json or msgpack"))
    except SchemaRejection:
        raise
    except Exception as err:  # any decoder failure is a malformed payload, never a crash
        raise SchemaRejection("malformed", f"not {encoding}: {type(err).__name__}") from None
    model = MessageBatch if isinstance(data, dict) and "messages" in data else SensorMessage
    try:
        parsed = model.model_validate(data)
    except ValidationError as err:
        first = err.errors()[0]
        where = ".".join(str(p) for p in first["loc"]) or "message"
        raise SchemaRejection("schema", f"{where}: {first['msg']}") from None
    except Exception as err:  # e.g. RecursionError on absurdly nested input
        raise SchemaRejection("malformed", f"unparseable: {type(err).__name__}") from None
    return list(parsed.messages) if isinstance(parsed, MessageBatch) else [parsed]


def message_json_schema() -> dict[str, Any]:
    """JSON Schema (draft 2020-12) of what a sensor node may send: a message or a batch."""
    schema = TypeAdapter(SensorMessage | MessageBatch).json_schema()
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["title"] = f"fusetrack sensor message, version {SCHEMA_VERSION}"
    return schema
