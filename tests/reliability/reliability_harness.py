"""The reliability runs of the live node, at any scale: the suite here runs them small, and
``benchmarks/reliability.py`` runs them large and writes ``benchmarks/RELIABILITY.md``.

* :func:`run_fuzz`: hypothesis-generated payloads (mutated valid messages and batches, any JSON
  or MessagePack value, raw bytes, sealed and forged UDP frames) into one node: nothing raises,
  every message gets an outcome and every refusal is counted; :func:`run_mutations` does the
  same with byte-level mutations of valid encoded messages (cheap: for volume), and
  :func:`run_http_fuzz` through the web application's HTTP and WebSocket ingest.
* :func:`run_chaos`: a node served by a process forked from a fork server, fed over HTTP at a steady rate, killed
  with SIGKILL at random moments and restarted on its log: every acknowledged reading is in
  the log and replaying the log gives the published tracks.
* :func:`run_restart_replay`: captured UDP frames replayed into nodes restarted with and
  without a log (issue 18, item 5): none accepted; fresh frames still are.
* :func:`run_flood`: legitimate UDP readings with ``factor`` times as many forged frames from
  another address: the share of legitimate readings accepted and every datagram accounted for.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import signal
import socket
import threading
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import Any

import httpx
import msgpack
import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fusetrack.service.auth import seal
from fusetrack.service.config import NetworkConfig
from fusetrack.service.log import DurableLog, replay_log
from fusetrack.service.node import REJECTION_REASONS, FusionNode
from fusetrack.service.replay import demo_scenario
from fusetrack.service.schema import (
    MessageBatch,
    SensorMessage,
    encode_message,
    reading_from_vector,
)
from fusetrack.service.server import RunningNode, serve

# -- inputs ---------------------------------------------------------------------------------


def readings(cfg: NetworkConfig, n: int, seed: int = 0, spacing: float = 0.05) -> list[Any]:
    """``n`` valid ``(node, sensor, time, reading)`` of the demo network, times ``spacing``
    apart (the demo scenario's values, cycled)."""
    base = demo_scenario(cfg, seed=seed, duration=60.0).readings
    owner, kinds = cfg.owner(), {s.id: s.kind for s in cfg.sensors}
    out = []
    for i in range(n):
        r = base[i % len(base)]
        out.append(
            (
                owner[r.sensor],
                r.sensor,
                (i + 1) * spacing,
                reading_from_vector(kinds[r.sensor], r.value),
            )
        )
    return out


_JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=20),
    lambda inner: (
        st.lists(inner, max_size=5) | st.dictionaries(st.text(max_size=10), inner, max_size=5)
    ),
    max_leaves=20,
)
_FIELDS = ("version", "node", "seq", "sensor", "time", "reading", "covariance")
_READING_FIELDS = ("kind", "bearing", "azimuth", "polar", "range", "position", "u", "v", "values")


@st.composite
def mutated_messages(draw: Callable[..., Any]) -> dict[str, Any]:
    """A valid message of the demo network with a few fields replaced, dropped or added."""
    sensors = {"mic_west": ("array-west", [0.3]), "tag": ("tag-reader", [30.0, 20.0])}
    sensor = draw(st.sampled_from(sorted(sensors)))
    node, z = sensors[sensor]
    kind = "bearing" if sensor == "mic_west" else "position_fix"
    m = SensorMessage(
        node=node,
        seq=draw(st.integers(0, 2**63 - 1)),
        sensor=sensor,
        time=draw(st.floats(-100.0, 100.0)),
        reading=reading_from_vector(kind, z),
    ).model_dump(mode="json", exclude_none=True)
    for _ in range(draw(st.integers(0, 3))):
        where = draw(st.sampled_from(["message", "reading"]))
        inner = m.get("reading")
        on_reading = where == "reading" and isinstance(inner, dict)
        target = inner if on_reading else m
        names = _READING_FIELDS if on_reading else _FIELDS
        action = draw(st.sampled_from(["replace", "drop", "add"]))
        name = draw(st.sampled_from(names))
        if action == "drop":
            target.pop(name, None)
        elif action == "replace":
            target[name] = draw(_JSON)
        else:
            target[draw(st.text(max_size=8))] = draw(_JSON)
    return m


