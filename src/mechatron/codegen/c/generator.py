"""Standalone C99 from the fixed-step step function (docs/realtime.md).

The numerics come from :func:`mechatron.solvers.fixed.make_step`, the very CasADi
function that the desktop fixed-step run evaluates, emitted by CasADi's code generator;
the templates in ``templates/c`` wrap it into a model instance with an ``init``/``step``
API, parameter setters, output getters, a host harness writing the CSV of
``mechatron simulate --out``, and a Makefile.
"""

from __future__ import annotations

import csv
import io
import re
from dataclasses import dataclass, field
from pathlib import Path

import casadi as ca
import numpy as np

import mechatron
from mechatron._io import atomic_dir, write_text
from mechatron.codegen._common import (CodegenError, c_array, c_double, c_identifier,
                                       c_string, render, unique_identifiers)
from mechatron.compiler.compiled import CompiledModel
from mechatron.core.component import Component
from mechatron.solvers.fixed import METHODS, make_step
from mechatron.solvers.initial import initialize

__all__ = ["CModel", "generate_c", "prepare", "Prepared"]


@dataclass
class Prepared:
    """What every generator needs: the compiled model, the step and output functions on
    the augmented state ``[X; z]``, the initial state and the parameter values."""

    cm: CompiledModel
    name: str                # C identifier of the model
    solver: str
    dt: float
    iterations: int
    t0: float
    t_stop: float
    p: np.ndarray            # parameter values of the export (SI)
    x_start: np.ndarray      # augmented initial state [X0; z0]
    step: ca.Function        # <name>_casadi_step(x, u, p, t) -> (x_next, y)
    output: ca.Function      # <name>_casadi_output(x, u, p, t) -> y
    deriv: ca.Function       # <name>_casadi_deriv(x, u, p, t) -> der(states)

    @property
    def functions(self) -> list[ca.Function]:
        return [self.step, self.output, self.deriv]


@dataclass
class CModel:
    """The files of a generated model and the facts a user needs about them."""

    name: str
    directory: Path
    files: dict[str, Path]
    solver: str
    dt: float
    iterations: int
    t0: float
    t_stop: float
    parameters: list[str]
    outputs: list[str]
    n_states: int
    operations: int = 0
    info: dict = field(default_factory=dict)

    @property
    def harness(self) -> Path:
        """Path of the host harness once built (:func:`mechatron.codegen.c.build`)."""
        return self.directory / f"{self.name}_run"


def _compiled(model) -> CompiledModel:
    if isinstance(model, CompiledModel):
        return model
    if isinstance(model, Component):
        return mechatron.compile_model(model)
    raise TypeError(f"code generation: expected a Component or CompiledModel, got "
                    f"{type(model).__name__}.")


