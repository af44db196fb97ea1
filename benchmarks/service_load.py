"""Load and fault test of the live fusion node, on loopback only; stops by itself.

    python benchmarks/service_load.py                       # 100 nodes x 10 msg/s, 4 Hz, 10 min
    python benchmarks/service_load.py --duration 60 --faults --out benchmarks/service_faults.json

A node (``fusetrack serve``, its own process, wall clock) fuses bearings from ``--nodes`` sensor
nodes placed on a ring around a target that circles inside it; each node sends ``--rate`` signed
UDP messages per second, stamped with its own clock. A reader on ``/ws/tracks`` records when each
tick arrives. Measured:

* **loss**: messages sent vs accepted + refused by the node (``/health``); with ``--faults`` the
  packets the senders dropped on purpose are not counted as sent;
* **tick latency**: arrival of the tick at the WebSocket reader minus the moment it fell due
  (window end + lag), p50 / p99 / max;
* **memory**: the node process's resident set size every 5 s (first, last, max);
* **tracking**: position RMSE of the published ticks against the true circle.

``--faults`` adds: 20 % of UDP packets dropped; nodes 0-9 silent from 20 % to 35 % of the run
(then back); node 10's clock 30 s fast from 40 % to 50 % (refused as ``future``); node 11's clock
5 s slow from 60 % to 70 % (refused as ``late``). The report says whether ``/health`` saw each.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import signal
import socket
import sqlite3
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import httpx
import msgpack
import numpy as np
import yaml
from websockets.sync.client import connect

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results
from fusetrack.service.auth import seal

CENTRE, RADIUS, RING, PERIOD = (50.0, 50.0), 25.0, 60.0, 60.0
SIGMA = math.radians(2.0)


_RUN = _results.Run()  # replaced when main() starts a run


def truth(t: float) -> np.ndarray:
    a = 2 * math.pi * t / PERIOD
    return np.array([CENTRE[0] + RADIUS * math.cos(a), CENTRE[1] + RADIUS * math.sin(a)])


def free_port(kind: int) -> int:
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def network(n: int, fusion_hz: float, alignment: str = "all") -> dict:
    sensors, nodes = [], []
    for i in range(n):
        a = 2 * math.pi * i / n
        pos = [CENTRE[0] + RING * math.cos(a), CENTRE[1] + RING * math.sin(a)]
        sensors.append({"id": f"s{i}", "kind": "bearing", "position": pos, "sigma": SIGMA})
        nodes.append({"id": f"n{i}", "key": f"load-test-key-{i:06d}-abcdef", "sensors": [f"s{i}"]})
    v = 2 * math.pi * RADIUS / PERIOD
    return {
        "area": [0, 100, 0, 100],
        "sensors": sensors,
        "nodes": nodes,
        "fusion": {
            "rate_hz": fusion_hz,
            "alignment": alignment,
            "clock": "wall",
            "lag": 0.2,
            "max_future": 10.0,
        },
        "tracker": {
            "filter": "ekf",
            "motion": {"model": "constant_velocity", "q": 1.0},
            "prior_mean": [CENTRE[0] + RADIUS, CENTRE[1], 0.0, v],
            "prior_std": [5.0, 5.0, 2.0, 2.0],
        },
        "limits": {"buffer_size": 1024},
    }


def cpu_seconds(pid: int) -> float:
    """User + system CPU seconds of a process so far (from /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return math.nan


def _num(v: float | None) -> str:
    return "–" if v is None else f"{v:.0f}"


def _share(v: float | None) -> str:
    return "–" if v is None else f"{v:.2f}"


def write_report(results: list[Path], out: Path) -> None:
    """A markdown table of result files (``--report``): the numbers as measured."""
    rows = []
    for path in results:
        r = json.loads(path.read_text())
        lat, mem = r["tick_latency_ms"], r["memory_mb"]
        faults = r.get("faults_seen")
        rows.append(
            f"| {path.name} | {r['nodes']} x {r['rate_per_node']:g}/s, {r['fusion_hz']:g} Hz, "
            f"{r['alignment']}, {r['duration_s']:g} s{' + faults' if r['faults'] else ''} "
            f"| {r['sent']} | {r['accepted']} | {r['accepted'] / r['duration_s']:.0f} "
            f"| {sum(r['refused'].values())} | {r['lost']} "
            f"| {r['ticks']} / {r['ticks_expected']} | {r['tick_compute_ms_mean']:.0f} "
            f"| {_num(r.get('node_cpu_ms_per_tick'))} "
            f"| {_share(r.get('node_cpu_share'))} / {_share(r.get('generator_cpu_share'))} "
            f"| {lat['p50']:.0f} / {lat['p99']:.0f} / {lat['max']:.0f} "
            f"| {mem['first']:.0f} → {mem['last']:.0f} (max {mem['max']:.0f}) "
            f"| {r['position_rmse_m']:.2f} | {r['node_catch_up_after_last_send_s']:.1f} "
            f"| {r['load_average'][0]:.1f} |"
        )
        if faults:
            rows[-1] += (
                f" silent during outage {faults['silent_sensors_during_disconnect_max']}, after "
                f"{faults['silent_sensors_after_return_max']}; future {faults['future_refused']}"
                f"/{faults['messages_of_jumped_clocks']['ahead']}, late {faults['late_refused']}"
                f"/{faults['messages_of_jumped_clocks']['back']}; sender dropped "
                f"{r['dropped_by_sender']} |"
            )
        else:
            rows[-1] += " |"
    head = (
        "| run | load | sent | accepted | accepted/s | refused | lost | ticks / due "
        "| tick compute (ms, mean) | node CPU per tick (ms, all work) "
        "| CPU share: node / generator "
        "| tick latency p50 / p99 / max (ms) | node RSS (MiB) | position RMSE (m) "
        "| catch-up after last send (s) | load avg (1 min) | faults seen |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
    )
    out.write_text(
        "# Fusion node under load (written by `benchmarks/service_load.py --report`)\n\n"
        "Loopback only; sender, node and WebSocket reader on this machine (2 cores shared with "
        "other jobs: see the load average column). Latency: a tick's arrival at a WebSocket reader "
        "minus the moment it fell due (window end + lag).\n\n" + head + "\n".join(rows) + "\n"
    )


def main() -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--nodes", type=int, default=100)
    ap.add_argument("--rate", type=float, default=10.0, help="messages per second per node")
    ap.add_argument("--fusion-hz", type=float, default=4.0)
    ap.add_argument("--duration", type=float, default=600.0, help="seconds of sending")
    ap.add_argument("--alignment", choices=["all", "closest"], default="all")
    ap.add_argument("--faults", action="store_true")
    ap.add_argument(
        "--batch", type=int, default=1, help="readings per UDP frame per node (a MessageBatch)"
    )
    ap.add_argument("--log", action="store_true", help="the node keeps a durable log")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=None, help="JSON results file")
    ap.add_argument(
        "--report", type=Path, nargs="+", default=None, help="result JSON files: write --md"
    )
    ap.add_argument("--md", type=Path, default=Path("benchmarks/SERVICE.md"))
    args = ap.parse_args()
    if args.report:
        write_report(args.report, args.md)
        return 0
    global _RUN
    _RUN = _results.Run()  # the run starts now (date, load average at the start)
    rng = np.random.default_rng(args.seed)

    tmp = Path(tempfile.mkdtemp(prefix="fusetrack-load-"))
    cfg = network(args.nodes, args.fusion_hz, args.alignment)
    if args.log:
        cfg["log"] = str(tmp / "node.sqlite")
    (tmp / "net.yaml").write_text(yaml.safe_dump(cfg))
    http_port, udp_port = free_port(socket.SOCK_STREAM), free_port(socket.SOCK_DGRAM)
    node = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "fusetrack.cli",
            "serve",
            "--config",
            str(tmp / "net.yaml"),
            "--port",
            str(http_port),
            "--udp-port",
            str(udp_port),
        ],
        stdout=subprocess.DEVNULL,
    )
    url = f"http://127.0.0.1:{http_port}"
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(1))  # so the node is stopped too
    try:
        for _ in range(1200):
            try:
                httpx.get(url + "/health", timeout=1.0)
                break
            except httpx.HTTPError:
                time.sleep(0.1)
        else:
            raise SystemExit("the node did not start")
        return run(args, cfg, node, url, udp_port, rng)
    finally:
        node.terminate()
        node.wait(timeout=30)


