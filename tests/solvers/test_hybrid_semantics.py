"""Hybrid semantics of Modelica 3 in the Python language: discrete variables, pre(),
when/elsewhen, reinit, event iteration to a fixed point (and its error), initial() and
terminal(), sample(start, interval) clocks, initial equations. Checked against analytic
answers on every kind of solver (variable step in CasADi, compiled rodas4, fixed step)."""

import casadi as ca
import numpy as np
import pytest

import mechatron as mt
from mechatron.solvers.native import compiler

VARIABLE = ["auto", pytest.param("rodas4", marks=pytest.mark.skipif(
    compiler() is None, reason="no C compiler for rodas4"))]


# -- a counter on a sample clock -------------------------------------------------------

class Counter(mt.Component):
    """``n`` counts the ticks of ``sample(0, T)`` (the tick at t = 0 included)."""

    T = mt.Parameter("s", default=0.1, doc="Sample interval")
    n = mt.Discrete("1", start=0, kind="integer", doc="Number of ticks so far")

    def equations(self):
        return [mt.when(mt.sample(0.0, self.T), update={self.n: mt.pre(self.n) + 1})]


@pytest.mark.parametrize("solver", VARIABLE)
def test_counter_counts_the_ticks_of_a_sample_clock(solver):
    t = np.linspace(0.0, 1.0, 101)[1:] - 0.005        # between the ticks
    res = mt.simulate(Counter(), 1.0, solver=solver, t_out=t)
    np.testing.assert_array_equal(res["n"], np.floor(t / 0.1) + 1)
    assert res.final("n") == 10          # ticks at 0, 0.1, ..., 0.9 before t = 0.995


def test_counter_in_fixed_step_counts_every_tick_on_the_grid():
    res = mt.simulate(Counter(), 1.0, solver="rk4", dt=0.01)
    # a tick at a step end is seen at that step end: n(t_k) = k + 1 for t_k = 0.1 k
    expected = np.floor(np.round(res.t / 0.1, 9)) + 1
    np.testing.assert_array_equal(res["n"], expected)


# -- chained whens: one action's effect triggers another at the same instant -----------

class Chain(mt.Component):
    """A tick counter ``a``; when ``a`` reaches 3, ``b`` is set; when ``b`` is set, ``c``
    records the time: all three at the same instant t = 2 (ticks at 0, 1, 2)."""

    a = mt.Discrete("1", start=0, kind="integer", doc="Ticks")
    b = mt.Discrete("1", start=False, kind="boolean", doc="a has reached 3")
    c = mt.Discrete("s", start=-1.0, doc="Time at which b was set")
    x = mt.Variable("1", start=0.0, doc="A continuous state")
    m = mt.Discrete("1", start=0, kind="integer", doc="Set when x reaches 0.5")
    tm = mt.Discrete("s", start=-1.0, doc="Time at which m was seen set")

    def equations(self):
        return [mt.der(self.x) == 1.0,
                mt.when(mt.sample(0.0, 1.0), update={self.a: self.a + 1}),
                mt.when(self.a >= 3, update={self.b: True}),
                mt.when(self.b, update={self.c: self.time}),
                # a chain started by a located crossing
                mt.when(self.x >= 0.5, update={self.m: 1}),
                mt.when(self.m >= 1, update={self.tm: self.time})]


@pytest.mark.parametrize("solver", VARIABLE)
def test_chained_whens_fire_at_the_same_instant(solver):
    res = mt.simulate(Chain(), 3.5, solver=solver, rtol=1e-10, atol=1e-12)
    assert res.final("a") == 4
    assert res.final("b") == 1.0
    assert res.final("c") == pytest.approx(2.0, abs=1e-9)
    assert res.final("tm") == pytest.approx(0.5, abs=1e-9)


def test_chained_whens_in_fixed_step():
    res = mt.simulate(Chain(), 3.5, solver="euler", dt=0.125)
    assert res.final("c") == pytest.approx(2.0, abs=1e-12)
    assert res.final("tm") == pytest.approx(0.5, abs=1e-12)


# -- a latch: when / elsewhen ------------------------------------------------------------

