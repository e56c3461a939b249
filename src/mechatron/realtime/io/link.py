"""What the packet links (``udp``, ``serial``) share: matching commands to steps."""

from __future__ import annotations

from mechatron.realtime.io.base import Command, PlantIO
from mechatron.realtime.io.protocol import COMMAND, HELLO, SAMPLE, STOP, Packet

__all__ = ["PacketLink"]


class PacketLink(PlantIO):
    """A link that carries the bridge's packets; subclasses move bytes
    (:meth:`_send`, :meth:`_recv` up to a deadline)."""

    def _send(self, p: Packet) -> None:
        raise NotImplementedError

    def _recv(self, deadline: float) -> Packet | None:
        raise NotImplementedError

    def start(self, timeout: float = 10.0) -> None:
        from mechatron.errors import SimulationError
        until = self.now() + timeout
        while True:
            p = self._recv(until)
            if p is None:
                raise SimulationError(f"hil io {self.kind}: no HELLO from the controller "
                                      f"within {timeout:g} s. Is it running and wired to "
                                      "this link?")
            if p.type == HELLO:
                return

    def write(self, seq, t, sensors) -> None:
        self._send(Packet(SAMPLE, seq, float(sensors[0]), float(t)))
        self.stats.sent += 1

    def read(self, seq, deadline) -> Command | None:
        while True:
            p = self._recv(deadline)
            if p is None:
                self.stats.lost += 1
                return None
            if p.type != COMMAND:
                continue
            if p.seq == seq:
                self.stats.received += 1
                return Command(seq, (p.a, p.b), bool(p.flags & 1))
            if p.seq < seq:
                self.stats.late += 1          # an older step's reply: too late, dropped

    def stop(self) -> None:
        for _ in range(3):
            self._send(Packet(STOP, 0))
