"""The node's UDP listener: each datagram is one sealed frame (:func:`.auth.seal`).

The socket is read by :meth:`UdpListener.drain`, which takes *every* datagram waiting (not one per
event-loop turn, as asyncio's datagram transport does). The tick loop drains the socket right
before it fires a tick, so a reading that reached the host before its tick fell due is fused
even when the loop was busy (a long tick, a burst), instead of being refused as late. Nothing is
sent back: UDP senders learn about refusals from ``/health`` and ``/metrics``.

The datagrams waiting are read first and then handed over together
(:meth:`.node.FusionNode.ingest_frames`: each is checked alone, the accepted readings are logged,
buffered and counted at once). Each datagram is charged to its sender's address (a
source that keeps failing authentication is dropped unchecked). One drain takes at most a few
hundred datagrams per event-loop turn, so a flood cannot hold ``/health`` and the ticks for
seconds (issue 18: 13 s); what the kernel drops because the socket's buffer is full is read
from ``/proc/net/udp`` (Linux) and shown as ``/health``'s ``udp_dropped``.
"""

from __future__ import annotations

import asyncio
import os
import socket
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .node import FusionNode

MAX_DATAGRAM = 65535
DRAIN_PER_TURN = 512  # datagrams handled per reader callback before the loop runs others


def udp_socket(host: str = "127.0.0.1", port: int = 0, rcvbuf: int = 8 * 2**20) -> socket.socket:
    """A bound non-blocking UDP socket (``port=0``: any free port; see ``getsockname()``)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_DGRAM)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
    except OSError:
        pass
    sock.bind((host, port))
    sock.setblocking(False)
    return sock


class UdpListener:
    """Feeds the datagrams arriving on ``sock`` to ``node`` (from the node's event loop)."""

    def __init__(self, node: FusionNode, sock: socket.socket) -> None:
        self.node = node
        self.sock = sock
        self.loop: asyncio.AbstractEventLoop | None = None

    def drain(self, limit: int = 10_000) -> int:
        """Handle the waiting datagrams (at most ``limit``); return how many."""
        frames: list[tuple[bytes, object]] = []
        recv = self.sock.recvfrom
        while len(frames) < limit:
            try:
                data, addr = recv(MAX_DATAGRAM)
            except (BlockingIOError, InterruptedError):
                break
            except OSError:  # e.g. ICMP port unreachable reported on the socket: not fatal
                continue
            frames.append((data, addr[0]))
        if frames:  # checked one by one, accepted together (FusionNode.ingest_frames)
            self.node.ingest_frames(frames)
        return len(frames)

    def start(self) -> UdpListener:
        self.loop = asyncio.get_running_loop()
        self.loop.add_reader(self.sock.fileno(), self.drain, DRAIN_PER_TURN)
        self.node.udp_dropped = lambda: kernel_drops(self.sock)
        return self

    def close(self) -> None:
        if self.loop is not None:
            self.loop.remove_reader(self.sock.fileno())
            self.loop = None


def kernel_drops(sock: socket.socket) -> int | None:
    """Datagrams the kernel dropped for ``sock`` (its receive buffer was full): the ``drops``
    column of ``/proc/net/udp`` or ``udp6`` for the socket's inode; None where there is none."""
    inode = str(os.fstat(sock.fileno()).st_ino)
    for table in ("/proc/net/udp", "/proc/net/udp6"):
        try:
            with open(table) as f:
                for line in f:
                    cols = line.split()
                    if len(cols) > 12 and cols[9] == inode:
                        return int(cols[12])
        except OSError:
            continue
    return None
