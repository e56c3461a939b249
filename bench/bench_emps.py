"""EMPS estimation on real data: Mechatron's general path against SciPy, same model, same run.

The EMPS benchmark (A. Janot, M. Gautier, M. Brunot, "Data Set and Reference Models of
EMPS", 2019 Workshop on Nonlinear System Identification Benchmarks): M, Fv, Fc and the
offset force of a positioning axis under its sampled cascade controller, from the logged
reference and motor position of ``emps_estimation.csv`` (24,841 samples at 1 kHz),
starting from M 60, Fv 100, Fc 10, offset 0, as ``examples/emps_estimate.toml`` does.

* Mechatron: ``EstimationProblem`` on the database model ``emps`` (sampled controller and
  saturation as events inside the fitted model) + ``estimate`` (exact forward
  sensitivities through the Radau substeps and the events, Levenberg-Marquardt). Wall
  time from problem set-up to result, first run (native code compiled or loaded from the
  cache) and second run.
* Peer: ``scipy.optimize.least_squares`` (trust-region reflective, 2-point finite
  differences) on the same residuals (the same compiled model and discretization,
  without sensitivities), from the same start.

Fit figures: the parameters and their differences from the authors' IDIM-LS values, the
position NRMSE on the estimation set and the position RMS error on the validation set
(``emps_validation_pulses.csv``, not fitted) beside the authors' parameters in the same
simulation.

The data are read from ``<repo>/../shared/data/emps`` or ``$MECHATRON_EMPS_DATA``; when
absent, data simulated from the model with the reference values (1 um noise) stand in
(``"data": "synthetic"``). ``tiny``: the first 800 samples.

Run: ``python bench/bench_emps.py [--quick]``; prints one JSON document.
"""

from __future__ import annotations

import _common  # noqa: F401  (import path)
from _common import ROOT, log, main

import os
import time
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

import mechatron as mt
from mechatron.estimation import EstimationProblem, Experiment, estimate
from mechatron.estimation.data import load_experiment
from mechatron.estimation.problem import validation_errors
from mechatron.models.emps import REFERENCE

NAMES = ["M", "Fv", "Fc", "offset"]
START = {"M": 60.0, "Fv": 100.0, "Fc": 10.0, "offset": 0.0}
SIGMA = 2e-6
GOAL_S = 10.0


def data_dir() -> Path:
    return Path(os.environ.get("MECHATRON_EMPS_DATA")
                or ROOT / ".." / "shared" / "data" / "emps")


def _at_rest(e: Experiment) -> Experiment:
    q0 = float(e.outputs["qm"][0])
    e.x0.update(q=q0, q_prev=q0, qf_prev=q0)
    return e


def _real(name: str, n: int | None) -> Experiment:
    path = data_dir() / name
    pulses = "pulse" in name
    inputs = {"qg": "qg_m", **({"pulse": "pulse_V"} if pulses else {})}
    e = load_experiment(path, time="t_s", inputs=inputs, outputs={"qm": "qm_m"},
                        units={"qg": "m", "pulse": "V", "qm": "m"}, sigma={"qm": SIGMA},
                        name=path.stem, params={} if pulses else {"pulse": 0.0})
    if n is not None:
        e = Experiment(name=e.name, t=e.t[:n], inputs={k: v[:n] for k, v in e.inputs.items()},
                       outputs={k: v[:n] for k, v in e.outputs.items()}, units=e.units,
                       params=e.params, sigma=e.sigma)
    return _at_rest(e)


def _synthetic(name: str, n: int, seed: int, pulses: bool) -> Experiment:
    """Moves of 0.2 m back and forth with rests, simulated with the reference values."""
    t = np.round(np.arange(n) * 1e-3, 9)
    qg = 0.1 * (1 - np.cos(2 * np.pi * t / 3.0)) * (1 + 0.2 * np.sin(2 * np.pi * t / 7.0))
    pulse = 5.0 * ((t % 1.0) < 0.5) * (t > 1.0) if pulses else np.zeros(n)
    res = mt.simulate(mt.models.get("emps").build(), float(t[-1]), t_out=t,
                      inputs={"qg": (t, qg), "pulse": (t, pulse)}, rtol=1e-9, atol=1e-12)
    qm = res["q"] + 1e-6 * np.random.default_rng(seed).standard_normal(n)
    inputs = {"qg": qg, **({"pulse": pulse} if pulses else {})}
    return _at_rest(Experiment(name=name, t=t, inputs=inputs, outputs={"qm": qm},
                               sigma={"qm": SIGMA},
                               params={} if pulses else {"pulse": 0.0}))


def _problem(cm, exp, validation=()):
    free = [dict(name="M", initial=START["M"], min=1.0),
            dict(name="Fv", initial=START["Fv"], min=0.0),
            dict(name="Fc", initial=START["Fc"], min=0.0),
            dict(name="offset", initial=START["offset"], scale=10.0)]
    return EstimationProblem(cm, [exp], free, inputs={"qg": "qg", "pulse": "pulse"},
                             outputs={"qm": "q"}, validation=validation)


def _errors(values: dict) -> dict:
    return {n: 100 * (values[n] / REFERENCE[n] - 1) for n in NAMES}


