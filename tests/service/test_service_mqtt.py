"""The MQTT bridge against a real broker (amqtt, started by the fixture in its own process on a
free port): sealed readings of two nodes in (JSON and MessagePack), tracks out, forged and stale
frames refused and counted, a broker restart survived, acknowledgements after the log commit."""

from __future__ import annotations

import json
import math
import signal
import socket
import sqlite3
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator

import httpx
import pytest

from fusetrack.core import ConfigError
from fusetrack.service import FusionNode, encode_message, parse_config, seal
from fusetrack.service.config import MqttConfig
from fusetrack.service.replay import demo_scenario
from fusetrack.service.schema import SensorMessage, reading_from_vector
from fusetrack.service.server import RunningNode, build_node

paho = pytest.importorskip("paho.mqtt.client")
pytest.importorskip("amqtt.broker")
from paho.mqtt.enums import CallbackAPIVersion  # noqa: E402

BROKER = """
import asyncio, sys
from amqtt.broker import Broker

async def main():
    broker = Broker({
        "listeners": {"default": {"type": "tcp", "bind": "127.0.0.1:%s" % sys.argv[1]}},
        "plugins": {"amqtt.plugins.authentication.AnonymousAuthPlugin": {"allow_anonymous": True}},
    })
    await broker.start()
    print("ready", flush=True)
    await asyncio.Event().wait()

asyncio.run(main())
"""

SENDERS = ("array-west", "tag-reader")  # two nodes: mic_west's bearings, the tag's fixes


class Broker:
    """An amqtt broker in a child process; :meth:`restart` kills it and starts a new one on the
    same port (the bridge's connection drops, its session is gone)."""

    def __init__(self) -> None:
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            self.port = s.getsockname()[1]
        self.proc: subprocess.Popen[str] | None = None

    def start(self) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-c", BROKER, str(self.port)],
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
        )
        assert self.proc.stdout is not None
        assert self.proc.stdout.readline().strip() == "ready", "the broker did not start"

    def stop(self) -> None:
        if self.proc is not None:
            self.proc.kill()
            self.proc.wait(timeout=10)
            self.proc = None

    def restart(self) -> None:
        self.stop()
        self.start()


@pytest.fixture
def broker() -> Iterator[Broker]:
    b = Broker()
    b.start()
    yield b
    b.stop()


def _client(broker: Broker, name: str, on_connect: Callable[..., None] | None = None) -> object:
    client = paho.Client(CallbackAPIVersion.VERSION2, client_id=name, protocol=paho.MQTTv311)
    client.reconnect_delay_set(0.1, 0.5)
    if on_connect is not None:
        client.on_connect = on_connect
    client.connect_async("127.0.0.1", broker.port)
    client.loop_start()
    return client


def _wait(what: Callable[[], bool], timeout: float = 10.0) -> None:
    deadline = time.monotonic() + timeout
    while not what():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.05)


def _with_mqtt(network, broker: Broker, **extra):
    section = {
        "port": broker.port,
        "subscribe": ["sensors/+/readings"],
        "publish_tracks": "fusetrack/tracks",
        "client_id": "fusetrack-test-node",
        "reconnect_min": 0.1,
        "reconnect_max": 0.5,
        **extra,
    }
    return network.model_copy(update={"mqtt": MqttConfig.model_validate(section)})


def _sealed(network, readings, first_seq=1, key=None, sent=None):
    """(node, frame) per reading: odd ones in JSON, even ones in MessagePack."""
    owner, keys = network.owner(), network.keys()
    kinds = {s.id: s.kind for s in network.sensors}
    out = []
    for i, r in enumerate(readings):
        node = owner[r.sensor]
        m = SensorMessage(
            node=node,
            seq=first_seq + i,
            sensor=r.sensor,
            time=r.time,
            reading=reading_from_vector(kinds[r.sensor], r.value),
        )
        encoding = "json" if i % 2 else "msgpack"
        payload = encode_message(m, encoding)
        out.append((node, seal(node, key or keys[node], payload, encoding, sent=sent)))
    return out


def _publish(sender, frames) -> None:
    for node, frame in frames:
        sender.publish(f"sensors/{node}/readings", frame, qos=1).wait_for_publish(5)


