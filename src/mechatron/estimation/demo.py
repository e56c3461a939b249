"""The seed's chapter 6 on the virtual bench, end to end (for ``mechatron demo``).

1. Measure: locked-rotor, voltage-step and multi-step runs and a friction curve from the
   virtual bench (hidden truth: table 6-1).
2. Classic tests (6.1): R, L, k, B, T_C, J and the Stribeck curve.
3. Sensitivity (6.2): Sobol indices of the current and speed errors; the best sample.
4. Estimation (6.3): R, L, k, J, B, T_C and the current offset from the locked-rotor and
   multi-step runs, starting from the best sensitivity sample; breakaway friction fixed at
   the Stribeck fit.
5. Response optimization (6.4): the speed PI gains, overshoot < 5%, settling by 25 ms,
   |i| <= 3 A, verified by an independent simulation.

:func:`demo_run` returns the key figures and writes plots into ``out_dir``; it does not
print.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

__all__ = ["demo_run"]

FREE = ("R", "L", "k", "J", "B", "T_C")


def demo_run(out_dir, *, seed: int = 0, samples: int = 16, workers: int | None = 1) -> dict:
    """Run the workflow; returns ``{"classic", "sensitivity", "estimation",
    "optimization", "files", "checks", "wall_s"}`` (errors in percent of the truth)."""
    from mechatron.estimation import classic
    from mechatron.estimation.bench import VirtualBench
    from mechatron.estimation.optimize import (DesignVariable, ResponseProblem,
                                               SignalBound, StepResponse,
                                               optimize_response, verify)
    from mechatron.estimation.problem import EstimationProblem, FreeParameter, estimate
    from mechatron.estimation.sensitivity import Distribution, run_sensitivity
    from mechatron.models.dc_motor_control import DCMotorSpeedPIVoltage

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    bench = VirtualBench(seed=seed)
    truth = bench.truth

    def err(v, n):
        return 100 * (v / truth[n] - 1)

    # 1-2: measurements and classic tests
    locked, step, multi = bench.locked_rotor(), bench.voltage_step(t_stop=0.04), \
        bench.multi_step()
    curve = bench.friction_curve(np.concatenate([np.linspace(0.01, 1, 25),
                                                 np.linspace(1.5, 150, 20)]))
    R = classic.locked_rotor_resistance(locked)
    L = classic.electrical_time_constant(locked, R.value)
    k, B, T_C = classic.free_running_constants(multi, R.value)
    J = classic.mechanical_time_constant(step, R.value, k.value, B.value, L.value)
    fric = classic.fit_stribeck(curve.w, k.value * curve.i)
    cls = {"R": R.value, "L": L.value, "k": k.value, "B": B.value, "T_C": T_C.value,
           "J": J.value, "T_brk": fric["T_brk"].value, "w_brk": fric["w_brk"].value}
    classic_out = {"values": cls, "errors_pct": {n: err(v, n) for n, v in cls.items()},
                   "current_offset_A": R.details["offset_A"]}
    fixed = {"T_brk": fric["T_brk"].value, "w_brk": fric["w_brk"].value}

    # 3: sensitivity around the classic values (+-30%)
    prob_s = EstimationProblem(bench.model(), [bench.voltage_step(t_stop=0.02)],
                               [FreeParameter(n, cls[n], 0.0) for n in FREE],
                               inputs={"V": "V"}, outputs={"i": "i", "w": "rate(phi)"},
                               offsets=["i"], fixed=fixed)
    dists = {n: Distribution("uniform", 0.7 * cls[n], 1.3 * cls[n]) for n in FREE}
    sens = run_sensitivity(prob_s, dists, n=samples, method="sobol", seed=seed,
                           workers=workers)
    best = sens.best[0]
    files = [sens.plot_tornado(out / "sensitivity_tornado.png")]

    # 4: estimation from the best sample
    prob = EstimationProblem(bench.model(), [multi, locked],
                             [FreeParameter(n, best[n], 0.0) for n in FREE],
                             inputs={"V": "V"}, outputs={"i": "i", "w": "rate(phi)"},
                             offsets=["i"], fixed=fixed)
    res = estimate(prob)
    files += [res.plot_fit(out / "estimation_fit.png"),
              res.plot_trajectory(out / "estimation_trajectory.png")]
    est = {"values": {n: res.parameters[n] for n in FREE},
           "start": {n: best[n] for n in FREE},
           "errors_pct": {n: err(res.parameters[n], n) for n in FREE},
           "ci95": {n: list(res.ci95[n]) for n in FREE},
           "ci95_contains_truth": {n: bool(res.ci95[n][0] <= truth[n] <= res.ci95[n][1])
                                   for n in FREE},
           "iterations": res.iterations, "wall_s": res.wall_time, "nrmse": res.nrmse}

    # 5: response optimization of the speed PI loop
    reqs = [StepResponse("w", 100.0, rise_time=0.01, overshoot_pct=5.0,
                         settling_time=0.025),
            SignalBound("i", -3.0, 3.0)]
    rp = ResponseProblem(DCMotorSpeedPIVoltage(),
                         [DesignVariable("Kp", 0.05, 1e-4, 1.0),
                          DesignVariable("Ki", 5.0, 0.0, 200.0)],
                         reqs, t_stop=0.05, n_points=1001)
    opt = optimize_response(rp)
    before, after = verify(rp, opt.initial), verify(rp, opt.values)
    files.append(opt.plot(out / "speed_pi_optimization.png"))
    optim = {"start": dict(zip(opt.names, map(float, opt.initial))),
             "optimized": opt.parameters, "iterations": opt.iterations,
             "wall_s": opt.wall_time,
             "requirements": [{"requirement": a["requirement"], "limit": a["limit"],
                               "start": b["value"], "optimized": a["value"],
                               "met": a["met"]}
                              for a, b in zip(after["rows"], before["rows"])],
             "all_met": after["all_met"]}

    checks = {
        "classic R within 3%": abs(classic_out["errors_pct"]["R"]) < 3,
        "classic k within 3%": abs(classic_out["errors_pct"]["k"]) < 3,
        "estimation R, L, k, J, B within 2%": all(abs(est["errors_pct"][n]) < 2
                                                  for n in ("R", "L", "k", "J", "B")),
        "95% intervals contain the truth": all(est["ci95_contains_truth"][n]
                                               for n in ("R", "L", "k", "J", "B")),
        "sensitivity puts k, R, J first": set(sens.ranking[:3]) == {"k", "R", "J"},
        "speed PI requirements met": after["all_met"],
    }
    return {"truth": {n: truth[n] for n in (*FREE, "T_brk", "w_brk")},
            "classic": classic_out,
            "sensitivity": {"ranking": sens.ranking, "simulations": sens.evaluations,
                            "simulations_per_s": sens.throughput,
                            "best_sample": best},
            "estimation": est, "optimization": optim,
            "files": [str(f) for f in files], "checks": checks,
            "wall_s": time.perf_counter() - start}
