"""``solver="auto"``: BDF without events; with events an L-stable Rosenbrock method when
the stiffness probe finds the model stiff (or it is a DAE), else Dormand-Prince.
``stats.solver`` and ``stats.solver_reason`` say which ran and why."""

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechatron as mt
from mechatron.solvers.initial import initialize
from mechatron.solvers.stiffness import probe

FAST, T_STOP, LEVEL = 1e5, 10.0, 0.6


class TwoScales(mt.Component):
    """Time constants 1e-5 s and 1 s and one state event: ``a`` follows ``b`` through a
    fast lag; ``b`` gets an extra drive once ``a`` exceeds 0.6."""

    a = mt.Variable("1", start=0.0, doc="Fast state")
    b = mt.Variable("1", start=0.0, doc="Slow state")

    def equations(self):
        return [mt.der(self.a) == -FAST * (self.a - self.b),
                mt.der(self.b) == 1 - self.b + mt.if_else(self.a > LEVEL, 0.5, 0)]


def reference():
    """SciPy's Radau on the hand-written ODE, the event located by solve_ivp."""
    def rhs(extra):
        return lambda t, y: [-FAST * (y[0] - y[1]), 1 - y[1] + extra]

    def crossing(t, y):
        return y[0] - LEVEL
    crossing.terminal = True
    first = solve_ivp(rhs(0.0), (0, T_STOP), [0.0, 0.0], method="Radau", rtol=1e-11,
                      atol=1e-13, events=crossing)
    t_ev = float(first.t_events[0][0])
    second = solve_ivp(rhs(0.5), (t_ev, T_STOP), first.y[:, -1], method="Radau",
                       rtol=1e-11, atol=1e-13)
    return t_ev, second.y[:, -1]


def test_stiff_model_with_an_event_takes_hundreds_of_steps_not_hundreds_of_thousands():
    res = mt.simulate(TwoScales(), T_STOP)
    assert res.stats["solver"] == "rosenbrock"
    assert res.stats["solver_reason"].startswith("events, stiff")
    # an explicit method is held to h < 3.3e-5 s by the fast mode for all 10 s: about
    # 300,000 steps; the L-stable method follows the slow mode
    assert res.stats.steps < 500
    assert res.stats.events == {"": 1}
    t_ev, (a, b) = reference()
    assert res.event_times[""] == pytest.approx(t_ev, abs=1e-5)
    assert res.final("a") == pytest.approx(a, rel=1e-5)
    assert res.final("b") == pytest.approx(b, rel=1e-5)
    # after the event b -> 1.5 with the slow time constant; a lags it by (1.5 - b)/FAST
    assert b == pytest.approx(1.5 - 0.9 * np.exp(-(T_STOP - t_ev)), rel=1e-9)


def test_the_probe_estimates_the_explicit_stability_bound():
    cm = mt.compile_model(TwoScales())
    X0, z0, _ = initialize(cm, cm.p0)
    verdict = probe(cm, 0.0, X0, z0, cm.p0, T_STOP)
    # eigenvalues of [[-1e5, 1e5], [0, -1]]: -1e5 and -1
    assert verdict.rho == pytest.approx(FAST)
    assert verdict.rho_kept == pytest.approx(1.0)
    assert verdict.explicit_steps == pytest.approx(T_STOP * FAST / 3.3)
    assert verdict.stiff


class Bouncer(mt.Component):
    """A non-stiff oscillator with a switched force: ``x'' = -w^2 x - a sign(x)``."""

    w2 = mt.Parameter("1/s^2", default=4.0, doc="Squared angular frequency")
    a = mt.Parameter("m/s^2", default=0.5, doc="Switched acceleration")
    x = mt.Variable("m", start=1.0, doc="Position")
    v = mt.Variable("m/s", start=0.0, doc="Velocity")

    def equations(self):
        return [mt.der(self.x) == self.v,
                mt.der(self.v) == -self.w2 * self.x - mt.if_else(self.x > 0, self.a,
                                                                 -self.a)]


def test_non_stiff_model_with_events_runs_dormand_prince():
    res = mt.simulate(Bouncer(), 3.0, rtol=1e-9, atol=1e-12)
    assert res.stats.solver == "erk"
    assert res.stats.solver_reason.startswith("events, not stiff")
    # piecewise harmonic: for x > 0 about the centre -0.125, x = -0.125 + 1.125 cos(2 t),
    # which reaches x = 0 where cos(2 t) = 0.125 / 1.125
    t_first = np.arccos(0.125 / 1.125) / 2.0
    assert res.event_times[""] <= 3.0
    assert res.stats.events[""] >= 2
    first = mt.simulate(Bouncer(), t_first + 0.01, rtol=1e-10, atol=1e-12)
    assert first.event_times[""] == pytest.approx(t_first, abs=1e-8)


class Smooth(mt.Component):
    """``x' = -x``."""

    x = mt.Variable("1", start=1.0, doc="State")

    def equations(self):
        return [mt.der(self.x) == -self.x]


def test_without_events_auto_runs_bdf(monkeypatch):
    monkeypatch.setenv("MECHATRON_NATIVE", "0")      # the compiled path turned off
    res = mt.simulate(Smooth(), 1.0)
    assert res.stats.solver == "cvodes"
    assert "no events" in res.stats.solver_reason


def test_a_small_ode_without_events_runs_compiled_by_default():
    from mechatron.solvers.native import compiler
    if compiler() is None:
        pytest.skip("no C compiler")
    cm = mt.compile_model(Smooth())
    res = mt.simulate(cm, 1.0)
    assert res.stats.solver == "rodas4"
    assert "compiled to C" in res.stats.solver_reason
    t = res.t
    assert np.max(np.abs(res["x"] - np.exp(-t))) < 1e-6
    # a second compile of the same structure finds the same library (cached by the
    # hash of its source, in which parameters are arguments)
    cm2 = mt.compile_model(Smooth(x=0.5))
    again = mt.simulate(cm2, 1.0)
    assert again.stats.solver == "rodas4"
    assert cm2._cache["native_rodas4"].path == cm._cache["native_rodas4"].path
    assert np.max(np.abs(again["x"] - 0.5 * np.exp(-t))) < 1e-6


class KinkedLag(mt.Component):
    """A fast lag (1 us) following a triangle wave written without an event (``fabs`` of
    a sawtooth from ``floor``): kinks in the right-hand side that no event marks."""

    x = mt.Variable("1", start=0.0)

    def equations(self):
        saw = self.time / 1e-3 - ca.floor(self.time / 1e-3)
        return [1e-6 * mt.der(self.x) == -self.x + ca.fabs(2 * saw - 1)]


def test_auto_leaves_a_kinked_right_hand_side_to_cvodes():
    """A Rosenbrock step with its (stiffly damped) error estimate steps over such kinks
    and interpolates through them; CVODES shortens its steps there. The choice is read
    from the expression graph; the result follows the triangle to the lag's error."""
    res = mt.simulate(KinkedLag(), 3e-3, t_out=np.linspace(0.0, 3e-3, 601), rtol=1e-8,
                      atol=1e-10)
    assert res.stats.solver == "cvodes"
    t = res.t[10:]
    tri = np.abs(2 * (t / 1e-3 - np.floor(t / 1e-3)) - 1)
    assert np.max(np.abs(res["x"][10:] - tri)) < 5e-3    # lag of 1 us on slope 2000/s


def test_a_solver_asked_for_says_so():
    res = mt.simulate(Smooth(), 1.0, solver="rk45")
    assert (res.stats.solver, res.stats.solver_reason) == ("erk", "asked for")
