"""The node's rules: every bad input refused with its reason and counted; the durable log
replays to the same tracks; a restarted node resumes from it."""

from __future__ import annotations

import json
import sqlite3

import numpy as np
import pytest

from fusetrack.core import ConfigError
from fusetrack.service.config import load_config, parse_config
from fusetrack.service.log import DurableLog, replay_log
from fusetrack.service.node import FusionNode
from fusetrack.service.replay import demo_network, demo_scenario
from fusetrack.service.schema import SensorMessage, reading_from_vector


def msg(node, seq, sensor, t, kind, z, **kw):
    return SensorMessage(
        node=node, seq=seq, sensor=sensor, time=t, reading=reading_from_vector(kind, z), **kw
    )


def test_each_bad_message_is_refused_with_its_reason(network):
    node = FusionNode(network)
    cases = [
        (msg("array-east", 1, "mic_west", 1.0, "bearing", [0.1]), "array-west", "node_mismatch"),
        (msg("array-west", 2, "mic_north", 1.0, "bearing", [0.1]), "array-west", "unknown_sensor"),
        (msg("array-west", 3, "mic_west", 1.0, "range", [3.0]), "array-west", "wrong_kind"),
        (
            msg("array-west", 4, "mic_west", 1.0, "image_position", [3.0, 1.0]),
            "array-west",
            "wrong_kind",  # image positions are fused, but this sensor reports bearings
        ),
        (
            msg("tag-reader", 1, "tag", 1.0, "position_fix", [1.0, 2.0, 3.0]),
            "tag-reader",
            "wrong_size",
        ),
        (
            msg(
                "tag-reader",
                2,
                "tag",
                1.0,
                "position_fix",
                [1.0, 2.0],
                covariance=[[1.0, 2.0], [2.0, 1.0]],
            ),
            "tag-reader",
            "bad_covariance",
        ),
        (
            msg(
                "tag-reader",
                3,
                "tag",
                1.0,
                "position_fix",
                [1.0, 2.0],
                covariance=[[1.0], [2.0, 1.0]],
            ),
            "tag-reader",
            "bad_covariance",
        ),
        (msg("array-west", 5, "mic_west", 11.0, "bearing", [0.1]), "array-west", "future"),
        (msg("array-west", 6, "mic_west", 0.0, "bearing", [0.1]), "array-west", "late"),
    ]
    for m, who, reason in cases:
        out = node.ingest_message(m, who)
        assert (out.accepted, out.reason) == (False, reason), (m, out)
        assert str(m.seq) in json.dumps(out.as_dict())
    assert sum(node.rejected.values()) == len(cases)
    assert node.ingest_message(
        msg("array-west", 7, "mic_west", 1.0, "bearing", [0.1]), "array-west"
    ).accepted
    # oversized and undecodable payloads never raise
    assert node.ingest_payload(b"x" * 70000, "json", "array-west")[0].reason == "oversized"
    assert node.ingest_payload(b"\xc1\xc1", "msgpack", "array-west")[0].reason == "malformed"
    assert node.ingest_frame(b"hello")[0].reason == "bad_frame"
    assert node.authorize("Bearer nope") is None and node.authorize(None) is None


def test_overload_and_ring_buffer_bounds(network):
    cfg = network.model_copy(
        update={"limits": network.limits.model_copy(update={"buffer_size": 5, "max_pending": 8})}
    )
    node = FusionNode(cfg)
    outs = [
        node.ingest_message(
            msg("array-west", s, "mic_west", 0.01 * s, "bearing", [0.1]), "array-west"
        )
        for s in range(1, 8)
    ]
    assert all(o.accepted for o in outs)
    assert (
        len(node.aligner.buffers["mic_west"]) == 5 and node.aligner.buffers["mic_west"].dropped == 2
    )
    for s in range(1, 4):
        node.ingest_message(
            msg("array-east", s, "mic_east", 0.01 * s, "bearing", [0.1]), "array-east"
        )
    over = node.ingest_message(
        msg("array-east", 9, "mic_east", 0.2, "bearing", [0.1]), "array-east"
    )
    assert over.reason == "overload"


