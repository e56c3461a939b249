"""``mf624``: the Humusoft MF624 data-acquisition card through the Linux UIO driver.

The kernel's ``uio_mf624`` driver exposes the card's three memory regions as the maps of
``/dev/uioN``: map 0 is BAR0 (the PCI bridge's local registers), map 1 BAR2 (A/D, D/A,
digital I/O), map 2 BAR4 (counters and encoder inputs); map ``i`` is mmap'ed at offset
``i * page size`` of the device file, its size and in-page offset read from
``/sys/class/uio/uioN/maps/map<i>/{size,offset}``.

Register offsets and conversions (sources: the Humusoft MF624 user's manual, as used by
Humusoft's own hudaqlib ``MF624.c`` and by the MF624 model in QEMU by R. Lisovy,
``hw/misc/mf624.c``; facts only, no code taken):

====== ====== ==== ===================================================================
BAR    offset size register
====== ====== ==== ===================================================================
BAR0   0x54   32   GPIOC: bit 17 EOLC (1 while an A/D conversion runs), bit 23 LDAC
                   (1 holds the D/A outputs), bit 26 DACEN (1 enables them)
BAR2   0x00   16   read: ADDATA (FIFO of the converted channels); write: ADCTRL (mask
                   of the channels to convert)
BAR2   0x10   16   read: DIN (8 digital inputs); write: DOUT (8 digital outputs)
BAR2   0x20   16   read: ADSTART (a read starts the conversion); write: DA0, then DA1 to
                   DA7 at 0x22 ... 0x2E
BAR4   0x6C   32   write: IRCCTRL (8 bits per encoder: mode, count control, reset mode,
                   filter); read: IRCSTATUS
BAR4   0x70   32   IRC0 (signed count of encoder input 0), IRC1 to IRC3 at 0x74 ... 0x7C
====== ====== ==== ===================================================================

- A/D: 14 bits, two's complement, +-10 V: ``v = 10 * int16(raw << 2) / 0x8000``.
- D/A: 14 bits, offset binary, +-10 V: ``raw = 0x4000 (v + 10) / 20`` clipped to
  ``0 .. 0x3FFF``.
- GPIOC keeps its other bits at ``0x024006C0``.

Registers are read and written with loads and stores of their width (``memoryview``
casts: one 16- or 32-bit access each, as the card requires).
"""

from __future__ import annotations

import mmap
import os
from pathlib import Path
from typing import Sequence

from mechatron.realtime.io.base import Command, PlantIO

__all__ = ["MF624IO", "MF624Registers", "ad_to_volts", "volts_to_da", "quadrature",
           "GPIOC", "ADCTRL", "ADDATA", "ADSTART", "DIN", "DOUT", "DA0", "IRCCTRL",
           "IRCSTATUS", "IRC0", "GPIOC_BASE", "GPIOC_EOLC", "GPIOC_LDAC", "GPIOC_DACEN",
           "MAP_SIZES"]

# BAR0
GPIOC = 0x54
GPIOC_BASE, GPIOC_EOLC, GPIOC_LDAC, GPIOC_DACEN = 0x024006C0, 1 << 17, 1 << 23, 1 << 26
# BAR2
ADDATA = ADCTRL = 0x00
DIN = DOUT = 0x10
ADSTART = DA0 = 0x20
# BAR4
IRCCTRL = IRCSTATUS = 0x6C
IRC0 = 0x70
#: Sizes of the three maps (BAR0, BAR2, BAR4) of the card, in bytes.
MAP_SIZES = (128, 128, 128)
PAGE = mmap.PAGESIZE


def ad_to_volts(raw: int) -> float:
    """Volts of a 16-bit ADDATA word (14-bit two's complement, +-10 V)."""
    word = (raw << 2) & 0xFFFF
    return 10.0 * (word - 0x10000 if word & 0x8000 else word) / 0x8000


def volts_to_da(v: float) -> int:
    """The D/A word of ``v`` volts (14-bit offset binary, +-10 V, clipped)."""
    raw = 0x4000 * (v + 10.0) / 20.0
    return 0x3FFF if raw >= 0x3FFF else 0 if raw <= 0 else int(raw)


