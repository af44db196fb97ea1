"""Authentication of sensor nodes: one secret key per node.

* **UDP**: every datagram is a sealed frame (:func:`seal`)::

      b"FT" | version (1 byte) | encoding (b"j" JSON / b"m" MessagePack) | len(node) (1 byte)
      | node id (UTF-8) | HMAC-SHA256(key, everything before the tag + payload) (32 bytes) | payload

  :func:`open_frame` checks the tag with the node's key *before* the payload is parsed, so an
  unauthenticated packet never reaches the parser. A forged or altered frame is ``bad_mac``.
* **HTTP / WebSocket writes**: ``Authorization: Bearer <token>`` where the token is derived
  from the node's key (:func:`bearer_token`), so the key itself never travels.
* **Replays**: each message carries a per-node sequence number; :class:`SequenceWindow` accepts
  a number once, tolerating reordering within a window of the last 64 (the IPsec anti-replay
  window, RFC 4303 §3.4.3), and rejects anything older.
* **Floods**: :class:`FailureLimiter` gives each source address a token bucket of
  authentication failures; once a source has spent it, its datagrams are dropped before their
  tag is computed (issue 18: forged frames from one sender starved the legitimate ones).
"""

from __future__ import annotations

import hashlib
import hmac
from collections.abc import Hashable, Mapping
from dataclasses import dataclass, field

MAGIC = b"FT"
FRAME_VERSION = 1
TAG_SIZE = 32
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


def seal(node: str, key: bytes, payload: bytes, encoding: str = "json") -> bytes:
    """A UDP frame carrying ``payload`` from ``node``, tagged with the node's key."""
    name = node.encode()
    if not 0 < len(name) < 256:
        raise ValueError(f"node={node!r} is invalid: expected 1 to 255 UTF-8 bytes")
    head = MAGIC + bytes([FRAME_VERSION]) + _ENCODING_BYTES[encoding] + bytes([len(name)]) + name
    tag = hmac.new(key, head + payload, hashlib.sha256).digest()
    return head + tag + payload


def open_frame(frame: bytes, keys: Mapping[str, bytes]) -> tuple[str, str, bytes]:
    """``(node, encoding, payload)`` of an authentic frame; :class:`Rejected` otherwise."""
    if len(frame) < 5 + TAG_SIZE or frame[:2] != MAGIC:
        raise Rejected("bad_frame", "not a fusetrack frame (magic b'FT' missing or too short)")
    if frame[2] != FRAME_VERSION:
        raise Rejected("bad_frame", f"frame version={frame[2]} is invalid: expected 1")
    encoding = _ENCODING_NAMES.get(frame[3])
    if encoding is None:
        raise Rejected(
            "bad_frame", f"encoding byte={frame[3:4]!r} is invalid: expected b'j' or b'm'"
        )
    n = frame[4]
    end = 5 + n
    if n == 0 or len(frame) < end + TAG_SIZE:
        raise Rejected("bad_frame", "truncated node id or tag")
    try:
        node = frame[5:end].decode()
    except UnicodeDecodeError:
        raise Rejected("bad_frame", "node id is not UTF-8") from None
    key = keys.get(node)
    if key is None:
        raise Rejected("unknown_node", f"node={node!r} has no key in the network config")
    tag, payload = frame[end : end + TAG_SIZE], frame[end + TAG_SIZE :]
    expected = hmac.digest(key, frame[:end] + payload, "sha256")  # one-shot C HMAC
    if not hmac.compare_digest(tag, expected):
        raise Rejected("bad_mac", f"HMAC of the frame from node={node!r} does not match its key")
    return node, encoding, payload


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
