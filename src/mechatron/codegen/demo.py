"""The code-generation part of ``mechatron demo``: the DC motor's C and FMU, end to end."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import mechatron as mt
from mechatron.codegen._common import CodegenError
from mechatron.codegen.c import build, generate_c, measure_ns_per_step, run_harness
from mechatron.codegen.compare import max_relative_difference
from mechatron.codegen.fmu import export_fmu

__all__ = ["demo_run", "DEMO_DT", "DEMO_T_STOP"]

DEMO_DT = 1e-4        # 10 kHz
DEMO_T_STOP = 0.1


def _fmu_check(path: Path, desk) -> dict:
    """Validate and simulate the FMU with FMPy when it is installed."""
    try:
        from fmpy import simulate_fmu
        from fmpy.validation import validate_fmu
    except ImportError:
        return {"fmpy": False}
    problems = validate_fmu(str(path))
    res = simulate_fmu(str(path), stop_time=DEMO_T_STOP, output_interval=DEMO_DT,
                       output=["inertia.w", "inductor.i"])
    diff = max(float(np.max(np.abs(res[n] - desk[n])) / np.max(np.abs(desk[n])))
               for n in ("inertia.w", "inductor.i"))
    return {"fmpy": True, "validation_problems": problems,
            "max_rel_difference_to_desktop": diff}


def demo_run(out_dir) -> dict:
    """Generate, compile and run the DC motor's C (RK4 at 10 kHz), time one step, and
    export and check its FMI 2.0 co-simulation FMU.

    Returns
    -------
    dict
        ``c_dir``, ``csv``, ``steps``, ``max_rel_difference`` (harness against the desktop
        fixed-step run, every logged variable), ``final_w`` and ``analytic_w`` (the steady
        state ``k V / (R B + k^2)``), ``ns_per_step``, ``operations``, ``fmu`` (path) and
        ``fmu_check`` (FMPy's validation problems and the FMU's deviation from the desktop
        run, when FMPy is installed).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    entry = mt.models.get("dc_motor")
    cm = mt.compile_model(entry.build())
    code = generate_c(cm, out / "dc_motor_c", solver="rk4", dt=DEMO_DT, t_stop=DEMO_T_STOP,
                      name="dc_motor")
    build(code)
    csv = out / "dc_motor_c.csv"
    c_res = run_harness(code, out=csv)
    desk = mt.simulate(cm, DEMO_T_STOP, solver="rk4", dt=DEMO_DT)
    diff = max_relative_difference(c_res, desk)
    timing = measure_ns_per_step(code, steps=500_000)
    v = entry.values()
    fmu = out / "dc_motor.fmu"
    try:
        export_fmu(cm, fmu, fmi=2, kind="cs", solver="rk4", dt=DEMO_DT, t_stop=DEMO_T_STOP,
                   name="dc_motor")
        fmu_check = _fmu_check(fmu, desk)
    except CodegenError as exc:         # e.g. no FMI platform name for this machine
        fmu, fmu_check = None, {"error": str(exc)}
    return {"c_dir": str(code.directory), "csv": str(csv), "steps": len(desk.t) - 1,
            "max_rel_difference": diff, "final_w": c_res.final("inertia.w"),
            "analytic_w": v["k"] * v["V"] / (v["R"] * v["B"] + v["k"] ** 2),
            "ns_per_step": timing["ns_per_step"], "operations": code.operations,
            "fmu": None if fmu is None else str(fmu), "fmu_check": fmu_check}
