"""Node authentication: HMAC frames accepted, forgeries and replays refused and counted."""

from __future__ import annotations

import hashlib
import hmac

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fusetrack.service.auth import (
    Rejected,
    SequenceWindow,
    bearer_token,
    node_of_token,
    open_frame,
    seal,
)
from fusetrack.service.node import FusionNode
from fusetrack.service.schema import SensorMessage, encode_message, reading_from_vector

KEYS = {"west": b"k" * 16, "east": b"e" * 20}


def test_frame_layout_and_tag_are_the_documented_hmac_sha256():
    frame = seal("west", KEYS["west"], b'{"a":1}', "json", sent=1_764_000_000.25)
    # version 2: the send time, 1_764_000_000_250_000 microseconds, big-endian, under the tag
    head = b"FT\x02j\x04west" + (1_764_000_000_250_000).to_bytes(8, "big")
    assert frame.startswith(head) and frame.endswith(b'{"a":1}')
    tag = frame[len(head) : len(head) + 32]
    assert tag == hmac.new(b"k" * 16, head + b'{"a":1}', hashlib.sha256).digest()
    assert open_frame(frame, KEYS) == ("west", "json", b'{"a":1}', 1_764_000_000.25)
    assert open_frame(seal("east", KEYS["east"], b"\x90", "msgpack"), KEYS)[1] == "msgpack"
    # version 1 (no send time) still opens; its send time is None
    old = seal("west", KEYS["west"], b'{"a":1}', "json", version=1)
    head = b"FT\x01j\x04west"
    assert old[len(head) : len(head) + 32] == hmac.digest(b"k" * 16, head + b'{"a":1}', "sha256")
    assert open_frame(old, KEYS) == ("west", "json", b'{"a":1}', None)


def test_a_changed_send_time_breaks_the_tag():
    """The send time is authenticated: moving it forward to make a captured frame fresh again
    is a forgery."""
    frame = bytearray(seal("west", KEYS["west"], b"x", "json", sent=1000.0))
    frame[9 + 7] ^= 0x40  # the send time's last byte (+64 microseconds)
    with pytest.raises(Rejected, match="bad_mac"):
        open_frame(bytes(frame), KEYS)
    with pytest.raises(ValueError, match=r"sent=-1\.0 is invalid"):
        seal("west", KEYS["west"], b"x", sent=-1.0)


@pytest.mark.parametrize("where", [0, 3, 5, 12, 40, -1])
def test_any_altered_byte_is_refused(where):
    frame = bytearray(seal("west", KEYS["west"], b"payload bytes", "json"))
    frame[where] ^= 0x01
    with pytest.raises(Rejected) as err:
        open_frame(bytes(frame), KEYS)
    assert err.value.reason in ("bad_mac", "bad_frame", "unknown_node")


def test_forgery_with_another_nodes_key_or_an_unknown_node():
    forged = seal("west", KEYS["east"], b"x", "json")  # east pretends to be west
    with pytest.raises(Rejected, match="bad_mac"):
        open_frame(forged, KEYS)
    with pytest.raises(Rejected, match="unknown_node"):
        open_frame(seal("north", b"n" * 16, b"x", "json"), KEYS)
    with pytest.raises(Rejected, match="bad_frame"):
        open_frame(b"GET / HTTP/1.1\r\n" + b"x" * 40, KEYS)
    with pytest.raises(Rejected, match="bad_frame"):
        open_frame(b"FT\x01j", KEYS)


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=120))
def test_fuzz_random_datagrams_are_refused_not_raised(data):
    with pytest.raises(Rejected):
        open_frame(data, KEYS)


def test_sequence_window_hand_cases():
    w = SequenceWindow(size=4)
    assert [w.accept(s) for s in (10, 10, 8, 9, 7, 6, 11, 8, 7)] == [
        True,  # first
        False,  # replay
        True,  # late but inside the window (10-8 = 2 < 4)
        True,
        True,  # 10-7 = 3 < 4
        False,  # 10-6 = 4: too old
        True,  # new highest
        False,  # seen
        False,  # 11-7 = 4: too old now
    ]


