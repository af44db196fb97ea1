"""The fusion node's state and rules, without any networking (the app and UDP listener call it).

What happens to a message (:meth:`FusionNode.ingest_frame` for UDP, :meth:`ingest_payload` for
HTTP/WebSocket after the bearer token named the node):

1. a source address that has failed authentication too often (``limits.auth_failure_burst``,
   refilled at ``auth_failures_per_second``) is dropped first, unchecked (``rate_limited``);
   then authenticated (UDP: the frame's HMAC, :mod:`.auth`; its send time must be recent and,
   on a node without a log, not before the node started: :class:`.auth.FrameFreshness`),
   size-checked, parsed and validated against the schema (:mod:`.schema`);
2. checked against the network: the message's node is the authenticated one, its sequence
   number is new (replays refused), the sensor exists, belongs to that node, is of the kind
   the message says, the value has the sensor's size, the time is not beyond the clock by more
   than ``max_future`` and not before what was already fused (late);
3. if accepted: appended to the durable log, put in its sensor's ring buffer, counted.

Every refusal has a reason and is counted (``/metrics``, ``/health``, the dashboard); nothing a
sender does raises out of the node. :meth:`advance` fires the ticks that are due, runs the
engine, logs and publishes each :class:`~.schema.TrackState`.
"""

from __future__ import annotations

import asyncio
import heapq
import itertools
import json
import math
import sqlite3
import time
from collections import Counter, deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from prometheus_client import CollectorRegistry, Gauge, Histogram, generate_latest
from prometheus_client import Counter as PromCounter

from ..core import ConfigError, invalid
from .alignment import Aligner
from .auth import (
    FailureLimiter,
    FrameFreshness,
    Rejected,
    SequenceWindow,
    node_of_token,
    open_frame,
)
from .config import FUSED_KINDS, NetworkConfig
from .engine import build_engine
from .log import DurableLog, reading_of, replay_ticks
from .schema import SchemaRejection, SensorMessage, TrackState, decode_messages

MAX_TICKS_PER_ADVANCE = 1000  # a long catch-up is done in slices, the loop stays responsive

REJECTION_REASONS: tuple[str, ...] = (
    "oversized",
    "bad_frame",
    "unknown_node",
    "bad_mac",
    "unauthorized",
    "rate_limited",
    "legacy_frame",
    "stale",
    "clock_skew",
    "unauthorized_read",
    "too_many_subscribers",
    "malformed",
    "schema",
    "node_mismatch",
    "replay",
    "unknown_sensor",
    "forbidden_sensor",
    "unfusable",
    "wrong_kind",
    "wrong_size",
    "bad_covariance",
    "future",
    "late",
    "overload",
)

UNAUTHENTICATED_REASONS: tuple[str, ...] = (
    "bad_frame",
    "unknown_node",
    "bad_mac",
    "unauthorized",
    "rate_limited",
)
"""Refusals of messages no node's key vouches for (``/health``'s ``dropped_unauthenticated``)."""


@dataclass(frozen=True)
class Outcome:
    """What became of one message: accepted, or refused with a reason."""

    accepted: bool
    reason: str = ""
    detail: str = ""
    seq: int | None = None

    def as_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {"accepted": self.accepted}
        if self.seq is not None:
            d["seq"] = self.seq
        if not self.accepted:
            d["reason"], d["detail"] = self.reason, self.detail
        return d


