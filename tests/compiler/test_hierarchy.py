"""Subsystems with their own ports (Modelica's inside and outside connectors): an RC stage
used twice and four times, three levels deep, parameters passed on, open ports, reversed
ports, signal subsystems, and check_balance agreeing with the compiler. Physics against
the exact solution of the linear network."""

import re

import numpy as np
import pytest
from scipy.linalg import expm

import mechatron as mt
from mechatron.core.balance import check_balance
from mechatron.errors import ModelError, UnitError
from mechatron.library import blocks
from mechatron.library import electrical as el

TIGHT = dict(rtol=1e-11, atol=1e-13)


class Stage(mt.Component):
    """Series resistor from p to n, capacitor from n to gnd."""

    R = mt.Parameter("Ohm", default=1.0, min=0, doc="Series resistance")
    C = mt.Parameter("F", default=1.0, min=0, doc="Shunt capacitance")
    p = el.Pin(doc="Input")
    n = el.Pin(doc="Output")
    gnd = el.Pin(doc="Common")
    r = el.Resistor(R=R)
    c = el.Capacitor(C=C)

    def equations(self):
        return [mt.connect(self.p, self.r.p), mt.connect(self.r.n, self.c.p, self.n),
                mt.connect(self.c.n, self.gnd)]


class Pair(mt.Component):
    """Two stages in series: the second level."""

    R = mt.Parameter("Ohm", default=1.0, min=0, doc="Series resistance per stage")
    C = mt.Parameter("F", default=1.0, min=0, doc="Capacitance per stage")
    p = el.Pin(doc="Input")
    n = el.Pin(doc="Output")
    gnd = el.Pin(doc="Common")
    first = Stage(R=R, C=C)
    second = Stage(R=R, C=C)

    def equations(self):
        return [mt.connect(self.p, self.first.p),
                mt.connect(self.first.n, self.second.p),
                mt.connect(self.second.n, self.n),
                mt.connect(self.first.gnd, self.second.gnd, self.gnd)]


def ladder_exact(R, C, V, t):
    """Node voltages of an open-ended RC ladder (stage k: R[k] in series, C[k] to ground)
    under a step V, from the matrix exponential of its nodal equations."""
    n = len(R)
    G = np.zeros((n, n))
    b = np.zeros(n)
    for k in range(n):
        g = 1.0 / R[k]
        G[k, k] += g
        if k == 0:
            b[0] = g * V
        else:
            G[k - 1, k - 1] += g
            G[k - 1, k] -= g
            G[k, k - 1] -= g
    A = -G / np.asarray(C)[:, None]
    x_inf = np.linalg.solve(G, b)
    return np.array([x_inf - expm(A * tk) @ x_inf for tk in t])


def test_stage_used_twice_in_series_matches_the_exact_answer():
    class Two(mt.Component):
        src = el.DCVoltageSource(V=1.0)
        s1 = Stage()
        s2 = Stage(R=2.0, C=0.5)
        g = el.ElectricalReference()

        def equations(self):
            return [mt.connect(self.src.p, self.s1.p), mt.connect(self.s1.n, self.s2.p),
                    mt.connect(self.src.n, self.g.port, self.s1.gnd, self.s2.gnd)]

    t = np.linspace(0, 3, 31)
    res = mt.simulate(Two(), 3.0, t_out=t, **TIGHT)
    exact = ladder_exact([1.0, 2.0], [1.0, 0.5], 1.0, t)
    np.testing.assert_allclose(res["s1.c.v"], exact[:, 0], atol=1e-9)
    np.testing.assert_allclose(res["s2.c.v"], exact[:, 1], atol=1e-9)
    # the stage's open output carries no current; its input takes the stage's current
    np.testing.assert_allclose(res["s2.n.i"], 0.0, atol=1e-12)
    np.testing.assert_allclose(res["s1.p.i"], res["s1.r.i"], atol=1e-12)
    np.testing.assert_allclose(res["s2.p.i"], -res["s1.n.i"], atol=1e-12)


