"""The C heap kept in the process while a compile runs (glibc only).

A compile of 10^5 equations frees and allocates again hundreds of megabytes of C memory
(CasADi's expression graphs and the work vectors of the functions formed over them).
glibc hands freed memory at the top of its heap back to the kernel once more than its
trim threshold is free there, and serves blocks above its mmap threshold (at most
32 MiB) by mappings of their own, unmapped when freed; under its default, dynamic
thresholds, the compile of the RC ladder of 100000 sections grows the heap by 530 MB
more than its peak (memory trimmed and taken again) and maps 240 MB afresh, each page
a fault of the kernel's on first touch. `kept_heap` turns both off for the length of
a compile (no mapping of its own for any block, no trimming), hands the memory the
compile freed back afterwards when more than the trim threshold below is free
(``malloc_trim``: a small compile's few megabytes stay for the next), and leaves the
thresholds where glibc's dynamic rule settles once a process has freed a block of
32 MiB: mappings for blocks from 32 MiB, trimming above 64 MiB free. (Setting any
threshold ends the dynamic rule for the process; a process that compiles a large model
reaches these values under it anyway.)

Nothing is changed when the C library is not glibc, when ``GLIBC_TUNABLES`` or the
``MALLOC_*_`` variables already tune malloc (the user's choice stands), or when
``MECHATRON_KEEP_HEAP=0``. Compiles may nest or run in threads: the first to enter sets
the options, the last to leave restores them.
"""

from __future__ import annotations

import ctypes
import os
import threading
from contextlib import contextmanager

__all__ = ["kept_heap"]

# mallopt parameters (glibc's malloc.h)
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
_M_MMAP_MAX = -4

_KEEP_TRIM = 2**31 - 1          # mallopt takes an int: 2 GiB free at the top, at most
_MMAP_MAX = 65536               # glibc's default number of mappings of its own
_MMAP_THRESHOLD = 32 << 20      # where the dynamic rule stops (64-bit glibc)
_TRIM_THRESHOLD = 2 * _MMAP_THRESHOLD

_lock = threading.Lock()
_depth = 0
_libc: ctypes.CDLL | None | bool = False      # False: not looked up yet


def _glibc() -> ctypes.CDLL | None:
    """The C library if it is glibc and malloc is left to its defaults, else None."""
    global _libc
    if _libc is not False:
        return _libc
    _libc = None
    if os.environ.get("MECHATRON_KEEP_HEAP", "1") == "0":
        return None
    if "glibc.malloc" in os.environ.get("GLIBC_TUNABLES", "") or any(
            key.startswith("MALLOC_") and key.endswith("_") for key in os.environ):
        return None
    try:
        version = os.confstr("CS_GNU_LIBC_VERSION") or ""
    except (AttributeError, ValueError, OSError):       # not a GNU system
        version = ""
    if not version.startswith("glibc"):
        return None
    try:
        lib = ctypes.CDLL(None)
        mallopt, trim, info = lib.mallopt, lib.malloc_trim, lib.mallinfo2
    except (OSError, AttributeError):      # (mallinfo2: glibc 2.33 on)
        return None
    mallopt.argtypes, mallopt.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    trim.argtypes, trim.restype = [ctypes.c_size_t], ctypes.c_int
    info.argtypes, info.restype = [], _MallInfo2
    _libc = lib
    return lib


class _MallInfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in (
        "arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks",
        "uordblks", "fordblks", "keepcost")]


@contextmanager
def kept_heap():
    """Within the block, glibc neither maps blocks of their own nor trims its heap;
    after it, the memory freed is handed back (see the module's docstring)."""
    global _depth
    lib = _glibc()
    if lib is None:
        yield
        return
    with _lock:
        _depth += 1
        if _depth == 1:
            lib.mallopt(_M_MMAP_MAX, 0)
            lib.mallopt(_M_TRIM_THRESHOLD, _KEEP_TRIM)
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0:
                lib.mallopt(_M_MMAP_MAX, _MMAP_MAX)
                lib.mallopt(_M_MMAP_THRESHOLD, _MMAP_THRESHOLD)
                lib.mallopt(_M_TRIM_THRESHOLD, _TRIM_THRESHOLD)
                if lib.mallinfo2().fordblks > _TRIM_THRESHOLD:
                    lib.malloc_trim(0)
