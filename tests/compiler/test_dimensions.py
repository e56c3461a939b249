"""The dimension check of every equation (compiler/dimensions.py): errors name the
component, the equation and both dimensions; numbers and free signals are wildcards;
functions need dimensionless arguments; the whole library and database pass."""

import math
import random

import casadi as ca
import pytest

import mechatron as mt
from mechatron.compiler.dimensions import (FREE, NUMBER, component_dimension_problems,
                                           dimension_problems, format_dimension, infer,
                                           unit_dimension)
from mechatron.compiler.flatten import _SumEquation, flatten
from mechatron.core import Across, Connector, Through
from mechatron.core.domains import ELECTRICAL
from mechatron.errors import UnitError
from mechatron.library import blocks
from mechatron.library import electrical as el
from mechatron.library import rotational as rot
from mechatron.library import translational as tr
from mechatron.library.catalog import components
from mechatron.units import ureg


# ---------------------------------------------------------------- circuits under test
class WrongInductor(el.OnePort):
    """An inductor with the ``der`` forgotten: ``v = L i`` (wrong on purpose)."""

    L = mt.Parameter("H", default=1e-3, min=0, doc="Inductance")

    def equations(self):
        return [self.v == self.L * self.i]


class RightInductor(el.OnePort):
    """``v = L di/dt``."""

    L = mt.Parameter("H", default=1e-3, min=0, doc="Inductance")

    def equations(self):
        return [self.v == self.L * mt.der(self.i)]


def circuit(part, **parts):
    """A 1 V source and a 1 Ohm resistor in series with ``part`` (and any others)."""
    m = mt.System("circuit")
    src = m.add("src", el.DCVoltageSource(V=1.0))
    r = m.add("r1", el.Resistor(R=1.0))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, r.p)
    node = r.n
    for name, p in [("x1", part)] + list(parts.items()):
        m.add(name, p)
        m.connect(node, p.p)
        node = p.n
    m.connect(node, src.n, g.port)
    return m


def one_port(unit_of_q, equation):
    """A one-port whose single equation is ``equation(self)``, with a parameter ``q`` in
    ``unit_of_q`` and a current ``i_s`` (1 A)."""

    class Custom(el.OnePort):
        """``v = f(i)`` for tests."""

        q = mt.Parameter(unit_of_q, default=1.0, doc="A parameter for the test")
        i_s = mt.Parameter("A", default=1.0, doc="A current scale")

        def equations(self):
            return [equation(self)]
    return Custom()


# ------------------------------------------------------------------------ the errors
def test_missing_der_names_the_component_the_equation_and_both_dimensions():
    with pytest.raises(UnitError) as info:
        mt.compile_model(circuit(WrongInductor()))
    msg = str(info.value)
    assert msg == ("WrongInductor 'x1': v == (L*i): the left side is V (kg*m^2/(A*s^3)), "
                   "the right side is Wb (kg*m^2/(A*s^2)). Is a der() missing?")
    assert info.value.path == "circuit" and info.value.problems == [msg]
    assert isinstance(info.value, ValueError)


def test_the_right_inductor_compiles_and_keeps_its_time_constant():
    cm = mt.compile_model(circuit(RightInductor(L=0.5)))
    assert "dimensions" in cm.report["timings"]
    res = mt.simulate(cm, 1.0, t_out=[0.0, 0.5, 1.0], rtol=1e-9, atol=1e-12)
    # i = (1 - exp(-t R/L)) / R with R = 1, L = 0.5
    assert res.final("x1.i") == pytest.approx(1 - math.exp(-2.0), rel=1e-6)


def test_every_problem_is_reported_once_and_together():
    class WrongResistor(el.OnePort):
        """``v = R i`` with R declared in siemens (wrong on purpose)."""

        R = mt.Parameter("S", default=1.0, doc="Resistance, declared in the wrong unit")

        def equations(self):
            return [self.v == self.R * self.i]

    with pytest.raises(UnitError, match=r"model 'circuit': 2 equations with inconsistent "
                                        r"dimensions") as info:
        mt.compile_model(circuit(WrongInductor(), x2=WrongResistor()))
    problems = info.value.problems
    assert len(problems) == 2
    assert problems[1] == ("WrongResistor 'x2': v == (R*i): the left side is V "
                           "(kg*m^2/(A*s^3)), the right side is A^3*s^3/(kg*m^2). "
                           "Check the units declared for its variables and parameters.")