def test_readings_in_tracks_out_forgeries_counted_broker_restart_survived(network, broker):
    cfg = _with_mqtt(network, broker)
    scn = demo_scenario(network, seed=0, duration=8.0)
    owner = network.owner()
    readings = [r for r in scn.readings if owner[r.sensor] in SENDERS]
    split = 4.25  # readings before it, the broker restarts, the rest after it
    before = [r for r in readings if r.time < split]
    after = [r for r in readings if r.time >= split]

    ticks: list[dict] = []
    lock = threading.Lock()

    def on_tick(client, userdata, message) -> None:
        with lock:
            ticks.append(json.loads(message.payload))

    def listen(client, userdata, flags, reason, properties) -> None:
        client.subscribe("fusetrack/tracks", qos=1)

    with RunningNode(build_node(cfg), udp_port=None) as running:
        health = lambda: httpx.get(running.url + "/health").json()  # noqa: E731
        reader = _client(broker, "tracks-reader", listen)
        reader.on_message = on_tick
        sender = _client(broker, "sensor-sender")
        _wait(lambda: health()["mqtt"]["subscribed"] and reader.is_connected())
        _wait(lambda: sender.is_connected())

        frames = _sealed(network, readings)  # sent now: after the node started (not stale)
        first, rest = frames[: len(before)], frames[len(before) :]
        _publish(sender, first)
        forged = _sealed(network, before[:1], first_seq=1000, key=b"not-the-key-of-this-node")
        _publish(sender, forged)
        old = _sealed(network, before[:1], first_seq=2000, sent=time.time() - 3600)
        _publish(sender, old)  # authentic, but held back an hour: refused as over UDP
        _wait(lambda: health()["mqtt"]["received"] == len(first) + 2)
        h = health()
        assert h["mqtt"]["accepted"] == len(first) and h["accepted"] == len(first)
        refused = {"bad_mac": 1, "stale": 1}
        assert h["mqtt"]["refused"] == refused and h["rejected"] == refused
        _wait(lambda: len(ticks) > 0)  # the stream paused: the node fused what came

        broker.restart()
        _wait(lambda: health()["mqtt"]["connections"] == 2 and health()["mqtt"]["subscribed"])
        _wait(lambda: reader.is_connected() and sender.is_connected())
        with lock:
            seen = len(ticks)
        _publish(sender, rest)
        _wait(lambda: health()["accepted"] == len(readings))
        last = math.floor(after[-1].time * network.fusion.rate_hz + 1e-9)
        _wait(lambda: bool(ticks) and ticks[-1]["tick"] >= last)
        h = health()
        reader.loop_stop()
        sender.loop_stop()

    assert h["mqtt"]["accepted"] == len(readings) and h["mqtt"]["refused"] == refused
    assert h["mqtt"]["published"] >= len(ticks) and h["mqtt"]["publish_dropped"] == 0
    later = ticks[seen:]
    assert later, "no tracks arrived after the broker restarted"
    got = ticks[-1]
    assert got["type"] == "tick" and got["track"] == got["tracks"][0]
    fused = {s for t in ticks for s in (t["track"] or {}).get("sensors", [])}
    assert fused == {"mic_west", "tag"}  # both nodes' readings were fused
    k = int(abs(scn.truth_times - got["time"]).argmin())
    assert math.dist(got["track"]["position"], scn.truth[k, :2]) < 3.0


def test_a_reading_is_acknowledged_only_once_it_is_in_the_log(
    network, broker, tmp_path, monkeypatch
):
    """QoS 1: the bridge's PUBACK to the broker (after which the broker forgets the message)
    goes out only once the node has ingested the reading and committed its log: at each
    acknowledgement, another reader of the log already sees the reading."""
    path = tmp_path / "node.sqlite"
    cfg = _with_mqtt(network, broker, publish_tracks=None)
    cfg = cfg.model_copy(update={"log": cfg.log.model_copy(update={"path": str(path)})})
    readings = demo_scenario(network, seed=0, duration=3.0).readings
    readings = [r for r in readings if r.sensor == "mic_west"]
    logged_at_ack: list[int] = []
    real_ack = paho.Client.ack

    def ack(client, mid, qos):
        with sqlite3.connect(path) as db:
            logged_at_ack.append(db.execute("SELECT COUNT(*) FROM messages").fetchone()[0])
        return real_ack(client, mid, qos)

    monkeypatch.setattr(paho.Client, "ack", ack)
    node = build_node(cfg)
    with RunningNode(node, udp_port=None):
        sender = _client(broker, "sensor-sender")
        _wait(lambda: sender.is_connected() and node.mqtt_status()["subscribed"])
        frames = _sealed(network, readings)
        _publish(sender, frames)
        _wait(lambda: len(logged_at_ack) == len(frames))
        sender.loop_stop()
    # the k-th acknowledgement: at least k readings committed (a burst is committed at once)
    assert all(n >= k for k, n in enumerate(logged_at_ack, 1)), logged_at_ack
    assert logged_at_ack[-1] == len(frames)
    again = FusionNode(cfg, log=build_node(cfg).log)  # redelivered after a crash: a replay
    assert [o.reason for o in again.ingest_frame(frames[0][1])] == ["replay"]