class _Metrics:
    """The node's Prometheus metrics (its own registry: several nodes may share a process)."""

    def __init__(self, sensors: list[str]) -> None:
        self.registry = CollectorRegistry()
        r = self.registry
        self.accepted = PromCounter(
            "fusetrack_messages_accepted", "accepted readings", ["sensor"], registry=r
        )
        self.rejected = PromCounter(
            "fusetrack_messages_rejected", "refused messages", ["reason"], registry=r
        )
        self.rejected_by = {reason: self.rejected.labels(reason) for reason in REJECTION_REASONS}
        self.ticks = PromCounter("fusetrack_ticks", "fusion ticks published", registry=r)
        self.tick_seconds = Histogram(
            "fusetrack_tick_seconds",
            "compute time of one fusion tick",
            buckets=(0.0005, 0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.25, 1.0),
            registry=r,
        )
        self.tick_delay = Histogram(
            "fusetrack_tick_delay_seconds",
            "wall time from a tick falling due to its publication (wall clock only)",
            buckets=(0.001, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 5.0),
            registry=r,
        )
        self.buffered = Gauge("fusetrack_buffered_readings", "unfused readings", registry=r)
        self.age = Gauge(
            "fusetrack_sensor_age_seconds",
            "wall seconds since a sensor's last reading",
            ["sensor"],
            registry=r,
        )
        self.subscribers = Gauge("fusetrack_ws_subscribers", "WebSocket readers", registry=r)
        # one child per sensor, looked up once (labels() costs microseconds per message)
        self.accepted_by = {s: self.accepted.labels(s) for s in sensors}


