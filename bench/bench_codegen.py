"""Generated C: nanoseconds per fixed-step step of every database model, beside the
physical limit estimated from the step's operation count.

For each model of the database (its default variant), the C of the RK4 step (and, for the
DC motor, backward Euler with 2 Newton iterations and ode14x with 1) is generated, built
with the generated Makefile (``-O2``) and timed by its harness (``--bench N``: N steps
in a loop, best of seven). The limit is ``max(latency, issue) / clock``: the longest chain
of dependent operations weighted by their latencies, or all operations issued on two
add/multiply units, whichever is larger (:func:`mechatron.codegen.c.generator.
operation_profile`), at the clock that ``/proc/cpuinfo`` reports (a boost clock can beat
it). Goal: the DC motor's RK4 step under 100 ns.

Run: ``python bench/bench_codegen.py [--quick]``; prints one JSON document.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import _common  # noqa: F401  (import path)
from _common import log, main

import mechatron as mt
from mechatron.codegen import build, generate_c, measure_ns_per_step
from mechatron.codegen.c.generator import operation_profile, prepare

GOAL_NS = 100.0


def _clock_hz() -> float | None:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("cpu mhz"):
                return float(line.split(":")[1]) * 1e6
    except (OSError, ValueError):
        pass
    return None


def _one(cm, solver: str, iterations: int, dt: float, steps: int, out: Path,
         clock: float | None) -> dict:
    prep = prepare(cm, solver=solver, dt=dt, iterations=iterations)
    prof = operation_profile(prep.step)
    t0 = time.perf_counter()
    code = generate_c(cm, out, solver=solver, dt=dt, iterations=iterations)
    build(code)
    build_s = time.perf_counter() - t0
    timing = measure_ns_per_step(code, steps=steps, repeats=7)
    cycles = max(prof["latency_cycles"], prof["issue_cycles"])
    limit = cycles / clock * 1e9 if clock else None
    return {"solver": solver, "iterations": iterations if solver not in ("euler", "heun", "rk4")
            else None, "dt": dt, "states": cm.nx, "outputs": len(cm.names), **prof,
            "ns_per_step": timing["ns_per_step"], "all_ns_per_step": timing["all_ns_per_step"],
            "finite": timing["finite"], "limit_ns": limit,
            "ratio_to_limit": timing["ns_per_step"] / limit if limit else None,
            "generate_and_build_s": build_s}


def run(quick: bool = False) -> dict:
    """Time the generated C of every database model."""
    steps = 100_000 if quick else 1_000_000
    clock = _clock_hz()
    rows = {}
    with tempfile.TemporaryDirectory(prefix="mechatron_bench_codegen_") as tmp:
        for entry in mt.models.list():
            if quick and entry.name != "dc_motor":
                continue
            log(f"codegen {entry.name}")
            try:
                cm = mt.compile_model(entry.build())
                dt = entry.experiment.dt or entry.experiment.t_stop / 5000
                configs = [("rk4", 1)]
                if entry.name == "dc_motor":
                    dt = 1e-4
                    configs += [("backward_euler", 2), ("ode14x", 1)]
                rows[entry.name] = [
                    _one(cm, s, it, dt, steps, Path(tmp) / f"{entry.name}_{s}", clock)
                    for s, it in configs]
            except Exception as exc:      # one model that cannot be generated: report it
                rows[entry.name] = {"error": f"{type(exc).__name__}: {exc}"}
    dc = rows.get("dc_motor")
    rk4 = dc[0]["ns_per_step"] if isinstance(dc, list) else None
    return {"clock_hz": clock, "steps_timed": steps, "models": rows,
            "dc_motor_rk4_ns": rk4, "goal_ns": GOAL_NS,
            "goal_met": None if rk4 is None else rk4 < GOAL_NS,
            "notes": ["ns_per_step: best of seven runs of the compiled harness "
                      "(-O2, -ffp-contract=off), outputs (every logged variable) included.",
                      "limit_ns: max(latency_cycles, issue_cycles) / clock_hz, a lower "
                      "bound from the operation count; boost clocks can beat it."]}


if __name__ == "__main__":
    main(run)