def _mixed_pins(flow_unit: str) -> mt.System:
    """A source, a resistor and a load whose pins are another connector class of the
    electrical domain, declaring its flow in ``flow_unit``, joined in two nodes of three
    and four members (flow sums)."""

    class OtherPin(Connector, domain=ELECTRICAL):
        """An electrical pin of its own class."""

        v = Across("V", doc="Electric potential at the pin")
        i = Through(flow_unit, doc="Flow into the pin")

    class Load(mt.Component):
        """A conductance across two `OtherPin`s."""

        p = OtherPin(doc="Positive pin")
        n = OtherPin(doc="Negative pin")
        G = mt.Parameter(f"{flow_unit}/V", default=1.0, doc="Flow per volt")

        def equations(self):
            return [self.p.i == self.G * (self.p.v - self.n.v), self.p.i + self.n.i == 0]

    m = mt.System("mixed_pins")
    src = m.add("src", el.DCVoltageSource(V=1.0))
    g = m.add("g", el.ElectricalReference())
    r = m.add("r", el.Resistor(R=1.0))
    load = m.add("load", Load())
    m.connect(src.p, r.p, load.p)
    m.connect(r.n, load.n, src.n, g.port)
    return m


def test_flow_sums_of_one_connector_class_are_not_walked_and_others_are():
    """A flow sum whose terms are all the same variable of one connector class agrees by
    construction and is not walked by the dimension check; a sum over two connector
    classes is walked (their units may differ in scale: mA and A agree)."""
    flat = flatten(_mixed_pins("mA"))
    sums = [eq for eq in flat.equations if type(eq) is _SumEquation]
    assert len(sums) == 2 and not any(eq.uniform for eq in sums)
    assert dimension_problems(flat) == []
    flat = flatten(circuit(RightInductor()))
    sums = [eq for eq in flat.equations if type(eq) is _SumEquation]
    assert sums and all(eq.uniform for eq in sums)
    assert dimension_problems(flat) == []


def test_connectors_whose_variables_differ_in_dimension_do_not_connect():
    """Two connector classes of one domain whose flow is declared in watts and in amperes
    cannot be joined: the node would sum a power and a current. Each such pair of
    ports is named, with the variable and both units, whatever the size of the node."""
    with pytest.raises(mt.errors.ConnectError) as info:
        flatten(_mixed_pins("W"))
    problems = info.value.problems
    assert len(problems) == 3
    assert problems[0] == (
        "cannot connect 'r.p' (Pin) with 'load.p' (OtherPin): their i is declared in A "
        "(A) and in W (kg*m^2/s^3). Declare the connectors' variables in units of one "
        "dimension.")
    assert {p.split(":")[0] for p in problems[1:]} == {
        "cannot connect 'r.n' (Pin) with 'load.n' (OtherPin)",
        "cannot connect 'load.n' (OtherPin) with 'src.n' (Pin)"}


def test_a_mismatch_inside_one_side_is_described():
    part = one_port("Ohm", equation=lambda s: s.v == s.q * s.i + s.i)
    with pytest.raises(UnitError, match=r"Custom 'x1': v == \(\(q\*i\)\+i\): on the "
                                        r"right side, it adds V \(kg\*m\^2/\(A\*s\^3\)\) "
                                        r"and A\."):
        mt.compile_model(circuit(part))


def test_functions_need_dimensionless_arguments():
    part = one_port("Ohm", equation=lambda s: s.v == s.q * s.i * ca.sin(s.v))
    with pytest.raises(UnitError, match=r"sin\(\) needs a dimensionless argument, got V "
                                        r"\(kg\*m\^2/\(A\*s\^3\)\)"):
        mt.compile_model(circuit(part))
    for fn in (ca.exp, ca.log, ca.tanh, ca.atan, ca.cosh):
        part = one_port("Ohm", equation=lambda s, fn=fn: s.v == s.q * s.i * fn(s.i))
        with pytest.raises(UnitError, match=r"\(\) needs a dimensionless argument, got A"):
            mt.compile_model(circuit(part))
    # a dimensionless argument is fine: v = q * tanh(i / i_s), q in V, i_s in A; with
    # q = 1 V, i_s = 1 A in series with 1 Ohm from 1 V: i + tanh(i) = 1
    ok = one_port("V", equation=lambda s: s.v == s.q * ca.tanh(s.i / s.i_s))
    res = mt.simulate(circuit(ok), 0.1)
    i = res.final("x1.i")
    assert i + math.tanh(i) == pytest.approx(1.0, abs=1e-8)


