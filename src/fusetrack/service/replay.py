"""``fusetrack replay``: play a simulated scenario or a recording into a running node, as the
separate sensor nodes would (each node signs its own messages with its own key and numbers
them with its own sequence).

Sources: a scenario name from :data:`SCENARIOS` (``demo``: the demo experiment's target, two
microphone arrays, a camera and a radio tag; ``two-targets`` and ``grid``: :mod:`.scenarios`), a recording ``.jsonl`` (one message per line, as
the schema has it; ``node`` and ``seq`` are replaced) or a node's durable log ``.sqlite``.
Destinations: ``udp://HOST:PORT`` (sealed frames, :mod:`.auth`) or ``http://HOST:PORT``
(``POST /ingest`` with each node's bearer token).
"""

from __future__ import annotations

import dataclasses
import json
import math
import secrets
import socket
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import httpx
import numpy as np

from ..core import ConfigError, invalid
from ..world import AREA, DemoScene, simulate_demo
from .auth import bearer_token, seal
from .config import NetworkConfig, parse_config
from .log import DurableLog
from .schema import (
    Encoding,
    MessageBatch,
    SensorMessage,
    encode_message,
    reading_from_vector,
)


@dataclass(frozen=True)
class Recorded:
    """One reading to send: when (source time, s), which sensor, its value."""

    time: float
    sensor: str
    value: tuple[float, ...]


@dataclass(frozen=True)
class Scenario:
    """A simulated run: the readings to send, the truth behind them and the network it needs."""

    readings: list[Recorded]
    truth_times: np.ndarray
    truth: np.ndarray  # (T, d) true states at truth_times
    network: NetworkConfig


def demo_network(keys: dict[str, str] | None = None, **fusion: Any) -> NetworkConfig:
    """The network of the demo scene's sensors (``examples/network.yaml`` is the same).

    ``keys``: node id -> key (default: fresh random keys); ``fusion``: overrides of the fusion
    section (default: 2 Hz, every reading in order, data clock, 1 s lag, start at 0).
    """
    scn = DemoScene()
    nodes = {
        "array-west": "mic_west",
        "array-east": "mic_east",
        "camera-1": "camera",
        "tag-reader": "tag",
    }
    keys = keys or {n: secrets.token_hex(16) for n in nodes}
    sensors = []
    for sid, model in scn.sensors().items():
        if sid == "tag":
            sensors.append(
                {"id": sid, "kind": "position_fix", "cov": np.asarray(model.cov).tolist()}
            )
        else:
            sensors.append(
                {
                    "id": sid,
                    "kind": "bearing",
                    "position": np.asarray(model.position).tolist(),
                    "sigma": float(model.sigma),
                    "heading": float(model.heading),
                    "fov": float(model.fov),
                }
            )
    return parse_config(
        {
            "area": list(AREA),
            "sensors": sensors,
            "nodes": [{"id": n, "key": keys[n], "sensors": [s]} for n, s in nodes.items()],
            "fusion": {
                "rate_hz": 1.0 / scn.dt,
                "alignment": "all",
                "clock": "data",
                "lag": 1.0,
                "start": 0.0,
                **fusion,
            },
            "tracker": {
                "filter": "ekf",
                "motion": {"model": "coordinated_turn_rate", "q": scn.q, "q_omega": scn.q_omega},
                "prior_mean": list(scn.prior_mean),
                "prior_std": list(scn.prior_std),
            },
        },
        "demo network",
    )


def demo_scenario(network: NetworkConfig, seed: int = 0, duration: float | None = None) -> Scenario:
    """The demo scene's simulation (:mod:`fusetrack.world.demo_scene`, one Monte Carlo run of the
    demo experiment) as readings to send."""
    scn = DemoScene()
    if duration is not None:
        scn = dataclasses.replace(scn, duration=duration)
    truth, reports = simulate_demo(scn, np.random.default_rng(seed))
    readings = [Recorded(m.time, m.sensor_id, tuple(float(v) for v in m.value)) for m in reports]
    times = np.concatenate([[0.0], scn.times])
    return Scenario(readings, times, truth, network)


