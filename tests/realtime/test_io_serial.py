"""The serial backend against the reference firmware's protocol code compiled for this
machine (mt_fw.c, ctrl_core.c, mt_packet.c and the generated controller, with the host
board layer fw_host.c) over a pseudo-terminal pair; the frame format against an
independent struct/CRC implementation written here."""

import json
import os
import shutil
import struct
import subprocess

import numpy as np
import pytest

from mechatron.realtime.cgen import build_firmware_host
from mechatron.realtime.io import SerialIO, open_io
from mechatron.realtime.io import protocol as pr
from mechatron.realtime.loop import build_loop, run_mil
from mechatron.realtime.plant_loop import run_plant

RATE = 10_000.0


def _crc_ccitt_false(data: bytes) -> int:      # table-free, bit by bit, written here
    crc = 0xFFFF
    for byte in data:
        for bit in range(7, -1, -1):
            top = (crc >> 15) ^ ((byte >> bit) & 1)
            crc = ((crc << 1) & 0xFFFF) ^ (0x1021 if top else 0)
    return crc


def test_frame_format_and_crc():
    assert pr.crc16(b"123456789") == 0x29B1 == _crc_ccitt_false(b"123456789")
    f = pr.frame(pr.Packet(pr.SAMPLE, 77, 12.0, 0.0077))
    assert len(f) == 32 and f[:2] == b"\xa5\x5a"
    assert struct.unpack("<4sBBHIdd", f[2:30]) == (b"MTH1", 1, 0, 0, 77, 12.0, 0.0077)
    assert struct.unpack("<H", f[30:])[0] == _crc_ccitt_false(f[2:30])


def test_parser_resynchronises_and_counts_bad_frames():
    good = [pr.frame(pr.Packet(pr.COMMAND, k, 0.5 + k, -1.0)) for k in range(3)]
    bad = bytearray(good[1])
    bad[12] ^= 0x40
    p = pr.FrameParser()
    got = []
    stream = b"\x00\xa5" + good[0] + bytes(bad) + b"\xa5\x5a\x01" + good[2]
    for i in range(0, len(stream), 5):            # arriving in pieces
        got += p.feed(stream[i:i + 5])
    assert [(q.seq, q.a) for q in got] == [(0, 0.5), (2, 2.5)]
    assert p.bad_frames >= 1


needs_cc = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc)")


@pytest.fixture(scope="module")
def firmware(tmp_path_factory):
    loop = build_loop("speed", rate=RATE)
    return loop, build_firmware_host(loop, tmp_path_factory.mktemp("fw"))


class DroppingSerial(SerialIO):
    """Drops the samples of some steps on the way out (a lossy line)."""

    def __init__(self, *a, drop=(), **kw):
        super().__init__(*a, **kw)
        self.drop = set(drop)

    def write(self, seq, t, sensors):
        if seq in self.drop:
            self.stats.sent += 1
            self.stats.dropped_on_purpose += 1
            return
        super().write(seq, t, sensors)


def _run(firmware, tmp_path, steps, drop=()):
    loop, exe = firmware
    master, slave = os.openpty()
    stats = tmp_path / "fw.json"
    fw = subprocess.Popen([str(exe), "--tty", os.ttyname(slave), "--rate", "20000",
                           "--stats", str(stats)])
    try:
        io = DroppingSerial(fd=master, drop=drop)
        # lockstep: the plant waits up to 0.5 s for each reply (the firmware ticks at
        # 20 kHz); a sample that never went out costs its step that wait, never a stall
        out = run_plant(io, loop, rate=RATE, duration=steps / RATE, lockstep=0.5)
        assert fw.wait(timeout=20) == 0
    finally:
        if fw.poll() is None:
            fw.kill()
        os.close(slave)
        io.close()
    return out, json.loads(stats.read_text())


@needs_cc
def test_serial_plant_and_firmware_core_reproduce_mil(firmware, tmp_path):
    """No sample lost: the firmware's controller answers every step, and the run equals
    MIL (the same generated controller and plant functions) to rounding, through the
    reference step at 0.05 s."""
    loop, _ = firmware
    steps = 700
    out, fw = _run(firmware, tmp_path, steps)
    s, log = out["stats"], out["log"]
    assert s["received"] == steps and s["lost"] == 0 and s["bad_frames"] == 0
    assert fw["samples"] == steps and fw["lost_samples"] == 0 and fw["stopped"] is True
    mil = run_mil(loop, steps)
    np.testing.assert_allclose(log["duty"], mil["duty"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(log["w"], mil["w"], rtol=0, atol=1e-9)
    assert mil["w"][-1] > 5.0                  # the loop moved the motor


@needs_cc
def test_lost_samples_are_reported_on_both_sides_and_never_stall(firmware, tmp_path):
    steps, drop = 300, {40, 41, 150, 299}
    out, fw = _run(firmware, tmp_path, steps, drop=drop)
    s, log = out["stats"], out["log"]
    assert s["steps"] == steps                          # the run went to its end
    assert s["lost"] == len(drop) and s["received"] == steps - len(drop)
    assert s["dropped_on_purpose"] == len(drop)
    assert np.all(log["got"][sorted(drop)] == 0)
    k = 41
    assert log["duty"][k] == log["duty"][k - 2]         # the previous command held
    # the firmware saw the gaps in the sequence numbers and filled them in (the last
    # dropped one, 299, had no later sample to reveal it)
    assert fw["lost_samples"] == len(drop) - 1 and fw["samples"] == steps - len(drop)


def test_open_io_names_the_backends():
    from mechatron.errors import SimulationError
    with pytest.raises(SimulationError, match="unknown backend 'can'.*sim, udp, serial"):
        open_io("can")
    with pytest.raises(SimulationError, match="cannot open /nonexistent/tty"):
        open_io("serial", tty_path="/nonexistent/tty")
