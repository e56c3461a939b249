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

Python's own arenas (``kept_heap(arenas=True)``, asked for by the compile of a model of
`ARENAS_FROM` elements or more). CPython's allocator of small objects takes memory from
the kernel in arenas of 1 MiB and hands an arena back as soon as its last object is
freed: the compile of the RC ladder of 100000 sections maps 1256 arenas and hands 918 of
them back while it runs, so that most of the memory its passes free is faulted in and
zeroed by the kernel once more when the next pass allocates. A small allocator in C
(``arenas.c``, built once with the C compiler of the compiled solvers into the cache
folder and installed in front of CPython's own, see `_arena_helper`) lists the arenas
handed back within the block and gives them out again, and hands them all back after
it: 104 000 page faults and 1.2 s fewer at N = 100000 (23.2 s against 24.4 s), none of
either at N = 1000. No compiler, another Python than CPython, or a build that fails: the
arenas are left to CPython, as before.
"""

from __future__ import annotations

import ctypes
import os
import sys
import threading
from contextlib import contextmanager
from importlib import resources

__all__ = ["kept_heap", "ARENAS_FROM"]

#: elements (components and ports) from which a compile keeps Python's arenas
ARENAS_FROM = 20000

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
_arenas: ctypes.PyDLL | None | bool = False   # the arena helper; False: not built yet
_keeping = False                              # whether the helper keeps arenas now


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


class _ArenaAllocator(ctypes.Structure):
    """CPython's ``PyObjectArenaAllocator``: a context and two functions."""
    _fields_ = [("ctx", ctypes.c_void_p), ("alloc", ctypes.c_void_p),
                ("free", ctypes.c_void_p)]


def _arena_helper() -> ctypes.PyDLL | None:
    """The allocator of `arenas.c` installed in front of CPython's arena allocator (once
    per process; it hands everything on until told to keep), or None where it cannot be:
    ``MECHATRON_KEEP_HEAP=0``, another Python than CPython, no C compiler, or a build or
    load that fails. Built on first use like the compiled solvers (cached by its
    source)."""
    global _arenas
    if _arenas is not False:
        return _arenas
    _arenas = None
    if os.environ.get("MECHATRON_KEEP_HEAP", "1") == "0" or \
            sys.implementation.name != "cpython":
        return None
    try:
        api = ctypes.pythonapi
        get, put = api.PyObject_GetArenaAllocator, api.PyObject_SetArenaAllocator
    except AttributeError:
        return None
    from mechatron.solvers.native import FLAGS, BuildError, build_library, compiler
    cc = compiler()
    if cc is None:
        return None
    source = resources.files("mechatron.compiler").joinpath("arenas.c").read_text()
    try:
        lib = ctypes.PyDLL(str(build_library(source, "arenas", "helpers", FLAGS, cc)))
        chain, keep, release, counts = (lib.mt_arenas_chain, lib.mt_arenas_keep,
                                        lib.mt_arenas_release, lib.mt_arenas_counts)
    except (BuildError, OSError, AttributeError):
        return None
    pointer = ctypes.POINTER(_ArenaAllocator)
    get.argtypes, get.restype = [pointer], None
    put.argtypes, put.restype = [pointer], None
    chain.argtypes, chain.restype = [pointer, pointer], None
    keep.argtypes, keep.restype = [ctypes.c_int], None
    release.argtypes, release.restype = [], ctypes.c_size_t
    counts.argtypes, counts.restype = [ctypes.POINTER(ctypes.c_size_t * 3)], None
    previous, ours = _ArenaAllocator(), _ArenaAllocator()
    get(ctypes.byref(previous))
    chain(ctypes.byref(previous), ctypes.byref(ours))
    put(ctypes.byref(ours))
    _arenas = lib
    return lib


def arena_counts() -> dict[str, int] | None:
    """The arena helper's counts (None if it is not installed): arenas ``listed`` now,
    ``reused`` from the list and ``asked`` for by CPython since it was installed."""
    lib = _arenas or None
    if lib is None:
        return None
    out = (ctypes.c_size_t * 3)()
    lib.mt_arenas_counts(ctypes.byref(out))
    return {"listed": out[0], "reused": out[1], "asked": out[2]}


@contextmanager
def kept_heap(arenas: bool = False):
    """Within the block, glibc neither maps blocks of their own nor trims its heap, and
    with ``arenas`` Python's arenas handed back are kept for reuse; after the last block
    ends, the memory freed is handed back (see the module's docstring)."""
    global _depth, _keeping
    lib = _glibc()
    helper = _arena_helper() if arenas else None
    if lib is None and helper is None:
        yield
        return
    with _lock:
        _depth += 1
        if _depth == 1 and lib is not None:
            lib.mallopt(_M_MMAP_MAX, 0)
            lib.mallopt(_M_TRIM_THRESHOLD, _KEEP_TRIM)
        if helper is not None and not _keeping:
            helper.mt_arenas_keep(1)
            _keeping = True
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0:
                if _keeping:
                    _arenas.mt_arenas_keep(0)
                    _arenas.mt_arenas_release()
                    _keeping = False
                if lib is not None:
                    lib.mallopt(_M_MMAP_MAX, _MMAP_MAX)
                    lib.mallopt(_M_MMAP_THRESHOLD, _MMAP_THRESHOLD)
                    lib.mallopt(_M_TRIM_THRESHOLD, _TRIM_THRESHOLD)
                    if lib.mallinfo2().fordblks > _TRIM_THRESHOLD:
                        lib.malloc_trim(0)