class Latch(mt.Component):
    """Set when ``sin(2 pi t) >= 0.5``, reset when it falls to ``-0.5``: on from
    ``k + 1/12`` to ``k + 7/12``. ``both`` sees two conditions rise at one instant: the
    first branch wins."""

    q = mt.Discrete("1", start=False, kind="boolean", doc="Latched output")
    first = mt.Discrete("1", start=0, kind="integer", doc="Branch taken at t = 1")
    x = mt.Variable("1", start=0.0, doc="Equals t")
    f = mt.Parameter("Hz", default=1.0, doc="Frequency of u")

    def equations(self):
        u = ca.sin(2 * np.pi * self.f * self.time)
        return [mt.der(self.x) == 1.0,
                mt.when(u >= 0.5, update={self.q: True})
                  .elsewhen(u <= -0.5, update={self.q: False}),
                mt.when(self.time >= 1.0, update={self.first: 1})
                  .elsewhen(self.x >= 1.0, update={self.first: 2})]


@pytest.mark.parametrize("solver", VARIABLE)
def test_latch_holds_between_set_and_reset(solver):
    t = np.linspace(0, 2, 2001)
    res = mt.simulate(Latch(), 2.0, solver=solver, t_out=t, rtol=1e-10, atol=1e-12)
    phase = np.mod(t, 1.0)
    on = (phase > 1 / 12 + 1e-6) & (phase < 7 / 12 - 1e-6)
    off = (phase < 1 / 12 - 1e-6) | (phase > 7 / 12 + 1e-6)
    assert np.all(res["q"][on] == 1.0) and np.all(res["q"][off] == 0.0)
    # two events at the same time (t = 1 and x = 1): one instant, the first branch wins
    assert res.final("first") == 1


# -- bouncing ball with a rest condition -----------------------------------------------

G, E, H0, V_REST = 9.81, 0.5, 1.0, 0.5


class RestingBall(mt.Component):
    """Free fall with impacts ``v := -e pre(v)``; an impact slower than ``v_rest`` puts
    the ball to rest on the floor (``h`` re-initialized exactly onto its switching
    surface ``h = 0``, gravity switched off by the Boolean ``resting``)."""

    h = mt.Variable("m", start=H0, doc="Height")
    v = mt.Variable("m/s", start=0.0, doc="Velocity")
    resting = mt.Discrete("1", start=False, kind="boolean", doc="On the floor")
    impacts = mt.Discrete("1", start=0, kind="integer", doc="Number of impacts")

    def equations(self):
        slow = -mt.pre(self.v) < V_REST
        return [mt.der(self.h) == self.v,
                mt.der(self.v) == mt.if_else(self.resting, 0.0, -G),
                mt.when(self.h <= 0, update=[
                    mt.reinit(self.v, mt.if_else(slow, 0.0, -E * mt.pre(self.v))),
                    mt.reinit(self.h, 0.0),
                    (self.resting, slow),
                    (self.impacts, self.impacts + 1)])]


def ball_impacts():
    """Impact times t_k and speeds: t_1 = sqrt(2 h0 / g), then gaps 2 e^k v_1 / g."""
    v1 = np.sqrt(2 * G * H0)
    times, speeds = [v1 / G], [v1]
    while speeds[-1] >= V_REST:
        speeds.append(E * speeds[-1])
        times.append(times[-1] + 2 * speeds[-1] / G)
    return np.array(times), np.array(speeds)


@pytest.mark.parametrize("solver", VARIABLE)
def test_bouncing_ball_comes_to_rest_at_the_analytic_time(solver):
    times, speeds = ball_impacts()          # the last impact is slower than v_rest
    assert speeds[-1] < V_REST <= speeds[-2]
    cm = mt.compile_model(RestingBall())
    for k in range(len(times) - 1):
        mid = 0.5 * (times[k] + times[k + 1])
        res = mt.simulate(cm, mid, solver=solver, rtol=1e-11, atol=1e-12)
        assert res.event_times[""] == pytest.approx(times[k], abs=1e-9)
        assert res.final("impacts") == k + 1
        # after impact k: upwards at e * speed_k, minus gravity since
        assert res.final("v") == pytest.approx(E * speeds[k] - G * (mid - times[k]),
                                               rel=1e-8)
    res = mt.simulate(cm, times[-1] + 1.0, solver=solver, rtol=1e-11, atol=1e-12)
    assert res.final("resting") == 1.0
    assert res.final("impacts") == len(times)
    assert res.final("h") == 0.0 and res.final("v") == 0.0      # exactly on the floor
    assert np.all(np.isfinite(res["h"]))
    assert res.event_times[""] == pytest.approx(times[-1], abs=1e-9)