def _encode(value: Any, encoding: str) -> bytes | None:
    try:
        if encoding == "json":
            return json.dumps(value).encode()  # NaN and Infinity included, as a sender may
        return bytes(msgpack.packb(value, use_bin_type=True))
    except (OverflowError, ValueError, TypeError):  # e.g. an integer MessagePack cannot hold
        return None


payloads = st.one_of(
    st.tuples(mutated_messages(), st.sampled_from(["json", "msgpack"])).map(
        lambda t: (_encode(t[0], t[1]), t[1])
    ),
    st.tuples(
        st.lists(mutated_messages(), min_size=1, max_size=4), st.sampled_from(["json", "msgpack"])
    ).map(lambda t: (_encode({"version": 1, "messages": t[0]}, t[1]), t[1])),
    st.tuples(_JSON, st.sampled_from(["json", "msgpack"])).map(
        lambda t: (_encode(t[0], t[1]), t[1])
    ),
    st.tuples(st.binary(max_size=300), st.sampled_from(["json", "msgpack"])),
)
"""``(payload bytes or None, encoding)`` as a sender might post them."""


# -- fuzzing --------------------------------------------------------------------------------


def _accounted(node: FusionNode, before: tuple[int, int], outcomes: list[Any]) -> None:
    """Every outcome counted once, every refusal with a known reason."""
    accepted, rejected = sum(node.accepted.values()), sum(node.rejected.values())
    assert outcomes, "no outcome"
    assert all(o.accepted or o.reason in REJECTION_REASONS for o in outcomes), outcomes
    assert accepted - before[0] == sum(o.accepted for o in outcomes)
    assert rejected - before[1] == sum(not o.accepted for o in outcomes)


def run_fuzz(cfg: NetworkConfig, examples: int) -> dict[str, Any]:
    """Fuzz one node's decoder and checks (payloads as posted, and in sealed UDP frames, some
    forged or altered); deterministic (``derandomize``). Returns the counts."""
    node = FusionNode(cfg, wall=lambda: 0.0)
    keys = cfg.keys()
    inputs = Counter[str]()

    @settings(
        max_examples=examples,
        deadline=None,
        database=None,
        derandomize=True,
        suppress_health_check=list(HealthCheck),
    )
    @given(payloads, st.sampled_from(["post", "frame", "forged", "flipped"]), st.integers(0, 10**6))
    def one(payload: tuple[bytes | None, str], how: str, salt: int) -> None:
        body, encoding = payload
        if body is None:
            return
        inputs[how] += 1
        before = (sum(node.accepted.values()), sum(node.rejected.values()))
        if how == "post":
            outcomes = node.ingest_payload(body, encoding, "array-west")
        else:
            key = keys["array-west"] if how != "forged" else b"forged-key-%07d" % (salt % 10**7)
            frame = bytearray(seal("array-west", key, body, encoding, sent=node.wall()))
            if how == "flipped":
                frame[salt % len(frame)] ^= 1 + salt % 255
            outcomes = node.ingest_frame(bytes(frame), f"10.0.{salt % 256}.1")
        _accounted(node, before, outcomes)

    one()
    return _summary(node, inputs)


def _summary(node: FusionNode, inputs: Counter[str]) -> dict[str, Any]:
    """The counts of a fuzz run, and whether the node still accepts a valid reading after it
    (from a node the run did not use)."""
    m = SensorMessage(
        node="camera-1",
        seq=1,
        sensor="camera",
        time=node.aligner.fused_until + 0.5,
        reading=reading_from_vector("bearing", [0.1]),
    )
    return {
        "inputs": sum(inputs.values()),
        "by_kind": dict(inputs),
        "accepted": sum(node.accepted.values()),
        "rejected": dict(sorted(node.rejected.items())),
        "still_accepts": node.ingest_message(m, "camera-1").accepted,
    }


