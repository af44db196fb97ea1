"""Reliability runs of the live node at full size; writes ``benchmarks/RELIABILITY.md``.

    python benchmarks/reliability.py                        # full size (a few minutes)
    python benchmarks/reliability.py --mutations 10000 --examples 500 --kills 3 --flood 1000

The same runs as ``tests/reliability/`` (:mod:`reliability_harness` there), larger:

* hypothesis-generated payloads (``--examples``) and byte-level mutations of valid messages
  (``--mutations``) into one node: every input gets an outcome, every refusal a known reason and
  the counters add up, or the run stops with the failing input;
* ``--kills`` SIGKILLs of a serving process fed over HTTP (up to ``--rate`` messages/s), each
  at a random moment, restarting on the same log: acknowledged readings missing from the log,
  and whether replaying the log gives the published tracks;
* ``--captured`` sealed UDP frames captured and replayed into nodes restarted with and without
  a log, with their version-1 copies (issue 18, item 5);
* ``--flood`` legitimate UDP readings with ``--factor`` forged frames each from another address:
  the share accepted and the datagrams not accounted for.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests" / "reliability"))

from reliability_harness import (  # noqa: E402
    run_chaos,
    run_flood,
    run_fuzz,
    run_http_fuzz,
    run_mutations,
    run_restart_replay,
)

from fusetrack.service.replay import demo_network  # noqa: E402

KEYS = {
    "array-west": "bench-key-array-west-000001",
    "array-east": "bench-key-array-east-000002",
    "camera-1": "bench-key-camera-1-00000003",
    "tag-reader": "bench-key-tag-reader-000004",
}

TESTED = """\
| Issue 18 item | What broke | Now | Test |
|---|---|---|---|
| 1 | a sequence-number jump of 2^33 took 2.4 GiB, 10^17 MemoryError | the replay window forgets what a jump passes over | `tests/service/test_service_auth.py::test_a_huge_sequence_jump_is_accepted_in_bounded_memory` |
| 2 | one sender's batch stamped ahead moved the data clock from 78 s to 3,048 s | the data clock is the `fusion.clock_quorum`-th latest node's time; runaway readings refused as `future` | `tests/service/test_service_node.py::test_one_node_stamping_ahead_cannot_drag_the_data_clock`, `..._follows_the_heard_nodes_when_others_are_quiet` |
| 3 | forged UDP frames from one sender: 27,453 of 60,000 legitimate readings accepted, loss not in /health | a source failing authentication `limits.auth_failure_burst` times is dropped before its HMAC is computed (HTTP: 429); `/health`: `dropped_unauthenticated`, `rate_limited`, `udp_dropped` | `tests/service/test_service_auth.py::test_a_forged_flood_...`, `..._get_429_...`, `..._kernel_drops_...`; the flood run below |
| 4 | damaged, foreign or locked logs gave raw tracebacks; another config resumed silently | a ConfigError naming the log and the way out; the config fingerprint; `fusetrack log check`, `log recover`; `log.durability: full` | `tests/service/test_service_node.py::test_damaged_foreign_and_directory_logs_...`, `tests/service/test_service_log_repair.py` |
| 5 | strings accepted as numbers, `bearer` refused, 16 MB WebSocket buffering, unlimited subscribers, no TLS or read protection, Ctrl-C traceback | strict schema, case-insensitive scheme, `ws_max_size`, `limits.max_subscribers`, `--tls-cert/--tls-key`, `readers`, exit 130 | `tests/service/test_service_schema.py`, `test_service_node.py`, `test_service_access.py`, `tests/cli` |
| 5 | without `--log` a captured UDP frame was accepted again after a restart | UDP frame version 2 carries its send time under the HMAC; a node without a log refuses frames sent before it started (`stale`) and version-1 frames (`legacy_frame`); any node refuses frames older than `limits.max_frame_age` (`stale`) or ahead by more than `limits.max_clock_skew` (`clock_skew`) | `tests/service/test_service_auth.py::test_a_captured_frame_is_refused_after_a_restart_without_a_log`, `..._version_1_frames_need_a_log_...`; the restart run below |
| 6 | CLI paths failing after the work, unknown keys ignored, replay tracebacks | checked before work, refused with the valid keys | `tests/service/test_service_cli.py`, `tests/cli` |
"""


def _table(rows: list[tuple[str, Any]]) -> str:
    return "\n".join(["| | |", "|---|---|", *(f"| {k} | {v} |" for k, v in rows)])


def report(args: argparse.Namespace, got: dict[str, Any]) -> str:
    fuzz, mut, chaos, flood = got["fuzz"], got["mutations"], got["chaos"], got["flood"]
    http = got["http"]
    reasons: dict[str, int] = {}
    for run in (fuzz, mut):
        for reason, n in run["rejected"].items():
            reasons[reason] = reasons.get(reason, 0) + n
    restart = got["restart_replay"]
    replays_accepted = sum(r.get("accepted", 0) for r in restart["replayed"].values())
    replays_accepted += restart["legacy_no_log"].get("accepted", 0)
    lost = chaos["acknowledged_missing"] + flood["uncounted"]
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return f"""# Reliability of the live node