def prepare(model, *, solver: str = "rk4", dt: float, iterations: int = 3,
            params: dict | None = None, t0: float = 0.0, t_stop: float | None = None,
            name: str | None = None) -> Prepared:
    """Compile (if needed), initialize and build the step and output functions."""
    cm = _compiled(model)
    blocks = [b["path"] for b in cm.report.get("external_blocks") or []]
    if blocks:
        raise CodegenError(f"model '{cm.name}': {', '.join(blocks)} is an imported FMU, "
                           "which generated C cannot step (the co-simulation steps it from "
                           "Python). Generate code for the model without it, or the FMU's "
                           "own model.", path=cm.name)
    if solver not in METHODS:
        raise CodegenError(f"model '{cm.name}': unknown fixed-step solver '{solver}'. "
                           f"Choose one of {', '.join(METHODS)}.", path=cm.name)
    if not (isinstance(dt, (int, float)) and np.isfinite(dt) and dt > 0):
        raise CodegenError(f"model '{cm.name}': the step size must be a number > 0, got "
                           f"{dt!r}. Give one with --dt, e.g. --dt 1e-4.", path=cm.name)
    if int(iterations) < 1:
        raise CodegenError(f"model '{cm.name}': iterations must be >= 1, got "
                           f"{iterations!r}.", path=cm.name)
    cname = c_identifier(name or cm.name)
    p = cm.parameter_vector(params)
    X0, z0, _ = initialize(cm, p, t0)
    x_start = np.concatenate([np.asarray(X0, float).ravel(), np.asarray(z0, float).ravel()])
    if not np.all(np.isfinite(x_start)):
        raise CodegenError(f"model '{cm.name}': the initial state is not finite; check the "
                           "start values and parameters.", path=cm.name)
    base = make_step(cm, solver, float(dt), int(iterations))
    xa = ca.SX.sym("x", x_start.size)
    u = ca.SX.sym("u", base.size1_in(1))
    ps = ca.SX.sym("p", p.size)
    t = ca.SX.sym("t")
    x_next, y = base(xa, u, ps, t)
    step = ca.Function(f"{cname}_casadi_step", [xa, u, ps, t], [x_next, y],
                       ["x", "u", "p", "t"], ["x_next", "y"])
    X, z = xa[:cm.nX], _solve_algebraic(cm, t, xa[:cm.nX], xa[cm.nX:], ps, int(iterations))
    output = ca.Function(f"{cname}_casadi_output", [xa, u, ps, t], [cm.f_out(t, X, z, ps)],
                         ["x", "u", "p", "t"], ["y"])
    xdot = cm.f_ode(t, X, z, ps)[:cm.nx] if cm.nx else ca.SX(0, 1)
    deriv = ca.Function(f"{cname}_casadi_deriv", [xa, u, ps, t], [xdot],
                        ["x", "u", "p", "t"], ["xdot"])
    if t_stop is None:
        t_stop = t0 + 1000 * dt
    return Prepared(cm=cm, name=cname, solver=solver, dt=float(dt),
                    iterations=int(iterations), t0=float(t0), t_stop=float(t_stop), p=p,
                    x_start=x_start, step=step, output=output, deriv=deriv)


def _solve_algebraic(cm: CompiledModel, t, X, z, p, iterations: int):
    """The algebraic unknowns by ``iterations`` Newton steps from the guess ``z`` (the
    fixed cost of the step function's own algebraic solves)."""
    if cm.nz == 0:
        return z
    zs = ca.SX.sym("zs", cm.nz)
    g = cm.f_alg(t, X, zs, p)
    jac = ca.jacobian(g, zs)
    for _ in range(iterations):
        jz, gz = ca.substitute([jac, g], [zs], [z])
        z = z - ca.solve(jz, gz)
    return z


_DEFINITION = re.compile(r"^(?:CASADI_SYMBOL_EXPORT\s+|static\s+)?[\w\s\*]+?\b\w+\(([^()]*)\)"
                         r"\s*\{\s*$")


def _mark_parameters_used(code: str) -> str:
    """Add ``(void)name;`` for every parameter of every function definition, so that the
    code CasADi emits compiles with ``-Wall -Wextra -Werror`` (it leaves work arrays and
    memory indices unused in small functions)."""
    out = []
    for line in code.splitlines():
        out.append(line)
        m = _DEFINITION.match(line)
        if not m or m.group(1).strip() in ("", "void"):
            continue
        names = [re.findall(r"\w+", part)[-1] for part in m.group(1).split(",")]
        out.append("  " + " ".join(f"(void){n};" for n in names))
    return "\n".join(out) + "\n"


_READ = re.compile(r"\barg\[(\d+)\]\? (arg\[\1\]\[\d+\]) : 0")
_WRITE = re.compile(r"\bif \(res\[(\d+)\]!=0\) (res\[\1\]\[\d+\]=)")


def _drop_null_checks(code: str) -> str:
    """Remove CasADi's test of every argument and result pointer before each scalar
    read (``arg[i]? arg[i][k] : 0``) and write (``if (res[i]!=0) res[i][k]=``).

    Mechatron's callers (``NAME.c``, the FMU wrappers) pass every argument and result
    of the step, output and derivative functions, so the tests only cost a branch per
    scalar in the real-time step. The arithmetic is untouched."""
    return _WRITE.sub(r"\2", _READ.sub(r"\2", code))