# -- a sampled PI controller with anti-windup ------------------------------------------

KP, KI, TS, TAU, K_PLANT, R_REF, U_MAX = 2.0, 8.0, 0.05, 0.2, 1.0, 1.0, 1.5


class SampledPI(mt.Component):
    """First-order plant ``tau y' = -y + K u`` under a PI controller sampled at ``Ts``
    with output limit ``u_max`` and conditional integration (the integral is frozen while
    the output is saturated: the Boolean ``saturated`` remembers it)."""

    y = mt.Variable("1", start=0.0, doc="Plant output")
    u = mt.Discrete("1", start=0.0, doc="Controller output (held)")
    integral = mt.Discrete("1", start=0.0, doc="Integral state")
    saturated = mt.Discrete("1", start=False, kind="boolean", doc="Output at its limit")

    def equations(self):
        e = R_REF - self.y
        v = KP * e + self.integral
        return [TAU * mt.der(self.y) == -self.y + K_PLANT * self.u,
                mt.when(mt.sample(0.0, TS), update={
                    self.u: mt.if_else(v > U_MAX, U_MAX, v),
                    self.saturated: v > U_MAX,
                    self.integral: mt.if_else(v > U_MAX, self.integral,
                                              self.integral + KI * TS * e)})]


def pi_by_hand(n):
    """The same loop with the exact zero-order-hold discretization of the plant."""
    a = np.exp(-TS / TAU)
    y, integral, us, sats = 0.0, 0.0, [], []
    for _ in range(n):
        e = R_REF - y
        v = KP * e + integral
        u = min(v, U_MAX)
        if v <= U_MAX:
            integral += KI * TS * e
        us.append(u)
        sats.append(v > U_MAX)
        y = a * y + (1 - a) * K_PLANT * u
    return np.array(us), np.array(sats)


@pytest.mark.parametrize("solver", VARIABLE)
def test_sampled_pi_with_anti_windup_matches_the_exact_discretization(solver):
    n = 40
    t = (np.arange(n) + 0.5) * TS
    res = mt.simulate(SampledPI(), t[-1], solver=solver, t_out=t, rtol=1e-11, atol=1e-12)
    us, sats = pi_by_hand(n)
    np.testing.assert_allclose(res["u"], us, atol=1e-8)
    np.testing.assert_array_equal(res["saturated"], sats.astype(float))
    assert sats[0] and not sats[-1]              # it saturated, then recovered
    assert res.final("y") == pytest.approx(R_REF, abs=2e-2)


# -- event iteration without a fixed point ---------------------------------------------

class Toggle(mt.Component):
    """After t = 1 each action makes the other condition true: no consistent state."""

    armed = mt.Discrete("1", start=False, kind="boolean", doc="Armed at t = 1")
    n = mt.Discrete("1", start=0, kind="integer", doc="Toggled")

    def equations(self):
        return [mt.when(self.time >= 1.0, update={self.armed: True}),
                mt.when(mt.logic_and(self.armed, self.n < 0.5), update={self.n: 1}),
                mt.when(mt.logic_and(self.armed, self.n >= 0.5), update={self.n: 0})]


@pytest.mark.parametrize("solver", VARIABLE + ["rk4"])
def test_event_iteration_without_fixed_point_names_the_conditions(solver):
    with pytest.raises(mt.errors.SimulationError,
                       match=r"event iteration at t = 1 s .* no consistent state after 100 "
                             r"rounds; these conditions keep changing: .*n < 0\.5") as err:
        mt.simulate(Toggle(), 2.0, solver=solver, dt=0.25 if solver == "rk4" else None)
    assert "n" in str(err.value)


