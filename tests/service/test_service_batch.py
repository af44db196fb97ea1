"""Readings in batches: a frame of N readings (and N frames drained at once) is N readings
logged and fused, exactly as one by one; a bad reading is named by its index and field; a
replayed or forged batch is refused whole; an HTTP batch is in the log when it is answered."""

from __future__ import annotations

import sqlite3

import msgpack
import numpy as np
import pytest
from fastapi.testclient import TestClient

from fusetrack.service.app import create_app
from fusetrack.service.auth import bearer_token, seal
from fusetrack.service.config import parse_config
from fusetrack.service.log import DurableLog
from fusetrack.service.node import FusionNode

T0 = 1_800_000_000.0  # the fake wall clock's start (Unix seconds)


def ring(buffer_size=256):
    """Three bearing sensors, all node "hub"'s, plus node "lone" with one; wall clock, 4 Hz."""
    sensors = [
        {"id": f"s{i}", "kind": "bearing", "position": [50 + 60 * c, 50 + 60 * s], "sigma": 0.03}
        for i, (c, s) in enumerate([(1, 0), (0, 1), (-1, 0), (0, -1)])
    ]
    return parse_config(
        {
            "area": [0, 100, 0, 100],
            "sensors": sensors,
            "nodes": [
                {"id": "hub", "key": "batch-test-key-hub-0001", "sensors": ["s0", "s1", "s2"]},
                {"id": "lone", "key": "batch-test-key-lone-002", "sensors": ["s3"]},
            ],
            "fusion": {"rate_hz": 4.0, "alignment": "all", "clock": "wall", "lag": 0.1},
            "limits": {"buffer_size": buffer_size},
            "tracker": {
                "filter": "ekf",
                "motion": {"model": "constant_velocity", "q": 1.0},
                "prior_mean": [50.0, 50.0, 0.0, 0.0],
                "prior_std": [10.0, 10.0, 2.0, 2.0],
            },
        }
    )


class Clock:
    def __init__(self) -> None:
        self.now = T0

    def __call__(self) -> float:
        return self.now


def message(seq, sensor, t, bearing, node="hub"):
    reading = {"kind": "bearing", "bearing": bearing}
    return {"version": 1, "node": node, "seq": seq, "sensor": sensor, "time": t, "reading": reading}


def frame(cfg, messages, node="hub", sent=T0):
    body = messages[0] if len(messages) == 1 else {"version": 1, "messages": messages}
    key = cfg.keys()[node]
    return seal(node, key, msgpack.packb(body, use_bin_type=True), "msgpack", sent=sent)


def readings(n=6):
    """``n`` readings of s0, s1, s2 in turn, 0.03 s apart, inside the first tick's window."""
    return [
        message(i + 1, f"s{i % 3}", T0 + 0.01 + 0.03 * i, 0.1 * (i % 3) - 2.0) for i in range(n)
    ]


def node_with_log(tmp_path, cfg, name):
    clock = Clock()
    return FusionNode(cfg, wall=clock, log=DurableLog(tmp_path / name)), clock


def fire_first_tick(node, clock):
    clock.now = T0 + 0.25 + 0.1 + 0.01  # tick 1's window (T0, T0 + 0.25] closed, lag passed
    return node.advance()


def logged(node):
    node.commit()
    return [(rid, m.seq, m.sensor) for rid, m in node.log.messages()]


def test_a_frame_of_n_readings_is_n_readings_logged_and_fused_as_one_by_one(tmp_path):
    cfg = ring()
    batched, clock_b = node_with_log(tmp_path, cfg, "batch.sqlite")
    single, clock_s = node_with_log(tmp_path, cfg, "single.sqlite")
    out = batched.ingest_frame(frame(cfg, readings()), "10.0.0.1")
    assert [o.accepted for o in out] == [True] * 6 and [o.seq for o in out] == [1, 2, 3, 4, 5, 6]
    # the same readings one frame each, drained together (the UDP listener's path)
    one_each = single.ingest_frames([(frame(cfg, [m]), "10.0.0.1") for m in readings()])
    assert [o.accepted for o in one_each] == [True] * 6
    expected = [(i + 1, i + 1, f"s{i % 3}") for i in range(6)]
    assert logged(batched) == logged(single) == expected
    assert batched.accepted == single.accepted == {"s0": 2, "s1": 2, "s2": 2}
    (a,), (b,) = fire_first_tick(batched, clock_b), fire_first_tick(single, clock_s)
    assert a.readings == b.readings == 6 and a.sensors == ["s0", "s1", "s2"]
    np.testing.assert_array_equal(a.state, b.state)
    (row,) = list(batched.log.tick_rows())
    assert row[3] == [1, 2, 3, 4, 5, 6]  # the tick fused every logged reading, in time order


def test_readings_drained_out_of_time_order_are_fused_in_time_order():
    cfg = ring()
    clock = Clock()
    node = FusionNode(cfg, wall=clock)
    late_first = list(reversed(readings(6)))
    for i, m in enumerate(late_first):
        m["seq"] = i + 1
    out = node.ingest_frames([(frame(cfg, [m]), "10.0.0.1") for m in late_first])
    assert all(o.accepted for o in out)
    buffered = node.aligner.buffers["s0"].items
    assert [r.time for r in buffered] == sorted(r.time for r in buffered)
    (state,) = fire_first_tick(node, clock)
    assert state.readings == 6