def casadi_source(prep: Prepared) -> str:
    """The C source of the step, output and derivative functions, as CasADi emits it
    without its null-pointer tests (every argument and result must be given)."""
    gen = ca.CodeGenerator(f"{prep.name}_casadi.c",
                           {"casadi_real": "double", "casadi_int": "int",
                            "prefix": f"{prep.name}_casadi_", "with_header": False})
    for f in prep.functions:
        gen.add(f)
    return _mark_parameters_used(_drop_null_checks(gen.dump()))


def reads_state_before_writing(step: ca.Function) -> bool:
    """Whether the SX ``step`` reads every entry of its input 0 (the state) before it
    writes any entry of its output 0 (the next state): then the generated step can
    update the state in place, without a scratch copy."""
    last_read, first_write = -1, step.n_instructions()
    for k in range(step.n_instructions()):
        op = step.instruction_id(k)
        if op == ca.OP_INPUT and step.instruction_input(k)[0] == 0:
            last_read = k
        elif op == ca.OP_OUTPUT and step.instruction_output(k)[0] == 0:
            first_write = min(first_write, k)
    return last_read < first_write


def count_operations(f: ca.Function) -> int:
    """Arithmetic operations of an SX function (inputs, outputs and constants excluded)."""
    skip = {ca.OP_CONST, ca.OP_INPUT, ca.OP_OUTPUT, ca.OP_PARAMETER}
    return sum(1 for k in range(f.n_instructions()) if f.instruction_id(k) not in skip)


def _header_line(names) -> str:
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow(["t", *names])
    return buf.getvalue()


#: characters of the CSV header per C string literal (at most 4 bytes each in UTF-8: under
#: the 4095 a C99 compiler must take)
HEADER_PIECE = 500


def _pieces(text: str) -> list[str]:
    """``text`` in pieces of at most `HEADER_PIECE` characters."""
    return [text[k:k + HEADER_PIECE] for k in range(0, len(text), HEADER_PIECE)] or [""]


def _parameter_bounds(cm: CompiledModel, i: int) -> tuple[float, float]:
    low, high = cm.param_bounds[i] if cm.param_bounds else (None, None)
    return (-np.inf if low is None else float(low), np.inf if high is None else float(high))


