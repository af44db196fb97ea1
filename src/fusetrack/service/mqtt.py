"""The node's MQTT bridge: readings in from subscribed topics, tracks out to a topic (paho-mqtt).

**Authentication.** Every MQTT message the bridge ingests is one sealed frame, byte for byte the
UDP datagram format (:func:`.auth.seal`: the node's id, the payload's encoding, JSON or
MessagePack, the send time and an HMAC-SHA256 tag under that node's key). The broker is only a relay: who may
publish on a topic is the broker's business (its ACLs), whether a reading is authentic is the
node's, checked with the same key and the same rules as over UDP
(:meth:`.node.FusionNode.ingest_frame`). A forged or altered frame is refused (``bad_mac``,
``unknown_node``, ``bad_frame``) and counted, and so is a stale one (``stale``: e.g. held by
the broker for longer than ``limits.max_frame_age`` while the node was away). Every message reaches the node through the one
broker connection, so refusals are not charged to a source address (one forger would otherwise
lock out every sender on the broker); each costs one HMAC.

**Acknowledgement.** The client acknowledges by hand (paho's ``manual_ack``): with QoS 1 or 2 a
message is acknowledged to the broker only after the node has ingested it and committed its
durable log, so a message the broker counts as delivered is accepted and logged, or refused
and counted (a refusal is final and acknowledged too, ``overload`` included, as over UDP). A message that was not acknowledged when
the connection dropped is delivered again by the broker (``clean_session: false``) and, if it
had been accepted, refused as a ``replay``.

**Tracks.** Each fusion tick's message, the same JSON text as ``/ws/tracks`` sends, is published
to ``publish_tracks`` (QoS ``qos``). While the broker is away, QoS 1/2 messages are queued (at
most ``max_queued``) and sent on reconnection.

**Reconnection.** paho's network thread reconnects with exponential backoff, from
``reconnect_min`` doubling up to ``reconnect_max`` seconds, and the bridge resubscribes on each
connection. Messages are handed from paho's thread to the node's event loop
(``call_soon_threadsafe``), which ingests everything that has arrived, commits the log once and
then acknowledges: the node itself is only ever touched from its loop.

``/health`` shows the bridge under ``mqtt``: connected, subscribed (the broker granted the
subscriptions), connections, received, accepted, refused (by reason), published,
publish_dropped and the last error.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import ssl
import threading
from collections import Counter
from typing import TYPE_CHECKING, Any

import paho.mqtt.client as paho
from paho.mqtt.enums import CallbackAPIVersion, MQTTErrorCode

from ..core import ConfigError, invalid
from .config import MqttConfig

if TYPE_CHECKING:
    from .node import FusionNode

log = logging.getLogger(__name__)


class MqttBridge:
    """Connects ``node`` to the broker of ``cfg``; :meth:`start` from the node's event loop."""

    def __init__(self, node: FusionNode, cfg: MqttConfig) -> None:
        self.node = node
        self.cfg = cfg
        self.loop: asyncio.AbstractEventLoop | None = None
        self.client = _client(cfg)
        self.client.on_connect = self._on_connect
        self.client.on_disconnect = self._on_disconnect
        self.client.on_message = self._on_message
        self.client.on_subscribe = self._on_subscribe
        self.client.on_connect_fail = self._on_connect_fail
        self.connected = False
        self.subscribed = False  # the broker granted every subscription on this connection
        self.generation = 0  # connections so far: an ack is only sent on the connection it came on
        self.received = 0
        self.accepted = 0
        self.refused: Counter[str] = Counter()
        self.published = 0
        self.publish_dropped = 0
        self.last_error = ""
        self.stopping = False
        self.lock = threading.Lock()  # guards inbox and drain_due (paho's thread and the loop)
        self.inbox: list[tuple[bytes, int, int, int]] = []  # (frame, mid, qos, connection)
        self.drain_due = False
        self.publisher: asyncio.Task[None] | None = None
        self.queue: asyncio.Queue[str] | None = None

    # -- lifecycle (event loop) --------------------------------------------------------------
    def start(self) -> MqttBridge:
        """Connect in the background (paho's thread retries until the broker answers) and start
        publishing tracks."""
        self.loop = asyncio.get_running_loop()
        self.node.mqtt_status = self.status
        if self.cfg.publish_tracks is not None:
            self.queue = self.node.subscribe()
            if self.queue is not None:
                self.publisher = asyncio.create_task(self._publish_tracks(self.queue))
        self.client.connect_async(self.cfg.host, self.cfg.port, self.cfg.keepalive)
        self.client.loop_start()
        return self

    async def stop(self) -> None:
        """Stop publishing, disconnect cleanly and join paho's thread. What arrives from now on
        is left unacknowledged: the broker delivers it again to the next session."""
        self.stopping = True
        if self.publisher is not None:
            self.publisher.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self.publisher
        if self.queue is not None:
            self.node.unsubscribe(self.queue)
        self.client.disconnect()
        await asyncio.to_thread(self.client.loop_stop)

    def status(self) -> dict[str, Any]:
        """What ``/health`` shows under ``mqtt``."""
        return {
            "broker": f"{self.cfg.host}:{self.cfg.port}",
            "connected": self.connected,
            "subscribed": self.subscribed,
            "connections": self.generation,
            "received": self.received,
            "accepted": self.accepted,
            "refused": dict(self.refused),
            "published": self.published,
            "publish_dropped": self.publish_dropped,
            "last_error": self.last_error,
        }

    # -- paho's thread -----------------------------------------------------------------------
    def _on_connect(self, client: paho.Client, _u: Any, _f: Any, reason: Any, _p: Any) -> None:
        if reason.is_failure:
            self.last_error = f"connection refused: {reason}"
            log.warning("mqtt: broker %s:%d refused: %s", self.cfg.host, self.cfg.port, reason)
            return
        self.generation += 1
        self.connected = True
        log.info("mqtt: connected to %s:%d", self.cfg.host, self.cfg.port)
        self.subscribed = not self.cfg.subscribe  # nothing to subscribe to: nothing to wait for
        if self.cfg.subscribe:
            topics: list[tuple[str, int]] = [(t, self.cfg.qos) for t in self.cfg.subscribe]
            client.subscribe(topics)

    def _on_connect_fail(self, _c: Any, _u: Any) -> None:
        if not self.last_error.startswith("cannot reach"):
            log.warning("mqtt: cannot reach %s:%d; retrying", self.cfg.host, self.cfg.port)
        self.last_error = f"cannot reach the broker {self.cfg.host}:{self.cfg.port}"

    def _on_subscribe(self, _c: Any, _u: Any, _mid: int, reasons: list[Any], _p: Any) -> None:
        refused = [t for t, r in zip(self.cfg.subscribe, reasons, strict=False) if r.is_failure]
        if refused:
            self.last_error = f"the broker refused the subscription to {refused}"
            log.warning("mqtt: %s", self.last_error)
        self.subscribed = not refused

    def _on_disconnect(self, _c: Any, _u: Any, _f: Any, reason: Any, _p: Any) -> None:
        self.connected = self.subscribed = False
        if reason.is_failure:
            self.last_error = f"disconnected: {reason}"
            log.warning("mqtt: lost the broker (%s); reconnecting", reason)

    def _on_message(self, _c: Any, _u: Any, message: paho.MQTTMessage) -> None:
        """Queue the message for the event loop; wake it unless a drain is already due."""
        assert self.loop is not None
        with self.lock:
            self.inbox.append((bytes(message.payload), message.mid, message.qos, self.generation))
            wake, self.drain_due = not self.drain_due, True
        if wake:
            self.loop.call_soon_threadsafe(self._drain)

    # -- the node's event loop ---------------------------------------------------------------
    def _drain(self) -> None:
        """Ingest every queued frame, commit the log once, then acknowledge them (QoS 1/2): a
        burst costs one commit (one fsync with ``log.durability: full``), not one per message."""
        with self.lock:
            batch, self.inbox, self.drain_due = self.inbox, [], False
        if self.stopping or not batch:
            return
        for frame, _, _, _ in batch:
            for outcome in self.node.ingest_frame(frame):
                if outcome.accepted:
                    self.accepted += 1
                else:
                    self.refused[outcome.reason] += 1
        self.node.commit()
        self.received += len(batch)
        for _, mid, qos, generation in batch:
            if qos > 0 and generation == self.generation:  # else the broker redelivers it
                self.client.ack(mid, qos)

    async def _publish_tracks(self, queue: asyncio.Queue[str]) -> None:
        assert self.cfg.publish_tracks is not None
        while True:
            text = await queue.get()
            info = self.client.publish(
                self.cfg.publish_tracks, text, qos=self.cfg.qos, retain=self.cfg.retain_tracks
            )
            kept = info.rc == MQTTErrorCode.MQTT_ERR_SUCCESS or (
                info.rc == MQTTErrorCode.MQTT_ERR_NO_CONN and self.cfg.qos > 0
            )  # QoS 1/2 while disconnected: queued, sent on reconnection
            if kept:
                self.published += 1
            else:
                self.publish_dropped += 1


