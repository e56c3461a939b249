"""Optional native compilation of the per-sample step functions, with a disk cache.

CasADi's virtual machine runs a Radau substep of a small model in some 10 us; compiled C
runs it ten times faster. When a C compiler is on the PATH, :func:`native` generates C
for a function (``Function.generate`` machinery), compiles it once into a shared library
kept in the cache directory (``$MECHATRON_CACHE`` or ``~/.cache/mechatron``; the file name
holds a hash of the C source and flags, so a changed model or method compiles anew), and
loads it with ``casadi.external``. Without a compiler, or if compiling fails, the
function is returned unchanged: results are the same, only slower.

Compiling costs about as much as some 36,000 interpreted calls of the same function,
whatever its size (both grow with its instructions); a function with many substeps
unrolled can take minutes to compile. :func:`native` therefore estimates the build time
from the function's instruction count first (:func:`build_estimate`) and runs a function
whose build would exceed :data:`MAX_BUILD_S` interpreted, with a warning that says so
(``$MECHATRON_JIT_MAX_BUILD_S`` sets the limit, 0 lifts it).
"""

from __future__ import annotations

import logging
import os

import casadi as ca

from mechatron.solvers.native import BuildError, build_library, cache_dir, compiler

__all__ = ["native", "compiler", "cache_dir", "build_estimate", "MAX_BUILD_S"]

log = logging.getLogger(__name__)

FLAGS = ("-O1", "-fPIC", "-shared")

#: The longest estimated build (s) :func:`native` starts; a larger function runs
#: interpreted. ``$MECHATRON_JIT_MAX_BUILD_S`` overrides it (0: no limit).
MAX_BUILD_S = 20.0

#: Generated C per instruction of an SX function, and the rate ``cc -O1`` compiles it
#: (measured on the estimation's step functions: 472 kB for 21,626 instructions, built
#: in 7 s; 710 kB for 33,429 in 11 s).
BYTES_PER_INSTRUCTION = 22.0
BYTES_PER_SECOND = 65e3


def build_estimate(fn: ca.Function) -> tuple[float, float]:
    """``(bytes of C, seconds to compile)`` expected for ``fn``, from its instruction
    count (its node count for an MX function), before any C is generated."""
    try:
        n = fn.n_instructions()
    except RuntimeError:
        n = fn.n_nodes()
    size = 4000.0 + BYTES_PER_INSTRUCTION * n
    return size, size / BYTES_PER_SECOND


def _limit() -> float:
    text = os.environ.get("MECHATRON_JIT_MAX_BUILD_S")
    try:
        return MAX_BUILD_S if text is None else float(text)
    except ValueError:
        return MAX_BUILD_S


def native(fn: ca.Function) -> ca.Function:
    """``fn`` compiled to native code (cached), or ``fn`` itself if that is not possible
    or its build would take longer than :data:`MAX_BUILD_S` (see the module)."""
    cc = compiler()
    if cc is None:
        return fn
    name = fn.name()
    size, seconds = build_estimate(fn)
    limit = _limit()
    if limit > 0 and seconds > limit:
        log.warning("%s: compiling its %.2g MB of C would take about %.0f s (limit %g s); "
                    "it runs interpreted instead (same results, slower). Fewer substeps "
                    "make it smaller; MECHATRON_JIT_MAX_BUILD_S=0 compiles it anyway.",
                    name, size / 1e6, seconds, limit)
        return fn
    try:
        cg = ca.CodeGenerator(f"{name}.c", {"with_header": False})
        cg.add(fn)
        lib = build_library(cg.dump(), name, "jit", FLAGS, cc)
        return ca.external(name, str(lib))
    except (BuildError, RuntimeError):
        return fn
