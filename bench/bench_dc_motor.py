"""DC motor, 0.5 s, variable step: Mechatron against hand-written SciPy ``solve_ivp``.

The model is the database entry ``dc_motor`` (acausal variant), compiled once. Mechatron's
figure is the wall time of ``mt.simulate`` on the compiled model: the first call (which
builds the CasADi/CVODES integrator) and the median of the following calls; for two
solvers: ``"cvodes"`` (SUNDIALS through CasADi, the default for ODEs) and ``"rodas4"``
(model and Rosenbrock integrator compiled to one C library; its first call in a fresh
cache folder includes the C compiler run, reported as ``build_s``). The SciPy
baselines integrate the same ODE

    L di/dt = V - R i - k w,      J dw/dt = k i - B w

written by hand as ``y' = A y + b``, with LSODA, with BDF and the analytic Jacobian ``A``,
and with BDF and a finite-difference Jacobian. Every run uses rtol 1e-6, atol 1e-8 and the
same 1001 output points. Final values are compared with the analytic steady state
``w = k V / (R B + k^2)``, ``i = B V / (R B + k^2)`` (reached within 0.5 s: the mechanical
time constant is about 1.4 ms).

Run: ``python bench/bench_dc_motor.py [--quick]``; prints one JSON document.
"""

from __future__ import annotations

import _common  # noqa: F401  (import path)
from _common import clock, log, logging_alternative, main, profiled, ratio, repeat, summary

import numpy as np
from scipy.integrate import solve_ivp

import mechatron as mt

T_STOP = 0.5
RTOL, ATOL = 1e-6, 1e-8
N_OUT = 1001


def _scipy_runs(P: dict, t_out: np.ndarray, n: int) -> dict:
    R, L, k, J, B, V = (P[key] for key in ("R", "L", "k", "J", "B", "V"))
    A = np.array([[-R / L, -k / L],
                  [k / J, -B / J]])
    b = np.array([V / L, 0.0])

    def rhs(t, y):
        return A @ y + b

    def jac(t, y):
        return A

    y0 = np.zeros(2)
    variants = {
        "scipy_LSODA": dict(method="LSODA"),
        "scipy_BDF_analytic_jac": dict(method="BDF", jac=jac),
        "scipy_BDF_fd_jac": dict(method="BDF"),
    }
    out = {}
    for name, opts in variants.items():
        def once(opts=opts):
            return solve_ivp(rhs, (0.0, T_STOP), y0, t_eval=t_out, rtol=RTOL, atol=ATOL,
                             **opts)
        sol, times = repeat(once, n)
        if not sol.success:
            out[name] = {"error": sol.message}
            continue
        out[name] = {"time": summary(times), "final_i": sol.y[0, -1],
                     "final_w": sol.y[1, -1], "nfev": sol.nfev, "njev": sol.njev,
                     "nlu": sol.nlu}
        log(f"dc_motor {name}: median {out[name]['time']['median_s'] * 1e3:.2f} ms")
    return out


def _integrator_only(cm, t_out, n: int) -> dict | None:
    """``integrate_variable`` alone (no initialization, no logging), via internals."""
    try:
        from mechatron.solvers.initial import initialize
        from mechatron.solvers.variable import integrate_variable
    except ImportError:
        return None
    p = cm.p0.copy()
    try:
        X0, z0, _ = initialize(cm, p, 0.0)
        _, times = repeat(lambda: integrate_variable(cm, t_out, X0, z0, p, solver="cvodes",
                                                     rtol=RTOL, atol=ATOL), n)
    except (TypeError, ValueError, RuntimeError) as exc:  # internals changed under us
        return {"error": f"{type(exc).__name__}: {exc}"}
    return summary(times)


def _rodas4_runs(cm, t_out, n: int, fresh_build: bool = True) -> dict:
    """``mt.simulate(solver="rodas4")``: the C build in an empty cache folder, then the
    median of repeated calls (the library loaded). ``fresh_build=False`` (the tests'
    tiny run) uses the user's cache instead of an empty one."""
    import os
    import tempfile

    def sim():
        return mt.simulate(cm, T_STOP, solver="rodas4", rtol=RTOL, atol=ATOL, t_out=t_out)

    saved = os.environ.get("MECHATRON_CACHE")
    with tempfile.TemporaryDirectory() as tmp:
        if fresh_build:
            os.environ["MECHATRON_CACHE"] = tmp
            cm._cache.pop("native_rodas4", None)
        try:
            res, build = clock(sim)
        finally:
            if saved is None:
                os.environ.pop("MECHATRON_CACHE", None)
            else:
                os.environ["MECHATRON_CACHE"] = saved
        res, times = repeat(sim, max(n, 25) if fresh_build else n)
    st = res.stats
    log(f"dc_motor mechatron rodas4: build {build * 1e3:.0f} ms, "
        f"median {summary(times)['median_s'] * 1e6:.0f} us")
    return {"build_s": build, "simulate": summary(times), "result": res,
            "stats": {"solver": st.solver, "steps": st.steps,
                      "rejected_steps": st.rejected_steps, "rhs_evals": st.rhs_evals,
                      "jac_evals": st.jac_evals}}