def test_event_iteration_without_fixed_point_at_the_start_is_an_initialization_error():
    class Now(Toggle):
        armed = mt.Discrete("1", start=True, kind="boolean", doc="Armed from the start")

    with pytest.raises(mt.errors.InitializationError, match=r"at the initial time"):
        mt.simulate(Now(), 1.0)


class Cascade(mt.Component):
    """Six modes, each switched by the previous one: all switch at the event of the first
    (t = 1). Re-reading the modes a fixed three times left the last ones behind."""

    x = mt.Variable("1", start=0.0, doc="Equals t")
    m1 = mt.Variable("1")
    m2 = mt.Variable("1")
    m3 = mt.Variable("1")
    m4 = mt.Variable("1")
    m5 = mt.Variable("1")
    m6 = mt.Variable("1")

    def equations(self):
        return [mt.der(self.x) == 1.0,
                self.m1 == mt.if_else(self.x > 1.0, 1.0, 0.0),
                self.m2 == mt.if_else(self.m1 > 0.5, 1.0, 0.0),
                self.m3 == mt.if_else(self.m2 > 0.5, 1.0, 0.0),
                self.m4 == mt.if_else(self.m3 > 0.5, 1.0, 0.0),
                self.m5 == mt.if_else(self.m4 > 0.5, 1.0, 0.0),
                self.m6 == mt.if_else(self.m5 > 0.5, 1.0, 0.0)]


@pytest.mark.parametrize("solver", VARIABLE)
def test_mode_variables_are_iterated_to_a_fixed_point(solver):
    t = np.array([0.0, 0.5, 1.0 + 1e-6, 1.5])
    res = mt.simulate(Cascade(), 1.5, solver=solver, t_out=t, rtol=1e-10, atol=1e-12)
    for k in range(1, 7):
        np.testing.assert_array_equal(res[f"m{k}"], [0.0, 0.0, 1.0, 1.0])


class Unstable(mt.Component):
    """A mode that contradicts itself once the first relation switches at t = 1: with
    ``x > 1`` the mode ``v > 0`` makes ``v = -1``, which makes it false, which makes
    ``v = 1``... (relations not gated by the mode they switch)."""

    x = mt.Variable("1", start=0.0, doc="Equals t")
    v = mt.Variable("1", doc="Self-contradicting signal")

    def equations(self):
        return [mt.der(self.x) == 1.0,
                self.v == mt.if_else(self.x > 1.0, mt.if_else(self.v > 0, -1.0, 1.0), 1.0)]


@pytest.mark.parametrize("solver", VARIABLE)
def test_modes_without_fixed_point_raise_instead_of_returning_an_inconsistent_set(solver):
    with pytest.raises(mt.errors.SimulationError, match=r"keep changing: .*0 < v"):
        mt.simulate(Unstable(), 2.0, solver=solver)


# -- special cases: t = 0, the switching surface, simultaneous events -------------------

class RisingAtZero(mt.Component):
    """``sin(2 pi t) > 0`` is zero at t = 0 and rising: a crossing at the start. Its
    rising edges at t = 0, 1, 2 are counted."""

    n = mt.Discrete("1", start=0, kind="integer", doc="Rising edges")
    t_first = mt.Discrete("s", start=-1.0, doc="Time of the first edge")
    f0 = mt.Parameter("Hz", default=1.0, doc="Frequency of the sine")

    def equations(self):
        return [mt.when(ca.sin(2 * np.pi * self.f0 * self.time) > 0, update={
            self.n: self.n + 1,
            self.t_first: mt.if_else(self.n < 0.5, self.time, self.t_first)})]


@pytest.mark.parametrize("solver", VARIABLE)
def test_zero_crossing_at_the_initial_time_is_an_event(solver):
    res = mt.simulate(RisingAtZero(), 2.5, solver=solver, rtol=1e-10, atol=1e-12)
    assert res.final("n") == 3
    assert res.final("t_first") == 0.0


