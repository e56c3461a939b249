"""Stiff contact with preload and Stribeck friction: what ``solver="auto"`` picks and costs.

Two masses on a line. The poppet ``m2`` is pressed onto its seat (``x2 = 0``) by a spring
``k2`` with preload ``F_pre``; the plunger ``m1``, held at ``x1 = -g0`` by a return spring
``k1``, driven by ``F(t) = F0 (1 - cos(2 pi f t)) / 2`` and braked by Stribeck friction
(Simscape's smooth law, as ``TranslationalFriction``), closes the gap ``g0`` and lifts the
poppet off its seat once per period. Both contacts are stiff penalty spring-dampers that
only push (``mechatron.library.rotational.contact``: contact, release and the instant the
damper would pull are events)::

    m1 x1'' = F(t) - k1 (x1 + g0) - F_fric(v1) - F_12
    m2 x2'' = F_12 + F_seat - F_pre - k2 x2
    F_12   = max(k_c (x1 - x2) + d_c (v1 - v2), 0)  while x1 > x2
    F_seat = max(-k_c x2 - d_c v2, 0)               while x2 < 0

The contact modes (``k_c / m = 1e8 1/s^2`` with heavy damping) and the friction at rest
(slope ``F_C / (v_brk / 10)``) give eigenvalues down to about -5e4 1/s on a run of 1 s:
stiff. ``auto`` should find that and run an implicit method with events. The reference
is SciPy's Radau (rtol 1e-10) on the same ODE written by hand (its error control steps
through the contact kinks). Printed: the solver auto chose and why, wall time (first run,
which builds the integrator, and the median of the next ones), steps, events, and the
largest difference to the reference of each state relative to its peak. Goals: under
0.5 s and within 1e-4. ``rk45`` is run once for comparison.

Run: ``python bench/bench_stiff_contact.py [--quick]``; prints one JSON document.
"""

from __future__ import annotations

import _common  # noqa: F401  (import path)
from _common import clock, log, main, repeat, summary

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp

import mechatron as mt
from mechatron.library.rotational.contact import penalty_force

M1, M2, K1, K2, F_PRE = 0.2, 0.1, 5000.0, 2000.0, 20.0   # kg, kg, N/m, N/m, N
K_C, D_C, G0 = 1e7, 5000.0, 2e-3                     # N/m, N s/m, m
F0, FREQ = 60.0, 2.0                                 # N, Hz
F_BRK, F_C, V_BRK, B = 5.0, 4.0, 0.01, 2.0           # N, N, m/s, N s/m
T_STOP = 1.0


class StiffContact(mt.Component):
    """Plunger, preloaded poppet on its seat, stiff contacts, Stribeck friction."""

    m1 = mt.Parameter("kg", default=M1, doc="Plunger mass")
    m2 = mt.Parameter("kg", default=M2, doc="Poppet mass")
    k1 = mt.Parameter("N/m", default=K1, doc="Return spring of the plunger")
    k2 = mt.Parameter("N/m", default=K2, doc="Poppet spring")
    F_pre = mt.Parameter("N", default=F_PRE, doc="Preload of the poppet spring")
    k_c = mt.Parameter("N/m", default=K_C, doc="Contact stiffness")
    d_c = mt.Parameter("N*s/m", default=D_C, doc="Contact damping")
    g0 = mt.Parameter("m", default=G0, doc="Gap between plunger and poppet at rest")
    F0 = mt.Parameter("N", default=F0, doc="Peak drive force")
    f = mt.Parameter("Hz", default=FREQ, doc="Drive frequency")
    F_brk = mt.Parameter("N", default=F_BRK, doc="Breakaway friction force")
    F_C = mt.Parameter("N", default=F_C, doc="Coulomb friction force")
    v_brk = mt.Parameter("m/s", default=V_BRK, doc="Breakaway velocity")
    b = mt.Parameter("N*s/m", default=B, doc="Viscous friction coefficient")
    x1 = mt.Variable("m", start=-G0, doc="Plunger position")
    v1 = mt.Variable("m/s", start=0.0, doc="Plunger velocity")
    x2 = mt.Variable("m", start=-F_PRE / K_C, doc="Poppet position (seat at 0)")
    v2 = mt.Variable("m/s", start=0.0, doc="Poppet velocity")
    f12 = mt.Variable("N", doc="Plunger-poppet contact force")
    f_seat = mt.Variable("N", doc="Seat contact force")
    f_fric = mt.Variable("N", doc="Friction force on the plunger")

    def equations(self):
        x = self.v1 / (self.v_brk * np.sqrt(2.0))
        drive = self.F0 * (1 - ca.cos(2 * np.pi * self.f * self.time)) / 2
        return [
            mt.der(self.x1) == self.v1,
            mt.der(self.x2) == self.v2,
            self.f12 == penalty_force(self.x1 - self.x2, self.v1 - self.v2, self.k_c,
                                      self.d_c),
            self.f_seat == penalty_force(-self.x2, -self.v2, self.k_c, self.d_c),
            # Simscape's Stribeck law, as stribeck() below and TranslationalFriction
            self.f_fric == (np.sqrt(2 * np.e) * (self.F_brk - self.F_C) * ca.exp(-x ** 2) * x
                            + self.F_C * ca.tanh(self.v1 / (self.v_brk / 10))
                            + self.b * self.v1),
            self.m1 * mt.der(self.v1) == drive - self.k1 * (self.x1 + self.g0)
            - self.f_fric - self.f12,
            self.m2 * mt.der(self.v2) == self.f12 + self.f_seat - self.F_pre
            - self.k2 * self.x2,
        ]


