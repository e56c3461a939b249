"""The bridge: packet format (independent struct implementation), CRC and stream framing
(ctypes on mt_packet.c), sequence numbers, missed/late counting of the plant runner."""

import ctypes
import json
import shutil
import socket
import struct
import subprocess

import numpy as np
import pytest

from mechatron.realtime.cgen import C_DIR, build_host
from mechatron.realtime.hil import RUNNER_COLUMNS, _read_log
from mechatron.realtime.loop import build_loop

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc)")

FMT = "<4sBBHIdd"            # docs/hil.md: magic, type, flags, reserved, seq, a, b
SAMPLE, COMMAND, HELLO, STOP = 1, 2, 3, 4


class Packet(ctypes.Structure):
    _fields_ = [("type", ctypes.c_uint8), ("flags", ctypes.c_uint8),
                ("seq", ctypes.c_uint32), ("a", ctypes.c_double), ("b", ctypes.c_double)]


class Parser(ctypes.Structure):
    _fields_ = [("buf", ctypes.c_uint8 * 32), ("n", ctypes.c_int),
                ("bad_frames", ctypes.c_uint32)]


@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    d = tmp_path_factory.mktemp("pkt")
    so = d / "libmtpacket.so"
    subprocess.run(["cc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-shared", "-fPIC",
                    "-o", str(so), str(C_DIR / "mt_packet.c")], check=True)
    lib = ctypes.CDLL(str(so))
    lib.mt_crc16.restype = ctypes.c_uint16
    return lib


def test_crc16_ccitt_false_check_value(lib):
    data = b"123456789"
    assert lib.mt_crc16(data, len(data)) == 0x29B1      # the catalogued check value


def test_packet_layout_matches_the_documented_format(lib):
    p = Packet(COMMAND, 1, 123456, 0.625, -3.5)
    buf = (ctypes.c_uint8 * 32)()
    lib.mt_frame_encode(ctypes.byref(p), buf)
    raw = bytes(buf)
    assert raw[:2] == b"\xa5\x5a"
    assert struct.unpack(FMT, raw[2:30]) == (b"MTH1", COMMAND, 1, 0, 123456, 0.625, -3.5)
    assert struct.unpack("<H", raw[30:32])[0] == lib.mt_crc16(raw[2:30], 28)


def test_frame_parser_resynchronises_after_garbage_and_corruption(lib):
    frames = []
    for seq in range(3):
        buf = (ctypes.c_uint8 * 32)()
        lib.mt_frame_encode(ctypes.byref(Packet(SAMPLE, 0, seq, seq * 1.5, 0.0)), buf)
        frames.append(bytearray(bytes(buf)))
    frames[1][10] ^= 0xFF                                   # corrupt the middle frame
    stream = b"\x00\xa5\x13" + bytes(frames[0]) + b"\xa5" + bytes(frames[1]) \
        + bytes(frames[2])
    parser = Parser()
    lib.mt_frame_parser_init(ctypes.byref(parser))
    got = []
    out = Packet()
    for b in stream:
        if lib.mt_frame_feed(ctypes.byref(parser), ctypes.c_uint8(b), ctypes.byref(out)):
            got.append((out.seq, out.a))
    assert got == [(0, 0.0), (2, 3.0)]
    assert parser.bad_frames >= 1


def _pk(type_, seq, a, b=0.0):
    return struct.pack(FMT, b"MTH1", type_, 0, 0, seq, a, b)


def test_plant_counts_missed_and_late_replies_and_holds_the_duty(tmp_path):
    """A controller written in Python (struct, per the documented format) skips some
    replies and answers one late; the runner must count them and hold the duty."""
    exes = build_host(build_loop("speed", rate=100.0), tmp_path)
    steps = 60
    plant = subprocess.Popen([str(exes["plant"]), "--rate", "100", "--steps", str(steps),
                              "--transport", "udp", "--wait", "0.9",
                              "--log", str(tmp_path / "log.bin"),
                              "--stats", str(tmp_path / "stats.json")],
                             stdout=subprocess.PIPE, text=True)
    try:
        kind, port = plant.stdout.readline().split()[1:]
        assert kind == "udp"
        s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        s.bind(("127.0.0.1", 0))
        s.settimeout(5)
        s.sendto(_pk(HELLO, 0, 0.0), ("127.0.0.1", int(port)))
        skip, late = {10, 20, 30}, 40
        seen = []
        while True:
            data, addr = s.recvfrom(64)
            magic, typ, _, _, seq, a, b = struct.unpack(FMT, data)
            assert magic == b"MTH1"
            if typ == STOP:
                break
            assert typ == SAMPLE and b == pytest.approx(seq / 100.0)
            seen.append(seq)
            if seq in skip or seq == late:
                continue
            if seq == late + 1:                  # the reply to 40 arrives after its step
                s.sendto(_pk(COMMAND, late, 0.9), addr)
            s.sendto(_pk(COMMAND, seq, 0.5 + seq * 1e-3, 7.0), addr)
        plant.wait(timeout=10)
    finally:
        if plant.poll() is None:
            plant.kill()
    assert seen == list(range(steps))           # sequence numbers 0, 1, 2, ... in order
    stats = json.loads((tmp_path / "stats.json").read_text())
    log = _read_log(tmp_path / "log.bin")
    assert stats["steps"] == steps and stats["columns"] == list(RUNNER_COLUMNS)
    for k in skip | {late}:
        assert log["got"][k] == 0
        assert log["duty"][k] == pytest.approx(log["duty"][k - 1])     # duty held
    assert stats["missed_steps"] >= 4 and stats["late_packets"] >= 1
    assert stats["lost_packets"] == stats["missed_steps"] - stats["late_packets"]
    ok = log["got"] == 1
    np.testing.assert_allclose(log["duty"][ok], 0.5 + np.arange(steps)[ok] * 1e-3)
    assert np.all(log["ref"][ok] == 7.0)
