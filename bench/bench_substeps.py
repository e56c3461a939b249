"""Substeps chosen from an error estimate: what a kink in the dynamics costs.

The saturated speed loop ``J w' = sat(Kp (r - w)) - B w`` with the saturation written with
``fmin``/``fmax`` (a kink, no event) against its smooth twin ``tanh(Kp (r - w))``, on the
same reference (6 s at 100 Hz, 1% noise of a 10 rad/s signal), data from CVODES at rtol
1e-10; and a 60 rad/s resonance sampled at 20 Hz, where the time constants' rule gives a
single substep. Per case: the substeps chosen, the step-doubling error estimate (standard
errors) at the start and at the estimates, the estimates against the truth (in standard
errors), and the wall time of problem set-up plus fit (interpreted CasADi, ``jit=False``
for both, so that no C compile enters the ratio).

Run: ``python bench/bench_substeps.py [--quick]``; prints one JSON document.
"""

from __future__ import annotations

import _common  # noqa: F401  (import path)
from _common import log, main

import logging
import time

import casadi as ca
import numpy as np

import mechatron as mt
from mechatron.estimation import EstimationProblem, Experiment, FreeParameter, estimate


class Kinked(mt.Component):
    J = mt.Parameter("1", default=0.01)
    B = mt.Parameter("1", default=0.05)
    Kp = mt.Parameter("1", default=1.0)
    r = mt.Input("1", start=0.0)
    w = mt.Variable("1", start=0.0)

    def equations(self):
        u = ca.fmin(ca.fmax(self.Kp * (self.r - self.w), -1.0), 1.0)
        return [self.J * mt.der(self.w) == u - self.B * self.w]


class Smooth(mt.Component):
    J = mt.Parameter("1", default=0.01)
    B = mt.Parameter("1", default=0.05)
    Kp = mt.Parameter("1", default=1.0)
    r = mt.Input("1", start=0.0)
    w = mt.Variable("1", start=0.0)

    def equations(self):
        return [self.J * mt.der(self.w) == ca.tanh(self.Kp * (self.r - self.w))
                - self.B * self.w]


class Resonator(mt.Component):
    w = mt.Parameter("1/s", default=60.0)
    zeta = mt.Parameter("1", default=0.02)
    r = mt.Input("1", start=0.0)
    x = mt.Variable("1", start=0.0)
    v = mt.Variable("1/s", start=0.0)

    def equations(self):
        return [mt.der(self.x) == self.v,
                mt.der(self.v) == self.w ** 2 * (self.r - self.x)
                - 2 * self.zeta * self.w * self.v]


def _reference(t, amp):
    return amp * (np.sin(2 * np.pi * 0.5 * t)
                  + 0.5 * np.sign(np.sin(2 * np.pi * 0.2 * t + 0.3)))


def case(model, t, out, sigma, amp, free, truth, substeps=None, seed=0):
    cm = mt.compile_model(model)
    r = _reference(t, amp)
    res = mt.simulate(cm, float(t[-1]), t_out=t, inputs={"r": (t, r)}, solver="cvodes",
                      rtol=1e-10, atol=1e-12)
    y = res[out] + sigma * np.random.default_rng(seed).standard_normal(t.size)
    exp = Experiment(t=t, inputs={"r": r}, outputs={"y": y}, sigma={"y": sigma},
                     name="synthetic", hold="linear")
    start = time.perf_counter()
    prob = EstimationProblem(cm, [exp], free, inputs={"r": "r"}, outputs={"y": out},
                             substeps=substeps, jit=False)
    built = time.perf_counter()
    fit = estimate(prob, refine=substeps is None)
    wall = time.perf_counter() - start
    d = fit.discretization["synthetic"]
    return {"substeps": d["substeps"], "chosen": d["chosen"],
            "error_initial": d["error_initial"], "error_final": d["error"],
            "setup_s": built - start, "wall_s": wall, "evaluations": fit.evaluations,
            "estimates": fit.parameters,
            "bias_in_std": {k: (fit.parameters[k] - v) / fit.std[fit.names.index(k)]
                            for k, v in truth.items()},
            "truth_in_ci95": {k: fit.ci95[k][0] <= v <= fit.ci95[k][1]
                              for k, v in truth.items()}}


def run(quick: bool = False, tiny: bool = False) -> dict:
    """Substeps, error estimates, estimates and wall times of the kink, smooth and resonance cases."""
    logger = logging.getLogger("mechatron")
    level = logger.level
    logger.setLevel(logging.ERROR)      # the cases' warnings are expected; restored below
    try:
        return _run(tiny)
    finally:
        logger.setLevel(level)


def _run(tiny: bool) -> dict:
    t_end = 2.0 if tiny else 6.0
    t = np.round(np.arange(0, t_end + 1e-9, 0.01), 12)
    loop_free = [FreeParameter("J", 0.02, 0), FreeParameter("B", 0.1, 0)]
    truth = {"J": 0.01, "B": 0.05}
    out = {}
    for name, model, sub in (("kink_error_based", Kinked(), None),
                             ("kink_one_substep", Kinked(), 1),
                             ("smooth_error_based", Smooth(), None)):
        out[name] = case(model, t, "w", 0.01, 10.0, loop_free, truth, substeps=sub)
        log(f"{name}: m = {out[name]['substeps']}, {out[name]['wall_s']:.2f} s")
    out["kink_over_smooth_wall"] = (out["kink_error_based"]["wall_s"]
                                    / out["smooth_error_based"]["wall_s"])
    tr = np.round(np.arange(0, 4 + 1e-9, 0.05), 12)
    res_free = [FreeParameter("w", 50.0, 0), FreeParameter("zeta", 0.02, 0)]
    for name, sub in (("resonance_error_based", None), ("resonance_time_constant_rule", 1)):
        out[name] = case(Resonator(), tr, "x", 0.01, 1.0, res_free,
                         {"w": 60.0, "zeta": 0.02}, substeps=sub)
        log(f"{name}: m = {out[name]['substeps']}, {out[name]['wall_s']:.2f} s")
    return out


if __name__ == "__main__":
    main(run)
