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
    frame = seal("west", KEYS["west"], b'{"a":1}', "json")
    head = b"FT\x01j\x04west"
    assert frame.startswith(head) and frame.endswith(b'{"a":1}')
    tag = frame[len(head) : len(head) + 32]
    assert tag == hmac.new(b"k" * 16, head + b'{"a":1}', hashlib.sha256).digest()
    assert open_frame(frame, KEYS) == ("west", "json", b'{"a":1}')
    assert open_frame(seal("east", KEYS["east"], b"\x90", "msgpack"), KEYS)[1] == "msgpack"


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


def _frame(network, node, seq, sensor="mic_west", time=1.0, key=None):
    m = SensorMessage(
        node=node, seq=seq, sensor=sensor, time=time, reading=reading_from_vector("bearing", [0.2])
    )
    k = key if key is not None else network.keys()[node]
    return seal(node, k, encode_message(m, "msgpack"), "msgpack")


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
