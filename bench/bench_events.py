"""Event iteration: cost of an event whose actions chain, per solver.

A sample clock of 1 kHz increments a counter; a second ``when`` fires when the counter
is a multiple of 3 (the chain settles in the same instant, three rounds), and a located
crossing of a continuous state adds a third kind of event. The benchmark reports compile
time, the C build of ``rodas4``, and microseconds per event for ``auto`` (CasADi's
Dormand-Prince with the compiled transition), ``rodas4`` and the fixed-step ``euler``
(event iteration at the end of every step), plus the counts checked against the analytic
ones (ticks ``floor(t / T) + 1``).

Run: ``python bench/bench_events.py [--quick]``; prints one JSON document.
"""

from __future__ import annotations

import _common  # noqa: F401  (import path)
from _common import clock, log, main

import casadi as ca

import mechatron as mt

T = 1e-3


class Chained(mt.Component):
    n = mt.Discrete("1", start=0, kind="integer", doc="Ticks")
    thirds = mt.Discrete("1", start=0, kind="integer", doc="Ticks that are multiples of 3")
    x = mt.Variable("1", start=0.0, doc="Sawtooth, reset at 1")
    resets = mt.Discrete("1", start=0, kind="integer", doc="Resets of x")

    def equations(self):
        third = ca.fmod(self.n, 3) < 0.5
        return [mt.der(self.x) == 7.0,
                mt.when(mt.sample(0.0, T), update={self.n: mt.pre(self.n) + 1}),
                mt.when(mt.logic_and(third, self.n > 0.5),
                        update={self.thirds: self.thirds + 1}),
                mt.when(self.x >= 1.0, update=[mt.reinit(self.x, 0.0),
                                               (self.resets, self.resets + 1)])]


def run(quick: bool = False, tiny: bool = False) -> dict:
    """Microseconds per event of a chained event iteration, per solver."""
    cm, t_compile = clock(mt.compile_model, Chained())
    t_stop = 0.02 if tiny else 0.2 if quick else 1.0
    _, build = clock(mt.simulate, cm, 0.01, solver="rodas4")
    rows = []
    for solver, dt in (("auto", None), ("rodas4", None), ("euler", T / 4)):
        res, wall = clock(mt.simulate, cm, t_stop - T / 2, solver=solver, dt=dt)
        events = sum(res.stats.events.values())
        rows.append({"solver": res.stats.solver, "t_stop_s": t_stop, "wall_s": wall,
                     "events": events, "us_per_event": 1e6 * wall / max(events, 1),
                     "ticks": res.final("n"), "ticks_expected": round(t_stop / T),
                     "thirds": res.final("thirds"), "resets": res.final("resets")})
        log(f"events {solver}: {events} events in {wall:.3f} s")
    return {"compile_s": t_compile, "rodas4_build_s": build, "rows": rows}


if __name__ == "__main__":
    main(run)