def _two_targets(network: NetworkConfig, seed: int = 0, duration: float | None = None) -> Scenario:
    from .scenarios import two_targets_scenario

    return two_targets_scenario(network, seed, duration)


def _grid(network: NetworkConfig, seed: int = 0, duration: float | None = None) -> Scenario:
    from .scenarios import grid_scenario

    return grid_scenario(network, seed, duration)


SCENARIOS: dict[str, Callable[..., Scenario]] = {
    "demo": demo_scenario,
    "two-targets": _two_targets,  # for examples/network-targets.yaml (:mod:`.scenarios`)
    "grid": _grid,  # for examples/network-grid.yaml
}


def load_recording(path: str | Path) -> list[Recorded]:
    """Readings from a ``.jsonl`` recording or a node's ``.sqlite`` durable log, in time order."""
    p = Path(path)
    if p.suffix not in (".sqlite", ".db", ".jsonl"):
        raise ConfigError(invalid("recording", str(p), "a .jsonl recording or a .sqlite node log"))
    if not p.is_file():  # opening a missing .sqlite would create an empty log (issue 18)
        raise ConfigError(invalid("recording", str(p), "an existing file"))
    if p.suffix in (".sqlite", ".db"):
        log = DurableLog(p)
        msgs = [m for _, m in log.messages()]
        log.db.close()
    else:
        lines = enumerate(p.read_text().splitlines())
        msgs = [m for i, line in lines if (m := _recorded_message(p, i, line)) is not None]
    out = [Recorded(m.time, m.sensor, tuple(m.reading.vector())) for m in msgs]
    return sorted(out, key=lambda r: r.time)


def _recorded_message(path: Path, i: int, line: str) -> SensorMessage | None:
    """Line ``i`` of a ``.jsonl`` recording as a message (None for a blank line); a line that is
    not a message raises :class:`ConfigError` naming the file and the line."""
    if not line.strip():
        return None
    try:
        data = json.loads(line)
        if not isinstance(data, dict):
            raise ValueError("not a JSON object")
        data.setdefault("node", "recording")
        data.setdefault("seq", i)
        return SensorMessage.model_validate(data)
    except ValueError as err:  # json.JSONDecodeError and pydantic.ValidationError are ValueErrors
        reason = str(err).splitlines()[0]
        raise ConfigError(
            invalid(f"{path.name} line {i + 1}", line[:80], f"one sensor message ({reason})")
        ) from None