def test_silent_sensor_degrades_health_not_the_service(network):
    clock = [1000.0]
    node = FusionNode(network, wall=lambda: clock[0])
    for s in range(1, 5):
        node.ingest_message(
            msg("array-west", s, "mic_west", 0.5 * s, "bearing", [0.5]), "array-west"
        )
    clock[0] += 1.0  # idle long enough: the data clock fuses what has come
    states = node.advance()
    assert [s.tick for s in states] == [1, 2, 3, 4]
    h = node.health()
    assert h["status"] == "degraded" and set(h["silent_sensors"]) == {"mic_east", "camera", "tag"}
    assert all(np.isfinite(s.state).all() for s in states)


def _feed(node, cfg, readings, seq0=1):
    from fusetrack.service.replay import _Senders

    owner, kinds = cfg.owner(), {s.id: s.kind for s in cfg.sensors}
    for i, x in enumerate(readings):
        m = msg(owner[x.sensor], seq0 + i, x.sensor, x.time, kinds[x.sensor], x.value)
        assert node.ingest_message(m, owner[x.sensor]).accepted
    del _Senders


def test_durable_log_replays_exactly_and_a_restart_resumes(tmp_path, network):
    cfg = network.model_copy(
        update={"tracker": network.tracker.model_copy(update={"filter": "pf", "particles": 200})}
    )
    scn = demo_scenario(cfg, seed=4, duration=12.0)
    first, second = scn.readings[:25], scn.readings[25:]
    path = tmp_path / "node.sqlite"
    clock = [0.0]
    node = FusionNode(cfg, wall=lambda: clock[0], log=DurableLog(path))
    _feed(node, cfg, first)
    live1 = node.advance()
    node.log.close()  # the process stops here
    # a new process on the same log resumes where it was ...
    node2 = FusionNode(cfg, wall=lambda: clock[0], log=DurableLog(path))
    assert node2.resumed_ticks == len(live1) and node2.aligner.last_tick == live1[-1].tick
    # ... refuses replays of what was logged before the restart ...
    again = node2.ingest_message(
        msg("array-west", 1, "mic_west", 99.0, "bearing", [0.1]), "array-west"
    )
    assert again.reason == "replay"
    _feed(node2, cfg, second, seq0=1000)
    clock[0] += 5.0  # the stream ends: flush
    live2 = node2.advance()
    assert live2[-1].time == pytest.approx(12.0)
    # ... and the tracks are those of one uninterrupted node over the same messages
    clock[0] = 0.0
    one = FusionNode(cfg, wall=lambda: clock[0])
    _feed(one, cfg, first)
    a = one.advance()
    _feed(one, cfg, second, seq0=1000)
    clock[0] += 5.0
    b = one.advance()
    np.testing.assert_array_equal([s.state for s in a + b], [s.state for s in live1 + live2])
    # offline replay of the log gives every published state exactly
    log = DurableLog(path)
    _, offline = replay_log(cfg, log)
    logged = [s for s, _ in log.ticks()]
    assert [s.model_dump() for s in offline] == [s.model_dump() for s in logged]
    assert len(logged) == len(live1) + len(live2)
    log.close()


def test_example_config_is_the_demo_network():
    cfg = load_config("examples/network.yaml")
    demo = demo_network()
    assert [s.model_dump() for s in cfg.sensors] == [s.model_dump() for s in demo.sensors]
    assert cfg.tracker == demo.tracker
    assert cfg.owner() == demo.owner()


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (lambda d: d["sensors"].append(dict(d["sensors"][0])), "unique"),
        (lambda d: d["nodes"][0].update(key="short"), "key"),
        (lambda d: d["nodes"][0].update(sensors=["ghost"]), "ghost"),
        (lambda d: d["sensors"][0].pop("sigma"), "sigma"),
        (lambda d: d["sensors"][0].update(sigma_deg=3), "not both"),
        (lambda d: d["fusion"].update(rate_hz=0), "rate_hz"),
        (lambda d: d["tracker"].update(prior_mean=[0, 0]), "prior"),
        (lambda d: d["tracker"].update(filter="kalman9000"), "filter"),
        (lambda d: d.setdefault("limits", {}).update(auth_failure_burst=0), "auth_failure_burst"),
    ],
)
def test_bad_configs_name_the_field(network, change, field):
    data = network.model_dump(mode="python")
    change(data)
    with pytest.raises(ConfigError, match=field):
        parse_config(data)