def test_bearer_tokens_are_derived_not_the_key():
    t = bearer_token(KEYS["west"])
    assert len(t) == 64 and KEYS["west"].decode() not in t
    tokens = {n: bearer_token(k) for n, k in KEYS.items()}
    assert node_of_token(t, tokens) == "west"
    assert node_of_token("0" * 64, tokens) is None


def _frame(network, node, seq, sensor="mic_west", time=1.0, key=None, sent=None, version=2):
    m = SensorMessage(
        node=node, seq=seq, sensor=sensor, time=time, reading=reading_from_vector("bearing", [0.2])
    )
    k = key if key is not None else network.keys()[node]
    return seal(node, k, encode_message(m, "msgpack"), "msgpack", sent=sent, version=version)


def test_node_accepts_counts_replays_and_forgeries(network):
    node = FusionNode(network)
    ok = node.ingest_frame(_frame(network, "array-west", 1))
    assert ok[0].accepted
    again = node.ingest_frame(_frame(network, "array-west", 1))  # the same datagram replayed
    assert not again[0].accepted and again[0].reason == "replay"
    forged = node.ingest_frame(_frame(network, "array-west", 2, key=b"wrong-key-123456"))
    assert forged[0].reason == "bad_mac"
    # a node may not report another node's sensor, even with a valid signature
    other = node.ingest_frame(_frame(network, "array-east", 1, sensor="mic_west"))
    assert other[0].reason == "forbidden_sensor"
    assert node.rejected == {"replay": 1, "bad_mac": 1, "forbidden_sensor": 1}
    assert sum(node.accepted.values()) == 1
    text = node.metrics_text().decode()
    assert 'fusetrack_messages_rejected_total{reason="replay"} 1.0' in text
    assert 'fusetrack_messages_rejected_total{reason="bad_mac"} 1.0' in text
    assert 'fusetrack_messages_accepted_total{sensor="mic_west"} 1.0' in text


def test_a_huge_sequence_jump_is_accepted_in_bounded_memory():
    """Issue 18: a jump of 2**33 in a sensor's sequence number shifted the window's bitmap by the
    jump (2.4 GiB); 10**17 raised MemoryError. The window now forgets what it jumped over."""
    w = SequenceWindow()
    assert w.accept(5) and w.accept(3)
    for seq in (2**33, 1_764_000_000_000_000, 10**17):  # a microsecond clock, then 10**17
        assert w.accept(seq)
        assert w.bitmap.bit_length() <= w.size
    assert not w.accept(1_764_000_000_000_000)  # older than the window now
    assert w.accept(10**17 + 1) and not w.accept(10**17 + 1)


def test_a_forged_flood_from_one_source_is_dropped_unchecked_and_counted(
    tmp_path, network, monkeypatch
):
    """Issue 18: 60,000 forged frames from one sender starved the legitimate ones and the loss
    was not in /health. A source spends ``auth_failure_burst`` failures, then its frames are
    dropped before their HMAC is computed; valid frames from other addresses all get through,
    every accepted one is in the durable log, and /health counts every dropped frame."""
    from fusetrack.service import node as node_module
    from fusetrack.service.log import DurableLog

    limits = network.limits.model_copy(
        update={"auth_failure_burst": 50, "auth_failures_per_second": 10.0}
    )
    cfg = network.model_copy(update={"limits": limits})
    clock = [1000.0]
    node = FusionNode(cfg, wall=lambda: clock[0], log=DurableLog(tmp_path / "n.sqlite"))
    checked = []
    real_open = node_module.open_frame
    monkeypatch.setattr(
        node_module, "open_frame", lambda f, k: checked.append(1) or real_open(f, k)
    )
    forged = _frame(network, "array-west", 10**6, key=b"attacker-key-0000", sent=clock[0])
    for seq in range(1, 201):  # 10 forged frames per valid one, all in the same wall second
        for _ in range(10):
            assert not node.ingest_frame(forged, "203.0.113.9")[0].accepted
        frame = _frame(network, "array-west", seq, time=seq * 0.01, sent=clock[0])
        ok = node.ingest_frame(frame, "10.0.0.1")
        assert ok[0].accepted
    assert node.rejected == {"bad_mac": 50, "rate_limited": 1950}
    assert len(checked) == 50 + 200  # the blocked source's frames were never authenticated
    health = node.health()
    assert health["accepted"] == 200
    assert health["dropped_unauthenticated"] == 2000 and health["rate_limited"] == 1950
    node.commit()
    assert [m.seq for _, m in node.log.messages()] == list(range(1, 201))
    # the bucket refills: one failure per 1 / auth_failures_per_second seconds
    clock[0] += 0.1
    assert node.ingest_frame(forged, "203.0.113.9")[0].reason == "bad_mac"
    assert node.ingest_frame(forged, "203.0.113.9")[0].reason == "rate_limited"


