"""PWM-driven DC motor: cost per switching event as the simulated time doubles.

A 10 kHz ``blocks.PWM`` (duty 0.5) drives the seed's DC motor through a controlled voltage
source; every period has two events (the tick that latches the duty and the falling edge),
handled inside CasADi's integrator by the compiled transition function (no Python per
event). The benchmark simulates 0.25, 0.5 and 1 s (``--quick``: 0.05, 0.1, 0.2 s) on the
compiled model and reports wall time, events, steps and microseconds per event: a flat
time per event means the cost is linear in the number of events. The mean armature
current (integrated by a state) is compared with the averaged model driven by
``DUTY * V``. Each duration runs twice: with ``solver="auto"`` (CasADi's Dormand-Prince
with events) and with ``solver="rodas4"`` (model, Rosenbrock integrator and event
location compiled to one C library), and the ratio of their wall times is printed.

Run: ``python bench/bench_pwm.py [--quick]``; prints one JSON document.
"""

from __future__ import annotations

import _common  # noqa: F401  (import path)
from _common import clock, log, main

import numpy as np

import mechatron as mt
from mechatron.models.dc_motor_pwm import pwm_motor

V, R, L, K, J, B = 19.2, 7.1, 3.408e-4, 0.151, 4.8e-6, 1.236e-4
F_PWM, DUTY = 10e3, 0.5


def _model(averaged: bool) -> mt.System:
    return pwm_motor(averaged, V=V, R=R, L=L, k=K, J=J, B=B, duty=DUTY, f_pwm=F_PWM)


def run(quick: bool = False, tiny: bool = False,
        durations: tuple[float, ...] | None = None) -> dict:
    """Wall time per event for doubling durations (default: 0.25, 0.5, 1 s; ``quick``:
    0.05, 0.1, 0.2 s; ``tiny``: 2 and 4 ms); mean current against the average."""
    cm, t_compile = clock(mt.compile_model, _model(False))
    avg_cm = mt.compile_model(_model(True))
    if durations is None:
        durations = ((0.002, 0.004) if tiny else (0.05, 0.1, 0.2) if quick
                     else (0.25, 0.5, 1.0))
    mt.simulate(cm, durations[0] / 10)          # builds the integrator once (warm-up)
    _, build = clock(mt.simulate, cm, durations[0] / 10, solver="rodas4")   # C build
    rows = []
    for solver in ("auto", "rodas4"):
        for t_stop in durations:
            grid = np.linspace(0, t_stop, 101)
            res, wall = clock(mt.simulate, cm, t_stop, t_out=grid, solver=solver)
            avg = mt.simulate(avg_cm, t_stop, t_out=grid, rtol=1e-9, atol=1e-12)
            events = sum(res.stats.events.values())
            mean_pwm = res.final("charge.y") / t_stop
            mean_avg = avg.final("charge.y") / t_stop
            rows.append({"t_stop_s": t_stop, "wall_s": wall, "events": events,
                         "steps": res.stats.steps, "solver": res.stats.solver,
                         "us_per_event": 1e6 * wall / events,
                         "mean_current_A": mean_pwm, "averaged_mean_current_A": mean_avg,
                         "rel_err_mean_current": abs(mean_pwm - mean_avg) / mean_avg})
            log(f"pwm {solver} {t_stop:g} s: {events} events in {wall:.3f} s "
                f"({rows[-1]['us_per_event']:.1f} us/event)")
    out = {"compile_s": t_compile, "rodas4_build_s": build, "f_pwm_hz": F_PWM, "rows": rows}
    walls = {}
    for solver in ("auto", "rodas4"):
        mine = [r for r in rows if (r["solver"] == "rodas4") == (solver == "rodas4")]
        out[f"us_per_event_growth_{solver}"] = mine[-1]["us_per_event"] / mine[0]["us_per_event"]
        walls[solver] = [r["wall_s"] for r in mine]
    out["ratio_auto_over_rodas4"] = [a / b for a, b in zip(walls["auto"], walls["rodas4"])]
    return out


if __name__ == "__main__":
    main(run)
