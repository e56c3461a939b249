"""``solver="rosenbrock"`` (CasADi's Rosenbrock-Wanner plug-in) on models with events:
discrete states are held exactly between events, every component counts its own events
once, and the switched trajectories match Dormand-Prince (``rk45``)."""

import casadi as ca
import numpy as np
import pytest

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import electrical as el

TS, F = 1e-3, 60.0


class Lag(mt.Component):
    """Test-only first-order lag ``tau dx/dt = u - x`` (a continuous state that reads a
    held value, so the step's Jacobian couples the two)."""

    u = mt.Input("1", doc="Input")
    x = mt.Variable("1", start=0.0, doc="Output")
    tau = mt.Parameter("s", default=1e-4, doc="Time constant")

    def equations(self):
        return [self.tau * mt.der(self.x) == self.u - self.x]


def held_sine():
    m = mt.System("held")
    s = m.add("s", blocks.Sine(amplitude=1.0, f=F))
    h = m.add("h", blocks.ZeroOrderHold(Ts=TS))
    lag = m.add("lag", Lag())
    m.connect(s.y, h.u)
    m.connect(h.y, lag.u)
    return m


def test_a_held_value_stays_exact_between_ticks():
    t_stop = 20 * TS
    t = np.linspace(0.0, t_stop, 2001)
    res = mt.simulate(held_sine(), t_stop, solver="rosenbrock", t_out=t, rtol=1e-8,
                      atol=1e-10)
    y = res["h.y"]
    k = np.floor(t / TS + 1e-9).astype(int)
    inside = np.abs(t / TS - np.round(t / TS)) > 1e-6          # off the tick instants
    # the value sampled at tick k, held bit for bit until tick k + 1 (the first one is
    # sin(0) = 0 exactly: a drift of 1e-21 would show)
    for j in range(20):
        seg = y[inside & (k == j)]
        assert seg.size > 50
        assert np.all(seg == seg[0])
        assert seg[0] == pytest.approx(np.sin(2 * np.pi * F * j * TS), abs=1e-12)
    assert np.all(y[inside & (k == 0)] == 0.0)
    assert res.stats.events == {"h": 20}
    # the lag follows the staircase: at the end of interval j it is
    # y_j + (x_j - y_j) exp(-TS/tau), exactly
    x, tau = 0.0, 1e-4
    for j in range(20):
        x = np.sin(2 * np.pi * F * j * TS) + (x - np.sin(2 * np.pi * F * j * TS)) \
            * np.exp(-TS / tau)
    assert res.final("lag.x") == pytest.approx(x, abs=1e-6)


def rectifiers(n=2):
    """``n`` identical half-wave rectifiers on one sine source."""
    m = mt.System("rectifiers")
    s = m.add("sine", blocks.Sine(amplitude=5.0, f=50.0))
    v = m.add("src", el.ControlledVoltageSource())
    g = m.add("g", el.ElectricalReference())
    m.connect(s.y, v.u)
    for k in range(n):
        d = m.add(f"d{k}", el.Diode(Vf=0.6, Ron=0.01, Goff=1e-8))
        r = m.add(f"r{k}", el.Resistor(R=100.0))
        m.connect(v.p, d.p)
        m.connect(d.n, r.p)
        m.connect(r.n, g.port)
    m.connect(v.n, g.port)
    return m


@pytest.mark.parametrize("solver", ["rosenbrock", "rk45"])
def test_identical_components_count_identical_events(solver):
    # two full periods: each diode turns on and off twice (the first period starts
    # blocking, as the sine starts at 0)
    res = mt.simulate(rectifiers(), 0.04, solver=solver, rtol=1e-9, atol=1e-12)
    assert res.stats.events == {"d0": 4, "d1": 4}
    np.testing.assert_array_equal(res["d0.i"], res["d1.i"])