@pytest.mark.parametrize(
    "section, field",
    [
        ({"subscribe": ["a/#/b"]}, "subscribe topic"),
        ({"subscribe": ["a/b+"]}, "subscribe topic"),
        ({"publish_tracks": "tracks/+"}, "publish_tracks"),
        ({}, "subscribe"),
        ({"subscribe": ["a"], "password": "x"}, "username"),
        ({"subscribe": ["a"], "port": 70000}, "mqtt.port"),
        ({"subscribe": ["a"], "tls": {"cert_file": "c.pem"}}, "key_file"),
        ({"subscribe": ["a"], "username": "u", "password_env": "FT_UNSET_MQTT_PW"}, "password_env"),
        ({"subscribe": ["a"], "qos": 3}, "mqtt.qos"),
        ({"subscribe": ["a"], "topics": ["a"]}, "mqtt.topics"),
    ],
)
def test_bad_mqtt_sections_are_refused_naming_the_field(network, section, field):
    data = network.model_dump(mode="json", exclude={"mqtt"})
    with pytest.raises(ConfigError, match=field.replace("+", r"\+")):
        parse_config({**data, "mqtt": section})


def test_the_mqtt_section_does_not_change_the_fingerprint(network, broker):
    """A log written without the bridge resumes with it (and the other way round)."""
    assert _with_mqtt(network, broker).fingerprint() == network.fingerprint()


def test_serve_starts_the_bridge_and_stops_cleanly(network, broker, tmp_path):
    """``fusetrack serve --config X`` with an ``mqtt`` section: readings over MQTT are accepted;
    Ctrl-C (SIGINT) stops the node and the bridge: the CLI's 130 (128 + SIGINT), no traceback."""
    import yaml

    config = tmp_path / "network.yaml"
    data = _with_mqtt(network, broker).model_dump(mode="json", exclude_none=True)
    config.write_text(yaml.safe_dump(data))
    argv = ["serve", "--config", str(config), "--port", "0", "--udp-port", "-1"]
    code = "import sys; from fusetrack.cli import main; sys.exit(main(sys.argv[1:]))"
    proc = subprocess.Popen(
        [sys.executable, "-c", code, *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        url = proc.stdout.readline().split()[-1]  # "fusion node: dashboard http://HOST:PORT/"

        def health() -> dict:
            try:  # the address is printed just before the server listens
                return httpx.get(url + "health").json()
            except httpx.ConnectError:
                return {"mqtt": {"subscribed": False}}

        _wait(lambda: health()["mqtt"]["subscribed"], timeout=20.0)
        sender = _client(broker, "sensor-sender")
        _wait(lambda: sender.is_connected())
        readings = demo_scenario(network, seed=0, duration=1.0).readings
        _publish(sender, _sealed(network, readings[:1]))
        _wait(lambda: health()["mqtt"]["accepted"] == 1)
        sender.loop_stop()
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=15) == 130
        assert "Traceback" not in (proc.stderr.read() if proc.stderr else "")
    finally:
        if proc.poll() is None:
            proc.kill()


def test_the_bridge_waits_for_a_broker_that_is_not_up_yet(network):
    """The first connection is retried too: a node started before its broker connects later."""
    broker = Broker()
    node = build_node(_with_mqtt(network, broker))
    try:
        with RunningNode(node, udp_port=None):
            _wait(lambda: node.mqtt_status()["last_error"].startswith("cannot reach"))
            assert not node.mqtt_status()["connected"]
            broker.start()
            _wait(lambda: node.mqtt_status()["subscribed"])
            assert node.mqtt_status()["connections"] == 1
    finally:
        broker.stop()


def test_unreadable_tls_files_are_a_config_error(network, tmp_path):
    from fusetrack.service.mqtt import MqttBridge

    junk = tmp_path / "ca.pem"
    junk.write_text("not a certificate")
    section = {"subscribe": ["a"], "tls": {"ca_file": str(junk)}}
    cfg = network.model_copy(update={"mqtt": MqttConfig.model_validate(section)})
    with pytest.raises(ConfigError, match=r"mqtt\.tls.*readable PEM"):
        MqttBridge(FusionNode(cfg), cfg.mqtt)


def test_tls_paths_are_relative_to_the_config_file(network, tmp_path):
    from fusetrack.service import load_config

    data = network.model_dump(mode="json", exclude={"mqtt"})
    data["mqtt"] = {"subscribe": ["a"], "tls": {"ca_file": "certs/ca.pem"}}
    (tmp_path / "network.yaml").write_text(json.dumps(data))  # JSON is YAML
    cfg = load_config(tmp_path / "network.yaml")
    assert cfg.mqtt is not None and cfg.mqtt.tls is not None
    assert cfg.mqtt.tls.ca_file == str(tmp_path / "certs" / "ca.pem")