def test_three_levels_deep_match_the_exact_answer_and_the_flat_model():
    class Ladder(mt.Component):
        src = el.DCVoltageSource(V=2.0)
        a = Pair(R=1.0, C=1.0)
        b = Pair(R=0.5, C=2.0)
        g = el.ElectricalReference()

        def equations(self):
            return [mt.connect(self.src.p, self.a.p), mt.connect(self.a.n, self.b.p),
                    mt.connect(self.src.n, self.g.port, self.a.gnd, self.b.gnd)]

    R, C = [1.0, 1.0, 0.5, 0.5], [1.0, 1.0, 2.0, 2.0]
    flat = mt.System("flat")
    src = flat.add("src", el.DCVoltageSource(V=2.0))
    g = flat.add("g", el.ElectricalReference())
    flat.connect(src.n, g.port)
    node = src.p
    for k in range(4):
        r = flat.add(f"r{k}", el.Resistor(R=R[k]))
        c = flat.add(f"c{k}", el.Capacitor(C=C[k]))
        flat.connect(node, r.p)
        flat.connect(r.n, c.p)
        flat.connect(c.n, g.port)
        node = r.n

    t = np.linspace(0, 10, 41)
    deep = mt.simulate(Ladder(), 10.0, t_out=t, **TIGHT)
    ref = mt.simulate(flat, 10.0, t_out=t, **TIGHT)
    exact = ladder_exact(R, C, 2.0, t)
    paths = ["a.first.c.v", "a.second.c.v", "b.first.c.v", "b.second.c.v"]
    for k, path in enumerate(paths):
        np.testing.assert_allclose(deep[path], exact[:, k], atol=1e-9)
        np.testing.assert_allclose(deep[path], ref[f"c{k}.v"], atol=1e-9)
    cm = mt.compile_model(Ladder())
    assert sorted(cm.state_names) == sorted(paths)
    assert check_balance(Ladder()).balanced and check_balance(Pair).balanced


def test_subsystems_in_a_system_and_any_part_order():
    t = np.linspace(0, 2, 11)
    results = []
    for order in ([0, 1, 2, 3], [3, 2, 1, 0], [2, 0, 3, 1]):
        m = mt.System("ordered")
        parts = [("src", lambda: el.DCVoltageSource(V=1.0)), ("s1", lambda: Stage()),
                 ("s2", lambda: Stage(R=3.0)), ("g", lambda: el.ElectricalReference())]
        for k in order:
            m.add(*[parts[k][0], parts[k][1]()])
        m.connect(m.s1.n, m.s2.p)
        m.connect(m.s2.gnd, m.g.port, m.s1.gnd, m.src.n)
        m.connect(m.s1.p, m.src.p)
        results.append(mt.simulate(m, 2.0, t_out=t, **TIGHT))
    exact = ladder_exact([1.0, 3.0], [1.0, 1.0], 1.0, t)
    for res in results:
        np.testing.assert_allclose(res["s2.c.v"], exact[:, 1], atol=1e-9)


def test_a_subsystem_drawn_backwards_carries_its_current_with_the_right_sign():
    class Shunt(mt.Component):
        R = mt.Parameter("Ohm", default=4.0, doc="Resistance")
        a = el.Pin(doc="One end")
        b = el.Pin(doc="Other end")
        r = el.Resistor(R=R)

        def equations(self):
            return [mt.connect(self.a, self.r.p), mt.connect(self.r.n, self.b)]

    class Loop(mt.Component):
        src = el.DCVoltageSource(V=8.0)
        s = Shunt()
        g = el.ElectricalReference()

        def equations(self):   # the shunt's b faces the source's positive pin
            return [mt.connect(self.src.p, self.s.b),
                    mt.connect(self.s.a, self.src.n, self.g.port)]

    cm = mt.compile_model(Loop())
    res = mt.simulate(cm, 1e-3)
    assert res.final("s.r.i") == pytest.approx(-2.0, rel=1e-12)   # from b to a: -V/R
    assert res.final("s.b.i") == pytest.approx(2.0, rel=1e-12)    # into the shunt at b
    assert res.final("src.i") == pytest.approx(-2.0, rel=1e-12)   # the source delivers


