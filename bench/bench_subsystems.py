"""Compile time of a model built from a reused subsystem against the same model built flat.

The RC ladder of ``bench_scaling`` (a 1 V source, N sections of a 1 Ohm series resistor and
a 1 mF capacitor to ground) in two forms:

* flat: ``mt.System`` with 2 N parts wired by the model;
* hierarchical: N instances of one ``Stage`` class (its own pins ``p``, ``n``, ``gnd``,
  a resistor and a capacitor wired inside), wired in series by the model. Each stage adds
  a component, two parameters passed on to its parts, three ports (six variables) and
  their connection sets. The class is wired once (``compiler/folding.py``): its ports
  are folded into the nodes outside and never become unknowns, but are still logged.

For N = 100 and 1000: the median time of ``mt.compile_model`` on fresh instances (the
instance is built outside the timed call; both forms compiled once before, then in turn),
equations before and after alias elimination, and the ratio hierarchical / flat (goal of
issue 15: within 1.2). Both compiled models are then simulated for 1 s and their capacitor
voltages compared (max abs difference), so the timing is of models that agree.

Run: ``python bench/bench_subsystems.py [--quick]``.
"""

from __future__ import annotations

import time

import _common  # noqa: F401  (import path)
from _common import log, main, ratio, summary

import numpy as np

import mechatron as mt
from bench_scaling import C_SHUNT, R_SERIES, V_SOURCE, rc_ladder
from mechatron.library import electrical as el


class Stage(mt.Component):
    """One ladder section: series resistor from p to n, capacitor from n to gnd."""

    R = mt.Parameter("Ohm", default=R_SERIES, doc="Series resistance")
    C = mt.Parameter("F", default=C_SHUNT, doc="Shunt capacitance")
    p = el.Pin(doc="Input")
    n = el.Pin(doc="Output")
    gnd = el.Pin(doc="Common")
    r = el.Resistor(R=R)
    c = el.Capacitor(C=C)

    def equations(self):
        return [mt.connect(self.p, self.r.p), mt.connect(self.r.n, self.c.p, self.n),
                mt.connect(self.c.n, self.gnd)]


def flat_ladder(n: int) -> mt.System:
    """The flat ladder of bench_scaling (the same parts and values)."""
    return rc_ladder(n)


def stage_ladder(n: int) -> mt.System:
    m = mt.System(f"stages_{n}")
    src = m.add("src", el.DCVoltageSource(V=V_SOURCE))
    gnd = m.add("gnd", el.ElectricalReference())
    m.connect(src.n, gnd.port)
    node = src.p
    for k in range(n):
        s = m.add(f"s{k}", Stage())
        m.connect(node, s.p)
        m.connect(s.gnd, gnd.port)
        node = s.n
    return m


def _compile_both(n, repeats):
    """Wall-clock and process-CPU medians of fresh compiles of both forms, with their
    equation counts. Both forms are compiled once first (first-use costs: lazy imports,
    per-class caches), then alternately, so that a change of load on a shared machine
    falls on both; CPU time is the less sensitive figure."""
    builds = {"flat": flat_ladder, "subsystem": stage_ladder}
    for build in builds.values():
        mt.compile_model(build(min(n, 10)))
    cpu = {k: [] for k in builds}
    wall = {k: [] for k in builds}
    compiled = {}
    for _ in range(repeats):
        for key, build in builds.items():
            model = build(n)             # building the instance is not compiling it
            w0, c0 = time.perf_counter(), time.process_time()
            compiled[key] = mt.compile_model(model)
            cpu[key].append(time.process_time() - c0)
            wall[key].append(time.perf_counter() - w0)
    out = {}
    for key, cm in compiled.items():
        counts = {k: cm.report.get(k) for k in ("variables", "equations")}
        out[key] = (cm, summary(wall[key]), summary(cpu[key]), counts)
    return out


def run(quick: bool = False, tiny: bool = False) -> dict:
    """Compile time of a reused subsystem against the flat model (issue 15)."""
    sizes = (5,) if tiny else (100,) if quick else (100, 1000)
    repeats = 1 if tiny else 3 if quick else 7
    rows = []
    for n in sizes:
        log(f"subsystems: N = {n}")
        both = _compile_both(n, repeats)
        cm_flat, t_flat, cpu_flat, c_flat = both["flat"]
        cm_sub, t_sub, cpu_sub, c_sub = both["subsystem"]
        t = np.linspace(0.0, 1.0, 101)
        a = mt.simulate(cm_flat, 1.0, t_out=t)
        b = mt.simulate(cm_sub, 1.0, t_out=t)
        diff = max(float(np.max(np.abs(a[f"c{k}.v"] - b[f"s{k}.c.v"]))) for k in range(n))
        rows.append({"N": n, "flat_compile": t_flat, "subsystem_compile": t_sub,
                     "ratio_subsystem_over_flat": ratio(t_sub["median_s"],
                                                        t_flat["median_s"]),
                     "flat_compile_cpu": cpu_flat, "subsystem_compile_cpu": cpu_sub,
                     "cpu_ratio_subsystem_over_flat": ratio(cpu_sub["median_s"],
                                                            cpu_flat["median_s"]),
                     "counts_flat": c_flat, "counts_subsystem": c_sub,
                     "states": [len(cm_flat.state_names), len(cm_sub.state_names)],
                     "max_abs_diff_v": diff})
    return {"rows": rows, "goal": "ratio_subsystem_over_flat <= 1.2 (issue 15)",
            "notes": ["Median of compile_model on fresh instances (built outside the timed "
                      "call). "
                      "Ratios matter; absolute times vary with load."]}


if __name__ == "__main__":
    main(run)
