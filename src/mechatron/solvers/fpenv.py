"""Subnormal numbers flushed to zero while a solver runs.

A network that carries a signal along thousands of parts (an RC ladder, a long chain of
masses) keeps most of its far states at values below the smallest normal double
(2.2e-308) for the whole run: an implicit step spreads every change along the chain, and
gradual underflow holds the far values at subnormal magnitudes instead of zero. On many
processors (Intel's among them) each arithmetic operation on a subnormal operand takes
around a hundred cycles instead of a few, so the same run is several times slower on one
machine than on another (RC ladder of 10000 sections: 0.69 s against 0.10 s). No physical
quantity in a simulation means anything at 1e-308, so while a solver runs Mechatron sets
the processor's flush-to-zero and subnormals-are-zero modes, as real-time targets and
compilers' fast-math modes do, and restores the caller's floating-point environment
afterwards (also when the run raises).

The modes are set through the C library's ``fegetenv``/``fesetenv`` with the layout of
``fenv_t`` that glibc documents for x86-64 (the SSE control register ``MXCSR``: FTZ bit 15,
DAZ bit 6) and AArch64 (``FPCR``: FZ bit 24). Elsewhere (another C library or processor),
or where the mode does not read back as set, :func:`flushing_available` is False and the
solvers run with the environment as they find it: the same values, at that processor's
speed on subnormals.
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import functools
import platform
import sys

__all__ = ["subnormals_flushed", "subnormals_kept", "flushing_available"]

#: Per machine: the size of ``fenv_t`` in 32-bit words, the index of the control word
#: among them, and the bits that flush subnormal results and operands to zero.
_LAYOUTS = {
    "x86_64": (8, 7, 0x8000 | 0x0040),     # MXCSR (byte 28): FTZ | DAZ
    "aarch64": (2, 0, 1 << 24),            # FPCR (byte 0): FZ, for inputs and results
}


class _Environment:
    """The C library's floating-point environment functions, and the flush bits."""

    def __init__(self, libm: ctypes.CDLL, words: int, index: int, bits: int):
        self._get, self._set = libm.fegetenv, libm.fesetenv
        self._get.argtypes = self._set.argtypes = [ctypes.c_void_p]
        self._get.restype = self._set.restype = ctypes.c_int
        self._type = ctypes.c_uint32 * words
        self._index, self._bits = index, bits

    def read(self) -> ctypes.Array:
        env = self._type()
        if self._get(env) != 0:
            raise OSError("fegetenv failed")
        return env

    def write(self, env: ctypes.Array) -> None:
        if self._set(env) != 0:
            raise OSError("fesetenv failed")

    def flushing(self, env: ctypes.Array) -> bool:
        return env[self._index] & self._bits == self._bits

    def keeping(self, env: ctypes.Array) -> bool:
        return env[self._index] & self._bits == 0

    def flushed(self, env: ctypes.Array, flush: bool = True) -> ctypes.Array:
        """A copy of ``env`` with the flush bits set (``flush``) or cleared."""
        out = self._type.from_buffer_copy(env)
        out[self._index] = (out[self._index] | self._bits if flush
                            else out[self._index] & ~self._bits)
        return out


@functools.cache
def _environment() -> _Environment | None:
    """The environment functions where the layout is known and setting the bits reads
    back as set (checked once, the caller's environment restored), else None."""
    layout = _LAYOUTS.get(platform.machine().lower())
    if layout is None or sys.platform != "linux" or platform.libc_ver()[0] != "glibc":
        return None
    try:
        env = _Environment(ctypes.CDLL(ctypes.util.find_library("m") or "libm.so.6"),
                           *layout)
        saved = env.read()
        try:
            env.write(env.flushed(saved))
            works = env.flushing(env.read())
        finally:
            env.write(saved)
    except (OSError, AttributeError):
        return None
    return env if works else None


def flushing_available() -> bool:
    """Whether :func:`subnormals_flushed` sets the flush-to-zero modes on this machine."""
    return _environment() is not None


class _SubnormalMode(contextlib.ContextDecorator):
    """Within the block (or the decorated function), this thread's floating-point
    arithmetic flushes subnormal operands and results to zero (``FLUSH``) or keeps them
    (IEEE 754's gradual underflow); the environment before it is restored after it. A
    caller already in that mode is left as it is, so blocks nest."""

    FLUSH = True

    def _recreate_cm(self):
        return type(self)()     # one per call: calls may nest or run in threads

    def __enter__(self):
        env = _environment()
        self._saved = None
        if env is not None:
            saved = env.read()
            if not (env.flushing(saved) if self.FLUSH else env.keeping(saved)):
                env.write(env.flushed(saved, self.FLUSH))
                self._saved = saved
        return self

    def __exit__(self, *exc):
        if self._saved is not None:
            _environment().write(self._saved)
            self._saved = None
        return False


class subnormals_flushed(_SubnormalMode):
    """Subnormal numbers taken as zero within the block: the solvers' integration."""


class subnormals_kept(_SubnormalMode):
    """Subnormal numbers kept within the block, whatever the caller's mode: consistent
    initialization, whose interior-point solver (IPOPT) has been seen to fail its
    restoration phase on a diode's exponential when they are flushed."""

    FLUSH = False