def run(args, cfg, node, url, udp_port, rng) -> int:
    lag, period = cfg["fusion"]["lag"], 1.0 / args.fusion_hz
    ticks: list[tuple[float, float, list[float]]] = []  # (tick time, arrival, position)
    reconnects: list[str] = []
    stop = threading.Event()

    def reader() -> None:
        # no keepalive pings on loopback: a busy machine must not close the reader
        while not stop.is_set():
            try:
                with connect(url.replace("http", "ws") + "/ws/tracks", ping_interval=None) as ws:
                    ws.recv(timeout=30)
                    while not stop.is_set():
                        try:
                            frame = json.loads(ws.recv(timeout=1.0))
                        except TimeoutError:
                            continue
                        track = frame["track"]
                        ticks.append((track["time"], time.time(), track["position"]))
            except Exception as err:  # reconnect, and say so
                reconnects.append(repr(err))

    memory: list[tuple[float, float]] = []
    health_log: list[dict] = []

    def monitor() -> None:
        while not stop.is_set():
            memory.append((time.time(), rss_mb(node.pid)))
            try:
                health_log.append(
                    {"t": time.time(), **httpx.get(url + "/health", timeout=5).json()}
                )
            except httpx.HTTPError:
                pass
            stop.wait(5.0 if not args.faults else 1.0)

    threads = [
        threading.Thread(target=reader, daemon=True),
        threading.Thread(target=monitor, daemon=True),
    ]
    for t in threads:
        t.start()
    time.sleep(1.0)

    keys = [n["key"].encode() for n in cfg["nodes"]]
    names = [(f"n{i}", f"s{i}") for i in range(args.nodes)]
    positions = np.array([s["position"] for s in cfg["sensors"]])
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4 * 2**20)
    seq = [0] * args.nodes
    pending: list[list[dict]] = [[] for _ in range(args.nodes)]  # --batch: readings not yet sent
    sent = dropped = frames = 0
    jumped = {"ahead": 0, "back": 0}
    behind = 0.0
    t_start = time.time()
    cpu_start = cpu_seconds(node.pid)
    gen_cpu_start = time.process_time()  # this process: sender, reader and monitor threads
    interval = 1.0 / args.rate
    k = 0
    while True:
        slot = t_start + k * interval
        now = time.time()
        if slot - t_start >= args.duration:
            break
        if slot > now:
            time.sleep(slot - now)
        stamp0 = time.time()
        behind = max(behind, stamp0 - slot)
        frac = (slot - t_start) / args.duration
        # every node's bearing of this slot at once (the sender must cost little: it shares
        # the machine with the node it measures)
        d = truth(stamp0 - t_start) - positions
        z = np.arctan2(d[:, 1], d[:, 0]) + SIGMA * rng.standard_normal(args.nodes)
        z = (z + math.pi) % (2 * math.pi) - math.pi
        drop = rng.random(args.nodes) < 0.2 if args.faults else None
        for i in range(args.nodes):
            stamp = time.time()  # each node's own clock reading: no two readings share a time
            if args.faults:
                if i < 10 and 0.20 <= frac < 0.35:
                    continue  # disconnected
                if i == 10 and 0.40 <= frac < 0.50:
                    stamp += 30.0  # clock jumped ahead
                    jumped["ahead"] += 1
                if i == 11 and 0.60 <= frac < 0.70:
                    stamp -= 5.0  # clock jumped back
                    jumped["back"] += 1
            seq[i] += 1
            node_id, sensor = names[i]
            # what encode_message(SensorMessage(...), "msgpack") writes, without the model
            m = {"version": 1, "node": node_id, "seq": seq[i], "sensor": sensor, "time": stamp,
                 "reading": {"kind": "bearing", "bearing": float(z[i])}}  # fmt: skip
            if drop is not None and drop[i]:
                dropped += 1
                continue
            pending[i].append(m)
            if len(pending[i]) < args.batch:
                continue
            body = pending[i][0] if args.batch == 1 else {"version": 1, "messages": pending[i]}
            frame = seal(node_id, keys[i], msgpack.packb(body, use_bin_type=True), "msgpack")
            sock.sendto(frame, ("127.0.0.1", udp_port))
            sent += len(pending[i])
            frames += 1
            pending[i] = []
        k += 1
    t_sent = time.time()
    gen_cpu = time.process_time() - gen_cpu_start
    expected_last = math.floor((t_sent - lag) / period) * period
    while time.time() - t_sent < 300 and (not ticks or ticks[-1][0] < expected_last - 1e-6):
        time.sleep(0.1)  # the node catches up with what was sent
    catch_up = time.time() - t_sent
    node_cpu = cpu_seconds(node.pid) - cpu_start
    stop.set()
    for t in threads:
        t.join(timeout=10)
    final = httpx.get(url + "/health", timeout=60).json()
    metrics = httpx.get(url + "/metrics", timeout=60).text
    tick_sum = float(re.search(r"^fusetrack_tick_seconds_sum ([\d.e+-]+)", metrics, re.M).group(1))
    tick_count = float(
        re.search(r"^fusetrack_tick_seconds_count ([\d.e+-]+)", metrics, re.M).group(1)
    )

    # tick time is relative to the node's wall grid; truth is a function of wall time
    # a tick falls due when its window has closed and the lag has passed (see alignment.py)
    window = period / 2 if args.alignment == "closest" else 0.0
    lat = np.array([arr - (tt + window + lag) for tt, arr, _ in ticks])
    tt_arr = np.array([tt for tt, _, _ in ticks])
    err = np.array(
        [
            np.linalg.norm(np.array(pos) - truth(tt - t_start))
            for tt, _, pos in ticks
            if tt > t_start + 5
        ]
    )
    refused = sum(final["rejected"].values())
    logged = None
    if args.log:  # every accepted reading is in the log once a tick has committed it
        time.sleep(2 * period)
        with sqlite3.connect(cfg["log"]) as db:
            logged = db.execute("SELECT count(*) FROM messages").fetchone()[0]
    mem = np.array([m for _, m in memory])
    result = {
        "nodes": args.nodes,
        "rate_per_node": args.rate,
        "fusion_hz": args.fusion_hz,
        "duration_s": args.duration,
        "faults": args.faults,
        "sent": sent,
        "dropped_by_sender": dropped,
        "accepted": final["accepted"],
        "refused": final["rejected"],
        "lost": sent - final["accepted"] - refused,
        "logged": logged,
        "accepted_not_logged": None if logged is None else final["accepted"] - logged,
        "sender_max_behind_s": behind,
        "node_catch_up_after_last_send_s": catch_up,
        "ticks": len(ticks),
        "reader_reconnects": len(reconnects),
        "alignment": args.alignment,
        "ticks_expected": round(args.duration * args.fusion_hz),
        "tick_compute_ms_mean": 1e3 * tick_sum / max(tick_count, 1.0),
        "node_cpu_share": node_cpu / (time.time() - t_start),
        "generator_cpu_share": gen_cpu / (t_sent - t_start),
        "offered_per_s": args.nodes * args.rate,
        "accepted_per_s": final["accepted"] / args.duration,
        "readings_per_frame": args.batch,
        "frames_sent": frames,
        "udp_dropped_by_kernel": final.get("udp_dropped"),
        "node_cpu_ms_per_tick": 1e3 * node_cpu / max(len(ticks), 1),
        "tick_latency_ms": {
            "p50": float(np.percentile(lat, 50) * 1e3),
            "p99": float(np.percentile(lat, 99) * 1e3),
            "max": float(lat.max() * 1e3),
        },
        "memory_mb": {"first": float(mem[0]), "last": float(mem[-1]), "max": float(mem.max())},
        "memory_mb_samples": [[round(t - t_start, 1), round(m, 1)] for t, m in memory],
        "tick_latency_ms_by_minute_p99": [
            float(
                np.percentile(
                    lat[(tt_arr >= t_start + 60 * i) & (tt_arr < t_start + 60 * (i + 1))], 99
                )
                * 1e3
            )
            for i in range(math.ceil(args.duration / 60))
            if np.any((tt_arr >= t_start + 60 * i) & (tt_arr < t_start + 60 * (i + 1)))
        ],
        "position_rmse_m": float(np.sqrt(np.mean(err**2))),
        "position_max_err_m": float(err.max()),
        "load_average": os.getloadavg(),
    }
    if args.faults:

        def silent(lo: float, hi: float) -> list[int]:
            a, b = t_start + lo * args.duration, t_start + hi * args.duration
            return [len(h["silent_sensors"]) for h in health_log if a <= h["t"] < b]

        # silent_after is 5 s: nodes 0-9 are reported from 5 s into their absence
        result["faults_seen"] = {
            "silent_sensors_during_disconnect_max": max(silent(0.20, 0.35), default=None),
            "silent_sensors_after_return_max": max(silent(0.45, 0.95), default=None),
            "future_refused": final["rejected"].get("future", 0),
            "late_refused": final["rejected"].get("late", 0),
            "messages_of_jumped_clocks": jumped,
        }
    result["metadata"] = _RUN.metadata()  # date, load at start and end, machine, versions, command
    text = json.dumps(result, indent=2)
    print(text)
    if args.out is not None:
        args.out.write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