@pytest.mark.parametrize("name", ["hbridge_rc_filter", "geared_drive", "bldc_motor"])
def test_switched_database_models_match_rk45(name):
    entry = mt.models.get(name)
    cm = mt.compile_model(entry.build())
    t_stop = entry.experiment.t_stop
    a = mt.simulate(cm, t_stop, solver="rk45", rtol=1e-9, atol=1e-11)
    b = mt.simulate(cm, t_stop, solver="rosenbrock", rtol=1e-9, atol=1e-11)
    assert b.stats.events == a.stats.events
    for state in cm.state_names:
        scale = max(1.0, np.abs(a[state]).max())
        assert abs(b.final(state) - a.final(state)) < 1e-5 * scale, state


@pytest.mark.parametrize("name", ["hbridge_rc_filter", "bldc_motor"])
def test_modes_counters_and_discrete_states_change_only_at_events(name):
    # the integration state itself: modes exactly +-1, counters whole numbers, and every
    # entry held between events (discrete states, modes, counters, event times) equal bit
    # for bit at consecutive output times with no event between them
    from mechatron.solvers.initial import initialize
    from mechatron.solvers.variable import held_states, integrate_variable
    entry = mt.models.get(name)
    cm = mt.compile_model(entry.build())
    t_stop = entry.experiment.t_stop
    grid = np.linspace(0.0, t_stop, 1001)
    X0, z0, _ = initialize(cm, cm.p0)
    X, _, _, used = integrate_variable(cm, grid, X0, z0, cm.p0, solver="rosenbrock",
                                       rtol=1e-8, atol=1e-10, max_step=t_stop / 50)
    assert used == "rosenbrock"
    nx, nr = cm.nx, cm.nr
    modes, counters = X[nx:nx + nr], X[nx + nr:nx + 2 * nr]
    assert np.all(np.abs(modes) == 1.0)
    assert np.all(counters == np.round(counters))
    quiet = np.all(np.diff(counters, axis=1) == 0, axis=0)     # no event in between
    assert quiet.sum() > 100
    held = held_states(cm)
    assert set(range(nx, cm.nX)) <= set(held)
    np.testing.assert_array_equal(X[held][:, 1:][:, quiet], X[held][:, :-1][:, quiet])


class ImplicitWithStep(mt.Component):
    """Test-only DAE with an event: ``y + exp(y) = 2 + x`` (an algebraic unknown left to
    the solver), ``dx/dt = -y + 3`` from t = 1 s on."""

    x = mt.Variable("1", start=0.5, doc="State")
    y = mt.Variable("1", start=0.6, doc="Algebraic unknown")

    def equations(self):
        return [mt.der(self.x) == -self.y + mt.if_else(self.time > 1.0, 3.0, 0.0),
                self.y + ca.exp(self.y) == 2 + self.x]


def test_algebraic_unknowns_hold_their_equation_at_every_output_time():
    cm = mt.compile_model(ImplicitWithStep())
    assert cm.alg_names == ["y"]
    res = mt.simulate(cm, 2.0)
    assert res.stats.solver == "rosenbrock"
    assert res.stats.solver_reason.startswith("events and 1 algebraic unknown")
    assert res.stats.events == {"": 1}
    assert res.event_times[""] == pytest.approx(1.0, abs=1e-9)
    # the plug-in corrects y at an output time by one Newton step from its interpolant;
    # the logged values are solved to convergence
    np.testing.assert_allclose(res["y"] + np.exp(res["y"]), 2 + res["x"], rtol=0,
                               atol=1e-12)


def test_a_discrete_controller_output_that_settles_at_zero_is_exactly_zero():
    # the encoder servo stops on a whole count: the sampled controller's error, and so its
    # output (a discrete state), is exactly 0 from then on; a drifting held state used to
    # end at -6.7e-32
    entry = mt.models.get("servo_encoder")
    res = mt.simulate(entry.build(), 0.1, solver="rosenbrock", rtol=1e-10, atol=1e-12)
    assert res.final("controller.y") == 0.0
    assert abs(res.final("rotor.w")) < 1e-9
