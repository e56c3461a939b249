"""``udp``: the bridge's datagrams (one 28-byte packet each)."""

from __future__ import annotations

import select
import socket

from mechatron.realtime.io.link import PacketLink
from mechatron.realtime.io.protocol import Packet, decode, encode

__all__ = ["UDPIO"]


class UDPIO(PacketLink):
    """Bind ``host:port`` (port 0: any free one, see :attr:`port`); the controller's
    address is learnt from its HELLO, or given as ``peer=(host, port)``."""

    kind = "udp"

    def __init__(self, port: int = 0, *, host: str = "127.0.0.1",
                 peer: tuple[str, int] | None = None) -> None:
        super().__init__()
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind((host, int(port)))
        self.sock.setblocking(False)
        self.port = self.sock.getsockname()[1]
        self.peer = peer

    def _send(self, p: Packet) -> None:
        if self.peer is not None:
            self.sock.sendto(encode(p), self.peer)

    def _recv(self, deadline: float) -> Packet | None:
        while True:
            left = deadline - self.now()
            if left <= 0 or not select.select([self.sock], [], [], left)[0]:
                return None
            data, addr = self.sock.recvfrom(64)
            p = decode(data)
            if p is None:
                self.stats.bad_frames += 1
                continue
            if self.peer is None:
                self.peer = addr
            return p

    def close(self) -> None:
        self.sock.close()
