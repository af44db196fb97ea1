"""Running a fusion node: in the foreground (``fusetrack serve``) or in a background thread
(``fusetrack demo --live``, the end-to-end tests) on uvicorn, with its UDP listener (and its
MQTT bridge when the config has an ``mqtt`` section, :mod:`.mqtt`)."""

from __future__ import annotations

import logging
import signal
import socket
import ssl
import sys
import threading
import time
from pathlib import Path
from typing import Any

import uvicorn

from ..core import ConfigError, invalid
from ..evaluation import colour_enabled
from .app import create_app
from .config import NetworkConfig
from .log import DurableLog
from .node import FusionNode
from .udp import udp_socket

log = logging.getLogger(__name__)


def build_node(cfg: NetworkConfig, log_path: str | Path | None = None) -> FusionNode:
    """A node for ``cfg``, resuming from its durable log when one is configured and exists."""
    path = log_path if log_path is not None else cfg.log.path
    return FusionNode(cfg, log=DurableLog(path, cfg.log.durability) if path else None)


def tcp_socket(host: str, port: int) -> socket.socket:
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    # proto=IPPROTO_TCP: asyncio then sets TCP_NODELAY on accepted connections (no 40 ms
    # Nagle + delayed-ACK stall per response)
    sock = socket.socket(family, socket.SOCK_STREAM, socket.IPPROTO_TCP)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
    except OSError as err:
        sock.close()
        raise ConfigError(invalid("port", port, f"a free TCP port on {host} ({err})")) from None
    return sock


def uvicorn_options(node: FusionNode) -> dict[str, Any]:
    """The HTTP server's settings: a WebSocket frame is refused above ``limits.max_message_bytes``
    before it is buffered (uvicorn's default buffers 16 MiB first, issue 18); log colours only
    on a terminal and never with ``NO_COLOR`` (uvicorn's own default ignores ``NO_COLOR``)."""
    return {
        "log_level": "warning",
        "use_colors": colour_enabled(sys.stderr),
        "ws": "websockets-sansio",
        "ws_max_size": node.cfg.limits.max_message_bytes,
    }


def tls_options(cert: str | Path | None, key: str | Path | None) -> dict[str, Any]:
    """uvicorn's TLS settings for ``--tls-cert``/``--tls-key`` (both or neither), checked by
    loading them before the node starts: HTTPS and WSS instead of HTTP and WS (UDP frames are
    authenticated by their HMAC but not encrypted)."""
    if cert is None and key is None:
        return {}
    if cert is None or key is None:
        given = "--tls-cert" if cert is not None else "--tls-key"
        raise ConfigError(invalid(given, str(cert or key), "--tls-cert and --tls-key together"))
    try:
        ssl.create_default_context(ssl.Purpose.CLIENT_AUTH).load_cert_chain(cert, key)
    except (OSError, ssl.SSLError) as err:
        raise ConfigError(
            invalid(
                "--tls-cert/--tls-key",
                f"{cert}, {key}",
                f"a PEM certificate and its private key ({type(err).__name__}: {err})",
            )
        ) from None
    return {"ssl_certfile": str(cert), "ssl_keyfile": str(key)}


class RunningNode:
    """A node served by uvicorn on its own thread; ``url`` and ``udp`` say where it listens."""

    def __init__(
        self,
        node: FusionNode,
        host: str = "127.0.0.1",
        http_port: int = 0,
        udp_port: int | None = 0,
        tls: dict[str, Any] | None = None,
    ) -> None:
        """``tls``: :func:`tls_options` (HTTPS/WSS)."""
        self.node = node
        self.http_sock = tcp_socket(host, http_port)
        self.udp_sock = udp_socket(host, udp_port) if udp_port is not None else None
        app = create_app(node, self.udp_sock)
        config = uvicorn.Config(app, lifespan="on", **uvicorn_options(node), **(tls or {}))
        self.server = uvicorn.Server(config)
        self.thread = threading.Thread(
            target=self.server.run, kwargs={"sockets": [self.http_sock]}, daemon=True
        )
        h, p = self.http_sock.getsockname()[:2]
        self.url = f"{'https' if tls else 'http'}://{h}:{p}"
        self.udp = None if self.udp_sock is None else self.udp_sock.getsockname()[:2]

    def start(self, timeout: float = 20.0) -> RunningNode:
        self.thread.start()
        deadline = time.monotonic() + timeout
        while not self.server.started:
            if not self.thread.is_alive() or time.monotonic() > deadline:
                raise RuntimeError("the fusion node did not start")
            time.sleep(0.01)
        return self

    def stop(self) -> None:
        self.server.should_exit = True
        self.thread.join(timeout=10)
        if self.node.log is not None:
            self.node.log.close()

    def __enter__(self) -> RunningNode:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()


class _ForegroundServer(uvicorn.Server):
    """uvicorn's server remembering a Ctrl-C: uvicorn re-raises the captured SIGINT after its
    graceful shutdown, but inside asyncio's runner that can end as a normal return (a race with
    the main task finishing), and the CLI would exit 0 instead of 128 + SIGINT."""

    interrupted = False

    def handle_exit(self, sig: int, frame: Any) -> None:
        if sig == signal.SIGINT:
            self.interrupted = True
        super().handle_exit(sig, frame)


def serve(
    cfg: NetworkConfig,
    host: str = "127.0.0.1",
    http_port: int = 8000,
    udp_port: int | None = 9000,
    log_path: str | Path | None = None,
    tls_cert: str | Path | None = None,
    tls_key: str | Path | None = None,
) -> None:
    """Serve a node in the foreground until interrupted (``fusetrack serve``)."""
    tls = tls_options(tls_cert, tls_key)  # checked before the log is opened
    node = build_node(cfg, log_path)
    http = tcp_socket(host, http_port)
    udp = udp_socket(host, udp_port) if udp_port is not None else None
    app = create_app(node, udp)
    where = f"{'https' if tls else 'http'}://{host}:{http.getsockname()[1]}/"
    print(f"fusion node: dashboard {where}", flush=True)  # the address the user opens: stdout
    if udp is not None:
        log.info("fusion node: listening for UDP on udp://%s:%d", host, udp.getsockname()[1])
    if cfg.mqtt is not None:
        m = cfg.mqtt
        log.info(
            "fusion node: MQTT bridge to %s:%d (readings from %s, tracks to %s)",
            m.host,
            m.port,
            ", ".join(m.subscribe) or "no topic",
            m.publish_tracks or "no topic",
        )
    if node.resumed_ticks and node.log is not None:
        log.info("fusion node: resumed %d ticks from %s", node.resumed_ticks, node.log.path)
    server = _ForegroundServer(uvicorn.Config(app, **uvicorn_options(node), **tls))
    try:
        server.run(sockets=[http])
    finally:
        if node.log is not None:
            node.log.close()
    if server.interrupted:  # stopped by Ctrl-C: the CLI's one-line note and exit code 130
        raise KeyboardInterrupt