class Elastic(mt.Component):
    """A ball between floor and ceiling (h in [0, 1]) at constant speed 1, reflected
    exactly onto each wall: the state is re-initialized onto its switching surface."""

    h = mt.Variable("m", start=0.25, doc="Position")
    v = mt.Variable("m/s", start=1.0, doc="Velocity")

    def equations(self):
        return [mt.der(self.h) == self.v, mt.der(self.v) == 0.0,
                mt.when(self.h >= 1.0, update=[mt.reinit(self.h, 1.0),
                                               mt.reinit(self.v, -mt.pre(self.v))]),
                mt.when(self.h <= 0.0, update=[mt.reinit(self.h, 0.0),
                                               mt.reinit(self.v, -mt.pre(self.v))])]


@pytest.mark.parametrize("solver", VARIABLE)
def test_reinit_onto_the_switching_surface_continues_correctly(solver):
    t = np.linspace(0, 4.5, 46)
    res = mt.simulate(Elastic(), 4.5, solver=solver, t_out=t, rtol=1e-10, atol=1e-12)
    assert np.all(np.isfinite(res["h"]))
    # a triangle wave of period 2 through h(0) = 0.25, rising
    phase = np.mod(t + 0.25, 2.0)
    np.testing.assert_allclose(res["h"], np.where(phase < 1, phase, 2 - phase), atol=1e-8)
    assert res.stats.events[""] == 4          # walls at t = 0.75, 1.75, 2.75, 3.75


class Simultaneous(mt.Component):
    """Three events at t = 0.5: a located crossing, a time relation and a clock tick."""

    x = mt.Variable("1", start=0.0, doc="Equals t")
    a = mt.Discrete("s", start=-1.0)
    b = mt.Discrete("s", start=-1.0)
    ticks = mt.Discrete("1", start=0, kind="integer")
    seen = mt.Discrete("1", start=-1.0, doc="Ticks seen by the crossing at t = 0.5")

    def equations(self):
        return [mt.der(self.x) == 1.0,
                mt.when(self.x >= 0.5, update={self.a: self.time, self.seen: self.ticks}),
                mt.when(self.time >= 0.5, update={self.b: self.time}),
                mt.when(mt.sample(0.0, 0.25), update={self.ticks: self.ticks + 1})]


@pytest.mark.parametrize("solver", VARIABLE)
def test_events_at_the_same_time_are_one_instant(solver):
    res = mt.simulate(Simultaneous(), 1.0, solver=solver, rtol=1e-10, atol=1e-12)
    assert res.final("a") == pytest.approx(0.5, abs=1e-9)
    assert res.final("b") == pytest.approx(0.5, abs=1e-9)
    assert res.final("ticks") == 4              # 0, 0.25, 0.5, 0.75: no tick lost
    # the actions of one round are simultaneous: the crossing reads the count before
    # the tick at 0.5 (ticks at 0 and 0.25)
    assert res.final("seen") == 2


# -- initial(), terminal(), discrete kinds ----------------------------------------------

class Ends(mt.Component):
    x = mt.Variable("1", start=2.0, doc="Decays")
    x0 = mt.Discrete("1", start=-1.0, doc="x at the initial event")
    xf = mt.Discrete("1", start=-1.0, doc="x at the terminal event")
    inits = mt.Discrete("1", start=0, kind="integer", doc="Initial events")
    rounded = mt.Discrete("1", start=0, kind="integer", doc="Integer assignment")
    flag = mt.Discrete("1", start=False, kind="boolean", doc="Boolean assignment")

    def equations(self):
        return [mt.der(self.x) == -self.x,
                mt.when(mt.initial(), update={self.x0: self.x, self.inits: self.inits + 1,
                                              self.rounded: 2.6, self.flag: 0.3}),
                mt.when(mt.terminal(), update={self.xf: self.x})]


