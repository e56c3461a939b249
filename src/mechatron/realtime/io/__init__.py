"""I/O backends of the HIL plant: one interface, four links to a controller.

Each step ``k`` the plant *writes* its measurements (the encoder count, ...) stamped with
``k`` and its time ``t_k``, and *reads* the controller's command for the same step before
a deadline. A backend never blocks past the deadline: a command that has not come is a
lost sample (the plant holds the previous command), one that comes later is counted late
and dropped. Every backend keeps the same counters (:class:`LinkStats`).

======== ==========================================================================
``sim``   the controller is a function in this process (:class:`SimIO`)
``udp``   the bridge's datagrams on loopback or a network (:class:`UDPIO`)
``serial`` a serial line (``/dev/ttyUSB0``, a pseudo-terminal): framed packets with
          sequence number, timestamp, payload and CRC-16 (:class:`SerialIO`)
``mf624`` the Humusoft MF624 card through the Linux UIO driver: analogue and digital
          I/O and encoder inputs by memory-mapped registers (:class:`MF624IO`)
======== ==========================================================================

:func:`open_io` builds one by name. The packet format is that of the C bridge
(``templates/c/mt_packet.h``, docs/hil.md "Packet format"), written again here in
Python (:mod:`mechatron.realtime.io.protocol`).
"""

from __future__ import annotations

from mechatron.realtime.io.base import Command, LinkStats, PlantIO
from mechatron.realtime.io.mf624 import MF624IO, MF624Registers
from mechatron.realtime.io.serial import SerialIO
from mechatron.realtime.io.sim import SimIO
from mechatron.realtime.io.udp import UDPIO

__all__ = ["PlantIO", "Command", "LinkStats", "SimIO", "UDPIO", "SerialIO", "MF624IO",
           "MF624Registers", "open_io", "BACKENDS"]

BACKENDS = {"sim": SimIO, "udp": UDPIO, "serial": SerialIO, "mf624": MF624IO}


def open_io(kind: str, **options) -> PlantIO:
    """The backend ``kind`` (``sim``, ``udp``, ``serial``, ``mf624``) built with
    ``options`` (the keyword arguments of its class)."""
    from mechatron.errors import SimulationError
    cls = BACKENDS.get(kind)
    if cls is None:
        raise SimulationError(f"hil io: unknown backend {kind!r}. Choose one of "
                              f"{', '.join(BACKENDS)}.")
    return cls(**options)