def test_a_reading_that_does_not_parse_refuses_its_batch_naming_index_and_field(tmp_path):
    cfg = ring()
    node, _ = node_with_log(tmp_path, cfg, "log.sqlite")
    batch = readings(4)
    batch[2]["reading"]["bearing"] = 10.0  # more than 2 pi
    (out,) = node.ingest_frame(frame(cfg, batch), "10.0.0.1")
    assert (out.accepted, out.reason) == (False, "schema")
    assert "messages.2.reading.bearing" in out.detail and "less than or equal" in out.detail
    del batch[1]["sensor"]
    batch[2]["reading"]["bearing"] = 0.1
    (out,) = node.ingest_frame(frame(cfg, batch), "10.0.0.1")
    assert "messages.1.sensor" in out.detail and "required" in out.detail.lower()
    assert logged(node) == [] and sum(node.accepted.values()) == 0  # refused whole


def test_a_refused_reading_in_a_parsed_batch_leaves_the_others_accepted(tmp_path):
    cfg = ring()
    node, _ = node_with_log(tmp_path, cfg, "log.sqlite")
    batch = readings(4)
    batch[1]["sensor"] = "s3"  # lone's sensor: hub may not report it
    batch[3]["time"] = T0 - 5.0  # before the fused time: late
    out = node.ingest_frame(frame(cfg, batch), "10.0.0.1")
    assert [(o.accepted, o.reason, o.seq) for o in out] == [
        (True, "", 1),
        (False, "forbidden_sensor", 2),
        (True, "", 3),
        (False, "late", 4),
    ]
    assert "s3" in out[1].detail
    assert logged(node) == [(1, 1, "s0"), (2, 3, "s2")]


def test_replayed_and_forged_batch_frames_are_refused_and_not_logged(tmp_path):
    cfg = ring()
    node, _ = node_with_log(tmp_path, cfg, "log.sqlite")
    sealed = frame(cfg, readings(3))
    assert all(o.accepted for o in node.ingest_frames([(sealed, "10.0.0.1")]))
    again = node.ingest_frames([(sealed, "10.0.0.1")])
    assert [o.reason for o in again] == ["replay"] * 3
    forged = bytearray(frame(cfg, [message(9, "s0", T0 + 0.2, 0.5)]))
    forged[-3] ^= 0x01  # one bit of the payload
    wrong_key = seal("hub", b"not-the-key-of-hub-0000", msgpack.packb(message(10, "s0", T0, 0.5)))
    outs = node.ingest_frames([(bytes(forged), "10.0.0.2"), (wrong_key, "10.0.0.2")])
    assert [o.reason for o in outs] == ["bad_mac", "bad_mac"]
    stale = frame(cfg, [message(11, "s0", T0 + 0.2, 0.5)], sent=T0 - 60.0)
    assert [o.reason for o in node.ingest_frames([(stale, "10.0.0.1")])] == ["stale"]
    assert [seq for _, seq, _ in logged(node)] == [1, 2, 3]


def test_an_http_batch_is_in_the_log_when_it_is_answered(tmp_path):
    cfg = ring()
    node = FusionNode(cfg, log=DurableLog(tmp_path / "log.sqlite"))
    now = node.started
    batch = [message(i + 1, f"s{i}", now + 0.5, 0.2) for i in range(3)]
    batch.append(message(4, "s9", now + 0.5, 0.2))  # no such sensor: refused, the rest kept
    token = bearer_token(cfg.keys()["hub"])
    with TestClient(create_app(node)) as client:
        r = client.post(
            "/ingest",
            content=msgpack.packb({"version": 1, "messages": batch}),
            headers={"Authorization": f"Bearer {token}", "Content-Type": "application/msgpack"},
        )
        assert r.status_code == 200 and (r.json()["accepted"], r.json()["rejected"]) == (3, 1)
        assert r.json()["results"][3]["reason"] == "unknown_sensor"
        # another connection sees them: committed before the answer
        with sqlite3.connect(tmp_path / "log.sqlite") as db:
            assert db.execute("SELECT seq FROM messages ORDER BY id").fetchall() == [
                (1,),
                (2,),
                (3,),
            ]


@pytest.mark.parametrize("size", [3, 5])
def test_a_buffer_keeps_its_newest_readings_when_a_batch_overflows_it(size):
    cfg = ring(buffer_size=size)
    node = FusionNode(cfg, wall=Clock())
    batch = [message(i + 1, "s0", T0 + 0.01 * (i + 1), 0.1) for i in range(8)]
    assert all(o.accepted for o in node.ingest_frame(frame(cfg, batch), "10.0.0.1"))
    buf = node.aligner.buffers["s0"]
    assert [r.id for r in buf.items] == list(range(9 - size, 9)) and buf.dropped == 8 - size
    assert node.aligner.pending == size