def run(quick: bool = False, tiny: bool = False) -> dict:
    """DC motor: Mechatron simulate vs SciPy solve_ivp (LSODA, BDF), same ODE, same rtol."""
    n_rep = 1 if tiny else 5 if quick else 15
    entry = mt.models.get("dc_motor")
    P = entry.values()
    w_inf = P["k"] * P["V"] / (P["R"] * P["B"] + P["k"] ** 2)
    i_inf = P["B"] * P["V"] / (P["R"] * P["B"] + P["k"] ** 2)
    paths = entry.output_paths("acausal")

    # compile time: a fresh instance each time
    compile_times, build_times = [], []
    for _ in range(n_rep):
        model, tb = clock(entry.build, "acausal")
        cm, tc = clock(mt.compile_model, model)
        build_times.append(tb)
        compile_times.append(tc)
    log(f"dc_motor compile (acausal): median {summary(compile_times)['median_s'] * 1e3:.1f} ms")

    t_out = np.linspace(0.0, T_STOP, N_OUT)

    def sim():
        return mt.simulate(cm, T_STOP, solver="cvodes", rtol=RTOL, atol=ATOL, t_out=t_out)

    res, first = clock(sim)
    res, times = repeat(sim, n_rep)
    mech = summary(times)
    stats = res.stats
    w_end, i_end = float(res[paths["w"]][-1]), float(res[paths["i"]][-1])
    log(f"dc_motor mechatron simulate: first {first * 1e3:.2f} ms, "
        f"median {mech['median_s'] * 1e3:.2f} ms")
    integ = _integrator_only(cm, t_out, n_rep)
    _, t_prof, where = profiled(sim)
    alternative = logging_alternative(cm, res, t_out)

    def default_sim():
        return mt.simulate(cm, T_STOP, rtol=RTOL, atol=ATOL, t_out=t_out)

    d_res, d_first = clock(default_sim)     # a library of this structure built or loaded
    d_res, d_times = repeat(default_sim, max(n_rep, 25) if not tiny else n_rep)
    default = {"first_call_s": d_first, "simulate": summary(d_times),
               "solver": d_res.stats.solver, "solver_reason": d_res.stats.solver_reason}
    log(f"dc_motor mechatron default ({d_res.stats.solver}): median "
        f"{default['simulate']['median_s'] * 1e6:.0f} us")
    rodas = _rodas4_runs(cm, t_out, n_rep, fresh_build=not tiny)
    r_res = rodas.pop("result")
    scipy_res = _scipy_runs(P, t_out, n_rep)

    def agreement(w, i):
        return {"final_w": w, "final_i": i, "rel_err_w": abs(w - w_inf) / w_inf,
                "rel_err_i": abs(i - i_inf) / i_inf}

    rodas.update(agreement(float(r_res[paths["w"]][-1]), float(r_res[paths["i"]][-1])))
    baselines = {}
    for name, r in scipy_res.items():
        if "error" in r:
            baselines[name] = r
            continue
        baselines[name] = {
            "time": r["time"],
            "ratio_scipy_over_mechatron": ratio(r["time"]["median_s"], mech["median_s"]),
            "ratio_scipy_over_mechatron_integrator_only":
                ratio(r["time"]["median_s"], (integ or {}).get("median_s")),
            "ratio_scipy_over_mechatron_rodas4":
                ratio(r["time"]["median_s"], rodas["simulate"]["median_s"]),
            "ratio_scipy_over_mechatron_default":
                ratio(r["time"]["median_s"], default["simulate"]["median_s"]),
            "counts": {"nfev": r["nfev"], "njev": r["njev"], "nlu": r["nlu"]},
            **agreement(r["final_w"], r["final_i"]),
        }
    return {
        "benchmark": "dc_motor",
        "settings": {"t_stop_s": T_STOP, "rtol": RTOL, "atol": ATOL, "output_points": N_OUT,
                     "mechatron_solver": "cvodes", "parameters_SI": P},
        "analytic_final": {"w_rad_s": w_inf, "i_A": i_inf},
        "compile_acausal": {"time": summary(compile_times),
                            "build_instance_time": summary(build_times),
                            "report_timings_s": cm.report.get("timings", {}),
                            "equations": cm.report.get("equations"),
                            "variables": cm.report.get("variables"),
                            "states": cm.report.get("states")},
        "mechatron": {
            "first_call_s": first,
            "simulate": mech,
            "integrator_only": integ,
            "profiled_call": {"seconds": t_prof, **where},
            "logging_by_buffer": alternative,
            "stats": {"solver": stats.solver, "steps": stats.steps,
                      "rejected_steps": stats.rejected_steps, "rhs_evals": stats.rhs_evals,
                      "jac_evals": stats.jac_evals, "wall_time_s": stats.wall_time},
            **agreement(w_end, i_end),
        },
        "mechatron_rodas4": rodas,
        "mechatron_default": default,
        "scipy": baselines,
        "notes": ["ratio = SciPy median time / Mechatron median simulate time (first call "
                  "excluded); > 1 means Mechatron is faster. ratio_..._rodas4: the same "
                  "with solver='rodas4'.",
                  "integrator_only: mechatron.solvers.variable.integrate_variable alone (the "
                  "CVODES run and the conversion of its states to NumPy), without "
                  "initialization and without evaluating the logged variables.",
                  "profiled_call: one more simulate call under cProfile; cumulative seconds of "
                  "the dominant native calls (they overlap).",
                  "logging_by_buffer: every logged variable evaluated with "
                  "casadi.Function.buffer into NumPy instead, for comparison."],
    }


if __name__ == "__main__":
    main(run)