Generated by `{" ".join(["python benchmarks/reliability.py", *args.argv])}` on {got["date"]}
({os.cpu_count()} CPUs, load average {load:.1f} at the end; {
        got["seconds"]:.0f} s). The same runs, small, are
the CI suite `tests/reliability/` (under 60 s). Messages lost: **{lost}**.

## What is tested

{TESTED}
## Fuzzing: {fuzz["inputs"] + mut["inputs"] + http["inputs"]:,} generated inputs, 0 crashes

Each input went to one node (`FusionNode.ingest_payload` as posted by a node with a valid
token, or `ingest_frame` in a UDP frame: sealed with the node's key, with a forged key, or with
a flipped byte); for each, the run asserts that an outcome came back, that every refusal has
one of the node's reasons and that the accepted and refused counters grew by exactly the
outcomes. After the run the node still accepts a valid reading. Through the web application
(`POST /ingest` and `/ws/ingest`, a valid token, mutated JSON and MessagePack): never a server
error, one outcome per message in every answer, and the node counted exactly those outcomes.

{
        _table(
            [
                (
                    "hypothesis inputs (mutated messages and batches, any JSON / MessagePack value, raw bytes)",
                    f"{fuzz['inputs']:,} {fuzz['by_kind']}",
                ),
                (
                    "byte-level mutations of valid JSON / MessagePack messages and batches",
                    f"{mut['inputs']:,} {mut['by_kind']}",
                ),
                (
                    "mutations through HTTP / WebSocket: HTTP statuses; outcomes = counted",
                    f"{http['inputs']:,}: {http['statuses']}; {http['outcomes']:,} = {http['counted']:,}",
                ),
                ("accepted (node calls)", fuzz["accepted"] + mut["accepted"]),
                ("refused, by reason", ", ".join(f"{k} {v:,}" for k, v in sorted(reasons.items()))),
                (
                    "node still accepts a valid reading afterwards",
                    fuzz["still_accepts"] and mut["still_accepts"],
                ),
            ]
        )
    }

## kill -9: {chaos["kills"]} kills, {chaos["acknowledged_missing"]} acknowledged readings lost

