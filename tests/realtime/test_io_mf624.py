"""The MF624 backend against a file-backed fake register map laid out as the UIO device
(map i at i * page size): register offsets and conversions as the card's manual gives
them, written here independently of the backend."""

import mmap
import struct

import numpy as np
import pytest

from mechatron.errors import SimulationError
from mechatron.realtime.io import MF624IO, MF624Registers
from mechatron.realtime.loop import build_loop
from mechatron.realtime.plant_loop import run_plant

PAGE = mmap.PAGESIZE
BAR0, BAR2, BAR4 = 0, PAGE, 2 * PAGE       # file offsets of the three maps


class Card:
    """The card's side, reading and writing the file directly."""

    def __init__(self, path):
        self.path = path

    def _rw(self, off, fmt, value=None):
        with open(self.path, "r+b") as f:
            f.seek(off)
            if value is None:
                return struct.unpack(fmt, f.read(struct.calcsize(fmt)))[0]
            f.write(struct.pack(fmt, value))

    def set_ad(self, volts):                 # 14-bit two's complement, +-10 V, in bits 0-13
        code = int(round(volts / 10.0 * 8192)) & 0x3FFF
        self._rw(BAR2 + 0x00, "<H", code)

    def dout(self):
        return self._rw(BAR2 + 0x10, "<H")

    def da_volts(self, ch):                  # 14-bit offset binary, 0 = -10 V
        return self._rw(BAR2 + 0x20 + 2 * ch, "<H") * 20.0 / 0x4000 - 10.0

    def gpioc(self):
        return self._rw(BAR0 + 0x54, "<I")

    def set_gpioc(self, v):
        self._rw(BAR0 + 0x54, "<I", v)

    def set_irc(self, ch, count):
        self._rw(BAR4 + 0x70 + 4 * ch, "<i", count)


@pytest.fixture
def card(tmp_path):
    path = tmp_path / "mf624.regs"
    regs = MF624Registers.fake(path)
    io = MF624IO(registers=regs, ad_channel=0, a_bit=0, b_bit=1, da={1: (1, 0.05)})
    yield io, Card(path)
    io.close()


def test_analogue_in_digital_and_analogue_out(card):
    io, c = card
    assert c.gpioc() & (1 << 26) and not c.gpioc() & (1 << 23)     # DACEN on, LDAC off
    for volts in (0.0, 1.65, 3.3, -2.5, 9.99):
        c.set_ad(volts)
        cmd = io.read(0, 0.0)
        assert cmd.values[0] == pytest.approx(volts / 3.3, abs=10 / 8192 / 3.3)
    # the count drives A (bit 0) and B (bit 1) in quadrature: A leads B counting up
    seen = []
    for count in range(-2, 7):
        io.write(count, 0.0, [count, 40.0])
        seen.append(c.dout() & 3)
    assert seen == [0b11, 0b10, 0b00, 0b01, 0b11, 0b10, 0b00, 0b01, 0b11]
    for prev, nxt in zip(seen, seen[1:]):          # exactly one track changes per count
        assert bin(prev ^ nxt).count("1") == 1
    assert c.da_volts(1) == pytest.approx(40.0 * 0.05, abs=20 / 0x4000)   # 2 V on DA1
    io.write(0, 0.0, [0, 500.0])                   # 25 V asks for more than the card has
    assert c.da_volts(1) == pytest.approx(10.0, abs=2 * 20 / 0x4000)
    io.stop()
    assert c.da_volts(1) == pytest.approx(0.0, abs=20 / 0x4000)


def test_encoder_inputs_are_signed_counts(card):
    io, c = card
    c.set_irc(0, 123456)
    c.set_irc(3, -789)
    assert io.encoder(0) == 123456 and io.encoder(3) == -789


def test_a_conversion_that_never_ends_is_a_lost_sample_not_a_stall(card):
    io, c = card
    io.polls = 50
    c.set_gpioc(c.gpioc() | (1 << 17))            # EOLC stays set: converting forever
    assert io.read(5, 0.0) is None
    assert io.stats.lost == 1 and io.conversion_timeouts == 1


def test_open_loop_plant_on_the_fake_card_matches_the_desktop_step(card):
    """The plant loop over the card: a constant 2.475 V on AD0 is a duty of 0.75; the
    plant then runs open loop, and its log equals the desktop step function's run."""
    io, c = card
    volts = 0.75 * 3.3
    c.set_ad(volts)
    duty = io.read(0, 0.0).values[0]               # the quantized duty the plant sees
    loop = build_loop("speed", rate=2000.0)
    out = run_plant(io, loop, rate=2000.0, duration=0.05, lockstep=0.01)
    x = loop.x0.copy()
    w = []
    for k in range(100):
        w.append(float(np.array(loop.plant_out(x)).ravel()[1]))
        x = np.array(loop.plant_step(x, duty, k)).ravel()
    np.testing.assert_allclose(out["log"]["w"], w, rtol=1e-12, atol=1e-12)
    assert np.all(out["log"]["duty"] == duty) and out["stats"]["lost"] == 0
    assert w[-1] > 1.0


def test_bad_channel_and_missing_device_are_clear_errors(tmp_path):
    with pytest.raises(SimulationError, match="ad_channel must be in 0..7, got 9"):
        MF624IO(registers=MF624Registers.fake(tmp_path / "r"), ad_channel=9)
    with pytest.raises(SimulationError, match="not a UIO device.*modprobe uio_mf624"):
        MF624IO("/dev/uio_nosuch")