def _mutate(data: bytes, rng: np.random.Generator, corpus: list[bytes]) -> bytes:
    """One to four random edits of ``data``: flip, insert, delete, duplicate, splice, or a
    number replaced by an extreme one (the mutations of a byte-level fuzzer such as radamsa)."""
    b = bytearray(data)
    for _ in range(int(rng.integers(1, 5))):
        n = max(len(b), 1)
        i, j = sorted(int(x) for x in rng.integers(0, n, 2))
        op = int(rng.integers(0, 6))
        if op == 0 and b:
            b[i % len(b)] ^= int(rng.integers(1, 256))
        elif op == 1:
            b[i:i] = rng.bytes(int(rng.integers(1, 16)))
        elif op == 2:
            del b[i:j]
        elif op == 3:
            b[j:j] = b[i:j]
        elif op == 4:
            other = corpus[int(rng.integers(len(corpus)))]
            b = b[:i] + bytearray(other[int(rng.integers(0, len(other))) :])
        else:
            extreme = [b"1e999", b"-0", b"NaN", b"99999999999999999999999", b'"1"', b"null"]
            b[i:j] = extreme[int(rng.integers(len(extreme)))]
    return bytes(b)


def run_mutations(cfg: NetworkConfig, n: int, seed: int = 0) -> dict[str, Any]:
    """``n`` byte-level mutations of valid encoded messages and batches (JSON, MessagePack),
    posted by their node or sealed in its UDP frame; each accounted for as in :func:`run_fuzz`."""
    rng = np.random.default_rng(seed)
    node = FusionNode(cfg, wall=lambda: 0.0)
    keys = cfg.keys()
    inputs = Counter[str]()
    west = [r for r in readings(cfg, 400, seed) if r[0] == "array-west"]
    corpus = []
    for i, (who, sensor, t, reading) in enumerate(west):
        m = SensorMessage(node=who, seq=i + 1, sensor=sensor, time=t, reading=reading)
        batch = MessageBatch(messages=[m, m.model_copy(update={"seq": i + 10_000})])
        for encoding in ("json", "msgpack"):
            corpus.append((encode_message(m, encoding), encoding))
            corpus.append((encode_message(batch, encoding), encoding))
    raw = [c for c, _ in corpus]
    for k in range(n):
        data, encoding = corpus[int(rng.integers(len(corpus)))]
        body = _mutate(data, rng, raw)
        before = (sum(node.accepted.values()), sum(node.rejected.values()))
        if k % 2:
            inputs["post"] += 1
            outcomes = node.ingest_payload(body, encoding, "array-west")
        else:
            inputs["frame"] += 1
            frame = seal("array-west", keys["array-west"], body, encoding, sent=node.wall())
            outcomes = node.ingest_frame(frame, "10.0.0.1")
        _accounted(node, before, outcomes)
    return _summary(node, inputs)