def template_values(prep: Prepared) -> dict:
    """The values of every placeholder of the C templates."""
    cm = prep.cm
    step = prep.step
    nxa, npar, nu, ny = prep.x_start.size, prep.p.size, step.size1_in(1), cm.f_out.size1_out(0)
    fs = prep.functions
    sz = {"arg": max(f.sz_arg() for f in fs), "res": max(f.sz_res() for f in fs),
          "iw": max(f.sz_iw() for f in fs), "w": max(f.sz_w() for f in fs)}
    taken: set[str] = set()
    pid = unique_identifiers(cm.param_names, taken)
    yid = unique_identifiers(cm.names, taken)
    common = {"name": prep.name, "NAME": prep.name.upper()}
    pdecl, pdef, ydecl, ydef = [], [], [], []
    for i, (path, ident) in enumerate(zip(cm.param_names, pid)):
        v = dict(common, ident=ident, path=path, unit=cm.param_units[i] or "1", index=i)
        pdecl.append(render("c/param_accessors.h.in", **v).rstrip())
        pdef.append(render("c/param_accessors.c.in", **v).rstrip())
    for i, (path, ident) in enumerate(zip(cm.names, yid)):
        v = dict(common, ident=ident, path=path, unit=cm.units[i] or "1", index=i)
        ydecl.append(render("c/output_getter.h.in", **v).rstrip())
        ydef.append(render("c/output_getter.c.in", **v).rstrip())
    bounds = [_parameter_bounds(cm, i) for i in range(npar)]
    in_place = reads_state_before_writing(step)
    inputs = []
    for k, ident in enumerate(unique_identifiers(n.upper() for n in cm.input_names)):
        doc = f": {cm.input_docs[k]}" if cm.input_docs[k] else ""
        comment = f"{cm.input_names[k]} [{cm.input_units[k] or '1'}]{doc}"
        comment = comment.replace("*/", "* /")
        inputs.append(f"#define {prep.name.upper()}_INPUT_{ident} {cm.input_index[k]}"
                      f"    /* {comment} */")
    return dict(
        common, model=cm.name, version=mechatron.__version__, solver=prep.solver,
        dt=c_double(prep.dt), t0=c_double(prep.t0), t_stop=c_double(prep.t_stop),
        iterations=prep.iterations, nxa=nxa, nx=cm.nx, np=npar, nu=nu, ny=ny,
        nxa_alloc=max(nxa, 1), np_alloc=max(npar, 1), nu_alloc=max(nu, 1),
        ny_alloc=max(ny, 1), sz_arg=sz["arg"], sz_res=sz["res"],
        sz_iw_alloc=max(sz["iw"], 1), sz_w_alloc=max(sz["w"], 1),
        x_start=c_array(c_double(v) for v in prep.x_start),
        p_default=c_array(c_double(v) for v in prep.p),
        p_min=c_array(c_double(b[0]) for b in bounds),
        p_max=c_array(c_double(b[1]) for b in bounds),
        parameter_names=c_array(c_string(n) for n in cm.param_names),
        output_names=c_array(c_string(n) for n in cm.names),
        parameter_declarations="\n".join(pdecl), parameter_definitions="\n".join(pdef),
        output_declarations="\n".join(ydecl), output_definitions="\n".join(ydef),
        csv_header=c_array(map(c_string, _pieces(_header_line(cm.names)))),
        ninputs=len(cm.input_names), input_defines="".join(i + "\n" for i in inputs),
        step_x_out="m->x" if in_place else "m->x_next",
        step_copy=("/* the step reads the whole state before writing it: updated in place */"
                   if in_place else "memcpy(m->x, m->x_next, sizeof m->x);"))


def generate_c(model, out_dir, *, solver: str = "rk4", dt: float, iterations: int = 3,
               params: dict | None = None, t0: float = 0.0, t_stop: float | None = None,
               name: str | None = None) -> CModel:
    """Write standalone C99 of ``model`` with a fixed-step ``solver`` into ``out_dir``.

    Parameters
    ----------
    model : Component or CompiledModel
    out_dir : path
        Created if missing; existing files of the same names are replaced.
    solver, dt, iterations
        The fixed-step method (:data:`mechatron.solvers.METHODS`), its step in s and the
        Newton iterations of its implicit solves: exactly those of
        ``mt.simulate(model, ..., solver=solver, dt=dt, iterations=iterations)``.
    params : dict, optional
        Parameter values (by instance path) that become the defaults of the C code; all
        parameters stay tunable at run time.
    t0, t_stop : float
        Start time, and the end time the harness runs to by default.
    name : str, optional
        Prefix of every C symbol (default: the model's name).

    Returns
    -------
    CModel
        Paths of ``NAME.h``, ``NAME.c``, ``NAME_casadi.c``, ``NAME_main.c``,
        ``NAME_arm.c`` and ``Makefile``.
    """
    prep = prepare(model, solver=solver, dt=dt, iterations=iterations, params=params,
                   t0=t0, t_stop=t_stop, name=name)
    return write_c(prep, out_dir)


def write_c(prep: Prepared, out_dir) -> CModel:
    """Write the C files of a prepared model.

    Nothing is half written: a new folder is built beside ``out_dir`` and renamed when
    complete; in an existing folder, each file is replaced only by its complete new
    version (other files of the folder are left alone).
    """
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise CodegenError(f"--out {out}: exists and is not a directory; give a directory "
                           "for the generated C files.", path=str(out))
    if out.is_dir():
        files = _write_files(prep, out, out)
    else:
        out.parent.mkdir(parents=True, exist_ok=True)
        with atomic_dir(out) as tmp:
            files = _write_files(prep, tmp, out)
    cm = prep.cm
    return CModel(name=prep.name, directory=out, files=files, solver=prep.solver,
                  dt=prep.dt, iterations=prep.iterations, t0=prep.t0, t_stop=prep.t_stop,
                  parameters=list(cm.param_names), outputs=list(cm.names),
                  n_states=cm.nx, operations=count_operations(prep.step))


