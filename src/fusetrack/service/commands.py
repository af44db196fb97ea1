"""The ``fusetrack serve``, ``replay``, ``log check|recover`` and ``demo --live`` commands.

:func:`add_service_parsers` and :func:`add_live_options` extend the CLI's parser (imports stay
light); :func:`run_service_command` runs whichever of the three was asked for. What the user came
for (the dashboard address, the replay's result) is printed to stdout; progress is logged.
"""

from __future__ import annotations

import argparse
import logging
import math
import time
from pathlib import Path
from typing import Any

log = logging.getLogger(__name__)


def add_service_parsers(sub: Any) -> None:
    """The ``serve``, ``log`` and ``replay`` subcommands (``fusetrack.cli`` calls this)."""
    serve = sub.add_parser(
        "serve", help="run a live fusion node (HTTP/WebSocket, UDP; MQTT with an mqtt section)"
    )
    serve.add_argument("--config", type=Path, required=True, help="network YAML")
    serve.add_argument("--host", default="127.0.0.1", help="address to listen on")
    serve.add_argument("--port", type=int, default=8000, help="HTTP/WebSocket port")
    serve.add_argument("--udp-port", type=int, default=9000, help="UDP port (-1: no UDP)")
    serve.add_argument("--log", type=Path, default=None, help="durable log (default: config's)")
    serve.add_argument("--tls-cert", type=Path, default=None, help="TLS certificate (PEM)")
    serve.add_argument("--tls-key", type=Path, default=None, help="its private key (PEM)")

    logs = sub.add_parser("log", help="check or recover a node's durable log (SQLite)")
    what = logs.add_subparsers(dest="log_command", required=True)
    check = what.add_parser("check", help="integrity, tables, config fingerprint, counts")
    check.add_argument("file", type=Path, help="the node log")
    check.add_argument("--config", type=Path, default=None, help="network YAML: its fingerprint")
    recover = what.add_parser("recover", help="copy what reads back into a new log")
    recover.add_argument("file", type=Path, help="the damaged node log")
    recover.add_argument("--out", type=Path, required=True, help="the new log (must not exist)")

    rep = sub.add_parser("replay", help="play a scenario or a recording into a running node")
    rep.add_argument("source", help="a scenario name (demo) or a .jsonl / .sqlite recording")
    rep.add_argument("--to", required=True, help="udp://HOST:PORT or http://HOST:PORT")
    rep.add_argument("--config", type=Path, required=True, help="network YAML (nodes and keys)")
    rep.add_argument("--speed", type=float, default=1.0, help="times real time (inf: no pacing)")
    rep.add_argument("--seed", type=int, default=0, help="scenario seed")
    rep.add_argument("--duration", type=float, default=None, help="scenario seconds")
    rep.add_argument("--encoding", choices=["json", "msgpack"], default="json")
    rep.add_argument(
        "--restamp", action="store_true", help="stamp readings with the send time (wall clock)"
    )


def add_live_options(demo: argparse.ArgumentParser) -> None:
    """``fusetrack demo --live`` and its options."""
    demo.add_argument(
        "--live", action="store_true", help="start a fusion node and replay the demo into it"
    )
    demo.add_argument("--speed", type=float, default=1.0, help="--live: times real time")
    demo.add_argument("--host", default="127.0.0.1", help="--live: address to listen on")
    demo.add_argument("--port", type=int, default=8000, help="--live: HTTP port (0: any)")
    demo.add_argument("--udp-port", type=int, default=0, help="--live: UDP port (0: any)")
    demo.add_argument("--duration", type=float, default=None, help="--live: scenario seconds")
    demo.add_argument(
        "--exit-after-replay", action="store_true", help="--live: stop when the replay ends"
    )
    demo.add_argument(
        "--scenario",
        choices=["demo", "two-targets", "grid"],
        default="demo",
        help="--live: the demo's target (EKF), two targets (radar + tag, MCMCDA) or the grid "
        "tracker (beam energies, camera columns, image positions)",
    )


