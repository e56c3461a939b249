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

import hashlib
import os
import subprocess
import tempfile
from pathlib import Path

import casadi as ca

from mechatron.solvers.native import cache_dir, compiler

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
        source = cg.dump()
        key = hashlib.sha1((source + " ".join(FLAGS) + cc).encode()).hexdigest()[:16]
        folder = cache_dir() / "jit"
        folder.mkdir(parents=True, exist_ok=True)
        lib = folder / f"{name}_{key}.so"
        if not lib.exists():
            with tempfile.TemporaryDirectory(dir=folder) as tmp:
                src = Path(tmp) / f"{name}.c"
                src.write_text(source)
                out = Path(tmp) / lib.name
                subprocess.run([cc, *FLAGS, str(src), "-o", str(out), "-lm"], check=True,
                               capture_output=True, timeout=300)
                os.replace(out, lib)          # atomic: parallel runs never see half a file
        return ca.external(name, str(lib))
    except (OSError, subprocess.SubprocessError, RuntimeError):
        return fn
