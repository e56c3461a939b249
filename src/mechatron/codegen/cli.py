"""The ``codegen`` and ``fmu`` commands (see :mod:`mechatron.cli` for the conventions).

``mechatron codegen NAME --solver S --dt H [--iterations N] --out DIR``
    Write standalone C99 of a database model; ``--check`` also builds the harness, runs
    it, compares it with the desktop fixed-step simulation and times one step; ``--arm``
    cross-compiles for a Cortex-M4 and reports flash and RAM.
``mechatron fmu NAME --fmi 2|3 --kind cs|me --out FILE.fmu``
    Export an FMU (sources and a binary for this platform inside).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import mechatron as mt
from mechatron.cli import (MODEL_HELP, CommandError, add_json, add_set, check_step_count,
                           emit, emit_json, table)
from mechatron.models.user import entry_for
from mechatron.solvers import METHODS

__all__ = ["add_commands", "cmd_codegen", "cmd_fmu"]


def add_commands(sub) -> None:
    """Add ``codegen`` and ``fmu`` to the ``mechatron`` command."""
    add_codegen(sub)
    add_fmu(sub)


def _add_solver(p: argparse.ArgumentParser) -> None:
    p.add_argument("--variant", metavar="V", help="variant to build (default: the first)")
    add_set(p)
    p.add_argument("--solver", metavar="S", default="rk4", choices=list(METHODS),
                   help="fixed-step method: " + ", ".join(METHODS) + " (default: rk4)")
    p.add_argument("--dt", type=float, metavar="H",
                   help="step size in s (default: the experiment's, if it has one)")
    p.add_argument("--iterations", type=int, default=3, metavar="N",
                   help="Newton iterations per implicit solve (default: %(default)s)")
    p.add_argument("--t-stop", type=float, metavar="T",
                   help="end time of the harness run (default: the experiment's)")


def add_codegen(sub) -> None:
    p = sub.add_parser("codegen", help="generate standalone C99 of a model",
                       description="Write standalone C99 of a database model with a "
                                   "fixed-step solver: NAME.h (init, step, parameter "
                                   "setters, output getters), NAME.c, NAME_casadi.c (the "
                                   "step function), a host harness writing the CSV of "
                                   "`mechatron simulate --out`, and a Makefile.")
    p.add_argument("name", metavar="NAME", help=MODEL_HELP)
    _add_solver(p)
    p.add_argument("--out", metavar="DIR", required=True, help="directory for the C files")
    p.add_argument("--check", action="store_true",
                   help="build the harness, compare it with the desktop fixed-step run "
                        "and time one step")
    p.add_argument("--arm", action="store_true",
                   help="cross-compile for a Cortex-M4 (arm-none-eabi-gcc) and report "
                        "flash and RAM")
    add_json(p)
    p.set_defaults(func=cmd_codegen)


def add_fmu(sub) -> None:
    p = sub.add_parser("fmu", help="export a model as an FMU",
                       description="Export a database model as an FMU: FMI 2.0 "
                                   "co-simulation (the fixed-step solver inside) or model "
                                   "exchange, or FMI 3.0 co-simulation. The FMU holds its "
                                   "C sources and a binary for this platform.")
    p.add_argument("name", metavar="NAME", help=MODEL_HELP)
    p.add_argument("--fmi", choices=["2", "3"], default="2", help="FMI version")
    p.add_argument("--kind", choices=["cs", "me"], default="cs",
                   help="co-simulation or model exchange (default: cs)")
    _add_solver(p)
    p.add_argument("--out", metavar="FILE.fmu", required=True, help="the FMU to write")
    add_json(p)
    p.set_defaults(func=cmd_fmu)


def _resolve(args):
    from mechatron.cli import _parse_sets
    entry = entry_for(args.name)
    params = _parse_sets(args.set, entry)
    variant = args.variant or entry.default_variant
    dt = args.dt if args.dt is not None else entry.experiment.dt
    if dt is None:
        raise CommandError(f"model '{entry.name}' has no default step size; give one with "
                           f"--dt, e.g. --dt 1e-4.")
    if not (np.isfinite(dt) and dt > 0):
        raise CommandError(f"--dt: the step size must be a number > 0, got {dt!r}.")
    if args.iterations < 1:
        raise CommandError(f"--iterations: at least 1, got {args.iterations}.")
    t_stop = args.t_stop if args.t_stop is not None else entry.experiment.t_stop
    if not (np.isfinite(t_stop) and t_stop > 0):
        raise CommandError(f"--t-stop: the end time must be a number > 0, got {t_stop!r}.")
    check_step_count(float(dt), t_stop)      # the harness run and the desktop comparison
    model = entry.build(variant, **params)
    return entry, variant, params, float(dt), float(t_stop), model


def cmd_codegen(args: argparse.Namespace) -> int:
    from mechatron.codegen import (build, cross_compile, generate_c, measure_ns_per_step,
                                   run_harness)
    from mechatron.codegen.c.build import have_cross_compiler
    from mechatron.codegen.compare import max_relative_difference

    entry, variant, params, dt, t_stop, model = _resolve(args)
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise CommandError(f"--out {out}: exists and is not a directory.")
    cm = mt.compile_model(model)
    code = generate_c(cm, out, solver=args.solver, dt=dt, iterations=args.iterations,
                      t_stop=t_stop, name=entry.name)
    result = {"model": entry.name, "variant": variant, "solver": args.solver, "dt": dt,
              "iterations": args.iterations, "directory": str(out),
              "files": [str(p) for p in code.files.values()],
              "parameters": code.parameters, "outputs": len(code.outputs),
              "operations_per_step": code.operations}
    if args.check:
        build(code)
        c_res = run_harness(code)
        # the generated C keeps the fixed iteration count: so does the run it is compared with
        desk = mt.simulate(cm, t_stop, solver=args.solver, dt=dt, iterations=args.iterations,
                           newton="count")
        result["unconverged_steps"] = desk.stats.unconverged_steps
        result["max_rel_difference_to_desktop"] = max_relative_difference(c_res, desk)
        result["steps"] = len(desk.t) - 1
        result["ns_per_step"] = measure_ns_per_step(code)["ns_per_step"]
    if args.arm:
        if not have_cross_compiler():
            raise CommandError("--arm: arm-none-eabi-gcc not found; install it (Debian: "
                               "apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi).")
        result["arm"] = cross_compile(code)
    if args.json:
        emit_json(result)
        return 0
    emit(f"{entry.name} ({variant}): C99 with {args.solver}, dt {dt:g} s"
         + (f", {args.iterations} Newton iteration(s)" if args.solver not in
            ("euler", "heun", "rk4") else "")
         + f"; {len(code.parameters)} tunable parameters, {len(code.outputs)} outputs, "
           f"{code.operations} operations per step")
    for path in code.files.values():
        emit(f"  wrote {path}")
    if args.check:
        emit(f"harness vs desktop fixed-step ({result['steps']} steps): max relative "
             f"difference {result['max_rel_difference_to_desktop']:.1e}; "
             f"{result['ns_per_step']:.1f} ns per step")
    if args.arm:
        a = result["arm"]
        emit(table(["target", "flash [B]", "RAM [B]"],
                   [[a["target"], a["flash_bytes"], a["ram_bytes"]]], right="12"))
    emit(f"build: make -C {out}    run: {out / (code.name + '_run')} --out f.csv")
    return 0


def cmd_fmu(args: argparse.Namespace) -> int:
    from mechatron.codegen.fmu import export_fmu

    entry, variant, params, dt, t_stop, model = _resolve(args)
    out = Path(args.out)
    if out.suffix.lower() != ".fmu":
        raise CommandError(f"--out {out}: an FMU file must end in .fmu.")
    if out.parent and not out.parent.is_dir():
        raise FileNotFoundError(f"--out {out}: directory '{out.parent}' does not exist; "
                                "create it first.")
    info = export_fmu(model, out, fmi=int(args.fmi), kind=args.kind, solver=args.solver,
                      dt=dt, iterations=args.iterations, t_stop=t_stop, name=entry.name)
    if args.json:
        emit_json({"model": entry.name, "variant": variant, **info})
        return 0
    kind = {"cs": "co-simulation", "me": "model exchange"}[args.kind]
    emit(f"{entry.name} ({variant}): FMI {args.fmi}.0 {kind}"
         + (f", {args.solver} dt {dt:g} s inside" if args.kind == "cs" else "")
         + f"; {info['variables']} variables; binary {info['platform']}")
    emit(f"  wrote {out}")
    return 0
