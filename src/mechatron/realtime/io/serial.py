"""``serial``: framed packets over a serial line (a USB-UART to the microcontroller, a
pseudo-terminal in the tests)."""

from __future__ import annotations

import os
import select
import termios
import tty

from mechatron.realtime.io.link import PacketLink
from mechatron.realtime.io.protocol import FrameParser, Packet, frame

__all__ = ["SerialIO", "BAUD_RATES"]

BAUD_RATES = {b: getattr(termios, f"B{b}") for b in
              (9600, 19200, 38400, 57600, 115200, 230400, 460800, 500000, 576000, 921600,
               1000000, 1152000, 1500000, 2000000, 3000000, 4000000)
              if hasattr(termios, f"B{b}")}


class SerialIO(PacketLink):
    """A serial line: ``tty`` (a device path, opened raw 8N1 at ``baud``) or ``fd`` (an
    open file descriptor, e.g. one end of :func:`os.openpty`, used as it is).

    A frame is 32 bytes: at 115200 baud (10 bits a byte) one frame each way takes 2.8 ms,
    so such a link keeps about 300 steps/s; at 1 Mbaud about 3,000.
    """

    kind = "serial"

    def __init__(self, tty_path: str | None = None, *, fd: int | None = None,
                 baud: int = 115200) -> None:
        from mechatron.errors import SimulationError
        super().__init__()
        if (tty_path is None) == (fd is None):
            raise SimulationError("hil io serial: give a device path or an open file "
                                  "descriptor (fd=), not both.")
        self.own = fd is None
        if fd is None:
            if baud not in BAUD_RATES:
                raise SimulationError(f"hil io serial: unsupported baud rate {baud!r}. "
                                      f"Choose one of {', '.join(map(str, BAUD_RATES))}.")
            try:
                fd = os.open(tty_path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
            except OSError as e:
                raise SimulationError(f"hil io serial: cannot open {tty_path}: "
                                      f"{e.strerror}. Is the adapter plugged in, and may "
                                      "this user open it (group dialout)?") from None
            tty.setraw(fd)
            attrs = termios.tcgetattr(fd)
            attrs[4] = attrs[5] = BAUD_RATES[baud]       # ispeed, ospeed
            termios.tcsetattr(fd, termios.TCSANOW, attrs)
            termios.tcflush(fd, termios.TCIOFLUSH)
        else:
            os.set_blocking(fd, False)
        self.fd = fd
        self.baud = baud
        self.parser = FrameParser()
        self._queue: list[Packet] = []

    def _send(self, p: Packet) -> None:
        data = frame(p)
        while data:
            try:
                n = os.write(self.fd, data)
            except BlockingIOError:
                select.select([], [self.fd], [], 0.01)
                continue
            data = data[n:]

    def _recv(self, deadline: float) -> Packet | None:
        while not self._queue:
            left = deadline - self.now()
            if left <= 0 or not select.select([self.fd], [], [], left)[0]:
                return None
            try:
                data = os.read(self.fd, 4096)
            except BlockingIOError:
                continue
            except OSError:               # the other end of a pty went away
                return None
            if not data:
                return None
            self._queue += self.parser.feed(data)
            self.stats.bad_frames = self.parser.bad_frames
        return self._queue.pop(0)

    def close(self) -> None:
        if self.own and self.fd >= 0:
            os.close(self.fd)
        self.fd = -1