def test_parameters_are_passed_on_through_expressions_and_tuned_without_recompiling():
    class Split(mt.Component):
        R = mt.Parameter("Ohm", default=1.0, min=0, doc="Total series resistance")
        C = mt.Parameter("F", default=1.0, doc="Capacitance")
        p = el.Pin(doc="Input")
        n = el.Pin(doc="Output")
        gnd = el.Pin(doc="Common")
        r1 = el.Resistor(R=R / 4)
        r2 = el.Resistor(R=3 * R / 4)
        c = el.Capacitor(C=C)

        def equations(self):
            return [mt.connect(self.p, self.r1.p), mt.connect(self.r1.n, self.r2.p),
                    mt.connect(self.r2.n, self.c.p, self.n), mt.connect(self.c.n, self.gnd)]

    class Top(mt.Component):
        src = el.DCVoltageSource(V=1.0)
        s = Split(R=2.0, C=0.25)
        g = el.ElectricalReference()

        def equations(self):
            return [mt.connect(self.src.p, self.s.p),
                    mt.connect(self.src.n, self.g.port, self.s.gnd)]

    cm = mt.compile_model(Top())
    assert "s.R" in cm.param_names and "s.r1.R" not in cm.param_names
    for R in (2.0, 8.0):
        res = mt.simulate(cm, 1.0, params={"s.R": R}, **TIGHT)
        tau = R * 0.25
        assert res.final("s.c.v") == pytest.approx(1 - np.exp(-1.0 / tau), abs=1e-9)
        assert res.final("s.r1.v") == pytest.approx(res.final("s.r2.v") / 3, abs=1e-12)


def test_setting_a_parameter_its_parent_passes_on_names_the_one_to_set(tmp_path):
    """In `nested_model`, ``Pair`` passes ``R`` on to its stages and each stage to its
    resistor: ``pair.first.R`` and ``pair.first.r.R`` have no value of their own, and
    setting either says to set ``pair.R`` (the chain followed to its source); a part's
    parameter bound to an expression (``h.a.R = R / 2``) says where it is written. Kept
    through saving the compiled model, and said by estimation too."""
    from mechatron.errors import ParameterError
    from tests.compiler.test_flatten_symbols import nested_model

    cm = mt.compile_model(nested_model())
    for name in ("pair.first.R", "pair.first.r.R"):
        message = rf"'{re.escape(name)}' is bound to R of 'pair(\.first)?' .* set 'pair\.R'"
        with pytest.raises(ParameterError, match=message + r" instead\."):
            mt.simulate(cm, 0.1, params={name: 2.0})
    with pytest.raises(ParameterError, match=r"'h\.a\.R' is bound to \(R / 2\) of 'h' .* "
                                             r"set the parameters it is written in\."):
        mt.simulate(cm, 0.1, params={"h.a.R": 2.0})
    loaded = mt.CompiledModel.load(cm.save(tmp_path / "bound.pkl"))
    assert loaded.binding_of("pair.first.r.R") == cm.binding_of("pair.first.r.R") != ""
    assert cm.binding_of("pair.R") == "" and cm.binding_of("nothing.R") == ""
    # an unknown name that is bound to nothing keeps the close matches
    with pytest.raises(ParameterError, match=r"unknown parameter\(s\) 'pair\.Rr' \(did "
                                             r"you mean pair\.R"):
        mt.simulate(cm, 0.1, params={"pair.Rr": 2.0})
    from mechatron.estimation import EstimationProblem, Experiment
    run = Experiment("run", t=[0.0, 0.5, 1.0], outputs={"v": [0.0, 0.3, 0.5]})
    with pytest.raises(ParameterError, match=r"free parameter 'pair\.first\.R' .* set "
                                             r"'pair\.R'"):
        EstimationProblem(cm, [run], ["pair.first.R"], outputs={"v": "c.v"})


def test_a_passed_on_parameter_of_the_wrong_dimension_is_named():
    class Bad(mt.Component):
        C = mt.Parameter("F", default=1.0, doc="Capacitance")
        p = el.Pin(doc="Input")
        n = el.Pin(doc="Output")
        r = el.Resistor(R=C)

        def equations(self):
            return [mt.connect(self.p, self.r.p), mt.connect(self.r.n, self.n)]

    class Top(mt.Component):
        src = el.DCVoltageSource(V=1.0)
        b = Bad()
        g = el.ElectricalReference()

        def equations(self):
            return [mt.connect(self.src.p, self.b.p), mt.connect(self.b.n, self.src.n,
                                                                 self.g.port)]

    with pytest.raises(UnitError, match=r"Resistor 'b.r': R = C: the expression is in "
                                        r"F .*, the parameter in Ohm"):
        mt.compile_model(Top())


