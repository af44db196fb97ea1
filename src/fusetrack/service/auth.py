"""Authentication of sensor nodes: one secret key per node.

* **UDP**: every datagram is a sealed frame (:func:`seal`)::

      b"FT" | version (1 byte: 2) | encoding (b"j" JSON / b"m" MessagePack) | len(node) (1 byte)
      | node id (UTF-8) | send time (8 bytes: big-endian unsigned Unix microseconds)
      | HMAC-SHA256(key, everything before the tag + payload) (32 bytes) | payload

  Version 1 is the same without the send time. :func:`open_frame` checks the tag with the
  node's key *before* the payload is parsed, so an unauthenticated packet never reaches the
  parser. A forged or altered frame (its send time included) is ``bad_mac``.
* **HTTP / WebSocket writes**: ``Authorization: Bearer <token>`` where the token is derived
  from the node's key (:func:`bearer_token`), so the key itself never travels.
* **Replays**: each message carries a per-node sequence number; :class:`SequenceWindow` accepts
  a number once, tolerating reordering within a window of the last 64 (the IPsec anti-replay
  window, RFC 4303 §3.4.3), and rejects anything older. The windows live in memory: a node
  with a durable log rebuilds them on restart, a node without one cannot, so
  :class:`FrameFreshness` also refuses a UDP frame sent before the node started (it cannot
  know whether it saw it) or too long ago (issue 18: a captured frame was accepted again after
  a restart). This is the timestamp half of Kerberos' replay defence (RFC 4120 §3.2.3: an
  authenticator is accepted within a clock-skew tolerance, and a replay cache covers the rest).
* **Floods**: :class:`FailureLimiter` gives each source address a token bucket of
  authentication failures; once a source has spent it, its datagrams are dropped before their
  tag is computed (issue 18: forged frames from one sender starved the legitimate ones).
"""

from __future__ import annotations

import hashlib
import hmac
import struct
import time
from collections.abc import Hashable, Mapping
from dataclasses import dataclass, field
from typing import NamedTuple

MAGIC = b"FT"
FRAME_VERSION = 2  # what :func:`seal` writes; :func:`open_frame` reads 1 and 2
FRAME_VERSIONS = (1, 2)
TAG_SIZE = 32
_SENT = struct.Struct(">Q")  # send time, Unix microseconds
_ENCODING_BYTES = {"json": b"j", "msgpack": b"m"}
_ENCODING_NAMES = {v[0]: k for k, v in _ENCODING_BYTES.items()}
MIN_KEY_BYTES = 16


class Rejected(Exception):
    """A message the node refuses; ``reason`` is the counter it is counted under."""

    def __init__(self, reason: str, detail: str = "") -> None:
        super().__init__(f"{reason}: {detail}" if detail else reason)
        self.reason = reason
        self.detail = detail or reason


def bearer_token(key: bytes) -> str:
    """The HTTP/WebSocket bearer token of the node whose key is ``key`` (hex, 64 characters)."""
    return hmac.new(key, b"fusetrack bearer token v1", hashlib.sha256).hexdigest()


class Frame(NamedTuple):
    """An authentic UDP frame: who sealed it, its payload's encoding, the payload and its send
    time (Unix seconds; None in a version-1 frame, which has none)."""

    node: str
    encoding: str
    payload: bytes
    sent: float | None


def seal(
    node: str,
    key: bytes,
    payload: bytes,
    encoding: str = "json",
    *,
    sent: float | None = None,
    version: int = FRAME_VERSION,
) -> bytes:
    """A UDP frame carrying ``payload`` from ``node``, tagged with the node's key; version 2
    carries ``sent`` (Unix seconds, default now) under the tag. ``version=1`` writes the old
    frame without a send time (nodes without a log refuse it: ``legacy_frame``)."""
    name = node.encode()
    if not 0 < len(name) < 256:
        raise ValueError(f"node={node!r} is invalid: expected 1 to 255 UTF-8 bytes")
    if version not in FRAME_VERSIONS:
        raise ValueError(f"version={version!r} is invalid: expected one of {FRAME_VERSIONS}")
    head = MAGIC + bytes([version]) + _ENCODING_BYTES[encoding] + bytes([len(name)]) + name
    if version >= 2:
        stamp = time.time() if sent is None else sent
        if not 0.0 <= stamp < 2.0**64 / 1e6:
            raise ValueError(f"sent={stamp!r} is invalid: expected Unix seconds >= 0")
        head += _SENT.pack(round(stamp * 1e6))
    tag = hmac.new(key, head + payload, hashlib.sha256).digest()
    return head + tag + payload