def test_pow_with_a_variable_exponent_needs_dimensionless_operands():
    part = one_port("1", equation=lambda s: s.v == s.v ** s.q)
    with pytest.raises(UnitError, match=r"the base of pow with a variable exponent must be "
                                        r"dimensionless, got V"):
        mt.compile_model(circuit(part))


def test_if_else_branches_must_agree():
    part = one_port("Ohm", equation=lambda s: s.v == mt.if_else(s.i > 0, s.q * s.i, s.i))
    with pytest.raises(UnitError, match=r"it adds V \(kg\*m\^2/\(A\*s\^3\)\) and A"):
        mt.compile_model(circuit(part))
    part = one_port("Ohm", equation=lambda s: s.v == mt.if_else(s.i > s.v, 0, s.q * s.i))
    with pytest.raises(UnitError, match=r"it compares V \(kg\*m\^2/\(A\*s\^3\)\) with A\."):
        mt.compile_model(circuit(part))


def test_event_actions_are_checked():
    class Kick(tr.Mass):
        """``m dv/dt = f``; at t >= 0.5 s the velocity is set to a force (wrong)."""

        F_kick = mt.Parameter("N", default=1.0, doc="A force, assigned to a velocity")

        def equations(self):
            return [mt.when(self.time >= 0.5, update={self.v: self.F_kick})]

    m = mt.System("kick")
    m.add("mass", Kick(m=1.0))
    m.add("ref", tr.TranslationalReference())
    m.add("spring", tr.TranslationalSpring(k=1.0))
    m.connect(m.mass.port, m.spring.A)
    m.connect(m.spring.B, m.ref.port)
    with pytest.raises(UnitError, match=r"Kick 'mass': v := F_kick \(event action\): "
                                        r"it adds m/s and N \(kg\*m/s\^2\)\. Check"):
        mt.compile_model(m)


# ------------------------------------------------------------------------- wildcards
def test_numbers_adapt_in_sums_and_comparisons_and_are_dimensionless_factors():
    eqs = [lambda s: s.v == s.q * s.i + 1e-3,                       # number in a sum
           lambda s: s.v == mt.if_else(s.i > 0, s.q * s.i, 0),      # 0 in a branch
           lambda s: s.v == 2 * s.q * s.i / 2.5,                     # factors
           lambda s: s.v == s.q * s.i * (1 + 0 * s.i / (s.i + 1e-9)),
           lambda s: s.v - s.q * s.i == 0]                           # x == 0
    for eq in eqs:
        mt.compile_model(circuit(one_port("Ohm", equation=eq)))
    # but a number does not carry a unit: 1e-3 * i is a current, not a voltage
    with pytest.raises(UnitError, match=r"the left side is V .*, the right side is A"):
        mt.compile_model(circuit(one_port("Ohm", equation=lambda s: s.v == 1e-3 * s.i)))


def test_free_signals_connect_to_anything_but_own_variables_are_strict():
    class SignalDriven(el.OnePort):
        """``v = u`` for a plain signal ``u`` (unit "1": a free signal)."""

        u = mt.Input("1", doc="Plain signal")

        def equations(self):
            return [self.v == self.u]

    m = circuit(SignalDriven())
    m.add("cmd", blocks.Constant(value=0.5))
    m.connect(m.cmd.y, m.x1.u)
    cm = mt.compile_model(m)
    assert mt.simulate(cm, 0.1).final("x1.i") == pytest.approx(0.5, rel=1e-9)

    class Strict(el.OnePort):
        """``v = k`` with ``k`` a dimensionless variable of a physical component."""

        k = mt.Variable("1", doc="A dimensionless variable, not a signal")

        def equations(self):
            return [self.v == self.k, self.k == 1]

    with pytest.raises(UnitError, match=r"Strict 'x1': v == k: the left side is V "
                                        r"\(kg\*m\^2/\(A\*s\^3\)\), the right side is "
                                        r"dimensionless"):
        mt.compile_model(circuit(Strict()))