class FusionNode:
    """A fusion node (see the module docstring). Not thread-safe: call it from one event loop."""

    def __init__(
        self,
        cfg: NetworkConfig,
        *,
        wall: Callable[[], float] = time.time,
        log: DurableLog | None = None,
    ) -> None:
        self.cfg = cfg
        self.wall = wall
        self.keys = cfg.keys()
        self.tokens = cfg.tokens()
        self.read_tokens = cfg.read_tokens()
        self.owner = cfg.owner()
        self.models = cfg.sensor_models()
        self.kinds = {s.id: s.kind for s in cfg.sensors}
        self.windows = {n: SequenceWindow() for n in self.keys}
        self.limiter = FailureLimiter(
            cfg.limits.auth_failures_per_second, cfg.limits.auth_failure_burst
        )
        self.udp_dropped: Callable[[], int | None] = lambda: None  # set by the UDP listener
        self.mqtt_status: Callable[[], dict[str, Any] | None] = lambda: None  # the MQTT bridge
        self.started = wall()
        fusion = cfg.fusion
        start = fusion.start
        if fusion.clock == "wall":
            start = math.floor(self.started * fusion.rate_hz) / fusion.rate_hz
        logged = None
        if log is not None:
            log.check_config(cfg.fingerprint())
            logged = log.meta("start")
            if logged is None:
                log.set_meta("start", repr(start))
            else:
                start = float(logged)
        self.log = log
        self.freshness = FrameFreshness(  # a resumed log restores the replay windows
            None if logged is not None else self.started,
            log is not None,
            cfg.limits.max_frame_age,
            cfg.limits.max_clock_skew,
        )
        self.aligner = Aligner(
            [s.id for s in cfg.sensors],
            fusion.rate_hz,
            start,
            fusion.alignment,
            fusion.lag,
            cfg.limits.buffer_size,
        )
        self.engine = build_engine(cfg, start)
        self.single = cfg.tracker.association.method == "none"  # one track, every tick
        self.next_id = log.next_id() if log is not None else 1
        self.watermark = -math.inf  # latest accepted reading time, any node
        self.node_time: dict[str, float] = {}  # each node's latest accepted reading time
        self.node_heard: dict[str, float] = {}  # wall time of each node's latest acceptance
        self.data_time = -math.inf  # the data clock (:meth:`update_data_clock`)
        self.data_clock = fusion.clock == "data"
        self.accepted: Counter[str] = Counter()
        self.rejected: Counter[str] = Counter()
        self.last: dict[str, dict[str, Any]] = {}
        self.history: deque[TrackState] = deque(maxlen=cfg.limits.history)
        self.latest: list[TrackState] = []  # what the last tick published
        self.latest_time: float | None = None
        self.recent_accepts: deque[float] = deque(maxlen=100_000)
        self.subscribers: set[asyncio.Queue[str]] = set()
        self.metrics = _Metrics(list(self.models))
        self.resumed_ticks = 0
        self.tick_errors = 0
        self.last_tick_error = ""
        if log is not None:
            self.resume(log)

    # -- clock -------------------------------------------------------------------------------
    def clock(self) -> float:
        """The fusion clock: Unix time (``wall``) or the data clock (:meth:`update_data_clock`)."""
        return self.wall() if self.cfg.fusion.clock == "wall" else self.data_time

    def update_data_clock(self) -> None:
        """The data clock: the ``fusion.clock_quorum``-th latest of the nodes' latest reading
        times, over the nodes heard within ``fusion.silent_after`` wall seconds (all heard nodes
        when none is). No single node can drag it ahead of the others (issue 18: one batch
        stamped ahead moved fusion time from 78 s to 3,048 s and every other sensor's readings
        were then late); with fewer nodes heard than the quorum, the heard ones set it, so
        quiet nodes never stall the fusion."""
        now, quiet = self.wall(), self.cfg.fusion.silent_after
        times = [t for n, t in self.node_time.items() if now - self.node_heard[n] <= quiet]
        times = times or list(self.node_time.values())
        if times:
            q = min(self.cfg.fusion.clock_quorum, len(times))
            self.data_time = heapq.nlargest(q, times)[-1]

    # -- ingest ------------------------------------------------------------------------------
    def reject(self, reason: str, detail: str = "", seq: int | None = None) -> Outcome:
        self.rejected[reason] += 1
        counter = self.metrics.rejected_by.get(reason)  # looked up once per reason
        (counter or self.metrics.rejected.labels(reason)).inc()
        return Outcome(False, reason, detail, seq)

    def refuse_unauthenticated(self, source: object, reason: str, detail: str) -> Outcome:
        """Refuse a message that failed authentication, charged to its source address: once the
        source has spent ``limits.auth_failure_burst`` failures it is ``rate_limited``."""
        if source is None:
            return self.reject(reason, detail)
        now = self.wall()
        if self.limiter.blocked(source, now):
            return self.reject("rate_limited", f"{source} failed authentication too often")
        self.limiter.fail(source, now)
        return self.reject(reason, detail)

    def ingest_frame(self, frame: bytes, source: object = None) -> list[Outcome]:
        """A UDP datagram from ``source`` (the sender's address): a sealed frame of one message
        or a batch (:meth:`ingest_frames` of one)."""
        return self.ingest_frames([(frame, source)])

    def ingest_frames(self, frames: Sequence[tuple[bytes, object]]) -> list[Outcome]:
        """UDP datagrams ``(frame, source address)`` read together (the listener's drain): each
        is authenticated, parsed and checked in turn exactly as alone; the accepted readings are
        then logged, buffered and counted at once (:meth:`_accept_all`). A source that failed
        authentication too often is dropped before its frame's HMAC is computed (issue 18: a
        flood of forged frames starved the legitimate ones). The outcomes, in order."""
        outcomes: list[Outcome] = []
        staged: list[tuple[SensorMessage, np.ndarray]] = []
        for frame, source in frames:
            outcomes.extend(self._open_and_check(frame, source, staged))
        self._accept_all(staged)
        return outcomes

    def _open_and_check(
        self, frame: bytes, source: object, staged: list[tuple[SensorMessage, np.ndarray]]
    ) -> list[Outcome]:
        if source is not None and self.limiter.blocked(source, self.wall()):
            return [self.reject("rate_limited", f"{source} failed authentication too often")]
        if len(frame) > self.cfg.limits.max_message_bytes:
            return [self.refuse_unauthenticated(source, "oversized", f"{len(frame)} bytes")]
        try:
            node, encoding, payload, sent = open_frame(frame, self.keys)
        except Rejected as err:
            return [self.refuse_unauthenticated(source, err.reason, err.detail)]
        try:  # authentic, but perhaps captured and replayed (issue 18): refused unparsed
            self.freshness.check(sent, self.wall())
        except Rejected as err:
            return [self.reject(err.reason, err.detail)]
        return self._decode_and_check(payload, encoding, node, staged)

    def ingest_payload(self, payload: bytes, encoding: str, node: str) -> list[Outcome]:
        """An authenticated payload (``node`` is who signed it or whose token came with it): one
        message, or a batch whose messages are checked in order, each accepted or refused on
        its own (a batch that does not parse is refused whole: ``schema`` naming the message's
        index and field, e.g. ``messages.3.reading.bearing``)."""
        staged: list[tuple[SensorMessage, np.ndarray]] = []
        outcomes = self._decode_and_check(payload, encoding, node, staged)
        self._accept_all(staged)
        return outcomes

    def _decode_and_check(
        self,
        payload: bytes,
        encoding: str,
        node: str,
        staged: list[tuple[SensorMessage, np.ndarray]],
    ) -> list[Outcome]:
        if len(payload) > self.cfg.limits.max_message_bytes:
            return [self.reject("oversized", f"{len(payload)} bytes")]
        try:
            messages = decode_messages(payload, encoding)
        except SchemaRejection as err:
            return [self.reject(err.reason, err.detail)]
        return [self._check(m, node, staged) for m in messages]

    def authorize(self, header: str | None) -> str | None:
        """The node an ``Authorization: Bearer ...`` header names, or None (the scheme name is
        case-insensitive, RFC 7235 §2.1: ``bearer`` was refused, issue 18)."""
        token = _bearer(header)
        return None if token is None else node_of_token(token, self.tokens)

    def may_read(self, header: str | None, token: str | None = None) -> bool:
        """Whether a reader may read tracks, sensors, health and metrics: always, unless the
        config names ``readers``; then a reader's or a node's bearer token is needed, in the
        ``Authorization`` header or as ``token`` (``?token=``: the dashboard, browsers'
        WebSockets). A refusal is counted as ``unauthorized_read``."""
        if not self.read_tokens:
            return True
        token = token or _bearer(header)
        if token and (node_of_token(token, self.read_tokens) or node_of_token(token, self.tokens)):
            return True
        self.reject("unauthorized_read", "missing or unknown reader token")
        return False

    def ingest_message(self, m: SensorMessage, node: str) -> Outcome:
        """Check one parsed message against the network and accept or refuse it."""
        staged: list[tuple[SensorMessage, np.ndarray]] = []
        outcome = self._check(m, node, staged)
        self._accept_all(staged)
        return outcome

    def _check(
        self, m: SensorMessage, node: str, staged: list[tuple[SensorMessage, np.ndarray]]
    ) -> Outcome:
        """Check one parsed message against the network: refused (counted), or accepted and
        added to ``staged`` (with its value) for :meth:`_accept_all`."""
        seq = m.seq
        if self.aligner.pending + len(staged) >= self.cfg.limits.max_pending:
            return self.reject("overload", "too many unfused readings; retry later", seq)
        if m.node != node:
            return self.reject(
                "node_mismatch", f"message says node={m.node!r}, signed by {node!r}", seq
            )
        if not self.windows[node].accept(seq):
            return self.reject(
                "replay", f"seq={seq} from node={node!r} was seen or is too old", seq
            )
        kind = self.kinds.get(m.sensor)
        if kind is None:
            return self.reject("unknown_sensor", f"sensor={m.sensor!r} is not configured", seq)
        if self.owner[m.sensor] != node:
            return self.reject(
                "forbidden_sensor", f"sensor={m.sensor!r} is not node {node!r}'s", seq
            )
        if m.reading.kind not in FUSED_KINDS:
            return self.reject(
                "unfusable", f"kind={m.reading.kind!r}: no tracker here fuses it", seq
            )
        if m.reading.kind != kind:
            return self.reject(
                "wrong_kind", f"sensor={m.sensor!r} reports {kind!r}, got {m.reading.kind!r}", seq
            )
        value = m.value()
        dim = self.models[m.sensor].dim
        if value.shape != (dim,):
            return self.reject(
                "wrong_size",
                f"value has {value.size} entries, sensor={m.sensor!r} needs {dim}",
                seq,
            )
        if m.covariance is not None and not _valid_covariance(m.covariance, dim):
            return self.reject(
                "bad_covariance",
                f"covariance must be a {dim}x{dim} symmetric positive definite matrix",
                seq,
            )
        clock = self.clock()
        ref = clock if math.isfinite(clock) else self.aligner.fused_until
        if m.time > ref + self.cfg.fusion.max_future:
            return self.reject(
                "future",
                f"time={m.time} is more than {self.cfg.fusion.max_future} s ahead of the fusion clock ({ref:.3f})",
                seq,
            )
        if self.aligner.is_late(m.time):
            return self.reject(
                "late",
                f"time={m.time} is at or before the fused time {self.aligner.fused_until:.3f}",
                seq,
            )
        staged.append((m, value))
        if self.data_clock:  # the data clock moves with each acceptance: the next check sees it
            self._accept_all(staged)
            staged.clear()
        return Outcome(True, seq=seq)

    def _accept_all(self, staged: Sequence[tuple[SensorMessage, np.ndarray]]) -> None:
        """Accept checked messages (in order): log them (one statement), buffer their readings
        (appended to each sensor's buffer together) and count them (one metric update per
        sensor), so that the per-message cost of a drained burst is the checks alone."""
        if not staged:
            return
        now, first = self.wall(), self.next_id
        self.next_id += len(staged)
        if self.log is not None:
            self.log.append_messages(first, [m for m, _ in staged], now)
        self.aligner.push_all([reading_of(m, first + i, v) for i, (m, v) in enumerate(staged)])
        counts = Counter(m.sensor for m, _ in staged)
        self.accepted.update(counts)
        for sensor, n in counts.items():
            self.metrics.accepted_by[sensor].inc(n)
        latest: dict[str, tuple[SensorMessage, np.ndarray]] = {}
        for m, v in staged:
            latest[m.sensor] = (m, v)
            if m.time > self.node_time.get(m.node, -math.inf):
                self.node_time[m.node] = m.time
            self.node_heard[m.node] = now
            if m.time > self.watermark:
                self.watermark = m.time
        for sensor, (m, v) in latest.items():
            self.last[sensor] = {"time": m.time, "value": v.tolist(), "received": now}
        self.recent_accepts.extend(itertools.repeat(now, len(staged)))
        if self.data_clock:  # O(nodes): only the data clock needs it (1000 nodes: 0.6 ms)
            self.update_data_clock()

    def commit(self) -> None:
        if self.log is not None:
            self.log.commit()

    def until_due(self) -> float | None:
        """Wall seconds until the next tick falls due (``wall`` clock; None with the ``data``
        clock, whose ticks follow the readings)."""
        if self.cfg.fusion.clock != "wall":
            return None
        k = self.aligner.last_tick + 1
        return self.aligner.window_end(k) + self.aligner.lag - self.wall()

    def behind(self) -> int:
        """How many ticks are due but not yet fused."""
        clock = self.clock()
        return len(self.aligner.due(clock, MAX_TICKS_PER_ADVANCE)) if math.isfinite(clock) else 0

    # -- fusion ------------------------------------------------------------------------------
    def advance(self, limit: int = MAX_TICKS_PER_ADVANCE) -> list[TrackState]:
        """Fire the ticks due by the clock (at most ``limit``); log and publish each state."""
        if self.cfg.fusion.clock == "data":
            self.update_data_clock()  # a node may have fallen quiet
        clock = self.clock()
        if not math.isfinite(clock):
            return []
        idle = self.cfg.fusion.idle_flush
        if self.cfg.fusion.clock == "data" and idle is not None and self.recent_accepts:
            if self.wall() - self.recent_accepts[-1] >= idle:
                # the stream has paused: fuse what has come (every node's, at most max_future
                # ahead of the quorum clock each)
                clock = max(clock, self.watermark) + self.aligner.lag
        states = []
        for k in self.aligner.due(clock, limit):
            t0 = time.perf_counter()
            readings = self.aligner.take(k)
            t = self.aligner.tick_time(k)
            try:
                published = self.engine.step_all(k, t, readings)
            except Exception as err:  # a tick that cannot fuse its readings predicts only
                self.tick_errors += 1
                self.last_tick_error = f"tick {k}: {type(err).__name__}: {err}"
                readings = []
                published = self.engine.step_all(k, t, readings)
            self.metrics.tick_seconds.observe(time.perf_counter() - t0)
            if self.cfg.fusion.clock == "wall":
                due = self.aligner.window_end(k) + self.aligner.lag
                self.metrics.tick_delay.observe(max(0.0, self.wall() - due))
            if self.log is not None:
                self.log.append_tick(k, t, published, [r.id for r in readings], self.single)
            self.history.extend(published)
            self.latest, self.latest_time = published, t
            self.metrics.ticks.inc()
            self._publish(k, t, published)
            states.extend(published)
        if states:
            self.commit()
        return states

    def resume(self, log: DurableLog) -> None:
        """Rebuild the state from the durable log: re-run its ticks, re-buffer unfused readings,
        restore the replay windows. A log whose rows do not read back (bad JSON, a message the
        schema refuses, a tick naming a missing reading) is refused with a clear message."""
        try:
            engine, states, last = replay_ticks(self.cfg, log)
        except (ValueError, KeyError, sqlite3.Error) as err:
            reason = str(err).splitlines()[0] if str(err) else type(err).__name__
            raise ConfigError(
                invalid(
                    "log",
                    str(log.path),
                    f"a log whose rows read back ({type(err).__name__}: {reason}); move it aside "
                    f"to start a new log, or `fusetrack log recover {log.path} --out NEW` to "
                    "keep what reads back",
                )
            ) from None
        if last:
            self.engine = engine
            self.history.extend(states)
            self.aligner.last_tick = last
            self.latest = [s for s in states if s.tick == last]
            self.latest_time = self.aligner.tick_time(last)
            self.resumed_ticks = last
        fused = {i for _, _, _, ids in log.tick_rows() for i in ids}
        for node, (t, heard) in log.node_times().items():
            self.node_time[node], self.node_heard[node] = t, heard
        self.update_data_clock()
        for rid, m in log.messages():
            self.watermark = max(self.watermark, m.time)
            if rid not in fused and not self.aligner.is_late(m.time):
                self.aligner.push(reading_of(m, rid))
        for node, seq in log.highest_seq().items():
            if node in self.windows:
                self.windows[node].restore(seq)

    # -- publication -------------------------------------------------------------------------
    def subscribe(self) -> asyncio.Queue[str] | None:
        """A queue of published track messages, or None when ``limits.max_subscribers`` are
        already open (unauthenticated readers could otherwise open any number, issue 18)."""
        if len(self.subscribers) >= self.cfg.limits.max_subscribers:
            self.reject("too_many_subscribers", "limits.max_subscribers reached")
            return None
        q: asyncio.Queue[str] = asyncio.Queue(maxsize=64)
        self.subscribers.add(q)
        self.metrics.subscribers.set(len(self.subscribers))
        return q

    def unsubscribe(self, q: asyncio.Queue[str]) -> None:
        self.subscribers.discard(q)
        self.metrics.subscribers.set(len(self.subscribers))

    def _publish(self, tick: int, t: float, states: list[TrackState]) -> None:
        """One WebSocket frame per tick: ``tracks`` (all), ``track`` (the first, or null)."""
        if not self.subscribers:
            return
        tracks = [s.model_dump_json() for s in states]
        head = json.dumps({"type": "tick", "tick": tick, "time": t})[:-1]
        first = tracks[0] if tracks else "null"
        text = f'{head},"track":{first},"tracks":[{",".join(tracks)}]}}'
        for q in self.subscribers:
            if q.full():  # a slow reader loses old ticks, never slows the node
                q.get_nowait()
            q.put_nowait(text)

    # -- views -------------------------------------------------------------------------------
    def rate(self, window: float = 5.0) -> float:
        """Accepted messages per second over the last ``window`` wall seconds."""
        now, n = self.wall(), 0
        for t in reversed(self.recent_accepts):  # newest first: stop at the window's start
            if now - t > window:
                break
            n += 1
        return n / window

    def tracks_view(self, history: int = 200) -> dict[str, Any]:
        """The last tick's tracks and the recent trail (``history`` states, all tracks)."""
        trail = list(self.history)[-history:] if history > 0 else []
        return {
            "tracks": [s.model_dump() for s in self.latest],
            "history": [
                {"track": s.track, "tick": s.tick, "time": s.time, "position": s.position}
                for s in trail
            ],
        }

    def sensors_view(self) -> list[dict[str, Any]]:
        now = self.wall()
        out: list[dict[str, Any]] = []
        for s in self.cfg.sensors:
            last = self.last.get(s.id)
            shown: dict[str, Any] | None = None
            if last is not None:
                shown = {**last, "age": now - last["received"]}
                if s.kind == "detection_function":  # its largest sample's direction (world)
                    angles = s.sampling().angles
                    peak = angles[int(np.argmax(last["value"]))]
                    shown["peak_direction"] = s.heading + float(peak)
            out.append(
                {
                    "id": s.id,
                    "kind": s.kind,
                    "node": self.owner.get(s.id),
                    "position": s.position,
                    "heading": s.heading,
                    "fov": s.fov,
                    "max_range": None if math.isinf(s.max_range) else s.max_range,
                    "accepted": self.accepted[s.id],
                    "buffered": len(self.aligner.buffers[s.id]),
                    "dropped": self.aligner.buffers[s.id].dropped,
                    "last": shown,
                }
            )
        return out

    def health(self) -> dict[str, Any]:
        now = self.wall()
        silent = [
            s
            for s in self.models
            if s not in self.last or now - self.last[s]["received"] > self.cfg.fusion.silent_after
        ]
        return {
            "status": "ok" if not silent else "degraded",
            "uptime": now - self.started,
            "clock": self.cfg.fusion.clock,
            "tick": self.aligner.last_tick,
            "time": self.latest_time,
            "tracks": len(self.latest),
            "silent_sensors": silent,
            "accepted": sum(self.accepted.values()),
            "rejected": dict(self.rejected),
            "dropped_unauthenticated": sum(self.rejected[r] for r in UNAUTHENTICATED_REASONS),
            "rate_limited": self.rejected["rate_limited"],
            "udp_dropped": self.udp_dropped(),
            "mqtt": self.mqtt_status(),
            "buffered": self.aligner.pending,
            "superseded": self.aligner.superseded,
            "dropped": sum(b.dropped for b in self.aligner.buffers.values()),
            "filter_resets": self.engine.resets,
            "tick_errors": self.tick_errors,
            "last_tick_error": self.last_tick_error,
            "messages_per_second": self.rate(),
            "resumed_ticks": self.resumed_ticks,
        }

    def metrics_text(self) -> bytes:
        now = self.wall()
        for s in self.models:
            last = self.last.get(s)
            self.metrics.age.labels(s).set(math.inf if last is None else now - last["received"])
        self.metrics.buffered.set(self.aligner.pending)
        return bytes(generate_latest(self.metrics.registry))


def _bearer(header: str | None) -> str | None:
    """The token of an ``Authorization: Bearer <token>`` header (any case of the scheme)."""
    scheme, _, token = (header or "").strip().partition(" ")
    if scheme.lower() != "bearer" or not token.strip():
        return None
    return token.strip()


def _valid_covariance(c: list[list[float]], dim: int) -> bool:
    try:
        a = np.asarray(c, dtype=float)
    except ValueError:  # ragged rows
        return False
    if a.shape != (dim, dim) or not np.allclose(a, a.T):
        return False
    try:
        np.linalg.cholesky(a)
    except np.linalg.LinAlgError:
        return False
    return True