def open_frame(frame: bytes, keys: Mapping[str, bytes]) -> Frame:
    """The :class:`Frame` of an authentic frame; :class:`Rejected` otherwise."""
    if len(frame) < 5 + TAG_SIZE or frame[:2] != MAGIC:
        raise Rejected("bad_frame", "not a fusetrack frame (magic b'FT' missing or too short)")
    version = frame[2]
    if version not in FRAME_VERSIONS:
        raise Rejected("bad_frame", f"frame version={version} is invalid: expected 1 or 2")
    encoding = _ENCODING_NAMES.get(frame[3])
    if encoding is None:
        raise Rejected(
            "bad_frame", f"encoding byte={frame[3:4]!r} is invalid: expected b'j' or b'm'"
        )
    n = frame[4]
    end = 5 + n + (_SENT.size if version >= 2 else 0)  # the HMAC-covered head
    if n == 0 or len(frame) < end + TAG_SIZE:
        raise Rejected("bad_frame", "truncated node id, send time or tag")
    try:
        node = frame[5 : 5 + n].decode()
    except UnicodeDecodeError:
        raise Rejected("bad_frame", "node id is not UTF-8") from None
    key = keys.get(node)
    if key is None:
        raise Rejected("unknown_node", f"node={node!r} has no key in the network config")
    tag, payload = frame[end : end + TAG_SIZE], frame[end + TAG_SIZE :]
    expected = hmac.digest(key, frame[:end] + payload, "sha256")  # one-shot C HMAC
    if not hmac.compare_digest(tag, expected):
        raise Rejected("bad_mac", f"HMAC of the frame from node={node!r} does not match its key")
    sent = _SENT.unpack_from(frame, 5 + n)[0] / 1e6 if version >= 2 else None
    return Frame(node, encoding, payload, sent)


@dataclass(frozen=True)
class FrameFreshness:
    """Which authentic UDP frames are recent enough to be new (issue 18, item 5).

    The sequence windows catch a replay only while they remember the frame. A node that resumed
    from its durable log has them back; one without a log (or on a new log) starts them empty,
    so it refuses any frame sent before it started (``started``, less ``max_clock_skew`` for
    senders whose clocks run behind; None: the windows were restored): it cannot know whether
    it saw it. Every node refuses a frame sent more than ``max_age`` seconds before its wall
    clock (``stale``: a captured or withheld frame is usable for that long at most) or more
    than ``max_clock_skew`` after it (``clock_skew``: such a frame would stay fresh too long).
    A version-1 frame has no send time: a node with a log (``legacy``, whose windows survive
    its restarts) accepts it, its replay being a ``replay``; others refuse it (``legacy_frame``).

    >>> f = FrameFreshness(started=100.0, legacy=False, max_age=30.0, max_clock_skew=2.0)
    >>> f.check(99.0, now=101.0), f.check(101.5, now=101.0)
    (None, None)
    >>> def reason(sent):
    ...     try:
    ...         f.check(sent, now=101.0)
    ...     except Rejected as err:
    ...         return err.reason
    >>> reason(97.0), reason(104.0), reason(None), reason(60.0)
    ('stale', 'clock_skew', 'legacy_frame', 'stale')
    """

    started: float | None
    legacy: bool
    max_age: float
    max_clock_skew: float

    def check(self, sent: float | None, now: float) -> None:
        """Raise :class:`Rejected` unless a frame sent at ``sent`` may be new at ``now``."""
        if sent is None:
            if not self.legacy:
                raise Rejected(
                    "legacy_frame",
                    "a version-1 frame has no send time and this node has no log, so it cannot "
                    "tell a replay from a new frame: seal version-2 frames (fusetrack.service."
                    "seal) or run the node with a log",
                )
            return
        if sent > now + self.max_clock_skew:
            raise Rejected(
                "clock_skew",
                f"frame sent at {sent:.3f} s, {sent - now:.3f} s ahead of this node's clock "
                f"(limits.max_clock_skew: {self.max_clock_skew:g} s): fix the sender's clock",
            )
        if sent < now - self.max_age:
            raise Rejected(
                "stale",
                f"frame sent at {sent:.3f} s, {now - sent:.3f} s ago "
                f"(limits.max_frame_age: {self.max_age:g} s)",
            )
        if self.started is not None and sent < self.started - self.max_clock_skew:
            raise Rejected(
                "stale",
                f"frame sent at {sent:.3f} s, before this node started at {self.started:.3f} s "
                f"(less {self.max_clock_skew:g} s of clock skew) with no log to resume: it "
                "cannot tell a replay (run the node with a log)",
            )