def test_signal_blocks_with_unitless_states_pass():
    """A transfer function's states are plain numbers of unknown dimension (its
    coefficients carry powers of s): a free signal each."""
    m = mt.System("tf")
    src = m.add("src", blocks.Step(final=1.0))
    tf = m.add("tf", blocks.TransferFunction(num=[2.0], den=[1.0, 3.0, 2.0]))
    m.connect(src.y, tf.u)
    res = mt.simulate(m, 3.0, rtol=1e-10, atol=1e-12)
    # 2 / ((s+1)(s+2)): step response 1 - 2 e^-t + e^-2t
    assert res.final("tf.y") == pytest.approx(1 - 2 * math.exp(-3) + math.exp(-6),
                                              rel=1e-6)


def test_odes_without_units_pass_but_declared_units_are_checked():
    """A component without ports whose variables are all of unit "1" is plain math (its
    number coefficients may hide units): its variables are free. Declared units in such
    a component are still checked."""

    class Decay(mt.Component):
        """``dx/dt = -a x``, ``y = x^2`` without units."""

        a = mt.Parameter("1", default=2.0, doc="Rate (a number)")
        x = mt.Variable(start=1.0, doc="State")
        y = mt.Variable(doc="Its square")

        def equations(self):
            return [mt.der(self.x) == -self.a * self.x, self.y == self.x ** 2]

    res = mt.simulate(Decay(), 1.0, rtol=1e-10, atol=1e-12)
    assert res.final("y") == pytest.approx(math.exp(-4.0), rel=1e-7)

    class Pendulum(mt.Component):
        """``dv/dt = -T x / L`` with ``T`` declared as a force (wrong: per unit mass)."""

        L = mt.Parameter("m", default=1.0, doc="Length")
        x = mt.Variable("m", start=0.1, doc="Position")
        v = mt.Variable("m/s", start=0.0, doc="Velocity")
        T = mt.Variable("N", doc="Rod tension per unit mass")

        def equations(self):
            return [mt.der(self.x) == self.v, mt.der(self.v) == -self.T * self.x / self.L,
                    self.T == 9.81]

    assert component_dimension_problems(Pendulum) == [
        "model 'Pendulum': der(v) == (-((T*x)/L)): the left side is m/s^2, the right side "
        "is N (kg*m/s^2). Check the units declared for its variables and parameters."]


def test_second_derivatives_and_time():
    class Falling(mt.Component):
        """``m x'' = -m g`` with ``x(t) = h - g t^2 / 2`` logged beside it."""

        m = mt.Parameter("kg", default=1.0, doc="Mass")
        g = mt.Parameter("m/s^2", default=9.81, doc="Gravity")
        h = mt.Parameter("m", default=100.0, doc="Initial height")
        x = mt.Variable("m", start=100.0, doc="Height")
        v = mt.Variable("m/s", start=0.0, doc="Velocity")
        x_exact = mt.Variable("m", doc="Analytic height")

        def equations(self):
            return [self.m * mt.der(self.v) == -self.m * self.g,
                    self.v == mt.der(self.x),
                    self.x_exact == self.h - self.g * self.time ** 2 / 2]

    res = mt.simulate(Falling(), 2.0, rtol=1e-10, atol=1e-10)
    assert res.final("x") == pytest.approx(100.0 - 9.81 * 2.0, rel=1e-7)
    assert res.final("x_exact") == pytest.approx(res.final("x"), rel=1e-7)

    class Second(Falling):
        """``m x'' = -m g`` written with a second derivative (and a wrong twin)."""

        a = mt.Variable("m/s^2", doc="Acceleration")

        def equations(self):
            return [self.a == mt.der(mt.der(self.x)),
                    self.a == mt.der(self.x)]

    problems = component_dimension_problems(Second)
    assert problems == ["model 'Second': a == der(x): the left side is m/s^2, the right "
                        "side is m/s. Is a der() missing?"]

    class Wrong(Falling):
        """``x = t`` (wrong on purpose)."""

        y = mt.Variable("m", doc="Not a time")

        def equations(self):
            return [self.y == self.time]

    with pytest.raises(UnitError, match=r"model 'Wrong': y == time: the left side is m, "
                                        r"the right side is s\."):
        mt.compile_model(Wrong())


# ------------------------------------------------------------------ escape hatches
def test_a_class_may_opt_out_and_so_may_a_compile():
    class Legacy(WrongInductor):
        """``v = L i`` kept on purpose (an opted-out class)."""

        check_dimensions = False

    cm = mt.compile_model(circuit(Legacy()))
    assert "dimensions" in cm.report["timings"]
    cm = mt.compile_model(circuit(WrongInductor()), check_dimensions=False)
    assert "dimensions" not in cm.report["timings"]
    # opting out covers the class's own equations only, not its neighbours'
    with pytest.raises(UnitError, match=r"WrongInductor 'x2'") as info:
        mt.compile_model(circuit(Legacy(), x2=WrongInductor()))
    assert len(info.value.problems) == 1