def test_a_passed_on_value_without_an_enclosing_parameter_is_an_error():
    class Holder(mt.Component):
        C = mt.Parameter("F", default=1.0, doc="Capacitance")

    m = mt.System("lonely")
    src = m.add("src", el.DCVoltageSource(V=1.0))
    r = m.add("r", el.Resistor(R=Holder.C * 2))     # the System has no parameter C
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, r.p)
    m.connect(r.n, src.n, g.port)
    with pytest.raises(ModelError, match=r"Resistor 'r': R = \(C \* 2\): C is not a "
                                         r"parameter of System"):
        mt.compile_model(m)


def test_signal_subsystems_pass_values_in_and_out():
    class Doubler(mt.Component):
        u = mt.Input("1", doc="In")
        y = mt.Output("1", doc="Out")
        gain = blocks.Gain(k=2.0)

        def equations(self):
            return [mt.connect(self.u, self.gain.u), mt.connect(self.gain.y, self.y)]

    class Chain(mt.Component):
        k = blocks.Constant(value=3.0)
        d1 = Doubler()
        d2 = Doubler()
        integ = blocks.Integrator(y=0.0)

        def equations(self):
            return [mt.connect(self.k.y, self.d1.u), mt.connect(self.d1.y, self.d2.u),
                    mt.connect(self.d2.y, self.integ.u)]

    res = mt.simulate(Chain(), 2.0)
    assert res.final("integ.y") == pytest.approx(24.0, rel=1e-9)
    assert res.final("d1.y") == 6.0 and res.final("d2.y") == 12.0
    assert check_balance(Doubler).balanced


def test_an_unconnected_subsystem_input_is_named():
    class Doubler(mt.Component):
        u = mt.Input("1", doc="In")
        y = mt.Output("1", doc="Out")
        gain = blocks.Gain(k=2.0)

        def equations(self):
            return [mt.connect(self.u, self.gain.u), mt.connect(self.gain.y, self.y)]

    class Top(mt.Component):
        d = Doubler()
        integ = blocks.Integrator(y=0.0)

        def equations(self):
            return [mt.connect(self.d.y, self.integ.u)]

    with pytest.raises(ModelError, match=r"signal input 'd.u' is not connected"):
        mt.compile_model(Top())


def test_check_balance_agrees_with_the_compiler_on_a_subsystem_missing_an_equation():
    class Leaky(mt.Component):      # a stage whose capacitor is declared but unwired
        p = el.Pin(doc="Input")
        n = el.Pin(doc="Output")
        r = el.Resistor(R=1.0)
        x = mt.Variable("V", doc="An unknown no equation defines")

        def equations(self):
            return [mt.connect(self.p, self.r.p), mt.connect(self.r.n, self.n)]

    report = check_balance(Leaky)
    assert not report.balanced and report.required - report.equations == 1

    class Top(mt.Component):
        src = el.DCVoltageSource(V=1.0)
        s = Leaky()
        g = el.ElectricalReference()

        def equations(self):
            return [mt.connect(self.src.p, self.s.p),
                    mt.connect(self.s.n, self.src.n, self.g.port)]

    assert check_balance(Top).required - check_balance(Top).equations == 1
    with pytest.raises(ModelError, match=r"Unmatched variable\(s\): s.x"):
        mt.compile_model(Top())


@pytest.mark.parametrize("entry", mt.models.list(), ids=lambda e: e.name)
def test_check_balance_agrees_with_the_compiler_on_the_database(entry):
    for variant in entry.variants:
        model = entry.build(variant)
        assert check_balance(model).balanced, (variant, check_balance(model).summary())


def test_the_subsystem_example_of_the_modeling_guide_runs():
    from pathlib import Path
    text = (Path(__file__).parents[2] / "docs" / "modeling.md").read_text()
    block = text.split("<!-- docs-example: subsystem -->", 1)[1]
    code = block.split("```python", 1)[1].split("```", 1)[0]
    namespace: dict = {}
    exec(compile(code, "docs/modeling.md (subsystem example)", "exec"), namespace)
    res = namespace["res"]                      # the tuned run: s2.R = 4 kOhm
    exact = ladder_exact([1e3, 4e3], [1e-6, 1e-6], 1.0, [0.01])
    assert res.final("s2.c.v") == pytest.approx(exact[0, 1], abs=1e-8)
    assert res.final("s1.c.v") == pytest.approx(exact[0, 0], abs=1e-8)
    assert res.final("s2.n.i") == pytest.approx(0.0, abs=1e-12)
