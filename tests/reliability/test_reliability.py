"""The reliability suite, small enough for CI (``benchmarks/reliability.py`` runs the same at
full size and writes ``benchmarks/RELIABILITY.md``; issue 18)."""

from __future__ import annotations

import os

from reliability_harness import (
    run_chaos,
    run_flood,
    run_fuzz,
    run_http_fuzz,
    run_mutations,
    run_restart_replay,
)


def test_fuzzed_messages_never_crash_the_node_and_every_refusal_is_counted(network):
    """Mutated valid messages and batches, any JSON / MessagePack value and raw bytes, posted
    or in sealed, forged or bit-flipped UDP frames: each gets an outcome, each refusal a known
    reason, and the counters add up (asserted per input inside :func:`run_fuzz`)."""
    got = run_fuzz(network, examples=int(os.environ.get("FUSETRACK_FUZZ_EXAMPLES", "400")))
    assert got["inputs"] > 300
    assert set(got["by_kind"]) == {"post", "frame", "forged", "flipped"}
    for reason in ("malformed", "schema", "bad_mac", "replay"):
        assert got["rejected"].get(reason, 0) > 0, reason
    assert got["still_accepts"]


def test_byte_mutations_of_valid_messages_never_crash_the_node(network):
    """The same with 5,000 byte-level mutations of valid encoded messages and batches (JSON and
    MessagePack; flips, inserts, deletions, splices, extreme numbers), posted or sealed."""
    got = run_mutations(network, n=5000, seed=2)
    assert got["inputs"] == 5000 and got["still_accepts"]
    assert got["accepted"] > 0  # some mutations leave a valid message
    for reason in ("malformed", "schema"):
        assert got["rejected"].get(reason, 0) > 0, reason


def test_http_and_websocket_ingest_of_mutated_payloads_never_answer_500(network):
    """400 mutated payloads posted to /ingest and sent on /ws/ingest (JSON and MessagePack):
    only 200/400/413/503 answers, one outcome per message, all counted by the node."""
    got = run_http_fuzz(network, n=400, seed=3)
    assert got["counted"] == got["outcomes"] >= 400
    assert set(got["statuses"]) <= {200, 400, 413, 503}


def test_kill_9_loses_no_acknowledged_reading_and_the_log_replays(network, tmp_path):
    """A serving process fed over HTTP (up to 1,000 messages/s), killed with SIGKILL at three
    random moments and restarted on its log each time: every reading the node acknowledged is
    in the log, the node resumes from it, and replaying it recomputes the published tracks."""
    got = run_chaos(network, tmp_path, kills=3, rate=1000.0, seed=1)
    assert got["acknowledged"] > 100
    assert got["acknowledged_missing"] == 0
    assert got["resumed_ticks"] == got["ticks"] > 0 and got["replay_equal"]


def test_captured_frames_replayed_after_a_restart_are_refused_with_or_without_a_log(
    network, tmp_path
):
    """Issue 18, item 5: 300 captured frames replayed into a node restarted 5 s later without a
    log are refused as stale, and as replays by one restarted on its log; their version-1
    copies are refused as legacy_frame without a log; fresh frames are accepted by both."""
    got = run_restart_replay(network, n=300, log_dir=tmp_path)
    assert got["accepted_before"] == 2 * 300
    assert got["replayed"] == {"no log": {"stale": 300}, "log": {"replay": 300}}
    assert got["legacy_no_log"] == {"legacy_frame": 300}
    n_nodes = len(network.nodes)
    assert got["fresh"] == {"no log": {"accepted": n_nodes}, "log": {"accepted": n_nodes}}


def test_an_unauthenticated_flood_at_ten_times_the_rate_starves_nothing(network):
    """1,000 legitimate UDP readings with 10 forged frames each from another address: at least
    95 % of the legitimate readings are accepted and every datagram is accounted for
    (accepted, refused with a reason, or counted as dropped by the kernel)."""
    got = run_flood(network, n=1000, factor=10, rate=1000.0)
    assert got["accepted_share"] >= 0.95
    assert got["uncounted"] == 0
    assert got["dropped_unauthenticated"] + (got["udp_dropped"] or 0) >= got["forged"] * 0.95
    assert got["rate_limited"] > 0.9 * got["forged"]  # dropped before authentication
