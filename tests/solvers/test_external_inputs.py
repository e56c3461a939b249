"""External inputs: ``simulate(..., inputs={...})`` on the root component's signal inputs.

Physics is checked against independent implementations: SciPy's ``solve_ivp`` of the same
RC equation with ``np.interp`` for the input, the analytic response of a first-order lag
to a sine, a hand-written NumPy RK4 loop with a zero-order-held input, and the same
circuit driven by ``blocks.Constant``.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechatron as mt
from mechatron.errors import ModelError, SimulationError, UnitError
from mechatron.library import blocks
from mechatron.library import electrical as el
from mechatron.solvers.inputs import SAMPLES
from mechatron.units import ureg

R, C = 1e3, 1e-6
TAU = R * C


class DrivenRC(mt.Component):
    """RC low-pass whose source voltage is the external input ``u``."""

    u = mt.Input("V", doc="Source voltage")
    src = el.ControlledVoltageSource()
    r = el.Resistor(R=R)
    c = el.Capacitor(C=C)
    g = el.ElectricalReference()

    def equations(self):
        return [mt.connect(self.u, self.src.u), mt.connect(self.src.p, self.r.p),
                mt.connect(self.r.n, self.c.p),
                mt.connect(self.src.n, self.c.n, self.g.port)]


class ConstantRC(mt.Component):
    k = blocks.Constant(value=1.7)
    src = el.ControlledVoltageSource()
    r = el.Resistor(R=R)
    c = el.Capacitor(C=C)
    g = el.ElectricalReference()

    def equations(self):
        return [mt.connect(self.k.y, self.src.u), mt.connect(self.src.p, self.r.p),
                mt.connect(self.r.n, self.c.p),
                mt.connect(self.src.n, self.c.n, self.g.port)]


@pytest.fixture(scope="module")
def rc():
    return mt.compile_model(DrivenRC())


def _rc_reference(t_tab, v_tab, t_eval, v0=0.0):
    sol = solve_ivp(lambda t, x: (np.interp(t, t_tab, v_tab) - x) / TAU,
                    (t_eval[0], t_eval[-1]), [v0], t_eval=t_eval, rtol=1e-12,
                    atol=1e-14, max_step=float(np.min(np.diff(t_tab))))
    return sol.y[0]


def _rc_exact(t_tab, v_tab, t_eval, v0=0.0):
    """Exact solution of ``tau dv/dt = u - v`` for ``u`` piecewise linear (held outside
    the table): on a segment ``u = a + b (t - t_k)`` and
    ``v = a - b tau + b (t - t_k) + (v_k - a + b tau) exp(-(t - t_k)/tau)``."""
    knots = np.union1d(t_tab, [t_eval[0], t_eval[-1]])
    knots = knots[(knots >= t_eval[0]) & (knots <= t_eval[-1])]
    out = np.empty_like(t_eval)
    vk = v0
    for a, b in zip(knots[:-1], knots[1:]):
        ua, ub = np.interp([a, b], t_tab, v_tab)
        slope = (ub - ua) / (b - a)

        def v(s, a=a, ua=ua, slope=slope, vk=vk):
            return ua - slope * TAU + slope * (s - a) + \
                (vk - ua + slope * TAU) * np.exp(-(s - a) / TAU)

        sel = (t_eval >= a) & (t_eval <= b)
        out[sel] = v(t_eval[sel])
        vk = v(b)
    return out


# ---------------------------------------------------------------- compiled representation
def test_root_inputs_are_parameter_slots(rc):
    assert rc.input_names == ["u"]
    assert rc.param_names[rc.input_index[0]] == "u"
    assert rc.input_units == ["V"] and rc.input_docs == ["Source voltage"]
    assert np.isnan(rc.input_defaults[0])          # no start value: must be given
    # the functions keep their signature (t, X, z, p): the input is a slot of p
    assert rc.f_ode.name_in() == ["t", "x", "z", "p"]
    assert rc.f_ode.size1_in(3) == len(rc.param_names)


def test_save_and_load_keep_the_inputs(rc, tmp_path):
    back = mt.CompiledModel.load(rc.save(tmp_path / "rc.pkl"))
    assert (back.input_names, back.input_index, back.input_units, back.input_docs) == \
        (rc.input_names, rc.input_index, rc.input_units, rc.input_docs)
    t = np.linspace(0, 4e-3, 9)
    a = mt.simulate(rc, 4e-3, inputs={"u": (t, np.cos(t * 1e3))})
    b = mt.simulate(back, 4e-3, inputs={"u": (t, np.cos(t * 1e3))})
    np.testing.assert_array_equal(a["c.v"], b["c.v"])


def test_inner_inputs_left_unconnected_stay_an_error():
    class Outer(mt.Component):
        inner = DrivenRC()

    # inner.u is no external input: it drives inner.src.u inside, but nothing drives it
    with pytest.raises(ModelError, match=r"signal input 'inner.u' is not connected"):
        mt.compile_model(Outer())


def test_a_root_input_driven_from_inside_is_two_drivers():
    class Loop(mt.Component):
        u = mt.Input("1")
        k = blocks.Constant(value=1.0)
        gain = blocks.Gain()

        def equations(self):
            return [mt.connect(self.k.y, self.u, self.gain.u)]

    with pytest.raises(ModelError, match=r"signal outputs k.y, u are connected together.*"
                       r"external input"):
        mt.compile_model(Loop())


def test_system_input():
    m = mt.System("rc_sys")
    u = m.input("u", unit="V", doc="Source voltage")
    m.add("src", el.ControlledVoltageSource())
    m.add("r", el.Resistor(R=R))
    m.add("c", el.Capacitor(C=C))
    m.add("g", el.ElectricalReference())
    m.connect(u, m.src.u)
    m.connect(m.src.p, m.r.p)
    m.connect(m.r.n, m.c.p)
    m.connect(m.src.n, m.c.n, m.g.port)
    res = mt.simulate(m, 5e-3, inputs={"u": "2 V"}, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res["c.v"], 2.0 * (1 - np.exp(-res.t / TAU)), atol=1e-8)
    with pytest.raises(ModelError, match="taken already"):
        m.input("r", unit="V")


# -------------------------------------------------------------------- variable step
def test_sine_table_matches_scipy_and_the_analytic_response(rc):
    w = 2 * np.pi * 300.0
    t_tab = np.linspace(0, 5e-3, 2001)
    v_tab = np.sin(w * t_tab)
    res = mt.simulate(rc, 5e-3, inputs={"u": (t_tab, v_tab)}, rtol=1e-10, atol=1e-12)
    # the same ODE with the same piecewise-linear input: solved exactly, and by SciPy
    np.testing.assert_allclose(res["c.v"], _rc_exact(t_tab, v_tab, res.t), rtol=0,
                               atol=1e-8)
    np.testing.assert_allclose(res["c.v"], _rc_reference(t_tab, v_tab, res.t), atol=1e-8)
    # analytic steady state + transient of dv/dt = (sin(w t) - v)/tau, v(0) = 0; the
    # table's linear interpolation differs from the sine by at most (w dt)^2/8, and the
    # lag (DC gain 1) passes that bound on to v
    wt = w * TAU
    exact = (np.sin(w * res.t) - wt * np.cos(w * res.t) + wt * np.exp(-res.t / TAU)) \
        / (1 + wt ** 2)
    bound = (w * (t_tab[1] - t_tab[0])) ** 2 / 8
    np.testing.assert_allclose(res["c.v"], exact, rtol=0, atol=bound)
    # the input is logged like any variable: the table, linear between its points
    np.testing.assert_allclose(res["u"], np.interp(res.t, t_tab, v_tab), atol=1e-15)
    np.testing.assert_allclose(res["src.u"], res["u"], atol=1e-15)


def test_a_callable_is_sampled_and_matches_the_analytic_response(rc):
    w = 2 * np.pi * 300.0
    res = mt.simulate(rc, 5e-3, inputs={"u": lambda t: np.sin(w * t) * ureg.V},
                      rtol=1e-10, atol=1e-12)
    wt = w * TAU
    exact = (np.sin(w * res.t) - wt * np.cos(w * res.t) + wt * np.exp(-res.t / TAU)) \
        / (1 + wt ** 2)
    # sampled on SAMPLES points: interpolation error at most (w dt)^2 / 8
    bound = (w * 5e-3 / (SAMPLES - 1)) ** 2 / 8
    np.testing.assert_allclose(res["c.v"], exact, rtol=0, atol=bound + 1e-9)


def test_table_is_held_constant_outside_its_range(rc):
    # the table covers [1 ms, 2 ms] only: 0 V before, 3 V after
    t_tab, v_tab = np.array([1e-3, 2e-3]), np.array([0.0, 3.0])
    res = mt.simulate(rc, 6e-3, inputs={"u": (t_tab, v_tab)}, rtol=1e-10, atol=1e-12)
    assert np.all(res["u"][res.t <= 1e-3] == 0.0)
    assert np.all(res["u"][res.t >= 2e-3] == 3.0)
    np.testing.assert_allclose(res["c.v"], _rc_exact(t_tab, v_tab, res.t), rtol=0,
                               atol=1e-8)


def test_constant_input_equals_a_constant_block(rc):
    ref = mt.simulate(ConstantRC(), 5e-3, rtol=1e-10, atol=1e-12)
    for value in (1.7, "1.7 V", "1700 mV", 1.7 * ureg.V):
        res = mt.simulate(rc, 5e-3, inputs={"u": value}, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(res["c.v"], ref["c.v"], rtol=0, atol=1e-10)
        assert np.all(res["u"] == 1.7)
    # an input is a parameter slot: params= gives a constant too
    res = mt.simulate(rc, 5e-3, params={"u": 1.7}, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res["c.v"], ref["c.v"], rtol=0, atol=1e-10)


def test_a_new_table_of_the_same_length_reuses_the_integrator(rc):
    t_tab = np.linspace(0, 5e-3, 101)
    mt.simulate(rc, 5e-3, inputs={"u": (t_tab, np.sin(1e3 * t_tab))}, rtol=1e-10,
                atol=1e-12)
    keys = {k for k in rc._cache if isinstance(k, tuple) and k[0] == "var"}
    res = mt.simulate(rc, 5e-3, inputs={"u": (t_tab * 0.9, 2 * np.cos(2e3 * t_tab))},
                      rtol=1e-10, atol=1e-12)
    assert {k for k in rc._cache if isinstance(k, tuple) and k[0] == "var"} == keys
    # and the second run used its own data
    np.testing.assert_allclose(
        res["c.v"], _rc_reference(t_tab * 0.9, 2 * np.cos(2e3 * t_tab), res.t), atol=1e-8)
    # a table of another length is another integrator
    t2 = np.linspace(0, 5e-3, 57)
    mt.simulate(rc, 5e-3, inputs={"u": (t2, t2)}, rtol=1e-10, atol=1e-12)
    assert len({k for k in rc._cache if isinstance(k, tuple) and k[0] == "var"}) == \
        len(keys) + 1


def test_input_through_events_relay_switches_when_the_ramp_crosses():
    class RelayRC(mt.Component):
        cmd = mt.Input("1", doc="Command")
        relay = blocks.Relay(on_point=0.5, off_point=-0.5, on_value=1.0, off_value=0.0)
        src = el.ControlledVoltageSource()
        r = el.Resistor(R=R)
        c = el.Capacitor(C=C)
        g = el.ElectricalReference()

        def equations(self):
            return [mt.connect(self.cmd, self.relay.u),
                    mt.connect(self.relay.y, self.src.u),
                    mt.connect(self.src.p, self.r.p), mt.connect(self.r.n, self.c.p),
                    mt.connect(self.src.n, self.c.n, self.g.port)]

    # ramp 0 -> 1 over 10 ms: the relay switches on at 5 ms, then v = 1 - exp(-(t-5ms)/tau)
    res = mt.simulate(RelayRC(), 10e-3, inputs={"cmd": ([0.0, 10e-3], [0.0, 1.0])},
                      rtol=1e-10, atol=1e-12)
    assert res.stats.events == {"relay": 1}
    assert res.event_times["relay"] == pytest.approx(5e-3, abs=1e-10)
    exact = np.where(res.t > 5e-3, 1 - np.exp(-(res.t - 5e-3) / TAU), 0.0)
    np.testing.assert_allclose(res["c.v"], exact, atol=1e-7)


def test_an_input_with_a_start_value_is_optional():
    class WithDefault(mt.Component):
        u = mt.Input("V", start=0.5, doc="Source voltage")
        gain = blocks.Gain(k=2.0)
        p_in = mt.Variable("W", doc="Power delivered by the source")
        src = el.ControlledVoltageSource()
        r = el.Resistor(R=R)
        c = el.Capacitor(C=C)
        g = el.ElectricalReference()

        def equations(self):
            # connected, and used in an equation directly
            return [mt.connect(self.u, self.gain.u), mt.connect(self.gain.y, self.src.u),
                    self.p_in == 2 * self.u * self.r.i, mt.connect(self.src.p, self.r.p),
                    mt.connect(self.r.n, self.c.p),
                    mt.connect(self.src.n, self.c.n, self.g.port)]

    cm = mt.compile_model(WithDefault())
    assert cm.input_defaults == [0.5]
    res = mt.simulate(cm, 5e-3, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res["c.v"], 1.0 * (1 - np.exp(-res.t / TAU)), atol=1e-8)
    res = mt.simulate(cm, 5e-3, inputs={"u": 1.0}, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res["c.v"], 2.0 * (1 - np.exp(-res.t / TAU)), atol=1e-8)
    np.testing.assert_allclose(res["p_in"], 2.0 * 2.0 / R * np.exp(-res.t / TAU),
                               atol=1e-10)


# ----------------------------------------------------------------------- fixed step
def test_rk4_with_a_table_equals_a_numpy_loop_with_zero_order_hold(rc):
    dt, n = 1e-5, 500
    t_tab = np.linspace(0, 5e-3, 37)
    v_tab = np.sin(2e3 * t_tab) + 0.3
    res = mt.simulate(rc, n * dt, solver="rk4", dt=dt, inputs={"u": (t_tab, v_tab)})

    def f(v, u):
        return (u - v) / TAU

    v, out = 0.0, [0.0]
    for k in range(n):
        u = np.interp(k * dt, t_tab, v_tab)      # sampled at the step start, held
        k1 = f(v, u)
        k2 = f(v + dt / 2 * k1, u)
        k3 = f(v + dt / 2 * k2, u)
        k4 = f(v + dt * k3, u)
        v = v + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        out.append(v)
    np.testing.assert_allclose(res["c.v"], out, rtol=0, atol=1e-12)
    # logged at the end of each step: the value held during that step
    held = np.interp(dt * np.arange(n), t_tab, v_tab)
    np.testing.assert_array_equal(res["u"][1:], held)
    assert res["u"][0] == v_tab[0]


def test_fixed_step_samples_a_callable_at_the_step_starts(rc):
    dt, n = 2e-5, 100

    def f(t):
        return 1.0 + t / 1e-3

    res = mt.simulate(rc, n * dt, solver="euler", dt=dt, inputs={"u": f})
    v = 0.0
    for k in range(n):
        v = v + dt * (1.0 + k * dt / 1e-3 - v) / TAU
    assert res["c.v"][-1] == pytest.approx(v, abs=1e-13)


# --------------------------------------------------------------------------- errors
def test_missing_input_names_it_and_shows_how(rc):
    with pytest.raises(SimulationError, match=r"input\(s\) u have no value and no "
                       r"default.*inputs=\{'u': \.\.\.\}"):
        mt.simulate(rc, 1e-3)


def test_unknown_input_name(rc):
    with pytest.raises(SimulationError, match=r"unknown input\(s\) 'uu' \(did you mean "
                       r"u\?\)\. External inputs: u"):
        mt.simulate(rc, 1e-3, inputs={"uu": 1.0})
    with pytest.raises(SimulationError, match=r"has no external inputs.*mt.Input"):
        mt.simulate(ConstantRC(), 1e-3, inputs={"u": 1.0})


def test_wrong_units(rc):
    with pytest.raises(UnitError, match=r"input 'u': expected a value in V"):
        mt.simulate(rc, 1e-3, inputs={"u": "3 A"})
    with pytest.raises(UnitError, match=r"input 'u': table values: expected values in V"):
        mt.simulate(rc, 1e-3, inputs={"u": ([0, 1e-3], [1, 2] * ureg.m)})
    with pytest.raises(UnitError, match=r"input 'u': function values"):
        mt.simulate(rc, 1e-3, inputs={"u": lambda t: t * ureg.s})


@pytest.mark.parametrize("table, message", [
    (([0.0, np.nan, 2e-3], [0.0, 1.0, 2.0]), r"input 'u': the table times hold 1 NaN/inf "
                                             r"value\(s\), first at index 1"),
    (([0.0, 1e-3, 2e-3], [0.0, np.inf, 2.0]), r"table values hold 1 NaN/inf"),
    (([0.0, 1e-3, 1e-3], [0.0, 1.0, 2.0]), r"must increase strictly; t\[1\] = 0.001 s is "
                                           r"followed by t\[2\] = 0.001 s"),
    (([1e-3, 0.0], [0.0, 1.0]), r"must increase strictly"),
    (([0.0], [1.0]), r"a table needs at least 2 points, got 1.*inputs=\{'u': 1.0\}"),
    (([0.0, 1.0, 2.0], [1.0, 2.0]), r"3 times and 2 values"),
    ((np.zeros((2, 2)), [1.0, 2.0]), r"expected a 1-D array, got shape \(2, 2\)"),
    ((["a", "b"], [1.0, 2.0]), r"expected numbers"),
])
def test_bad_tables(rc, table, message):
    with pytest.raises(SimulationError, match=message):
        mt.simulate(rc, 1e-3, inputs={"u": table})


def test_bad_values_and_functions(rc):
    with pytest.raises(SimulationError, match=r"inputs must be a dict .*got list"):
        mt.simulate(rc, 1e-3, inputs=[1.0])
    with pytest.raises(SimulationError, match=r"cannot use dict .* as a signal"):
        mt.simulate(rc, 1e-3, inputs={"u": {"t": 1}})
    with pytest.raises(SimulationError, match=r"input 'u' is nan"):
        mt.simulate(rc, 1e-3, inputs={"u": float("nan")})
    with pytest.raises(SimulationError, match=r"returned 3 values for 2 times"):
        mt.simulate(rc, 1e-3, inputs={"u": lambda t: np.ones(3)})
    with pytest.raises(SimulationError, match=r"not finite at t = 0.001 s"):
        mt.simulate(rc, 1e-3, inputs={"u": lambda t: np.where(t < 5e-4, 0.0, np.inf)})
    with pytest.raises(SimulationError, match=r"the function raised .*NumPy array"):
        mt.simulate(rc, 1e-3, inputs={"u": lambda t: float(t)})
    with pytest.raises(SimulationError, match=r"given both in params= and inputs="):
        mt.simulate(rc, 1e-3, params={"u": 1.0}, inputs={"u": 1.0})
    with pytest.raises(SimulationError, match=r"'rodas4' takes constant inputs only"):
        mt.simulate(rc, 1e-3, solver="rodas4", inputs={"u": ([0, 1e-3], [0, 1])})


# ------------------------------------------------------------------------------- CLI
@pytest.fixture()
def registered(monkeypatch):
    from mechatron.models import registry
    from mechatron.models.entry import Experiment, ModelEntry
    mt.models.list()
    entry = ModelEntry(name="driven_rc_test", description="RC driven by an input.",
                       parameters={}, variants={"acausal": lambda: DrivenRC()},
                       outputs={"acausal": {"v_C": "c.v", "u": "u"}},
                       output_units={"v_C": "V", "u": "V"},
                       experiment=Experiment(t_stop=5e-3))
    monkeypatch.setitem(registry._REGISTRY, entry.name, entry)
    return entry


def test_cli_input_constant_and_csv(registered, tmp_path, capsys):
    import json

    from mechatron.cli import main
    tight = ["--rtol", "1e-10", "--atol", "1e-12", "--json"]
    assert main(["simulate", "driven_rc_test", "--input", "u=2", *tight]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["final"]["v_C"] == pytest.approx(2 * (1 - np.exp(-5)), abs=1e-6)
    t_tab = np.linspace(0, 5e-3, 51)
    v_tab = np.sin(1e3 * t_tab)
    path = tmp_path / "drive.csv"
    np.savetxt(path, np.column_stack([t_tab, v_tab]), delimiter=",", header="t,volts",
               comments="")
    assert main(["simulate", "driven_rc_test", "--input", f"u={path}", *tight]) == 0
    out = json.loads(capsys.readouterr().out)
    ref = _rc_reference(t_tab, v_tab, np.array([0.0, 5e-3]))
    assert out["final"]["v_C"] == pytest.approx(ref[-1], abs=1e-6)
    assert out["final"]["u"] == pytest.approx(v_tab[-1], abs=1e-12)


@pytest.mark.parametrize("args, message", [
    ([], "input(s) u have no value"),
    (["--input", "u"], "expected NAME=VALUE"),
    (["--input", "u=nope.csv"], "no such file"),
    (["--input", "u=3 A"], "expected a value in V"),
    (["--input", "w=3"], "unknown input(s) 'w'"),
    (["--input", "u=inf"], "expected a finite value"),
])
def test_cli_input_errors_are_one_line(registered, capsys, args, message):
    from mechatron.cli import main
    assert main(["simulate", "driven_rc_test", *args]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.strip().count("\n") == 0
    assert message in err


def test_cli_csv_with_wrong_columns(registered, tmp_path, capsys):
    from mechatron.cli import main
    path = tmp_path / "bad.csv"
    path.write_text("time,a,b\n0,1,2\n1,2,3\n")
    assert main(["simulate", "driven_rc_test", "--input", f"u={path}"]) == 2
    err = capsys.readouterr().err
    assert "expected a column 't'" in err and err.strip().count("\n") == 0
