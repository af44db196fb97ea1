"""The wire schema: round trips, refusals with reasons, the published JSON Schema, a parser fuzz."""

from __future__ import annotations

import json
import math

import msgpack
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fusetrack.service.schema import (
    READING_KINDS,
    MessageBatch,
    SchemaRejection,
    SensorMessage,
    decode_messages,
    encode_message,
    message_json_schema,
    reading_from_vector,
)

VECTORS = {
    "bearing": [0.3],
    "doa": [-1.2, 0.7],
    "range": [12.5],
    "range_bearing": [40.0, -2.5],
    "position_fix": [1.0, -2.0, 3.5],
    "image_position": [320.5, 11.0],
    "detection_function": [0.0, 1.5, 2.25, 0.125],
}


@pytest.mark.parametrize("kind", READING_KINDS)
@pytest.mark.parametrize("encoding", ["json", "msgpack"])
def test_every_kind_round_trips(kind, encoding):
    z = VECTORS[kind]
    m = SensorMessage(
        node="n1", seq=7, sensor="s1", time=12.25, reading=reading_from_vector(kind, z)
    )
    (back,) = decode_messages(encode_message(m, encoding), encoding)
    assert back == m
    assert back.reading.kind == kind
    assert back.value().tolist() == z  # the measurement vector survives exactly


def test_batch_round_trips_in_order_with_covariance():
    ms = [
        SensorMessage(
            node="n1",
            seq=s,
            sensor="tag",
            time=0.5 * s,
            reading=reading_from_vector("position_fix", [s, -s]),
            covariance=[[1.0, 0.1], [0.1, 2.0]],
        )
        for s in range(5)
    ]
    back = decode_messages(encode_message(MessageBatch(messages=ms), "msgpack"), "msgpack")
    assert back == ms


def _raw(**over):
    d = {
        "version": 1,
        "node": "n1",
        "seq": 1,
        "sensor": "s1",
        "time": 1.0,
        "reading": {"kind": "bearing", "bearing": 0.1},
    }
    d.update(over)
    return json.dumps(d).encode()


@pytest.mark.parametrize(
    ("payload", "reason", "field"),
    [
        (b"{not json", "malformed", ""),
        (_raw(version=2), "schema", "version"),
        (_raw(extra=1), "schema", "extra"),
        (_raw(seq=-1), "schema", "seq"),
        (_raw(node="bad node!"), "schema", "node"),
        (_raw(reading={"kind": "bearing", "bearing": 7.0}), "schema", "bearing"),  # > 2 pi
        (_raw(reading={"kind": "doa", "azimuth": 0.0, "polar": -0.1}), "schema", "polar"),
        (_raw(reading={"kind": "range", "range": -1.0}), "schema", "range"),
        (_raw(reading={"kind": "sonar", "x": 1}), "schema", "reading"),
        (_raw(reading={"kind": "position_fix", "position": [1.0]}), "schema", "position"),
    ],
)
def test_bad_payloads_are_refused_with_a_reason_naming_the_field(payload, reason, field):
    with pytest.raises(SchemaRejection) as err:
        decode_messages(payload, "json")
    assert err.value.reason == reason
    assert field in err.value.detail


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_numbers_are_refused_in_both_encodings(bad):
    data = json.loads(_raw())
    data["time"] = bad
    with pytest.raises(SchemaRejection, match="time"):
        decode_messages(msgpack.packb(data), "msgpack")
    data["time"] = 1.0
    data["reading"]["bearing"] = bad
    with pytest.raises(SchemaRejection):
        decode_messages(json.dumps(data).encode(), "json")  # json.dumps writes NaN/Infinity


def test_batches_are_bounded():
    one = json.loads(_raw())
    batch = {"version": 1, "messages": [one] * 1001}
    with pytest.raises(SchemaRejection, match="messages"):
        decode_messages(json.dumps(batch).encode(), "json")


def test_json_schema_describes_every_kind_and_validates_like_the_models():
    schema = message_json_schema()
    text = json.dumps(schema)
    for kind in READING_KINDS:
        assert f'"{kind}"' in text
    assert schema["$schema"].endswith("2020-12/schema")
    defs = schema["$defs"]
    assert defs["SensorMessage"]["additionalProperties"] is False
    assert set(defs["SensorMessage"]["required"]) >= {"node", "seq", "sensor", "time", "reading"}


def test_reading_from_vector_refuses_unknown_kinds():
    with pytest.raises(ValueError, match="kind"):
        reading_from_vector("sonar", [1.0])


json_values = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-(2**63), 2**63 - 1)
    | st.floats()
    | st.text(max_size=8),
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner, max_size=4)
    ),
    max_leaves=20,
)


@settings(max_examples=150, deadline=None)
@given(st.binary(max_size=200) | json_values.map(lambda v: json.dumps(v).encode()))
def test_fuzz_decoder_only_ever_raises_schema_rejection(payload):
    for encoding in ("json", "msgpack"):
        try:
            out = decode_messages(payload, encoding)
        except SchemaRejection as err:
            assert err.reason in ("malformed", "schema")
        else:
            assert all(isinstance(m, SensorMessage) for m in out)


@settings(max_examples=60, deadline=None)
@given(
    st.dictionaries(
        st.sampled_from(["version", "node", "seq", "sensor", "time", "reading", "covariance", "x"]),
        json_values,
        max_size=7,
    )
)
def test_fuzz_near_messages_msgpack(fields):
    try:
        decode_messages(msgpack.packb(fields), "msgpack")
    except SchemaRejection:
        pass


def test_value_is_float_array():
    m = SensorMessage(
        node="a", seq=0, sensor="b", time=0.0, reading=reading_from_vector("doa", [0.1, 0.2])
    )
    assert m.value().dtype == np.float64 and m.value().shape == (2,)


@pytest.mark.parametrize(
    "field, value", [("seq", "123"), ("seq", 2.0), ("time", "0.5"), ("bearing", "0.3")]
)
def test_numbers_as_strings_are_refused(field, value):
    """Issue 18: ``"seq": "123"`` and ``"bearing": "0.3"`` were accepted although the schema says
    integer / number."""
    msg = {"node": "west", "seq": 1, "sensor": "mic_west", "time": 0.5,
           "reading": {"kind": "bearing", "bearing": 0.3}}  # fmt: skip
    if field == "bearing":
        msg["reading"]["bearing"] = value
    else:
        msg[field] = value
    with pytest.raises(SchemaRejection):
        decode_messages(json.dumps(msg).encode(), "json")