def test_recordings_jsonl_and_node_logs_replay_as_readings(tmp_path, network):
    from fusetrack.service.replay import load_recording

    scn = demo_scenario(network, seed=5, duration=3.0)
    clock = [0.0]
    node = FusionNode(network, wall=lambda: clock[0], log=DurableLog(tmp_path / "n.sqlite"))
    _feed(node, network, scn.readings)
    node.log.close()
    from_log = load_recording(tmp_path / "n.sqlite")
    assert [(r.time, r.sensor, r.value) for r in from_log] == [
        (r.time, r.sensor, r.value) for r in scn.readings
    ]
    lines = [
        json.dumps(
            {
                "sensor": r.sensor,
                "time": r.time,
                "reading": {"kind": "bearing", "bearing": r.value[0]},
            }
        )
        for r in scn.readings
        if r.sensor != "tag"
    ]
    (tmp_path / "rec.jsonl").write_text("\n".join(lines) + "\n")
    got = load_recording(tmp_path / "rec.jsonl")
    assert len(got) == len(lines) and all(r.sensor != "tag" for r in got)
    with pytest.raises(ConfigError, match="recording"):
        load_recording(tmp_path / "rec.csv")


def test_a_sensor_that_does_not_fit_the_state_is_a_config_error(network):
    data = network.model_dump(mode="python")
    data["sensors"].append(
        {
            "id": "doa1",
            "kind": "doa",
            "position": [0, 0, 1],
            "sigma_azimuth": 0.1,
            "sigma_polar": 0.1,
        }
    )
    data["nodes"][0]["sensors"].append("doa1")
    with pytest.raises(ConfigError, match="doa1"):
        parse_config(data)


def test_a_tick_that_fails_predicts_only_and_is_counted(tmp_path, network):
    clock = [0.0]
    node = FusionNode(network, wall=lambda: clock[0], log=DurableLog(tmp_path / "n.sqlite"))
    scn = demo_scenario(network, seed=6, duration=3.0)
    _feed(node, network, scn.readings)
    real = node.engine.filter.update
    calls = []

    def flaky(belief, group, rng=None):
        calls.append(1)
        if len(calls) == 3:
            raise np.linalg.LinAlgError("simulated")
        return real(belief, group, rng)

    node.engine.filter.update = flaky
    clock[0] = 10.0
    states = node.advance()
    assert (
        len(states) == 6
        and node.tick_errors == 1
        and "simulated" in node.health()["last_tick_error"]
    )
    assert all(np.all(np.isfinite(s.state)) for s in states)
    _, offline = replay_log(network, node.log)  # the log says what was really fused
    assert [s.model_dump() for s in offline] == [s.model_dump() for s in states]


def test_the_bearer_scheme_is_case_insensitive(network):
    """Issue 18: ``Authorization: bearer <token>`` was refused; RFC 7235 makes the scheme name
    case-insensitive. The token itself stays exact."""
    node = FusionNode(network)
    who, token = next(iter(node.tokens.items()))
    for scheme in ("Bearer", "bearer", "BEARER"):
        assert node.authorize(f"{scheme} {token}") == who
    assert node.authorize(f"Bearer {token.upper()}") is None
    assert node.authorize("Basic " + token) is None and node.authorize("Bearer") is None


def test_track_subscribers_are_capped(network):
    """Issue 18: 300 unauthenticated /ws/tracks subscribers opened with no limit; now at most
    ``limits.max_subscribers``, the rest counted as refused (the app closes them with 1013)."""
    cfg = network.model_copy(
        update={"limits": network.limits.model_copy(update={"max_subscribers": 2})}
    )
    node = FusionNode(cfg)
    first, second = node.subscribe(), node.subscribe()
    assert first is not None and second is not None
    assert node.subscribe() is None and node.rejected["too_many_subscribers"] == 1
    node.unsubscribe(first)
    assert node.subscribe() is not None