def run_service_command(args: argparse.Namespace) -> int:
    """Run ``serve``, ``replay`` or ``demo --live``; the caller maps FusetrackError to exit 2."""
    from .config import load_config

    if args.command == "serve":
        from .server import serve

        cfg = load_config(args.config)
        udp = None if args.udp_port < 0 else args.udp_port
        serve(cfg, args.host, args.port, udp, args.log, args.tls_cert, args.tls_key)
        return 0
    if args.command == "replay":
        return _replay(args, load_config(args.config))
    if args.command == "log":
        return _log_command(args)
    return _live_demo(args)


def _log_command(args: argparse.Namespace) -> int:
    """``fusetrack log check FILE`` (exit 1 when it finds problems) or ``log recover FILE
    --out NEW``."""
    from .config import load_config
    from .log_repair import check_log, recover_log

    if args.log_command == "check":
        cfg = load_config(args.config) if args.config is not None else None
        report = check_log(args.file, cfg)
        print("\n".join(report.lines()))
        return 0 if report.ok else 1
    got = recover_log(args.file, args.out)
    print(
        f"recovered {len(got.messages)} messages and {len(got.ticks)} ticks into {args.out}; "
        f"left out {got.dropped_messages} messages and {got.dropped_ticks} ticks"
    )
    for problem in got.problems:
        log.info("%s: %s", args.file, problem)
    return 0


def _replay(args: argparse.Namespace, cfg: Any) -> int:
    from .replay import SCENARIOS, load_recording, replay

    if args.source in SCENARIOS:
        readings = SCENARIOS[args.source](cfg, seed=args.seed, duration=args.duration).readings
    else:
        readings = load_recording(args.source)
    log.info(
        "replaying %d readings from %s to %s at %gx",
        len(readings),
        args.source,
        args.to,
        args.speed,
    )
    out = replay(
        readings,
        cfg,
        args.to,
        speed=args.speed,
        encoding=args.encoding,
        restamp=args.restamp,
    )
    print(f"sent {out['sent']} messages" + (f"; refused: {out['refused']}" if out["refused"] else ""))  # fmt: skip
    return 0


def _live_demo(args: argparse.Namespace) -> int:
    from .replay import SCENARIOS, demo_network, replay
    from .scenarios import NETWORKS
    from .server import RunningNode, build_node

    name = getattr(args, "scenario", "demo")
    cfg = demo_network() if name == "demo" else NETWORKS[name]()
    scenario = SCENARIOS[name](cfg, seed=args.seed, duration=args.duration)
    with RunningNode(build_node(cfg), args.host, args.port, args.udp_port) as running:
        assert running.udp is not None
        host, port = running.udp
        print(f"dashboard: {running.url}/", flush=True)
        log.info("replaying the %s scenario over udp://%s:%d at %gx", name, host, port, args.speed)
        out = replay(scenario.readings, cfg, f"udp://{host}:{port}", speed=args.speed)
        last = math.floor(scenario.truth_times[-1] * cfg.fusion.rate_hz + 1e-9)
        deadline = time.monotonic() + cfg.fusion.lag + (cfg.fusion.idle_flush or 0.0) + 2.0
        while running.node.aligner.last_tick < last and time.monotonic() < deadline:
            time.sleep(0.05)  # the node fuses the stream's last readings once it pauses
        state = running.node.history[-1] if running.node.history else None
        err = math.nan
        if state is not None and name == "demo":
            k = round(state.time / scenario.truth_times[1])
            err = math.dist(state.position, scenario.truth[k, :2])
        elif state is not None:  # the nearest target at the closest truth time
            k = int(abs(scenario.truth_times - state.time).argmin())
            targets = scenario.truth[k].reshape(-1, 2)
            err = min(math.dist(state.position, p) for p in targets)
        print(
            f"replay done: {out['sent']} messages sent, {running.node.aligner.last_tick} ticks, "
            f"{len(running.node.latest)} track(s); final position error {err:.2f} m",
            flush=True,
        )
        if args.exit_after_replay:
            return 0
        log.info("serving until Ctrl-C")
        try:
            while True:
                time.sleep(3600)
        except KeyboardInterrupt:
            log.info("interrupted: the node stops")
    return 0
