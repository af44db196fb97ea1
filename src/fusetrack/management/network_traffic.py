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

from ..core.errors import ConfigError, invalid

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


def simulate_traffic(cfg: NetworkConfig) -> dict[str, float]:
    """Mean end-to-end delay per round and mean delay per message kind (seconds)."""
    sim = _Sim(cfg)
    rec = cfg.record_bytes
    n_img = cfg.images_per_camera or max(1, round(10 * cfg.alpha))
    round_delays: list[float] = []

    def one_round(rnd: int) -> None:
        t0 = float(rnd)
        pending = {"routers": set(cfg.routers_with_objects)}
        finish: dict[int, float] = {}
        tracked = {
            r: sum(round(s * cfg.alpha) for s in cfg.assigned_share)
            for r in cfg.routers_with_objects
        }
        images_needed = len(cfg.camera_routers) * n_img

        def router_done(r: int, t: float, pending=pending, finish=finish, t0=t0) -> None:
            finish[r] = t
            pending["routers"].discard(r)
            if not pending["routers"]:
                round_delays.append(max(finish.values()) - t0)

        state = {r: {"acoustic": 0, "images": 0} for r in cfg.routers_with_objects}
        server = {"estimates": 0, "images": 0}

        def server_check(t: float, server=server, state=state, tracked=tracked) -> None:
            if server["estimates"] == len(state) and server["images"] == images_needed:
                for r in state:
                    sim.message(
                        "Final estimation data",
                        "srv",
                        f"R{r}",
                        rec * tracked[r],
                        t,
                        partial(router_done, r),
                    )

        def router_check(r: int, t: float, state=state, tracked=tracked, server=server) -> None:
            st = state[r]
            if cfg.protocol == "RBVC":
                if st["acoustic"] == 3 and st["images"] == images_needed:
                    sim.message(
                        "Final estimation data",
                        f"R{r}",
                        "srv",
                        rec * tracked[r],
                        t,
                        partial(router_done, r),
                    )
            elif st["acoustic"] == 3:
                st["acoustic"] = -1

                def got(te: float, server=server) -> None:
                    server["estimates"] += 1
                    server_check(te)

                sim.message(
                    "Estimation based on acoustic sensors", f"R{r}", "srv", rec * tracked[r], t, got
                )

        for r in cfg.routers_with_objects:
            for j in range(3):
                assigned = round(cfg.assigned_share[j] * cfg.alpha)

                def after_rfid(t: float, r=r, assigned=assigned) -> None:
                    def after_assign(t2: float) -> None:
                        def after_acoustic(t3: float) -> None:
                            state[r]["acoustic"] += 1
                            router_check(r, t3)

                        sim.message(
                            "Acoustic sensing data",
                            f"S{r}",
                            f"R{r}",
                            rec * max(assigned, 1),
                            t2,
                            after_acoustic,
                        )

                    sim.message(
                        "Assigned object data",
                        f"R{r}",
                        f"S{r}",
                        rec * max(assigned, 1),
                        t,
                        after_assign,
                    )

                sim.message(
                    "RFID detection data", f"S{r}", f"R{r}", rec * cfg.detected[j], t0, after_rfid
                )
        for c in cfg.camera_routers:
            for _ in range(n_img):
                if cfg.protocol == "RBVC":
                    for r in cfg.routers_with_objects:

                        def img_at_router(t: float, r=r) -> None:
                            state[r]["images"] += 1
                            router_check(r, t)

                        sim.message(
                            "Visual sensing data",
                            f"S{c}",
                            f"R{r}",
                            cfg.image_bytes,
                            t0,
                            img_at_router,
                            ack=True,
                        )
                else:

                    def img_at_server(t: float) -> None:
                        server["images"] += 1
                        server_check(t)

                    sim.message(
                        "Visual sensing data",
                        f"S{c}",
                        "srv",
                        cfg.image_bytes,
                        t0,
                        img_at_server,
                        ack=True,
                    )

    for rnd in range(cfg.rounds):
        one_round(rnd)
        sim.run()
    out = {"end_to_end": sum(round_delays) / max(len(round_delays), 1)}
    for kind, v in sim.hop_delays.items():
        out[kind] = sum(v) / len(v)
    return out
