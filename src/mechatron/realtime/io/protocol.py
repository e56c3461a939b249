"""The bridge's packet and frame format in Python (the C side: ``templates/c/mt_packet.h``).

A packet is 28 bytes, little-endian: magic ``MTH1``, type, flags, 2 reserved bytes,
``seq`` (uint32, the plant's step), ``a`` and ``b`` (float64). A SAMPLE carries the
encoder count in ``a`` and the plant's timestamp ``t_k`` in ``b``; a COMMAND the duty and
the controller's reference. On a byte stream a packet travels in a 32-byte frame: sync
``A5 5A``, the packet, its CRC-16/CCITT-FALSE (polynomial 0x1021, initial value 0xFFFF),
low byte first.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

__all__ = ["SAMPLE", "COMMAND", "HELLO", "STOP", "Packet", "encode", "decode", "frame",
           "crc16", "FrameParser", "PACKET_SIZE", "FRAME_SIZE"]

SAMPLE, COMMAND, HELLO, STOP = 1, 2, 3, 4
PACKET_SIZE, FRAME_SIZE = 28, 32
SYNC = b"\xa5\x5a"
_FMT = struct.Struct("<4sBBHIdd")
MAGIC = b"MTH1"


@dataclass(frozen=True)
class Packet:
    type: int
    seq: int
    a: float = 0.0
    b: float = 0.0
    flags: int = 0


def encode(p: Packet) -> bytes:
    """The 28 bytes of ``p``."""
    return _FMT.pack(MAGIC, p.type, p.flags, 0, p.seq & 0xFFFFFFFF, p.a, p.b)


def decode(raw: bytes) -> Packet | None:
    """The packet in 28 bytes, or None if the length or the magic is wrong."""
    if len(raw) != PACKET_SIZE:
        return None
    magic, typ, flags, _, seq, a, b = _FMT.unpack(raw)
    if magic != MAGIC:
        return None
    return Packet(typ, seq, a, b, flags)


def crc16(data: bytes) -> int:
    """CRC-16/CCITT-FALSE (check value of ``b"123456789"``: 0x29B1)."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc


def frame(p: Packet) -> bytes:
    """The 32-byte stream frame of ``p``."""
    body = encode(p)
    return SYNC + body + struct.pack("<H", crc16(body))


class FrameParser:
    """Finds frames in a byte stream; resynchronises on the next ``A5 5A`` after a bad
    frame and counts the bad ones."""

    def __init__(self) -> None:
        self.buf = bytearray()
        self.bad_frames = 0

    def feed(self, data: bytes) -> list[Packet]:
        """The packets completed by ``data``."""
        self.buf += data
        out = []
        while True:
            i = self.buf.find(SYNC)
            if i < 0:
                del self.buf[:max(len(self.buf) - 1, 0)]   # keep a trailing A5
                return out
            del self.buf[:i]
            if len(self.buf) < FRAME_SIZE:
                return out
            body = bytes(self.buf[2:2 + PACKET_SIZE])
            (crc,) = struct.unpack("<H", self.buf[2 + PACKET_SIZE:FRAME_SIZE])
            p = decode(body) if crc == crc16(body) else None
            if p is None:
                self.bad_frames += 1
                del self.buf[:1]          # look for the next sync inside this frame
                continue
            del self.buf[:FRAME_SIZE]
            out.append(p)
