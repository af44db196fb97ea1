"""Network traffic of router-based vs server-based visual compensation (Lee 2009, Sec. 5.2.3).

A discrete-event, packet-level model of the dissertation's NS-2 study (no link-layer parameters
are given there; the values below are the spec's choices). Five mesh routers form a string
``R1 - R2 - R3 - R4 - R5 - server``; each router serves three fusion sensor nodes (RFID reader +
acoustic sensor) over its own local channel, and a camera may hang off a router. Each channel
(local or backbone hop) carries one packet at a time, first come first served, at ``rate`` bit/s
with a fixed per-packet overhead. Images travel as packets with one ACK each, stop-and-wait.

Per round (one second) and per router with objects, both protocols do

1. RFID detection data, sensor -> router (the objects each reader detects);
2. assigned-object data, router -> sensor;
3. acoustic sensing data, sensor -> router (the particle filter runs in the router);

then

* RBVC (Fig. 5-42): every camera sends its images to every router with objects; a router that has
  all images fuses and sends its final estimation to the server;
* SBVC (Fig. 5-43): each router sends its acoustic estimation to the server, the cameras send
  their images to the server, and the server sends the final estimation back to each router.

The round's end-to-end delay is the time until the last router has its final estimation
(RBVC: delivered to the server; SBVC: received back from the server).
"""

from __future__ import annotations

import heapq
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial

from ..core import ConfigError, invalid

PROTOCOLS = ("RBVC", "SBVC")


@dataclass(frozen=True)
class NetworkConfig:
    protocol: str = "RBVC"
    routers_with_objects: tuple[int, ...] = (1,)
    camera_routers: tuple[int, ...] = (2, 4)
    alpha: float = 0.1  # fraction of detected objects assigned to acoustic tracking
    image_bytes: int = 40_000
    detected: tuple[int, int, int] = (30, 40, 50)
    assigned_share: tuple[int, int, int] = (30, 30, 40)
    rate: float = 11e6  # bit/s per channel
    overhead: float = 0.5e-3  # s per packet (MAC/PHY)
    packet_bytes: int = 1000
    ack_bytes: int = 40
    record_bytes: int = 16  # per object in RFID / assignment / bearing / estimate messages
    images_per_camera: int | None = None  # default: max(1, round(10 alpha)) per round
    rounds: int = 20
    n_routers: int = 5

    def __post_init__(self) -> None:
        if self.protocol not in PROTOCOLS:
            raise ConfigError(invalid("protocol", self.protocol, f"one of {PROTOCOLS}"))
        routers = set(range(1, self.n_routers + 1))
        for name, vals in (
            ("routers_with_objects", self.routers_with_objects),
            ("camera_routers", self.camera_routers),
        ):
            if not set(vals) <= routers:
                raise ConfigError(invalid(name, vals, f"routers in 1..{self.n_routers}"))
        if not 0 < self.alpha <= 1:
            raise ConfigError(invalid("alpha", self.alpha, "in (0, 1]"))
        if self.image_bytes <= 0 or self.rate <= 0:
            raise ConfigError(invalid("image_bytes/rate", (self.image_bytes, self.rate), "> 0"))


@dataclass
class _Sim:
    cfg: NetworkConfig
    now: float = 0.0
    free: dict[str, float] = field(default_factory=dict)
    events: list = field(default_factory=list)
    seq: itertools.count = field(default_factory=itertools.count)
    hop_delays: dict[str, list[float]] = field(default_factory=dict)

    def path(self, a: str, b: str) -> list[str]:
        """Channels from node a to node b (nodes: 'S<r>' sensor group of router r, 'R<r>', 'srv')."""

        def pos(n: str) -> int:
            return self.cfg.n_routers + 1 if n == "srv" else int(n[1:])

        chans = []
        if a.startswith("S"):
            chans.append(f"L{a[1:]}")
            a = f"R{a[1:]}"
        tail = []
        if b.startswith("S"):
            tail.append(f"L{b[1:]}")
            b = f"R{b[1:]}"
        pa, pb = pos(a), pos(b)
        step = 1 if pb > pa else -1
        for i in range(pa, pb, step):
            lo = min(i, i + step)
            chans.append(f"B{lo}")  # backbone hop between router lo and lo + 1 (or the server)
        return chans + tail

    def at(self, t: float, fn: Callable[[float], None]) -> None:
        heapq.heappush(self.events, (t, next(self.seq), fn))

    def transmit(
        self, chans: list[str], nbytes: int, t: float, done: Callable[[float], None]
    ) -> None:
        """Send one packet hop by hop; ``done(t_arrival)`` at the far end."""
        if not chans:
            self.at(t, done)
            return
        ch = chans[0]
        start = max(t, self.free.get(ch, 0.0))
        end = start + self.cfg.overhead + 8 * nbytes / self.cfg.rate
        self.free[ch] = end
        self.at(end, lambda te: self.transmit(chans[1:], nbytes, te, done))

    def message(
        self,
        kind: str,
        a: str,
        b: str,
        nbytes: int,
        t: float,
        done: Callable[[float], None],
        ack: bool = False,
    ) -> None:
        """A message of ``nbytes`` as packets; with ``ack`` stop-and-wait, one ACK per packet."""
        n = max(1, math.ceil(nbytes / self.cfg.packet_bytes))
        fwd, back = self.path(a, b), self.path(b, a)
        t0 = t

        def send(k: int, ts: float) -> None:
            size = min(self.cfg.packet_bytes, nbytes - k * self.cfg.packet_bytes)

            def arrived(ta: float) -> None:
                self.hop_delays.setdefault(kind, []).append(ta - ts)
                if k + 1 == n and not ack:
                    done(ta)
                elif ack:

                    def acked(tb: float) -> None:
                        self.hop_delays.setdefault(kind + " ACK", []).append(tb - ta)
                        if k + 1 == n:
                            self.hop_delays.setdefault("sum of " + kind, []).append(tb - t0)
                            done(tb)
                        else:
                            send(k + 1, tb)

                    self.transmit(back, self.cfg.ack_bytes, ta, acked)

            self.transmit(fwd, max(size, 1), ts, arrived)
            if not ack and k + 1 < n:
                send(k + 1, ts)

        send(0, t)

    def run(self) -> None:
        while self.events:
            t, _, fn = heapq.heappop(self.events)
            self.now = t
            fn(t)


