"""Optional native compilation of the per-sample step functions, with a disk cache.

CasADi's virtual machine runs a Radau substep of a small model in some 10 us; compiled C
runs it ten times faster. When a C compiler is on the PATH, :func:`native` generates C
for a function (``Function.generate`` machinery), compiles it once into a shared library
kept in the cache directory (``$MECHATRON_CACHE`` or ``~/.cache/mechatron``; the file name
holds a hash of the C source and flags, so a changed model or method compiles anew), and
loads it with ``casadi.external``. Without a compiler, or if compiling fails, the
function is returned unchanged: results are the same, only slower.
"""

from __future__ import annotations

import casadi as ca

from mechatron.solvers.native import BuildError, build_library, cache_dir, compiler

__all__ = ["native", "compiler", "cache_dir"]

FLAGS = ("-O1", "-fPIC", "-shared")


def native(fn: ca.Function) -> ca.Function:
    """``fn`` compiled to native code (cached), or ``fn`` itself if that is not possible."""
    cc = compiler()
    if cc is None:
        return fn
    name = fn.name()
    try:
        cg = ca.CodeGenerator(f"{name}.c", {"with_header": False})
        cg.add(fn)
        lib = build_library(cg.dump(), name, "jit", FLAGS, cc)
        return ca.external(name, str(lib))
    except (BuildError, RuntimeError):
        return fn