def test_a_captured_frame_is_refused_after_a_restart_without_a_log(network):
    """Issue 18, item 5: the replay windows live in memory, so a node restarted without a log
    accepted a captured frame again. A node without a log now refuses any frame sent before it
    started (less ``limits.max_clock_skew``); fresh frames, and senders whose clocks are off by
    less than the skew, still get through."""
    clock = [1000.0]
    first = FusionNode(network, wall=lambda: clock[0])
    captured = _frame(network, "array-west", 7, sent=clock[0])
    assert first.ingest_frame(captured)[0].accepted
    assert first.ingest_frame(captured)[0].reason == "replay"
    clock[0] = 1010.0  # killed, restarted without a log 10 s later (age < max_frame_age)
    node = FusionNode(network, wall=lambda: clock[0])
    skew = network.limits.max_clock_skew
    clock[0] = 1011.0
    replayed = node.ingest_frame(captured)
    assert not replayed[0].accepted and replayed[0].reason == "stale"
    assert "before this node started" in replayed[0].detail
    # the sender's next frame; a sender whose clock runs behind by just under the skew, right
    # after the restart; one ahead by just under the skew
    assert node.ingest_frame(_frame(network, "array-west", 8, sent=1011.0))[0].accepted
    behind = _frame(network, "array-east", 1, sensor="mic_east", sent=1010.0 - 0.9 * skew)
    assert node.ingest_frame(behind)[0].accepted
    ahead = _frame(network, "array-west", 9, sent=1011.0 + 0.9 * skew)
    assert node.ingest_frame(ahead)[0].accepted
    # further off than the skew: refused, counted
    too_far = _frame(network, "array-west", 10, sent=1011.0 + 1.5 * skew)
    assert node.ingest_frame(too_far)[0].reason == "clock_skew"
    too_old = _frame(network, "array-east", 2, sensor="mic_east", sent=1010.0 - 1.5 * skew)
    assert node.ingest_frame(too_old)[0].reason == "stale"
    assert node.rejected == {"stale": 2, "clock_skew": 1}
    assert sum(node.accepted.values()) == 3
    text = node.metrics_text().decode()
    assert 'fusetrack_messages_rejected_total{reason="stale"} 2.0' in text