def run(quick: bool = False, tiny: bool = False) -> dict:
    """EMPS estimation: Mechatron's general path and SciPy least_squares, same model."""
    n = 800 if tiny else None
    real = (data_dir() / "emps_estimation.csv").exists()
    if real:
        est = _real("emps_estimation.csv", n)
        val = _real("emps_validation_pulses.csv", n)
    else:
        log(f"EMPS data not found in {data_dir()}: synthetic data from the model")
        est = _synthetic("estimation", n or 12000, 0, False)
        val = _synthetic("validation_pulses", n or 12000, 1, True)
    out = {"data": "real" if real else "synthetic",
           "case": {"estimation_samples": int(est.n), "validation_samples": int(val.n),
                    "free": NAMES, "start": START, "reference": REFERENCE,
                    "citation": "Janot, Gautier, Brunot 2019 (EMPS benchmark)"},
           "goal_s": GOAL_S}

    # -- Mechatron: the general path
    times, setups, cpus = [], [], []
    for k in range(1 if tiny else 2):
        c0 = time.process_time()
        t0 = time.perf_counter()
        cm = mt.compile_model(mt.models.get("emps").build())
        prob = _problem(cm, est, [val])
        setups.append(time.perf_counter() - t0)
        res = estimate(prob)
        times.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
        log(f"mechatron estimation run {k + 1}: {times[-1]:.2f} s, CPU {cpus[-1]:.2f} s "
            f"({setups[-1]:.2f} s set-up)")
    theirs = validation_errors(prob, np.array([REFERENCE[n] for n in NAMES]))
    v = res.validation[val.name]["qm"]
    out["mechatron"] = {
        "wall_s_first": times[0], "wall_s_second": times[-1],
        "cpu_s_first": cpus[0], "cpu_s_second": cpus[-1],
        "setup_s_first": setups[0], "setup_s_second": setups[-1],
        "iterations": res.iterations, "simulations": res.evaluations,
        "message": res.message, "parameters": res.parameters,
        "errors_vs_reference_pct": _errors(res.parameters),
        "ci95": {k: list(v) for k, v in res.ci95.items()},
        "nrmse_position_estimation": res.nrmse[est.name]["qm"],
        "validation_rmse_position_m": v["rmse"],
        "validation_relerr_position_pct": v["relerr_pct"],
        "reference_parameters_validation_rmse_position_m":
            theirs[val.name]["qm"]["rmse"],
        "substeps": [b["substeps"] for b in prob.bound],
        "native_code": [bool(b["traj"].jit) for b in prob.bound]}
    log(f"mechatron: {res.parameters}; validation RMSE {1e6 * v['rmse']:.3f} um")

    # -- SciPy least_squares with finite differences, the same residuals
    scales = np.array(prob.scales)
    lo, hi = prob.bounds
    x0 = prob.initial / scales
    c0 = time.process_time()
    t0 = time.perf_counter()
    sol = least_squares(lambda x: prob.residuals(x * scales), x0, jac="2-point",
                        method="trf", bounds=(lo / scales, hi / scales),
                        max_nfev=10 if tiny else 200, xtol=1e-10, ftol=1e-12)
    wall = time.perf_counter() - t0
    cpu = time.process_time() - c0
    est_sp = dict(zip(NAMES, sol.x * scales))
    vs = validation_errors(prob, sol.x * scales)[val.name]["qm"]
    out["scipy_least_squares_fd"] = {
        "wall_s": wall, "cpu_s": cpu, "nfev": int(sol.nfev),
        "njev": int(sol.njev) if sol.njev is not None else None,
        "message": sol.message, "parameters": est_sp,
        "errors_vs_reference_pct": _errors(est_sp),
        "cost": float(sol.cost * 2), "mechatron_cost": float(res.cost),
        "validation_rmse_position_m": vs["rmse"],
        "ratio_scipy_over_mechatron": wall / times[-1],
        "ratio_cpu_scipy_over_mechatron": cpu / cpus[-1]}
    log(f"scipy least_squares (2-point): {wall:.2f} s, CPU {cpu:.2f} s, {sol.nfev} "
        "residual evaluations, "
        f"{est_sp}")

    # -- Mechatron on SciPy's footing: the fit alone on the problem already set up (no
    # set-up, no step-doubling check at the solution; its statistics and validation run
    # are still in it)
    c0 = time.process_time()
    t0 = time.perf_counter()
    fit = estimate(prob, refine=False)
    fit_wall, fit_cpu = time.perf_counter() - t0, time.process_time() - c0
    out["mechatron"].update(fit_only_s=fit_wall, fit_only_cpu_s=fit_cpu,
                            fit_only_parameters=fit.parameters)
    out["scipy_least_squares_fd"].update(ratio_scipy_over_mechatron_fit=wall / fit_wall,
                                         ratio_cpu_scipy_over_mechatron_fit=cpu / fit_cpu)
    log(f"mechatron, the fit alone on the set-up problem: {fit_wall:.2f} s, CPU "
        f"{fit_cpu:.2f} s, {fit.parameters}")
    out["notes"] = [
        f"goal: EMPS estimation under {GOAL_S:g} s (wall_s_second: set-up and fit, native "
        "code loaded from the cache; cpu_s_*: process CPU time, the figure to read on a "
        "loaded machine).",
        "both fits simulate the same compiled model with the same Radau transcription; "
        "SciPy's Jacobian costs 4 extra simulations per evaluation, Mechatron's one "
        "simulation with sensitivities.",
        "SciPy's wall_s is the fit alone, on the problem Mechatron set up; "
        "mechatron.fit_only_s is Mechatron's on the same footing (estimate(prob, "
        "refine=False): no set-up, no step-doubling check at the solution, its statistics "
        "and validation run included).",
        "errors are relative to the authors' IDIM-LS values, a different criterion (force "
        "by inverse model) on the same data: a few percent in Fv and Fc is the floor."]
    return out


if __name__ == "__main__":
    main(run)