def run_http_fuzz(cfg: NetworkConfig, n: int, seed: int = 0) -> dict[str, Any]:
    """``n`` mutated payloads through the web application (``POST /ingest`` and frames on
    ``/ws/ingest``, JSON and MessagePack, with a valid token): never a server error, every
    answer lists one outcome per message and the node's counters add up to the outcomes."""
    from fastapi.testclient import TestClient

    from fusetrack.service.app import create_app

    rng = np.random.default_rng(seed)
    node = FusionNode(cfg, wall=lambda: 0.0)
    token = {"Authorization": f"Bearer {node.tokens['array-west']}"}
    corpus = []
    for i, (who, sensor, t, reading) in enumerate(readings(cfg, 200, seed)):
        m = SensorMessage(node=who, seq=i + 1, sensor=sensor, time=t, reading=reading)
        corpus += [(encode_message(m, "json"), "json"), (encode_message(m, "msgpack"), "msgpack")]
    raw = [c for c, _ in corpus]
    statuses = Counter[int]()
    outcomes = 0
    with (
        TestClient(create_app(node)) as client,
        client.websocket_connect("/ws/ingest", headers=token) as ws,
    ):
        for k in range(n):
            data, encoding = corpus[int(rng.integers(len(corpus)))]
            body = _mutate(data, rng, raw)
            if k % 2:
                ctype = "application/msgpack" if encoding == "msgpack" else "application/json"
                r = client.post("/ingest", content=body, headers={**token, "Content-Type": ctype})
                statuses[r.status_code] += 1
                assert r.status_code in (200, 400, 413, 503), (r.status_code, body)
                answer = r.json()
            else:
                if encoding == "msgpack":
                    ws.send_bytes(body)
                else:
                    ws.send_text(body.decode(errors="replace"))
                answer = ws.receive_json()
            assert answer["accepted"] + answer["rejected"] == len(answer["results"]) >= 1
            outcomes += len(answer["results"])
    counted = sum(node.accepted.values()) + sum(node.rejected.values())
    assert counted == outcomes, (counted, outcomes)
    return {"inputs": n, "statuses": dict(statuses), "outcomes": outcomes, "counted": counted}


# -- kill -9 and restart --------------------------------------------------------------------


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _serve_child(cfg: NetworkConfig, port: int, log_path: str) -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    try:
        serve(cfg, "127.0.0.1", port, None, log_path)
    finally:
        os._exit(0)


class _Sender:
    """Posts batches at a steady rate from a thread; remembers what was acknowledged."""

    def __init__(self, url: str, cfg: NetworkConfig, todo: list[Any], start: int, rate: float):
        self.url, self.todo, self.i, self.rate = url, todo, start, rate
        self.tokens = cfg.tokens()
        self.acked: set[tuple[str, int]] = set()
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self.run, daemon=True)

    sent = 0
    seconds = 0.0

    def run(self) -> None:
        batch = max(20, int(self.rate / 20))
        t0 = time.monotonic()
        sent = 0
        with httpx.Client(timeout=5.0) as client:
            while not self.stop.is_set() and self.i < len(self.todo):
                chunk = self.todo[self.i : self.i + batch]
                self.i += len(chunk)  # an unanswered chunk is skipped, never resent
                by_node: dict[str, list[SensorMessage]] = {}
                for seq, (node, sensor, t, reading) in enumerate(chunk, self.i - len(chunk) + 1):
                    m = SensorMessage(node=node, seq=seq, sensor=sensor, time=t, reading=reading)
                    by_node.setdefault(node, []).append(m)
                sent += len(chunk)  # posted, answered or not
                self.sent, self.seconds = sent, time.monotonic() - t0
                for node, msgs in by_node.items():
                    try:
                        r = client.post(
                            f"{self.url}/ingest",
                            content=MessageBatch(messages=msgs).model_dump_json(),
                            headers={"Authorization": f"Bearer {self.tokens[node]}"},
                        )
                    except httpx.HTTPError:
                        return  # the node is gone
                    for m, res in zip(msgs, r.json()["results"], strict=True):
                        if res["accepted"]:
                            self.acked.add((m.node, m.seq))
                ahead = sent / self.rate - (time.monotonic() - t0)
                if ahead > 0:
                    time.sleep(ahead)