@pytest.mark.parametrize("solver", VARIABLE + ["rk4"])
def test_initial_and_terminal_conditions_act_once_at_the_ends(solver):
    res = mt.simulate(Ends(), 1.0, solver=solver, rtol=1e-10, atol=1e-12,
                      dt=1e-3 if solver == "rk4" else None)
    assert np.all(res["x0"] == 2.0) and res.final("inits") == 1
    assert np.all(res["xf"][:-1] == -1.0)
    assert res.final("xf") == pytest.approx(2.0 * np.exp(-1.0), rel=1e-8)
    assert res.final("rounded") == 3 and res.final("flag") == 1.0


def test_reinit_of_a_discrete_variable_is_an_error():
    class Bad(mt.Component):
        n = mt.Discrete("1", start=0)
        x = mt.Variable("1", start=0.0)

        def equations(self):
            return [mt.der(self.x) == 1.0,
                    mt.when(self.x >= 1, update=[mt.reinit(self.n, 1.0)])]

    with pytest.raises(mt.errors.StructuralError, match=r"reinit\(n\) needs a continuous"):
        mt.compile_model(Bad())


def test_sample_condition_and_clock_action_are_not_mixed():
    with pytest.raises(mt.errors.ModelError, match=r"sample\(start, interval\) is a "
                                                   r"condition"):
        mt.sample(0.0, 0.1, update={})
    with pytest.raises(mt.errors.ModelError, match="one relation"):
        mt.when(True, update={})


# -- initial equations ------------------------------------------------------------------

class Lag(mt.Component):
    """``tau x' = -x + u`` started in steady state: x(0) = u without a start value."""

    tau = mt.Parameter("s", default=0.3)
    u = mt.Parameter("1", default=1.7)
    x = mt.Variable("1", start=0.0, doc="Output")
    n = mt.Discrete("1", start=0, kind="integer", doc="Set by an initial equation")

    def equations(self):
        return [self.tau * mt.der(self.x) == -self.x + self.u]

    def initial_equations(self):
        return mt.steady_state(self.x) + [self.n == 3]


def test_steady_state_initial_equation_replaces_the_start_value():
    res = mt.simulate(Lag(), 1.0, params={"u": 2.5})
    np.testing.assert_allclose(res["x"], 2.5, rtol=1e-9)
    assert res.final("n") == 3


def test_dc_motor_starts_in_steady_state_from_an_initial_equation():
    from mechatron.library import electrical as el
    from mechatron.library import electromechanical as em
    from mechatron.library import rotational as rot
    V, R, L, K, J, B = 12.0, 2.0, 1e-3, 0.05, 1e-4, 1e-4

    class Motor(mt.Component):
        src = el.DCVoltageSource(V=V)
        r = el.Resistor(R=R)
        ind = el.Inductor(L=L)
        emf = em.RotationalEMF(k=K)
        j = rot.Inertia(J=J)
        d = rot.RotationalDamper(D=B)
        g = el.ElectricalReference()
        f = rot.RotationalReference()

        def equations(self):
            return [mt.connect(self.src.p, self.r.p), mt.connect(self.r.n, self.ind.p),
                    mt.connect(self.ind.n, self.emf.p),
                    mt.connect(self.emf.n, self.src.n, self.g.port),
                    mt.connect(self.emf.A, self.j.port, self.d.A),
                    mt.connect(self.emf.B, self.d.B, self.f.port)]

        def initial_equations(self):
            return mt.steady_state(self.j.w, self.ind.i)

    res = mt.simulate(Motor(), 0.1)
    w_ss = K * V / (R * B + K ** 2)
    np.testing.assert_allclose(res["j.w"], w_ss, rtol=1e-7)
    np.testing.assert_allclose(res["ind.i"], B * w_ss / K, rtol=1e-7)


class Holder(mt.Component):
    """A part two levels down: its initial equations and discrete variable are found
    below a component that has neither."""

    inner = Lag(u=0.8)


