"""The node's UDP listener: each datagram is one sealed frame (:func:`.auth.seal`).

Datagrams are handled in the event loop that runs the node, one at a time, so a frame is
authenticated, parsed, checked and buffered before the next is read. Nothing is sent back
(UDP senders learn about refusals from ``/health`` and ``/metrics``).
"""

from __future__ import annotations

import asyncio
import socket
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .node import FusionNode


class _Protocol(asyncio.DatagramProtocol):
    def __init__(self, node: FusionNode) -> None:
        self.node = node

    def datagram_received(self, data: bytes, addr: tuple[str, int]) -> None:
        self.node.ingest_frame(data)

    def error_received(self, exc: Exception) -> None:  # e.g. ICMP unreachable: not fatal
        pass


def udp_socket(host: str = "127.0.0.1", port: int = 0, rcvbuf: int = 4 * 2**20) -> socket.socket:
    """A bound UDP socket (``port=0``: any free port; read it with ``getsockname()``)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_DGRAM)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
    except OSError:
        pass
    sock.bind((host, port))
    sock.setblocking(False)
    return sock


async def start_udp(node: FusionNode, sock: socket.socket) -> asyncio.DatagramTransport:
    """Listen on ``sock`` for ``node``; close the returned transport to stop."""
    loop = asyncio.get_running_loop()
    transport, _ = await loop.create_datagram_endpoint(lambda: _Protocol(node), sock=sock)
    return transport