class _Senders:
    """Per-node sequence numbers and the transport to the node."""

    def __init__(self, network: NetworkConfig, to: str, encoding: Encoding) -> None:
        self.network = network
        self.keys = network.keys()
        self.owner = network.owner()
        self.kinds = {s.id: s.kind for s in network.sensors}
        # sequence numbers start at the microsecond clock: a later replay never reuses one
        base = time.time_ns() // 1000
        self.seq = dict.fromkeys(self.keys, base)
        self.encoding = encoding
        url = urlsplit(to)
        if url.scheme not in ("udp", "http", "https") or not url.hostname or not url.port:
            raise ConfigError(invalid("--to", to, "udp://HOST:PORT or http://HOST:PORT"))
        self.scheme = url.scheme
        self.address = (url.hostname, url.port)
        self.udp: socket.socket | None = None
        self.http: httpx.Client | None = None
        if self.scheme == "udp":
            family = socket.AF_INET6 if ":" in url.hostname else socket.AF_INET
            self.udp = socket.socket(family, socket.SOCK_DGRAM)
        else:
            self.http = httpx.Client(base_url=f"{url.scheme}://{url.netloc}", timeout=10.0)
        self.sent = 0
        self.refused: dict[str, int] = {}

    def message(self, r: Recorded, stamp: float) -> SensorMessage:
        node = self.owner.get(r.sensor)
        if node is None:
            raise ConfigError(invalid("sensor", r.sensor, f"one of {sorted(self.owner)}"))
        self.seq[node] += 1
        reading = reading_from_vector(self.kinds[r.sensor], r.value)
        return SensorMessage(
            node=node, seq=self.seq[node], sensor=r.sensor, time=stamp, reading=reading
        )

    def send(self, messages: Sequence[SensorMessage]) -> None:
        by_node: dict[str, list[SensorMessage]] = {}
        for m in messages:
            by_node.setdefault(m.node, []).append(m)
        for node, ms in by_node.items():
            if self.udp is not None:
                for m in ms:
                    frame = seal(
                        node, self.keys[node], encode_message(m, self.encoding), self.encoding
                    )
                    self.udp.sendto(frame, self.address)
            else:
                assert self.http is not None
                body = encode_message(MessageBatch(messages=ms), self.encoding)
                ctype = "application/msgpack" if self.encoding == "msgpack" else "application/json"
                headers = {
                    "Authorization": f"Bearer {bearer_token(self.keys[node])}",
                    "Content-Type": ctype,
                }
                for attempt in range(20):
                    resp = self._post(body, headers)
                    if resp.status_code != 503:
                        break
                    time.sleep(min(1.0, 0.05 * 2**attempt))  # back-pressure: wait and retry
                if resp.status_code in (200, 503):
                    for res in resp.json().get("results", []):
                        if not res["accepted"]:
                            self.refused[res["reason"]] = self.refused.get(res["reason"], 0) + 1
                else:
                    self.refused[f"http_{resp.status_code}"] = self.refused.get(
                        f"http_{resp.status_code}", 0
                    ) + len(ms)
            self.sent += len(ms)

    def _post(self, body: bytes, headers: dict[str, str]) -> httpx.Response:
        assert self.http is not None
        try:
            return self.http.post("/ingest", content=body, headers=headers)
        except httpx.TransportError as err:
            raise ConfigError(
                invalid("--to", str(self.http.base_url), f"a running fusetrack node ({err})")
            ) from None

    def close(self) -> None:
        if self.udp is not None:
            self.udp.close()
        if self.http is not None:
            self.http.close()


def replay(
    readings: Sequence[Recorded],
    network: NetworkConfig,
    to: str,
    *,
    speed: float = 1.0,
    encoding: Encoding = "json",
    restamp: bool = False,
    progress: Callable[[float], None] | None = None,
) -> dict[str, Any]:
    """Send ``readings`` to the node at ``to``, paced at ``speed`` times real time
    (``inf``: as fast as possible). Readings at the same time go out together.
    ``restamp``: stamp each with the wall time it is sent (for nodes on the ``wall`` clock).
    Returns how many were sent and, over HTTP, how many the node refused and why."""
    if not speed > 0:
        raise ConfigError(invalid("speed", speed, "a number > 0 (inf: as fast as possible)"))
    if encoding not in ("json", "msgpack"):
        raise ConfigError(invalid("encoding", encoding, "'json' or 'msgpack'"))
    senders = _Senders(network, to, encoding)
    ordered = sorted(readings, key=lambda r: r.time)
    t_first = ordered[0].time if ordered else 0.0
    wall0 = time.monotonic()
    i = 0
    try:
        while i < len(ordered):
            t = ordered[i].time
            group = []
            while i < len(ordered) and abs(ordered[i].time - t) <= 1e-9:
                group.append(ordered[i])
                i += 1
            if math.isfinite(speed):
                delay = wall0 + (t - t_first) / speed - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
            stamp_now = time.time()
            senders.send([senders.message(r, stamp_now if restamp else r.time) for r in group])
            if progress is not None:
                progress(t)
    finally:
        senders.close()
    return {"sent": senders.sent, "refused": senders.refused}