# --------------------------------------------------- the inference against pint itself
UNITS = ["V", "A", "Ohm", "H", "F", "Wb", "N", "N*m", "m/s", "rad/s", "kg*m^2", "K",
         "W/K", "Pa", "m^3/s", "J", "s", "1", "rad", "mol", "cd", "N/m^1.5", "V*s/rad"]


def test_inferred_dimensions_match_pint_on_random_products():
    """Random monomials ``a^p * b^q / c`` of declared units, with number factors: the
    pass's dimension equals pint's dimensionality of the same product."""
    rng = random.Random(15)
    exprs, expected, syms, dims = [], [], [], []
    for k in range(200):
        units = [rng.choice(UNITS) for _ in range(3)]
        powers = [rng.choice([1, 2, 3, -1, 0.5, 1.5, -2]), rng.choice([1, -1, 2]), 1]
        s = [ca.SX.sym(f"s{k}_{j}") for j in range(3)]
        syms += s
        dims += [unit_dimension(u) for u in units]
        exprs.append(3.5 * s[0] ** powers[0] * s[1] ** powers[1] / s[2] + 0.0)
        q = (ureg.Quantity(1, units[0]) ** powers[0] * ureg.Quantity(1, units[1])
             ** powers[1] / ureg.Quantity(1, units[2]))
        expected.append(q.dimensionality)
    f = ca.Function("f", [ca.vertcat(*syms)], [ca.vertcat(*exprs)],
                    {"live_variables": False})
    got = infer(f, dims)
    for g, want in zip(got, expected):
        if g is NUMBER:     # a product whose powers cancel to a bare number
            assert not want
            continue
        exps = {b: 0 for b in ("[length]", "[mass]", "[time]", "[current]",
                               "[temperature]", "[substance]", "[luminosity]")}
        exps.update(want)
        assert g == unit_dimension(_unit_of(exps)), (format_dimension(g), want)


def _unit_of(exps):
    base = {"[length]": "m", "[mass]": "kg", "[time]": "s", "[current]": "A",
            "[temperature]": "K", "[substance]": "mol", "[luminosity]": "cd"}
    parts = [f"{base[b]}**{e}" for b, e in exps.items() if e]
    return "*".join(parts) or "1"


def test_dimension_words():
    assert format_dimension(unit_dimension("V")) == "kg*m^2/(A*s^3)"
    assert format_dimension(unit_dimension("rad/s")) == "1/s"
    assert format_dimension(unit_dimension("N/m^1.5")) == "kg/(m^(1/2)*s^2)"
    assert format_dimension(unit_dimension("1")) == "1"
    assert unit_dimension("rpm") == unit_dimension("1/s")
    assert unit_dimension("degC") == unit_dimension("K")


def test_free_and_number_propagate_through_a_function():
    x, y = ca.SX.sym("x"), ca.SX.sym("y")
    f = ca.Function("f", [ca.vertcat(x, y)],
                    [ca.vertcat(x * y, x + y, ca.sin(x), 2 * y, x + 1)],
                    {"live_variables": False})
    volt = unit_dimension("V")
    assert infer(f, [FREE, volt]) == [FREE, volt, 0, volt, FREE]


# ------------------------------------------------- the library and the database pass
@pytest.mark.parametrize("info", components(), ids=lambda c: c.qualname.split(".", 2)[-1])
def test_every_library_component_is_dimensionally_consistent(info):
    assert component_dimension_problems(info.cls) == []


def test_the_walk_catches_a_wrong_class():
    assert component_dimension_problems(WrongInductor) == [
        "model 'WrongInductor': v == (L*i): the left side is V (kg*m^2/(A*s^3)), the right "
        "side is Wb (kg*m^2/(A*s^2)). Is a der() missing?"]


ENTRIES = [(e.name, v) for e in mt.models.list() for v in e.variants]


@pytest.mark.parametrize("name,variant", ENTRIES, ids=[f"{n}-{v}" for n, v in ENTRIES])
def test_every_database_model_is_dimensionally_consistent(name, variant):
    model = mt.models.get(name).build(variant)
    flat = flatten(model)
    assert dimension_problems(flat, model) == []