def _wait_up(url: str, proc: Any, timeout: float = 120.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if not proc.is_alive():
            raise RuntimeError("the node process died at start")
        try:
            if httpx.get(f"{url}/health", timeout=1.0).status_code == 200:
                return
        except httpx.HTTPError:
            time.sleep(0.05)
    raise RuntimeError("the node did not start")


def run_chaos(
    cfg: NetworkConfig, workdir: Path, kills: int, rate: float = 1000.0, seed: int = 0
) -> dict[str, Any]:
    """Serve ``cfg`` in a process forked from a fork server with a durable log, feed it over HTTP at up to ``rate``
    messages/s, SIGKILL it after a random 0.3-1.0 s, restart on the same log; ``kills`` times.
    Then a last restart on the log: every acknowledged reading is in it, and replaying it gives
    the published tracks."""
    rng = np.random.default_rng(seed)
    log_path = str(workdir / "chaos.sqlite")
    todo = readings(cfg, int(rate * 1.2 * kills) + 100, seed)
    # forkserver, not fork: a child forked from the test process (threads of BLAS, Numba,
    # the sender) can inherit a held lock and hang; the fork server is a fresh single-threaded
    # interpreter with the node's modules imported once, so each start is still a quick fork
    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(["fusetrack.service", "reliability_harness"])
    acked: set[tuple[str, int]] = set()
    position, moments, sent, seconds = 0, [], 0, 0.0
    for _ in range(kills):
        port = _free_port()
        proc = ctx.Process(target=_serve_child, args=(cfg, port, log_path), daemon=True)
        proc.start()
        url = f"http://127.0.0.1:{port}"
        _wait_up(url, proc)
        sender = _Sender(url, cfg, todo, position, rate)
        sender.thread.start()
        moment = float(rng.uniform(0.3, 1.0))
        moments.append(moment)
        time.sleep(moment)
        assert proc.pid is not None
        os.kill(proc.pid, signal.SIGKILL)  # in the middle of whatever it was doing
        proc.join()
        sender.stop.set()
        sender.thread.join()
        acked |= sender.acked
        position = sender.i
        sent, seconds = sent + sender.sent, seconds + sender.seconds
    restarted = FusionNode(cfg, log=DurableLog(log_path))  # resumes (raises if it cannot)
    log = restarted.log
    assert log is not None
    try:
        logged = {(m.node, m.seq) for _, m in log.messages()}
        published = [s for s, _ in log.ticks()]
        _, replayed = replay_log(cfg, log)
    finally:
        log.close()
    return {
        "kills": kills,
        "kill_moments_s": [round(m, 3) for m in moments],
        "sent": sent,
        "send_rate": sent / seconds if seconds else 0.0,
        "resumed_ticks": restarted.resumed_ticks,
        "acknowledged": len(acked),
        "acknowledged_missing": len(acked - logged),
        "logged": len(logged),
        "ticks": len(published),
        "replay_equal": replayed == published,
    }


# -- captured frames replayed after a restart -----------------------------------------------


def run_restart_replay(
    cfg: NetworkConfig, n: int, log_dir: Path, gap: float = 5.0, seed: int = 0
) -> dict[str, Any]:
    """Issue 18, item 5: ``n`` sealed UDP frames (sent 1 ms apart) captured on their way to two
    nodes, one with a durable log and one without; both restarted ``gap`` wall seconds later and
    every captured frame replayed into each, and their version-1 copies (no send time) into the
    one without a log; then one fresh frame per sensor node. Returns the outcomes by reason."""
    clock = [1000.0]
    keys = cfg.keys()
    seq: Counter[str] = Counter()
    path = log_dir / "restart-replay.sqlite"

    def frame(who: str, sensor: str, t: float, reading: Any, version: int = 2) -> bytes:
        m = SensorMessage(node=who, seq=seq[who], sensor=sensor, time=t, reading=reading)
        body = encode_message(m, "msgpack")
        return seal(who, keys[who], body, "msgpack", sent=clock[0], version=version)

    bare = FusionNode(cfg, wall=lambda: clock[0])
    logged = FusionNode(cfg, wall=lambda: clock[0], log=DurableLog(path))
    captured, legacy, accepted = [], [], 0
    todo = readings(cfg, n, seed)
    for who, sensor, t, reading in todo:
        seq[who] += 1
        captured.append(frame(who, sensor, t, reading))
        legacy.append(frame(who, sensor, t, reading, version=1))
        accepted += bare.ingest_frame(captured[-1])[0].accepted
        accepted += logged.ingest_frame(captured[-1])[0].accepted
        clock[0] += 0.001
    logged.commit()
    assert logged.log is not None
    logged.log.close()
    clock[0] += gap
    bare = FusionNode(cfg, wall=lambda: clock[0])
    logged = FusionNode(cfg, wall=lambda: clock[0], log=DurableLog(path))

    def outcomes(node: FusionNode, frames: list[bytes]) -> dict[str, int]:
        got = Counter(o.reason or "accepted" for f in frames for o in node.ingest_frame(f))
        return dict(sorted(got.items()))

    replayed = {"no log": outcomes(bare, captured), "log": outcomes(logged, captured)}
    legacy_no_log = outcomes(bare, legacy)
    fresh: dict[str, bytes] = {}  # one new frame per sensor node
    t_fresh = todo[0][2]  # a reading time both nodes' data clocks allow (none has fused yet)
    for who, sensor, _, reading in todo:
        if who not in fresh:
            seq[who] += 1
            fresh[who] = frame(who, sensor, t_fresh, reading)
    frames = list(fresh.values())
    fresh_outcomes = {"no log": outcomes(bare, frames), "log": outcomes(logged, frames)}
    assert logged.log is not None
    logged.log.close()
    return {
        "captured": n,
        "accepted_before": accepted,
        "replayed": replayed,
        "legacy_no_log": legacy_no_log,
        "fresh": fresh_outcomes,
        "gap_s": gap,
    }


# -- unauthenticated flood ------------------------------------------------------------------


def run_flood(
    cfg: NetworkConfig, n: int, factor: int = 10, rate: float = 1000.0, seed: int = 0
) -> dict[str, Any]:
    """Send ``n`` legitimate UDP readings from 127.0.0.1 at ``rate``/s to a node, and
    ``factor`` forged frames per reading from 127.0.0.2 (a wrong key for a real node, an
    unknown node, garbage). Returns what was accepted and how every datagram was counted."""
    rng = np.random.default_rng(seed)
    keys = cfg.keys()
    todo = readings(cfg, n, seed)
    forged_body = b'{"node":"array-west","seq":1}' * 4
    forged = [
        seal("array-west", b"attacker-key-0001", forged_body),
        seal("nobody", b"attacker-key-0002", forged_body),
        b"FT\x01j" + rng.bytes(150),
    ]
    node = FusionNode(cfg)
    with RunningNode(node, udp_port=0) as running:
        assert running.udp is not None
        to = running.udp
        good, bad = (
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM),
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM),
        )
        good.bind(("127.0.0.1", 0))
        bad.bind(("127.0.0.2", 0))
        t0 = time.monotonic()
        for i, (who, sensor, t, reading) in enumerate(todo):
            m = SensorMessage(node=who, seq=i + 1, sensor=sensor, time=t, reading=reading)
            good.sendto(seal(who, keys[who], m.model_dump_json().encode()), to)
            for j in range(factor):
                bad.sendto(forged[j % len(forged)], to)
            ahead = (i + 1) / rate - (time.monotonic() - t0)
            if ahead > 0:
                time.sleep(ahead)
        sent = n * (1 + factor)
        deadline = time.monotonic() + 10.0
        while time.monotonic() < deadline:
            h = httpx.get(f"{running.url}/health").json()
            counted = h["accepted"] + sum(h["rejected"].values()) + (h["udp_dropped"] or 0)
            if counted >= sent:
                break
            time.sleep(0.1)
        good.close()
        bad.close()
    return {
        "legitimate": n,
        "forged": n * factor,
        "accepted": h["accepted"],
        "accepted_share": h["accepted"] / n,
        "dropped_unauthenticated": h["dropped_unauthenticated"],
        "rate_limited": h["rate_limited"],
        "udp_dropped": h["udp_dropped"],
        "uncounted": sent - counted,
        "seconds": time.monotonic() - t0,
        "rejected": h["rejected"],
    }