def test_initial_equations_of_a_system_and_of_parts_at_any_depth():
    """Flattening reads initial equations and discrete variables off the elements of
    the classes that declare them (the System's own, ``add_initial_equation``, among
    them): the RC discharge starts where the System's initial equation puts it, and the
    lags below start in steady state with their discrete variable set."""
    from mechatron.library import electrical as el
    R, C, V0 = 2.0, 0.25, 0.5
    m = mt.System("discharge")
    r = m.add("r", el.Resistor(R=R))
    c = m.add("c", el.Capacitor(C=C))
    g = m.add("g", el.ElectricalReference())
    m.add("lag", Lag(u=1.3))
    m.add("holder", Holder())
    m.connect(c.p, r.p)
    m.connect(r.n, c.n, g.port)
    m.add_initial_equation(lambda: c.v == V0)
    t = np.linspace(0.0, 1.0, 11)
    res = mt.simulate(m, 1.0, t_out=t, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res["c.v"], V0 * np.exp(-t / (R * C)), rtol=1e-6)
    np.testing.assert_allclose(res["lag.x"], 1.3, rtol=1e-9)
    np.testing.assert_allclose(res["holder.inner.x"], 0.8, rtol=1e-9)
    assert res.final("lag.n") == 3 and res.final("holder.inner.n") == 3


def test_conflicting_initial_equation_and_start_value_are_named():
    with pytest.raises(mt.errors.InitializationError,
                       match=r"Conflicting targets: .*(x = 1 \(high\).*initial equation|"
                             r"initial equation 'Lag: der\(x\) == 0'.*x = 1 \(high\))"):
        mt.simulate(Lag(x=1.0), 1.0)


# -- a user-written Coulomb clutch whose break-away test is not gated by its stuck mode --

F_C, J_C = 1.0, 0.01


class Clutch(mt.Component):
    """An inertia under ``tau = 2 sin(2 pi t)`` with Coulomb friction ``F``, its modes
    written by hand: sliding forward (w > 0), backward (w < 0), else stuck, where the
    break-away test ``|tau| > F`` is not gated by the stuck mode. At t = 0 re-reading all
    modes at once cycles between the two sliding modes (each points into the other);
    re-reading them one after the other finds the stuck mode."""

    w = mt.Variable("rad/s", start=0.0, doc="Speed")
    f = mt.Variable("N*m", doc="Friction torque")
    J = mt.Parameter("kg*m^2", default=J_C, doc="Inertia")
    F = mt.Parameter("N*m", default=F_C, doc="Coulomb friction torque")
    T0 = mt.Parameter("N*m", default=2.0, doc="Amplitude of the driving torque")
    f0 = mt.Parameter("Hz", default=1.0, doc="Frequency of the driving torque")

    def equations(self):
        tau = self.T0 * ca.sin(2 * np.pi * self.f0 * self.time)
        brk = ca.fabs(tau) > self.F
        return [self.J * mt.der(self.w) == tau - self.f,
                self.f == ca.if_else(self.w > 0, self.F, ca.if_else(
                    self.w < 0, -self.F, ca.if_else(brk, self.F * ca.sign(tau), tau)))]


def clutch_speed_at_1s():
    """Stuck until tau = F at t = 1/12; slides forward until w = 0 again (t2, where
    tau < -F already); then slides backward: w(1) = int_t2^1 (tau + F) dt / J."""
    from scipy.optimize import brentq

    def tau_integral(a, b):
        return -(np.cos(2 * np.pi * b) - np.cos(2 * np.pi * a)) / np.pi

    t1 = 1 / 12
    w_fwd = lambda t: (tau_integral(t1, t) - F_C * (t - t1)) / J_C     # noqa: E731
    t2 = brentq(w_fwd, 0.5, 0.9)
    assert 2 * np.sin(2 * np.pi * t2) < -F_C
    return (tau_integral(t2, 1.0) + F_C * (1.0 - t2)) / J_C


@pytest.mark.parametrize("solver", VARIABLE)
def test_clutch_with_ungated_break_away_slides_and_sticks_analytically(solver):
    res = mt.simulate(Clutch(), 1.0, solver=solver, rtol=1e-10, atol=1e-12,
                      t_out=np.linspace(0, 1, 101))
    stuck = res.t < 1 / 12 - 1e-9
    assert np.all(res["w"][stuck] == 0.0)
    assert res.final("w") == pytest.approx(clutch_speed_at_1s(), rel=1e-6)