def quadrature(count: int) -> tuple[int, int]:
    """Levels of the A and B tracks of an incremental encoder at ``count`` (x4): the
    Gray sequence 00, 10, 11, 01 for counts 0, 1, 2, 3 (mod 4); A leads B when counting
    up."""
    return ((0, 0), (1, 0), (1, 1), (0, 1))[count % 4]


class MF624Registers:
    """The card's three register maps, mmap'ed from a UIO device (``/dev/uioN``) or from
    a regular file laid out the same way (map ``i`` at ``i * page size``: the fake card
    of the tests)."""

    def __init__(self, path: str | os.PathLike, *, sizes: Sequence[int] | None = None,
                 offsets: Sequence[int] | None = None) -> None:
        from mechatron.errors import SimulationError
        path = Path(path)
        if sizes is None:
            sizes, offsets = _uio_maps(path)
        offsets = offsets or [0] * len(sizes)
        try:
            self.fd = os.open(path, os.O_RDWR | os.O_SYNC)
        except OSError as e:
            raise SimulationError(f"hil io mf624: cannot open {path}: {e.strerror}. Is "
                                  "the uio_mf624 module loaded (modprobe uio_mf624) and "
                                  "the device readable by this user?") from None
        self.maps = []
        self.views: list[tuple[memoryview, memoryview, int]] = []
        for i, (size, off) in enumerate(zip(sizes, offsets)):
            length = ((off + size + PAGE - 1) // PAGE) * PAGE
            m = mmap.mmap(self.fd, length, mmap.MAP_SHARED,
                          mmap.PROT_READ | mmap.PROT_WRITE, offset=i * PAGE)
            self.maps.append(m)
            view = memoryview(m)[off:off + size]
            self.views.append((view.cast("H"), view.cast("I"), off))

    @classmethod
    def fake(cls, path: str | os.PathLike) -> "MF624Registers":
        """A file-backed register map (created or reset to the card's power-on values:
        GPIOC at its base value, the D/A outputs at 0 V)."""
        path = Path(path)
        with open(path, "wb") as f:
            f.write(bytes(PAGE * len(MAP_SIZES)))
        regs = cls(path, sizes=MAP_SIZES)
        regs.write32(0, GPIOC, GPIOC_BASE)
        for ch in range(8):
            regs.write16(1, DA0 + 2 * ch, volts_to_da(0.0))
        return regs

    def read16(self, bar: int, offset: int) -> int:
        return self.views[bar][0][offset // 2]

    def write16(self, bar: int, offset: int, value: int) -> None:
        self.views[bar][0][offset // 2] = value & 0xFFFF

    def read32(self, bar: int, offset: int) -> int:
        return self.views[bar][1][offset // 4]

    def write32(self, bar: int, offset: int, value: int) -> None:
        self.views[bar][1][offset // 4] = value & 0xFFFFFFFF

    def close(self) -> None:
        for h, w, _ in self.views:
            h.release()
            w.release()
        self.views = []
        for m in self.maps:
            m.close()
        self.maps = []
        if self.fd >= 0:
            os.close(self.fd)
        self.fd = -1


def _uio_maps(dev: Path) -> tuple[list[int], list[int]]:
    from mechatron.errors import SimulationError
    sysfs = Path("/sys/class/uio") / dev.name / "maps"
    if not sysfs.is_dir():
        raise SimulationError(f"hil io mf624: {dev} is not a UIO device ({sysfs} is "
                              "missing). Load the driver (modprobe uio_mf624) and give "
                              "its /dev/uioN.")
    sizes, offsets = [], []
    for i in range(3):
        d = sysfs / f"map{i}"
        sizes.append(int((d / "size").read_text(), 0))
        offsets.append(int((d / "offset").read_text(), 0) if (d / "offset").exists() else 0)
    return sizes, offsets


class MF624IO(PlantIO):
    """The plant's I/O on an MF624, wired as in the seed's chapter 7.

    - **Command in**: analogue input ``ad_channel`` reads the controller's PWM after the
      RC low-pass; the command is ``volts * ad_gain`` (default ``1 / 3.3``: the duty of a
      3.3 V PWM pin). The card converts on demand, so every step has a fresh command.
    - **Encoder out**: the count (the first sensor value) drives digital outputs
      ``a_bit``/``b_bit`` as the A/B tracks (:func:`quadrature`); the controller's
      quadrature decoder follows only if the count moves by at most one per step.
    - **Analogue out**: ``da`` maps D/A channels to ``(sensor index, volts per unit)``,
      e.g. ``{0: (1, 0.05)}`` puts the speed on DA0 at 50 mV per rad/s.
    - **Encoder in**: :meth:`encoder` reads the card's IRC inputs (for a real motor on
      the card, or to check the wiring by looping DOUT back to an encoder input).

    ``device`` is ``/dev/uioN``, or a file made by :meth:`MF624Registers.fake`.
    """

    kind = "mf624"

    def __init__(self, device: str | os.PathLike = "/dev/uio0", *, ad_channel: int = 0,
                 ad_gain: float = 1 / 3.3, a_bit: int = 0, b_bit: int = 1,
                 da: dict[int, tuple[int, float]] | None = None,
                 registers: MF624Registers | None = None,
                 conversion_polls: int = 10_000) -> None:
        from mechatron.errors import SimulationError
        super().__init__()
        for name, ch, n in (("ad_channel", ad_channel, 8), ("a_bit", a_bit, 8),
                            ("b_bit", b_bit, 8), *(("da", c, 8) for c in (da or {}))):
            if not 0 <= int(ch) < n:
                raise SimulationError(f"hil io mf624: {name} must be in 0..{n - 1}, got "
                                      f"{ch!r}.")
        self.regs = registers or MF624Registers(device)
        self.ad_channel, self.ad_gain = int(ad_channel), float(ad_gain)
        self.a_bit, self.b_bit = int(a_bit), int(b_bit)
        self.da = dict(da or {})
        self.polls = int(conversion_polls)
        self.dout = 0
        self.conversion_timeouts = 0
        # enable the D/A outputs (DACEN, LDAC released), select the A/D channel once
        self.regs.write32(0, GPIOC, GPIOC_BASE | GPIOC_DACEN)
        self.regs.write16(1, ADCTRL, 1 << self.ad_channel)
        self.regs.write16(1, DOUT, 0)

    def write(self, seq, t, sensors) -> None:
        a, b = quadrature(int(sensors[0]))
        self.dout = (self.dout & ~((1 << self.a_bit) | (1 << self.b_bit))
                     | (a << self.a_bit) | (b << self.b_bit))
        self.regs.write16(1, DOUT, self.dout)
        for ch, (i, gain) in self.da.items():
            self.regs.write16(1, DA0 + 2 * ch, volts_to_da(float(sensors[i]) * gain))
        self.stats.sent += 1

    def read(self, seq, deadline) -> Command | None:
        self.regs.read16(1, ADSTART)                   # a read starts the conversion
        for _ in range(self.polls):
            if not self.regs.read32(0, GPIOC) & GPIOC_EOLC:
                break
        else:
            self.conversion_timeouts += 1
            self.stats.lost += 1
            return None
        volts = ad_to_volts(self.regs.read16(1, ADDATA))
        self.stats.received += 1
        return Command(seq, (volts * self.ad_gain,))

    def encoder(self, channel: int = 0) -> int:
        """The signed count of encoder input ``channel`` (0..3)."""
        raw = self.regs.read32(2, IRC0 + 4 * channel)
        return raw - (1 << 32) if raw & 0x80000000 else raw

    def digital_inputs(self) -> int:
        """The 8 digital inputs as one byte."""
        return self.regs.read16(1, DIN) & 0xFF

    def stop(self) -> None:
        for ch in self.da:                               # leave the outputs at 0 V
            self.regs.write16(1, DA0 + 2 * ch, volts_to_da(0.0))

    def close(self) -> None:
        self.regs.close()