def stribeck(v, v_st):
    """Simscape's smooth Stribeck-Coulomb-viscous law (``TranslationalFriction``)."""
    x = v / v_st
    return (np.sqrt(2 * np.e) * (F_BRK - F_C) * np.exp(-x ** 2) * x
            + F_C * np.tanh(v / (V_BRK / 10)) + B * v)


def reference(t_eval: np.ndarray) -> np.ndarray:
    """The same ODE by hand, SciPy Radau at rtol 1e-10, one smooth piece at a time.

    Each contact is on while its penetration and its force are both positive; the four
    switching functions keep their signs ``sigma`` over a piece, SciPy locates the zero
    crossing that ends it, and the crossing one flips (the forces are continuous there,
    so the pieces join without a jump)."""
    v_st = V_BRK * np.sqrt(2.0)

    def switches(y):
        x1, v1, x2, v2 = y
        return np.array([x1 - x2, K_C * (x1 - x2) + D_C * (v1 - v2), -x2,
                         -K_C * x2 - D_C * v2])

    def rhs(t, y, sigma):
        x1, v1, x2, v2 = y
        s = switches(y)
        f12 = s[1] if sigma[0] > 0 and sigma[1] > 0 else 0.0
        f_seat = s[3] if sigma[2] > 0 and sigma[3] > 0 else 0.0
        force = F0 * (1 - np.cos(2 * np.pi * FREQ * t)) / 2 - K1 * (x1 + G0)
        return [v1, (force - stribeck(v1, v_st) - f12) / M1,
                v2, (f12 + f_seat - F_PRE - K2 * x2) / M2]

    def crossing(k):
        def event(t, y, sigma):
            return sigma[k] * switches(y)[k]
        event.terminal, event.direction = True, -1
        return event

    y = np.array([-G0, 0.0, -F_PRE / K_C, 0.0])
    sigma = np.sign(switches(y))
    t, out = 0.0, np.full((4, t_eval.size), np.nan)
    events = [crossing(k) for k in range(4)]
    while t < T_STOP:
        sol = solve_ivp(rhs, (t, T_STOP), y, method="Radau", args=(sigma,), rtol=1e-10,
                        atol=1e-13, events=events, dense_output=True)
        if sol.status < 0:
            raise RuntimeError(f"reference failed: {sol.message}")
        t_end = sol.t[-1]
        inside = (t_eval >= t) & (t_eval <= t_end)
        if inside.any():
            out[:, inside] = sol.sol(t_eval[inside])
        for k, te in enumerate(sol.t_events):
            if te.size:
                sigma[k] = -sigma[k]
        t, y = t_end, sol.y[:, -1]
    return out


def run(quick: bool = False, tiny: bool = False) -> dict:
    """Wall time, steps, events and error of ``auto`` against the Radau reference."""
    cm, t_compile = clock(mt.compile_model, StiffContact())
    grid = np.linspace(0.0, T_STOP, 1001)
    first, t_first = clock(mt.simulate, cm, T_STOP, t_out=grid)
    res, times = repeat(lambda: mt.simulate(cm, T_STOP, t_out=grid),
                        1 if tiny else 2 if quick else 5)
    log(f"auto -> {res.stats.solver}: {res.stats.steps} steps, "
        f"{sum(res.stats.events.values())} events, {summary(times)['median_s']:.3f} s")
    ref, t_ref = clock(reference, grid)
    log(f"SciPy Radau reference in {t_ref:.1f} s")
    names = ["x1", "v1", "x2", "v2"]
    errors = {n: float(np.max(np.abs(res[n] - ref[i])) / np.max(np.abs(ref[i])))
              for i, n in enumerate(names)}
    out = {"solver": res.stats.solver, "solver_reason": res.stats.solver_reason,
           "compile_s": t_compile, "first_run_s": t_first, "wall": summary(times),
           "steps": res.stats.steps, "rejected_steps": res.stats.rejected_steps,
           "events": sum(res.stats.events.values()), "events_per_component":
           dict(res.stats.events), "max_rel_error": max(errors.values()),
           "rel_error_per_state": errors, "reference_s": t_ref,
           "goal_wall_s": 0.5, "goal_rel_error": 1e-4}
    out["meets_goals"] = bool(out["wall"]["median_s"] < 0.5 and out["max_rel_error"] < 1e-4)
    if not quick and not tiny:
        rk, t_rk = clock(mt.simulate, cm, T_STOP, t_out=grid, solver="rk45")
        out["rk45"] = {"wall_s": t_rk, "steps": rk.stats.steps,
                       "events": sum(rk.stats.events.values()),
                       "max_rel_error": max(float(np.max(np.abs(rk[n] - ref[i]))
                                                  / np.max(np.abs(ref[i])))
                                            for i, n in enumerate(names))}
        log(f"rk45: {rk.stats.steps} steps in {t_rk:.2f} s")
    return out


if __name__ == "__main__":
    main(run)