def test_damaged_foreign_and_directory_logs_are_refused_with_a_way_out(tmp_path, network):
    """Issue 18: a random-bytes, truncated, bad-JSON or foreign-config log, or a directory, ended
    in raw tracebacks (DatabaseError, KeyError, ValidationError); a changed config resumed
    silently. Each is now a ConfigError that names the log and says how to recover."""
    junk = tmp_path / "junk.sqlite"
    junk.write_bytes(np.random.default_rng(0).bytes(5000))
    (tmp_path / "dir.sqlite").mkdir()
    for path in (junk, tmp_path / "dir.sqlite"):
        with pytest.raises(ConfigError, match="move it aside"):
            DurableLog(path)
    # a log written under one config, reopened under another (a sensor's noise changed)
    path = tmp_path / "node.sqlite"
    clock = [0.0]
    node = FusionNode(network, wall=lambda: clock[0], log=DurableLog(path))
    _feed(node, network, demo_scenario(network, seed=1, duration=4.0).readings)
    clock[0] += 10.0
    node.advance()
    node.log.close()
    sensors = [s.model_copy() for s in network.sensors]
    sensors[0] = sensors[0].model_copy(update={"sigma": 2 * (sensors[0].sigma or 0.05)})
    other = network.model_copy(update={"sensors": sensors})
    with pytest.raises(ConfigError, match="written under this config"):
        FusionNode(other, log=DurableLog(path))
    # a row that no longer reads back (bad JSON in a logged message)
    with sqlite3.connect(path) as db:
        db.execute("UPDATE messages SET body = '{bad' WHERE rowid = 1")
    with pytest.raises(ConfigError, match="rows read back"):
        FusionNode(network, log=DurableLog(path))


def test_one_node_stamping_ahead_cannot_drag_the_data_clock(tmp_path, network):
    """Issue 18: with ``clock: data`` one sender's batch stamped ahead (each reading within
    ``max_future`` of the last) moved fusion time from 78 s to 3,048 s, after which every other
    sensor was refused as late, even after a restart. The data clock is now the second latest
    node's time (``fusion.clock_quorum: 2``): the runaway readings are refused as ``future``
    and counted, the honest nodes keep being fused, a restart resumes at the honest time."""
    clock = [0.0]
    path = tmp_path / "node.sqlite"
    node = FusionNode(network, wall=lambda: clock[0], log=DurableLog(path))
    honest = [("array-east", "mic_east"), ("camera-1", "camera"), ("tag-reader", "tag")]
    kinds = {s.id: s.kind for s in network.sensors}

    def send(t, seq):
        for who, sensor in honest:
            z = [30.0, 20.0] if kinds[sensor] == "position_fix" else [0.3]
            assert node.ingest_message(msg(who, seq, sensor, t, kinds[sensor], z), who).accepted

    for i in range(1, 79):  # 78 s of honest readings
        send(float(i), i)
    runaway = [
        node.ingest_message(
            msg("array-west", i, "mic_west", 78 + 9.0 * i, "bearing", [0.3]), "array-west"
        )
        for i in range(1, 331)  # 9 s further each time: up to 3,048 s
    ]
    accepted = [o.accepted for o in runaway]
    assert accepted == [True] + [False] * 329  # only 87 s is within max_future of 78 s
    assert node.rejected["future"] == 329 and node.clock() == 78.0
    node.advance()
    assert node.aligner.fused_until <= 78.0
    send(79.0, 79)  # the others are still fused, not late
    node.advance()
    assert node.clock() == 79.0 and node.rejected["late"] == 0
    node.log.close()
    again = FusionNode(network, wall=lambda: clock[0], log=DurableLog(path))
    assert again.clock() == 79.0


def test_the_data_clock_follows_the_heard_nodes_when_others_are_quiet(network):
    """No stall: with one node heard (the others never sent, or quiet for ``silent_after`` wall
    seconds) that node's time is the clock and its ticks are fused."""
    clock = [0.0]
    node = FusionNode(network, wall=lambda: clock[0])
    for i in range(1, 11):
        node.ingest_message(
            msg("array-west", i, "mic_west", float(i), "bearing", [0.3]), "array-west"
        )
    assert node.clock() == 10.0 and node.advance()
    node.ingest_message(msg("array-east", 1, "mic_east", 10.5, "bearing", [0.3]), "array-east")
    assert node.clock() == 10.0  # two nodes heard: the second latest
    clock[0] += network.fusion.silent_after + 1  # array-east falls quiet; array-west goes on
    for i in range(11, 21):
        node.ingest_message(
            msg("array-west", i, "mic_west", float(i), "bearing", [0.3]), "array-west"
        )
    assert node.clock() == 20.0
    with_one = network.model_copy(
        update={"fusion": network.fusion.model_copy(update={"clock_quorum": 1})}
    )
    lone = FusionNode(with_one, wall=lambda: clock[0])
    lone.ingest_message(msg("array-west", 1, "mic_west", 5.0, "bearing", [0.3]), "array-west")
    lone.ingest_message(msg("array-east", 1, "mic_east", 9.0, "bearing", [0.3]), "array-east")
    assert lone.clock() == 9.0  # clock_quorum 1: the latest reading, as before