def _write_files(prep: Prepared, folder: Path, out: Path) -> dict[str, Path]:
    """Write the C files into ``folder``; their paths once ``folder`` is ``out``."""
    values = template_values(prep)
    n = prep.name
    texts = {f"{n}.h": render("c/model.h.in", **values),
             f"{n}.c": render("c/model.c.in", **values),
             f"{n}_casadi.c": casadi_source(prep),
             f"{n}_main.c": render("c/main.c.in", **values),
             "mt_fpmode.h": render("c/mt_fpmode.h"),
             f"{n}_arm.c": render("c/arm_main.c.in", **values),
             "Makefile": render("c/Makefile.in", **values)}
    for fname, text in texts.items():
        write_text(folder / fname, text)
    return {fname: out / fname for fname in texts}


_SLOW_OPS = {ca.OP_DIV, ca.OP_SQRT, ca.OP_EXP, ca.OP_LOG, ca.OP_POW, ca.OP_SIN, ca.OP_COS,
             ca.OP_TAN, ca.OP_ATAN, ca.OP_ATAN2, ca.OP_TANH, ca.OP_CONSTPOW}
#: Typical double-precision costs on a current x86-64 core, in cycles: latency of one
#: operation, and issue cost (two add/multiply units; division and square root are not
#: pipelined; transcendental functions are library calls).
_LATENCY = {ca.OP_DIV: 13, ca.OP_SQRT: 20}
_ISSUE = {ca.OP_DIV: 4.5, ca.OP_SQRT: 6}
_LIBM_CYCLES = 40


def operation_profile(f: ca.Function) -> dict:
    """Operation count of an SX function and a lower bound of its execution time.

    Returns ``operations`` (arithmetic), ``slow_operations`` (division, square root,
    transcendental functions), ``depth`` (longest chain of dependent operations),
    ``latency_cycles`` (that chain weighted by each operation's latency: add/multiply 3
    cycles, division 13, square root 20, library functions 40) and ``issue_cycles``
    (every operation issued on two pipelined add/multiply units, division 4.5 cycles,
    square root 6, library functions 40). A step cannot take fewer cycles than the larger
    of the two; memory traffic and call overhead come on top.
    """
    skip = {ca.OP_CONST, ca.OP_INPUT, ca.OP_OUTPUT, ca.OP_PARAMETER}
    depth: dict[int, tuple[int, float]] = {}
    ops = slow = 0
    longest, latency, issue = 0, 0.0, 0.0
    for k in range(f.n_instructions()):
        op = f.instruction_id(k)
        if op == ca.OP_OUTPUT:
            continue
        out = f.instruction_output(k)
        target = out[0] if out else None
        if op in skip:
            if target is not None:
                depth[target] = (0, 0.0)
            continue
        ops += 1
        is_slow = op in _SLOW_OPS
        slow += is_slow
        lat = _LATENCY.get(op, _LIBM_CYCLES if is_slow else 3)
        issue += _ISSUE.get(op, _LIBM_CYCLES if is_slow else 0.5)
        before = [depth.get(i, (0, 0.0)) for i in f.instruction_input(k) if i >= 0]
        d = (1 + max((b[0] for b in before), default=0),
             lat + max((b[1] for b in before), default=0.0))
        if target is not None:
            depth[target] = d
        longest, latency = max(longest, d[0]), max(latency, d[1])
    return {"operations": ops, "slow_operations": slow, "depth": longest,
            "latency_cycles": latency, "issue_cycles": issue}