class _Round:
    """One round's message exchange (module docstring, steps 1-3 then RBVC or SBVC); appends
    the round's end-to-end delay to ``delays`` when the last router has its final estimation."""

    def __init__(
        self, sim: _Sim, cfg: NetworkConfig, rnd: int, n_img: int, delays: list[float]
    ) -> None:
        self.sim, self.cfg, self.n_img, self.delays = sim, cfg, n_img, delays
        self.rec = cfg.record_bytes
        self.t0 = float(rnd)
        self.pending = set(cfg.routers_with_objects)
        self.finish: dict[int, float] = {}
        self.tracked = {
            r: sum(round(s * cfg.alpha) for s in cfg.assigned_share)
            for r in cfg.routers_with_objects
        }
        self.images_needed = len(cfg.camera_routers) * n_img
        self.state = {r: {"acoustic": 0, "images": 0} for r in cfg.routers_with_objects}
        self.server = {"estimates": 0, "images": 0}

    def start(self) -> None:
        """Schedule the round's first messages: RFID detections, then the cameras' images."""
        for r in self.cfg.routers_with_objects:
            for j in range(3):
                self._sense(r, j)
        for c in self.cfg.camera_routers:
            for _ in range(self.n_img):
                if self.cfg.protocol == "RBVC":
                    for r in self.cfg.routers_with_objects:
                        self.sim.message(
                            "Visual sensing data",
                            f"S{c}",
                            f"R{r}",
                            self.cfg.image_bytes,
                            self.t0,
                            partial(self._image_at_router, r),
                            ack=True,
                        )
                else:
                    self.sim.message(
                        "Visual sensing data",
                        f"S{c}",
                        "srv",
                        self.cfg.image_bytes,
                        self.t0,
                        self._image_at_server,
                        ack=True,
                    )

    def _sense(self, r: int, j: int) -> None:
        """Steps 1-3 for sensor node ``j`` of router ``r``: RFID, assignment, acoustic data."""
        size = self.rec * max(round(self.cfg.assigned_share[j] * self.cfg.alpha), 1)

        def after_acoustic(t3: float) -> None:
            self.state[r]["acoustic"] += 1
            self._router_check(r, t3)

        def after_assign(t2: float) -> None:
            self.sim.message("Acoustic sensing data", f"S{r}", f"R{r}", size, t2, after_acoustic)

        def after_rfid(t: float) -> None:
            self.sim.message("Assigned object data", f"R{r}", f"S{r}", size, t, after_assign)

        detected = self.rec * self.cfg.detected[j]
        self.sim.message("RFID detection data", f"S{r}", f"R{r}", detected, self.t0, after_rfid)

    def _image_at_router(self, r: int, t: float) -> None:
        self.state[r]["images"] += 1
        self._router_check(r, t)

    def _image_at_server(self, t: float) -> None:
        self.server["images"] += 1
        self._server_check(t)

    def _estimate_at_server(self, t: float) -> None:
        self.server["estimates"] += 1
        self._server_check(t)

    def _router_done(self, r: int, t: float) -> None:
        self.finish[r] = t
        self.pending.discard(r)
        if not self.pending:
            self.delays.append(max(self.finish.values()) - self.t0)

    def _server_check(self, t: float) -> None:
        """SBVC: with every estimate and image in, the server sends each router its final estimation."""
        if (
            self.server["estimates"] == len(self.state)
            and self.server["images"] == self.images_needed
        ):
            for r in self.state:
                self.sim.message(
                    "Final estimation data",
                    "srv",
                    f"R{r}",
                    self.rec * self.tracked[r],
                    t,
                    partial(self._router_done, r),
                )

    def _router_check(self, r: int, t: float) -> None:
        """RBVC: with all acoustic data and images in, the router sends its final estimation;
        SBVC: with all acoustic data in, it sends its acoustic estimation to the server."""
        st = self.state[r]
        size = self.rec * self.tracked[r]
        if self.cfg.protocol == "RBVC":
            if st["acoustic"] == 3 and st["images"] == self.images_needed:
                self.sim.message(
                    "Final estimation data", f"R{r}", "srv", size, t, partial(self._router_done, r)
                )
        elif st["acoustic"] == 3:
            st["acoustic"] = -1
            self.sim.message(
                "Estimation based on acoustic sensors",
                f"R{r}",
                "srv",
                size,
                t,
                self._estimate_at_server,
            )


def simulate_traffic(cfg: NetworkConfig) -> dict[str, float]:
    """Mean end-to-end delay per round and mean delay per message kind (seconds)."""
    sim = _Sim(cfg)
    n_img = cfg.images_per_camera or max(1, round(10 * cfg.alpha))
    round_delays: list[float] = []
    for rnd in range(cfg.rounds):
        _Round(sim, cfg, rnd, n_img, round_delays).start()
        sim.run()
    out = {"end_to_end": sum(round_delays) / max(len(round_delays), 1)}
    for kind, v in sim.hop_delays.items():
        out[kind] = sum(v) / len(v)
    return out
