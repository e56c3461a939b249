"""The compiled variable-step solver ``"rodas4"``: model and integrator as one C library.

CasADi's SUNDIALS interface pays a fixed cost per step (its virtual machine evaluates the
model, its linear solver plug-in factorizes) that dominates small models: a two-state DC
motor spends about 2.5 us per CVODES step. Here CasADi generates C for the model's state
derivative, its Jacobian and time derivative, and every logged variable; the Rosenbrock
integrator of ``rodas4.c`` (Rodas4, L-stable, order 4 with an embedded order-3 estimate,
step-size control on the RMS error weighted by ``atol + rtol |x|``) is appended, and the
whole translation unit is compiled once with the system C compiler into a shared library
kept in the cache directory (``$MECHATRON_CACHE`` or ``~/.cache/mechatron``; the file
name holds a hash of the source and flags). One call then integrates the whole run and
writes every logged variable at every output time (Rodas4's own dense output between
steps, of order 3, built from the step's stages), so Python only prepares arrays and
reads the result.

Events: after every accepted step the relations' indicators (mode times distance) are
checked; one that went from positive to zero or below is located on the step's dense
output (secant iteration with Illinois safeguard, to :data:`EVENT_TOL`), and the
model's compiled transition (the same one the CasADi integrators call) updates the modes,
counters and discrete states before the integration restarts at the event.

Scope: ODE models (no algebraic unknowns left for a DAE solver) with up to
:data:`MAX_STATES` states (the Jacobian is dense). Other models raise a
:class:`~mechatron.errors.SimulationError` that names the solver to use instead.
Parameters are an argument of the library, so changing them never recompiles.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
from importlib import resources
from pathlib import Path

import casadi as ca
import numpy as np

from mechatron.compiler.compiled import CHATTER_FLAG, CompiledModel
from mechatron.errors import SimulationError
from mechatron.solvers.fpenv import subnormals_flushed

__all__ = ["integrate_native", "native_library", "auto_library", "build_library",
           "BuildError", "compiler", "cache_dir", "MAX_STATES", "AUTO_STATES", "AUTO_SOURCE"]

#: Largest state count the dense-Jacobian solver accepts (beyond it CVODES is faster).
MAX_STATES = 400
FLAGS = ("-O2", "-fPIC", "-shared", "-std=c99")
#: ``solver="auto"`` runs the compiled Rosenbrock method on ODE models without events of
#: up to this many states ...
AUTO_STATES = 60
#: ... whose generated C is at most this long (characters): such a library builds in
#: 0.3 s on a quiet machine and about 1.3 s on a loaded one (measured on the database
#: models; those with events generate 70-240 kB and take 2-7 s), once per model
#: structure: the file is cached by a hash of its source, parameters are an argument.
AUTO_SOURCE = 64_000
MAX_STEPS = 10_000_000
CHATTERING = -7
#: Width of the time bracket of a located event, relative to max(1 s, |t|).
EVENT_TOL = 1e-14
_MESSAGES = {
    -1: "took more than {max_steps} steps",
    -2: "the step size fell below the resolution of t (a discontinuity without an "
        "event, or a solution that blows up)",
    -3: "the model's equations gave a value that is not finite",
    -4: "the iteration matrix I/(h gamma) - J stayed singular",
    -5: "out of memory",
    -6: "events kept coming at the same instant (more than 1000 in a row)",
}


def compiler() -> str | None:
    """The C compiler used (``$CC``, ``cc`` or ``gcc``), or None."""
    cc = os.environ.get("CC")
    if cc and shutil.which(cc):
        return shutil.which(cc)
    return shutil.which("cc") or shutil.which("gcc")


def cache_dir() -> Path:
    """Where compiled libraries are kept (``$MECHATRON_CACHE`` or ``~/.cache/mechatron``)."""
    root = os.environ.get("MECHATRON_CACHE")
    return Path(root) if root else Path.home() / ".cache" / "mechatron"


def _check_scope(cm: CompiledModel) -> None:
    if cm.nz:
        raise SimulationError(
            f"model '{cm.name}': solver 'rodas4' integrates ODEs, and this model keeps "
            f"{cm.nz} algebraic unknown(s) for a DAE solver ({', '.join(cm.alg_names[:4])}). "
            "Use solver='auto' or 'idas'.", path=cm.name)
    if cm.nx > MAX_STATES:
        raise SimulationError(
            f"model '{cm.name}': solver 'rodas4' uses a dense Jacobian and accepts up to "
            f"{MAX_STATES} states; this model has {cm.nx}. Use solver='auto' (CVODES).",
            path=cm.name)


def _source(cm: CompiledModel) -> str:
    t = ca.SX.sym("t")
    x = ca.SX.sym("x", cm.nx)
    m = ca.SX.sym("m", cm.nX - cm.nx)     # modes, event counters, event times
    p = ca.SX.sym("p", cm.p0.size)
    z = ca.SX(0, 1)
    X = ca.vertcat(x, m)
    f = cm.f_ode(t, X, z, p)[:cm.nx]
    funcs = [
        ca.Function("mt_f", [t, x, m, p], [f]),
        ca.Function("mt_jac", [t, x, m, p], [ca.densify(ca.jacobian(f, x)),
                                             ca.densify(ca.jacobian(f, t))]),
        ca.Function("mt_out", [t, x, m, p], [ca.densify(cm.f_out(t, X, z, p))]),
    ]
    if cm.nr:
        k = ca.SX.sym("k")
        funcs += [ca.Function("mt_zero", [t, x, m, p], [ca.densify(cm.f_zero(t, X, z, p))]),
                  ca.Function("mt_trans", [k, t, x, m, p],
                              [ca.densify(cm.f_transition(k, t, X, z, p)[0])])]
    cg = ca.CodeGenerator("mt_model.c", {"with_header": False})
    for fn in funcs:
        cg.add(fn)
    template = resources.files("mechatron.solvers").joinpath("rodas4.c").read_text()
    sizes = (f"\n#define MT_NX {cm.nx}\n#define MT_NR {cm.nr}\n#define MT_NY {len(cm.names)}\n"
             f"#define MT_CHATTER_FLAG {CHATTER_FLAG:.17g}\n")
    return cg.dump() + sizes + template


class _Library:
    """A loaded library and its entry point."""

    def __init__(self, path: Path):
        self.path = path
        self.dll = ctypes.CDLL(str(path))
        fn = self.dll.mt_rodas4
        fn.restype = ctypes.c_int
        d, p, i = ctypes.c_double, ctypes.c_void_p, ctypes.c_long
        fn.argtypes = [p, i, p, p, d, d, d, d, i, d, p, p, p]
        self.run = fn


#: Operations whose result has a kink or a jump: a Rosenbrock step carries no event
#: location, and its embedded error estimate (damped on stiff components) can step over a
#: kink that its interpolant then misses, so ``auto`` leaves right-hand sides with them to
#: CVODES (which shortens its steps there).
_NONSMOOTH = frozenset(getattr(ca, f"OP_{name}") for name in (
    "IF_ELSE_ZERO", "FABS", "FMIN", "FMAX", "FLOOR", "CEIL", "SIGN", "COPYSIGN", "FMOD",
    "REMAINDER", "LT", "LE", "EQ", "NE", "NOT", "AND", "OR"))


def smooth_rhs(cm: CompiledModel) -> bool:
    """Whether the ODE right-hand side of ``cm`` is built from smooth operations only
    (none of :data:`_NONSMOOTH`); decided from the expression graph, not from numbers."""
    t = ca.SX.sym("t")
    X = ca.SX.sym("X", cm.nX)
    p = ca.SX.sym("p", cm.p0.size)
    fn = ca.Function("f", [t, X, p], [cm.f_ode(t, X, ca.SX(0, 1), p)[:cm.nx]])
    return not any(fn.instruction_id(k) in _NONSMOOTH for k in range(fn.n_instructions()))


def auto_library(cm: CompiledModel) -> _Library | None:
    """The library ``solver="auto"`` runs, or None when it keeps to CVODES/IDAS.

    A model qualifies when it is an ODE (no algebraic unknowns for a DAE solver) without
    events and with a smooth right-hand side (:func:`smooth_rhs`: a kink without an
    event, such as a trapezoidal back EMF written with ``if_else``, is left to CVODES),
    with at most :data:`AUTO_STATES` states and generated C of at most
    :data:`AUTO_SOURCE` characters, and a C compiler is found; ``MECHATRON_NATIVE=0`` in
    the environment turns this off. The decision is taken once per compiled model. A
    library that fails to build leaves the model to CVODES."""
    cached = cm._cache.get("native_auto")
    if cached is not None:
        return cached or None
    lib = None
    if (os.environ.get("MECHATRON_NATIVE", "1") != "0" and not cm.nz and not cm.nr
            and 0 < cm.nx <= AUTO_STATES and compiler() is not None and smooth_rhs(cm)):
        source = _source(cm)
        if len(source) <= AUTO_SOURCE:
            try:
                lib = native_library(cm, source)
            except SimulationError:
                lib = None
    cm._cache["native_auto"] = lib or False
    return lib


def native_library(cm: CompiledModel, source: str | None = None) -> _Library:
    """The compiled library of ``cm`` (built once, then cached on the model and on disk;
    ``source``: its generated C, if already made)."""
    lib = cm._cache.get("native_rodas4")
    if lib is not None:
        return lib
    _check_scope(cm)
    cc = compiler()
    if cc is None:
        raise SimulationError(
            f"model '{cm.name}': solver 'rodas4' compiles the model to C and no C compiler "
            "was found (cc, gcc, or $CC). Install one (Debian: apt-get install gcc) or use "
            "solver='auto'.", path=cm.name)
    try:
        path = build_library(source or _source(cm), _slug(cm.name), "rodas4", FLAGS, cc)
    except BuildError as exc:
        raise SimulationError(f"model '{cm.name}': solver 'rodas4': {exc}. Set "
                              "MECHATRON_CACHE to a writable folder if that is the cause, "
                              "or use solver='auto'.", path=cm.name) from None
    lib = cm._cache["native_rodas4"] = _Library(path)
    return lib


class BuildError(RuntimeError):
    """Compiling generated C into a shared library failed (the message says why)."""


def build_library(source: str, name: str, kind: str, flags: tuple[str, ...],
                  cc: str) -> Path:
    """Compile ``source`` into a shared library in the cache folder ``kind`` and return
    its path; a library of the same source, flags and compiler is reused. The file name
    holds a hash of them, and the library is moved into place atomically, so parallel
    runs never see half a file. Raises :class:`BuildError`."""
    key = hashlib.sha1((source + " ".join(flags) + cc).encode()).hexdigest()[:20]
    folder = _writable(cache_dir() / kind)
    path = folder / f"{name}_{key}.so"
    if path.exists():
        return path
    try:
        with tempfile.TemporaryDirectory(dir=folder) as tmp:
            src = Path(tmp) / f"{name}.c"
            src.write_text(source)
            out = Path(tmp) / path.name
            proc = subprocess.run([cc, *flags, str(src), "-o", str(out), "-lm"],
                                  capture_output=True, text=True, timeout=600)
            if proc.returncode != 0:
                tail = "\n".join(proc.stderr.strip().splitlines()[-6:])
                raise BuildError(f"compiling the generated C failed ({cc}): {tail}")
            os.replace(out, path)
    except (OSError, subprocess.SubprocessError) as exc:
        raise BuildError(f"could not build a library in {folder} ({exc})") from None
    return path


def _writable(folder: Path) -> Path:
    """``folder``, created if needed; a folder in the system's temporary directory when
    it cannot be written (a read-only home on a CI machine)."""
    user = getattr(os, "getuid", lambda: 0)()
    fallback = Path(tempfile.gettempdir()) / f"mechatron-{user}" / folder.name
    for candidate in (folder, fallback):
        try:
            candidate.mkdir(parents=True, exist_ok=True)
            if os.access(candidate, os.W_OK):
                return candidate
        except OSError:
            continue
    return folder        # the build below then fails with a message naming it


def _slug(name: str) -> str:
    return "".join(ch if ch.isalnum() else "_" for ch in name)[:40] or "model"


@subnormals_flushed()
def integrate_native(cm: CompiledModel, grid: np.ndarray, x0: np.ndarray, p: np.ndarray, *,
                     rtol: float, atol: float, max_step: float | None = None,
                     fixed_step: float | None = None):
    """Integrate on ``grid`` with the compiled Rodas4.

    Returns ``(Y, xf, stats)``: every logged variable at every grid point, shape
    ``(len(cm.names), grid.size)``; the final integration state ``X`` (states, then the
    relations' modes, event counters and event times); and a dict of solver counts.
    ``fixed_step`` makes every step that size and accepts it (convergence-order tests).
    """
    lib = native_library(cm)
    grid = np.ascontiguousarray(grid, dtype=float)
    x0 = np.ascontiguousarray(x0, dtype=float)
    p = np.ascontiguousarray(p, dtype=float)
    n_y = len(cm.names)
    y = np.empty((grid.size, n_y))
    xf = np.empty(max(cm.nX, 1))
    info = np.zeros(10)
    event_tol = EVENT_TOL * max(1.0, abs(float(grid[0])), abs(float(grid[-1])))
    code = lib.run(grid.ctypes.data, grid.size, x0.ctypes.data, p.ctypes.data,
                   float(rtol), float(atol), float(max_step or 0.0), event_tol, MAX_STEPS,
                   float(fixed_step or 0.0), y.ctypes.data, xf.ctypes.data,
                   info.ctypes.data)
    stats = {"n_steps": int(info[0]), "n_reject": int(info[1]), "n_rhs": int(info[2]),
             "n_jac": int(info[3]), "n_lu": int(info[4]), "n_events": int(info[8]),
             "n_zero": int(info[9])}
    if code == CHATTERING:
        # the transition marked a relation as chattering; mt.simulate names it from X
        y[int(info[7]):] = np.nan
    elif code != 0:
        what = _MESSAGES.get(code, f"failed with code {code}").format(max_steps=MAX_STEPS)
        raise SimulationError(
            f"model '{cm.name}': solver 'rodas4' stopped at t = {info[5]:.9g} s: {what}. "
            "Check the parameters, try a tighter tolerance or solver='auto'.",
            path=cm.name)
    return y.T, xf[:cm.nX], stats