def node_of_token(token: str, tokens: Mapping[str, str]) -> str | None:
    """The node whose bearer token is ``token`` (constant-time comparisons), or None."""
    found = None
    for node, expected in tokens.items():
        if hmac.compare_digest(token.encode(), expected.encode()):
            found = node
    return found


@dataclass
class SequenceWindow:
    """Anti-replay window over one node's sequence numbers (RFC 4303 §3.4.3).

    ``accept(seq)`` is True the first time ``seq`` is seen, if it is not older than
    ``highest - size + 1``; every later sight of the same number, and anything older, is False.

    >>> w = SequenceWindow()
    >>> [w.accept(s) for s in (5, 3, 5, 4, 3, 100, 36, 37)]
    [True, True, False, True, False, True, False, True]
    """

    size: int = 64
    highest: int = -1
    bitmap: int = 0  # bit i set: highest - i was seen

    def restore(self, highest: int) -> None:
        """After a restart: everything up to ``highest`` counts as seen."""
        self.highest = max(self.highest, highest)
        self.bitmap = (1 << self.size) - 1

    def accept(self, seq: int) -> bool:
        if seq > self.highest:
            shift = seq - self.highest
            # a jump past the window forgets it (shifting by the jump itself would build an
            # integer of `shift` bits: a jump of 2**33 took 2.4 GiB, issue 18)
            kept = self.bitmap << shift if shift < self.size else 0
            self.bitmap = (kept | 1) & ((1 << self.size) - 1)
            self.highest = seq
            return True
        offset = self.highest - seq
        if offset >= self.size or self.bitmap >> offset & 1:
            return False
        self.bitmap |= 1 << offset
        return True


@dataclass
class FailureLimiter:
    """Per-source token buckets of authentication failures (the token bucket of RFC 2697's
    single-rate meter): each source may fail ``burst`` times, refilled at ``rate`` failures per
    second. :meth:`blocked` is a dictionary look-up, so a source that has spent its bucket costs
    the node almost nothing per message; a source that never fails is never tracked.

    At most ``max_sources`` sources are remembered: past that, full buckets are forgotten and,
    if that is not enough, all of them (a flood from many forged addresses then gets ``burst``
    failures per address again, each still counted).

    >>> lim = FailureLimiter(rate=1.0, burst=2)
    >>> lim.fail("a", 0.0), lim.fail("a", 0.0), lim.blocked("a", 0.5), lim.blocked("a", 1.0)
    (None, None, True, False)
    """

    rate: float
    burst: float
    max_sources: int = 4096
    buckets: dict[Hashable, tuple[float, float]] = field(default_factory=dict)

    def _tokens(self, source: Hashable, now: float) -> float:
        tokens, since = self.buckets.get(source, (self.burst, now))
        return min(self.burst, tokens + max(0.0, now - since) * self.rate)

    def blocked(self, source: Hashable, now: float) -> bool:
        """True when ``source`` has no failure left: drop its message unchecked."""
        return source in self.buckets and self._tokens(source, now) < 1.0

    def fail(self, source: Hashable, now: float) -> None:
        """``source`` sent a message that failed authentication: spend one token."""
        if source not in self.buckets and len(self.buckets) >= self.max_sources:
            self._forget(now)
        self.buckets[source] = (self._tokens(source, now) - 1.0, now)

    def _forget(self, now: float) -> None:
        full = [s for s in self.buckets if self._tokens(s, now) >= self.burst]
        for s in full:
            del self.buckets[s]
        if len(self.buckets) >= self.max_sources:
            self.buckets.clear()