def _client(cfg: MqttConfig) -> paho.Client:
    """A paho client (MQTT 3.1.1, manual acknowledgements) with ``cfg``'s credentials, TLS,
    reconnection backoff and queue bound."""
    client = paho.Client(
        CallbackAPIVersion.VERSION2,
        client_id=cfg.client_id,
        clean_session=cfg.clean_session,
        protocol=paho.MQTTv311,
        manual_ack=True,
    )
    if cfg.username:
        client.username_pw_set(cfg.username, cfg.secret())
    if cfg.tls is not None:
        try:
            client.tls_set(
                ca_certs=cfg.tls.ca_file,
                certfile=cfg.tls.cert_file,
                keyfile=cfg.tls.key_file,
                cert_reqs=ssl.CERT_REQUIRED,
            )
        except (OSError, ssl.SSLError) as err:
            files = [f for f in (cfg.tls.ca_file, cfg.tls.cert_file, cfg.tls.key_file) if f]
            raise ConfigError(
                invalid("mqtt.tls", files, f"readable PEM files ({type(err).__name__}: {err})")
            ) from None
    client.reconnect_delay_set(cfg.reconnect_min, cfg.reconnect_max)  # type: ignore[arg-type]
    client.max_queued_messages_set(cfg.max_queued)
    return client