A node (`fusetrack serve`'s `serve()`, in a forked process, durable log, data clock) fed over
HTTP `POST /ingest` in batches at up to {args.rate:g} messages/s, killed with SIGKILL after a random
0.3-1.0 s and restarted on the same log, {chaos["kills"]} times; then restarted once more.

{
        _table(
            [
                (
                    "kill moments (s after start)",
                    ", ".join(f"{m:.2f}" for m in chaos["kill_moments_s"]),
                ),
                (
                    "messages posted / achieved rate",
                    f"{chaos['sent']:,} / {chaos['send_rate']:.0f} per s",
                ),
                ("acknowledged (accepted in an answered request)", f"{chaos['acknowledged']:,}"),
                ("acknowledged but missing from the log", chaos["acknowledged_missing"]),
                ("messages in the log", f"{chaos['logged']:,}"),
                (
                    "ticks logged / resumed by the last restart",
                    f"{chaos['ticks']} / {chaos['resumed_ticks']}",
                ),
                ("replaying the log gives the published tracks", chaos["replay_equal"]),
            ]
        )
    }

## Captured frames replayed after a restart: {replays_accepted} accepted

{restart["captured"]:,} sealed UDP frames (version 2, sent 1 ms apart) were captured on their
way to two nodes, one with a durable log and one without, which accepted them; both were
restarted {restart["gap_s"]:g} s later and every captured frame was replayed into each, and a
version-1 copy of each (no send time) into the one without a log; then one fresh frame per
sensor node went to both.

{
        _table(
            [
                ("accepted before the restart (both nodes)", f"{restart['accepted_before']:,}"),
                ("replayed into the node without a log", restart["replayed"]["no log"]),
                ("replayed into the node restarted on its log", restart["replayed"]["log"]),
                ("version-1 copies into the node without a log", restart["legacy_no_log"]),
                ("fresh frames afterwards (without / with a log)", restart["fresh"]),
            ]
        )
    }

## Unauthenticated flood at {args.factor}x the legitimate rate

{flood["legitimate"]:,} legitimate UDP readings from 127.0.0.1 at up to {
        args.rate:g}/s, each followed by
{args.factor} forged frames from 127.0.0.2 (a real node's name with a wrong key, an unknown node,
garbage), into a node in this process.

{
        _table(
            [
                (
                    "legitimate readings accepted",
                    f"{flood['accepted']:,} of {flood['legitimate']:,} ({100 * flood['accepted_share']:.1f} %)",
                ),
                ("forged frames", f"{flood['forged']:,}"),
                (
                    "dropped_unauthenticated (of which rate_limited: never authenticated)",
                    f"{flood['dropped_unauthenticated']:,} ({flood['rate_limited']:,})",
                ),
                ("dropped by the kernel (udp_dropped)", flood["udp_dropped"]),
                ("datagrams not accounted for", flood["uncounted"]),
                ("seconds", f"{flood['seconds']:.1f}"),
            ]
        )
    }

## Limits

- A node without a log that restarts within `limits.max_clock_skew` seconds of stopping may
  accept once a frame sent in those last seconds (it cannot know whether it saw it; with a
  log it can).
- UDP source addresses can be forged: a flood that spoofs a sensor node's own address gets that
  node's datagrams dropped with it (counted as `rate_limited`); HTTP clients are limited only on
  failed tokens, so a valid token always passes.
- With `clock: data`, while fewer nodes than `fusion.clock_quorum` are heard (for example one
  node alone at start-up), the heard ones set the clock.
- `log.durability: normal` (the default) keeps every acknowledged message through a killed
  process (above); `full` also through a power cut, at the cost of an fsync per commit.
- The chaos run's send rate is what one Python client thread reached on this machine, not the
  node's limit (`benchmarks/SERVICE.md` measures throughput).
"""


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--examples", type=int, default=2000, help="hypothesis inputs")
    p.add_argument("--mutations", type=int, default=100_000, help="byte-level mutations")
    p.add_argument("--http", type=int, default=5000, help="mutations via HTTP / WebSocket")
    p.add_argument("--kills", type=int, default=20)
    p.add_argument("--rate", type=float, default=1000.0, help="messages/s (chaos and flood)")
    p.add_argument("--flood", type=int, default=5000, help="legitimate readings in the flood")
    p.add_argument("--captured", type=int, default=5000, help="frames replayed after restarts")
    p.add_argument("--factor", type=int, default=10, help="forged frames per legitimate one")
    p.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "RELIABILITY.md")
    args = p.parse_args()
    args.argv = sys.argv[1:]
    cfg = demo_network(KEYS)
    t0 = time.monotonic()
    got: dict[str, Any] = {"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}
    got["fuzz"] = run_fuzz(cfg, args.examples)
    got["mutations"] = run_mutations(cfg, args.mutations, seed=1)
    got["http"] = run_http_fuzz(cfg, args.http, seed=1)
    with tempfile.TemporaryDirectory() as tmp:
        got["chaos"] = run_chaos(cfg, Path(tmp), args.kills, args.rate, seed=1)
        got["restart_replay"] = run_restart_replay(cfg, args.captured, Path(tmp))
    got["flood"] = run_flood(cfg, args.flood, args.factor, args.rate)
    got["seconds"] = time.monotonic() - t0
    args.out.write_text(report(args, got))
    (ROOT / "benchmarks" / "results").mkdir(exist_ok=True)
    (ROOT / "benchmarks" / "results" / "reliability.json").write_text(json.dumps(got, indent=1))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