def test_version_1_frames_need_a_log_and_every_frame_ages_out(tmp_path, network):
    """A version-1 frame has no send time: a node with a log (whose replay windows survive a
    restart) accepts it, and refuses its replay after the restart; a node without a log refuses
    it as ``legacy_frame``. A node that resumed its log accepts a recent frame sent before the
    restart; one on a new log does not. With or without a log, a frame sent longer ago than
    ``limits.max_frame_age`` is ``stale``."""
    from fusetrack.service.log import DurableLog

    clock = [1000.0]
    path = tmp_path / "n.sqlite"
    first = FusionNode(network, wall=lambda: clock[0], log=DurableLog(path))
    old = _frame(network, "array-west", 3, version=1)
    assert first.ingest_frame(old)[0].accepted
    first.commit()
    first.log.close()
    clock[0] = 1060.0
    resumed = FusionNode(network, wall=lambda: clock[0], log=DurableLog(path))
    assert resumed.ingest_frame(old)[0].reason == "replay"  # the log restored its window
    # with a log, a frame sent before the restart is accepted if it is new and recent
    assert resumed.ingest_frame(_frame(network, "array-west", 4, sent=1059.0))[0].accepted
    age = network.limits.max_frame_age
    late = _frame(network, "array-west", 5, sent=1060.0 - 1.01 * age)
    assert resumed.ingest_frame(late)[0].reason == "stale"
    bare = FusionNode(network, wall=lambda: clock[0])
    refused = bare.ingest_frame(_frame(network, "array-west", 1, version=1))
    assert refused[0].reason == "legacy_frame" and "version-1" in refused[0].detail
    assert bare.rejected == {"legacy_frame": 1}
    # a new log has no windows to restore: frames sent before the node started are refused as
    # without a log (an earlier node without a log may have seen them); version 1 is accepted
    fresh = FusionNode(network, wall=lambda: clock[0], log=DurableLog(tmp_path / "new.sqlite"))
    assert fresh.ingest_frame(_frame(network, "array-west", 1, sent=1050.0))[0].reason == "stale"
    assert fresh.ingest_frame(_frame(network, "array-west", 2, version=1))[0].accepted


def test_frame_age_must_exceed_the_clock_skew(network):
    from fusetrack.core import ConfigError
    from fusetrack.service.config import parse_config

    data = network.model_dump()
    data["limits"].update(max_frame_age=2.0, max_clock_skew=5.0)
    with pytest.raises(ConfigError, match="max_frame_age=2 is invalid: expected more than"):
        parse_config(data)


def test_http_clients_that_keep_failing_get_429_valid_tokens_still_pass(network):
    """The same over HTTP: after the burst a bad token is answered 429 (Retry-After) before the
    body is read, counted as rate_limited; a valid token from the same address is unaffected
    (a proxy in front of the node shows every client with one address)."""
    from fastapi.testclient import TestClient

    from fusetrack.service.app import create_app

    limits = network.limits.model_copy(update={"auth_failure_burst": 3})
    node = FusionNode(network.model_copy(update={"limits": limits}))
    m = SensorMessage(
        node="array-west",
        seq=1,
        sensor="mic_west",
        time=1.0,
        reading=reading_from_vector("bearing", [0.2]),
    )
    with TestClient(create_app(node)) as c:
        bad = {"Authorization": "Bearer " + "0" * 64}
        codes = [c.post("/ingest", content=b"{}", headers=bad).status_code for _ in range(5)]
        assert codes == [401, 401, 401, 429, 429]
        good = {"Authorization": "Bearer " + node.tokens["array-west"]}
        r = c.post("/ingest", content=m.model_dump_json(), headers=good)
        assert r.status_code == 200 and r.json()["accepted"] == 1
        health = c.get("/health").json()
    assert health["dropped_unauthenticated"] == 5 and health["rate_limited"] == 2
    assert node.rejected["unauthorized"] == 3


def test_what_the_kernel_drops_for_a_full_socket_is_counted():
    """/health's udp_dropped: datagrams lost before the node could read them are counted
    (``/proc/net/udp``), so received + dropped = sent."""
    import socket

    from fusetrack.service.udp import kernel_drops, udp_socket

    sock = udp_socket(rcvbuf=4096)
    out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    drops = kernel_drops(sock)
    if drops is None:
        pytest.skip("no /proc/net/udp here")
    for _ in range(300):
        out.sendto(b"x" * 1000, sock.getsockname())
    received = 0
    while True:
        try:
            sock.recv(2048)
        except BlockingIOError:
            break
        received += 1
    assert 0 < received < 300 and received + kernel_drops(sock) - drops == 300
    sock.close()
    out.close()
