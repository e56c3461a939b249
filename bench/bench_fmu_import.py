"""FMU import: cost per communication step of a model holding an ``mt.FMUComponent``.

The seed's DC motor (voltage and load torque in, speed out) is exported as an FMI 2.0
co-simulation FMU (RK4 at 10 us inside) and as a model-exchange FMU, then imported into a
speed loop with a PI controller sampled at the communication step (1 ms). The loop runs
with each host solver (rodas4, the default; rk45; fixed-step RK4 at 10 us), and with the
model-exchange FMU (integrated by FMPy's CVODE); the same loop with the motor as an
ordinary part is the peer. Reported: wall time, milliseconds per communication step, and
the largest speed difference at the communication points from the direct RK4 loop.

Run: ``python bench/bench_fmu_import.py [--quick]``; prints one JSON document.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import _common  # noqa: F401  (import path)
from _common import clock, log, main

import numpy as np

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import electrical as el
from mechatron.library import electromechanical as em
from mechatron.library import rotational as rot

DT, TS = 1e-5, 1e-3


class Motor(mt.Component):
    """The seed's DC motor with voltage and load torque inputs and the speed as output."""

    V = mt.Input("V", start=0.0, doc="Armature voltage")
    tau_load = mt.Input("N*m", start=0.0, doc="Load torque")
    w = mt.Output("rad/s", doc="Speed")
    source = el.ControlledVoltageSource()
    resistor = el.Resistor(R=7.1)
    inductor = el.Inductor(L=3.408e-4)
    emf = em.RotationalEMF(k=0.151)
    inertia = rot.Inertia(J=4.8e-6)
    damper = rot.RotationalDamper(D=1.236e-4)
    load = rot.IdealTorqueSource()
    ground = el.ElectricalReference()
    fixed = rot.RotationalReference()

    def equations(self):
        return [mt.connect(self.V, self.source.u),
                mt.connect(self.tau_load, self.load.tau_in),
                mt.connect(self.source.p, self.resistor.p),
                mt.connect(self.resistor.n, self.inductor.p),
                mt.connect(self.inductor.n, self.emf.p),
                mt.connect(self.emf.n, self.source.n, self.ground.port),
                mt.connect(self.emf.A, self.inertia.port, self.damper.A, self.load.B),
                mt.connect(self.emf.B, self.damper.B, self.load.A, self.fixed.port),
                self.w == self.inertia.w]


def _loop(plant) -> mt.System:
    m = mt.System("loop")
    ref = m.add("ref", blocks.Constant(value=100.0))
    err = m.add("err", blocks.Add(k1=1.0, k2=-1.0))
    pid = m.add("pid", blocks.DiscretePID(Ts=TS, Kp=0.05, Ki=2.0))
    zero = m.add("zero", blocks.Constant(value=0.0))
    m.add("plant", plant)
    m.connect(ref.y, err.u1)
    m.connect(plant.w, err.u2)
    m.connect(err.y, pid.u)
    m.connect(pid.y, plant.V)
    m.connect(zero.y, plant.tau_load)
    return m


def run(quick: bool = False, tiny: bool = False) -> dict:
    """Wall time per communication step of the co-simulated loop (0.3 s; ``quick``
    0.1 s; ``tiny`` 5 ms) with each host solver, beside the loop with the motor as a
    part."""
    from mechatron.codegen import export_fmu
    t_stop = 0.005 if tiny else 0.1 if quick else 0.3
    ticks = np.arange(int(round(t_stop / TS)) + 1) * TS
    folder = Path(tempfile.mkdtemp(prefix="mechatron_bench_fmu_"))
    cm_motor = mt.compile_model(Motor())
    paths = {}
    for kind in ("cs", "me"):
        paths[kind] = folder / f"motor_{kind}.fmu"
        export_fmu(cm_motor, paths[kind], fmi=2, kind=kind, solver="rk4", dt=DT,
                   t_stop=1.0)
    direct = mt.compile_model(_loop(Motor()))
    mt.simulate(direct, 2 * TS, solver="rk4", dt=DT)              # warm-up
    ref, t_direct = clock(mt.simulate, direct, t_stop, solver="rk4", dt=DT)
    w_ref = ref["plant.w"][np.searchsorted(ref.t, ticks - 1e-12)]
    rows = []
    for label, kind, kw in (("rodas4", "cs", {}), ("rk45", "cs", {"solver": "rk45"}),
                            ("rk4", "cs", {"solver": "rk4", "dt": DT}),
                            ("rodas4, model exchange", "me", {})):
        cm = mt.compile_model(_loop(mt.FMUComponent(paths[kind], Ts=TS, outputs=["w"])))
        mt.simulate(cm, 2 * TS, **kw)                                 # warm-up
        res, wall = clock(mt.simulate, cm, t_stop, **kw)
        w = res["plant.w"][np.searchsorted(res.t, ticks - 1e-12)]
        n = res.stats.communication_steps
        rows.append({"host": label, "fmu": kind, "wall_s": wall, "steps": n,
                     "ms_per_step": 1e3 * wall / n,
                     "max_abs_dw_vs_direct": float(np.max(np.abs(w - w_ref)))})
        log(f"fmu import {label}: {n} steps in {wall:.3f} s")
    return {"t_stop_s": t_stop, "communication_step_s": TS, "direct_rk4_s": t_direct,
            "rows": rows}


if __name__ == "__main__":
    main(run)
