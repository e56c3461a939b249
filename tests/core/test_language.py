"""The modeling language: declarations, inheritance, both ways to compose, user ODEs."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.core import Across, Connector, Domain, Through
from mechatron.library import electrical as el


class RCClass(mt.Component):
    src = el.DCVoltageSource(V=2.0)
    r1 = el.Resistor(R=1e3)
    c1 = el.Capacitor(C=1e-6)
    g = el.ElectricalReference()

    def equations(self):
        return [mt.connect(self.src.p, self.r1.p), mt.connect(self.r1.n, self.c1.p),
                mt.connect(self.src.n, self.c1.n, self.g.port)]


def rc_system():
    m = mt.System("RCClass")
    src = m.add("src", el.DCVoltageSource(V=2.0))
    r1 = m.add("r1", el.Resistor(R=1e3))
    c1 = m.add("c1", el.Capacitor(C=1e-6))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, r1.p)
    m.connect(r1.n, c1.p)
    m.connect(src.n, c1.n, g.port)
    return m


def test_class_and_builder_compile_to_the_same_model():
    a, b = mt.compile_model(RCClass()), mt.compile_model(rc_system())
    assert a.names == b.names and a.state_names == b.state_names
    assert a.report["equations"] == b.report["equations"]
    ra = mt.simulate(a, 5e-3, rtol=1e-10, atol=1e-12)
    rb = mt.simulate(b, 5e-3, rtol=1e-10, atol=1e-12)
    np.testing.assert_array_equal(ra.values, rb.values)
    np.testing.assert_allclose(ra["c1.v"], 2.0 * (1 - np.exp(-ra.t / 1e-3)), atol=1e-6)


def test_equations_add_up_along_the_class_hierarchy():
    class PowerResistor(el.Resistor):
        """A resistor that also reports its loss: adds one variable and one equation;
        the parent's v = R i and OnePort's equations stay without a super() call."""

        P = mt.Variable("W", doc="Dissipated power")

        def equations(self):
            return [self.P == self.v * self.i]

    m = RCClass()
    m._adopt("r1", PowerResistor(R=1e3))
    res = mt.simulate(m, 2e-3, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res["r1.v"], 1e3 * res["r1.i"], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(res["r1.P"], 1e3 * res["r1.i"] ** 2, rtol=1e-12, atol=1e-15)


def test_a_user_component_that_is_just_odes():
    class VanDerPol(mt.Component):
        """x'' - mu (1 - x^2) x' + x = 0 as two first-order ODEs."""

        mu = mt.Parameter("1", default=0.0, doc="Damping")
        x = mt.Variable("1", start=2.0, doc="Position")
        y = mt.Variable("1", start=0.0, doc="Velocity")

        def equations(self):
            return [mt.der(self.x) == self.y,
                    mt.der(self.y) == self.mu * (1 - self.x ** 2) * self.y - self.x]

    res = mt.simulate(VanDerPol(), 2 * np.pi, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res["x"], 2 * np.cos(res.t), atol=1e-7)
    cm = mt.compile_model(VanDerPol(mu=1.0))
    assert sorted(cm.state_names) == ["x", "y"]


def test_a_new_domain_needs_no_change_to_any_base_class():
    chemical = Domain("chemical", "potential mu (J/mol)", "molar flow n (mol/s)")

    class Port(Connector, domain=chemical):
        mu = Across("J/mol")
        n = Through("mol/s")

    class Store(mt.Component):
        port = Port()
        N = mt.Variable("mol", start=1.0)
        c = mt.Parameter("J/mol^2", default=2.0)

        def equations(self):
            return [mt.der(self.N) == self.port.n, self.port.mu == self.c * self.N]

    class Link(mt.Component):
        a = Port()
        b = Port()
        k = mt.Parameter("mol^2/(J*s)", default=0.5)

        def equations(self):
            return [self.a.n == self.k * (self.a.mu - self.b.mu), self.a.n + self.b.n == 0]

    m = mt.System("chem")
    s1, s2 = m.add("s1", Store()), m.add("s2", Store(N=0.0))
    link = m.add("link", Link())
    m.connect(s1.port, link.a)
    m.connect(link.b, s2.port)
    res = mt.simulate(m, 10.0, rtol=1e-10, atol=1e-12)
    assert res.final("s1.N") + res.final("s2.N") == pytest.approx(1.0, rel=1e-9)
    assert res.final("s1.N") == pytest.approx(0.5 + 0.5 * np.exp(-2 * 0.5 * 2.0 * 10.0),
                                              rel=1e-6)


def test_parameters_take_quantities_and_reject_wrong_dimensions():
    m = RCClass()
    m.r1._values["R"] = "1 kohm"
    m.c1._values["C"] = "1 uF"
    res = mt.simulate(m, 1e-3, t_out=[0.0, 1e-3])
    assert res.final("c1.v") == pytest.approx(2.0 * (1 - np.exp(-1.0)), rel=1e-5)


def test_variables_outside_compilation_explain_themselves():
    r = el.Resistor()
    with pytest.raises(mt.errors.ModelError, match="has a value only while the model "
                                                   "compiles"):
        r.v  # noqa: B018
    with pytest.raises(AttributeError, match="set it with the constructor"):
        r.R = 2.0


def test_compiled_model_saves_and_loads(tmp_path):
    cm = mt.compile_model(RCClass())
    path = cm.save(tmp_path / "rc.mtc")
    back = mt.CompiledModel.load(path)
    a, b = mt.simulate(cm, 1e-3), mt.simulate(back, 1e-3)
    np.testing.assert_array_equal(a.values, b.values)
    with pytest.raises(mt.errors.DataError, match="no such file"):
        mt.CompiledModel.load(tmp_path / "missing.mtc")


def test_system_rejects_part_names_that_shadow_its_methods():
    from mechatron.library import electrical as el
    m = mt.System("s")
    for name in ("add", "connect", "equations", "_values"):
        with pytest.raises(mt.errors.ModelError, match="method or attribute"):
            m.add(name, el.Resistor())
    m.add("r1", el.Resistor())


def test_a_declaration_hiding_an_inherited_port_names_both():
    from mechatron.library.electrical import OnePort
    with pytest.raises(TypeError, match=r"Shadow: 'p' is declared as a Variable \(variable\) "
                                        r"in Shadow, which would hide the port \(Pin\) 'p' "
                                        r"declared in OnePort"):
        class Shadow(OnePort):
            p = mt.Variable("V", doc="A potential")


def test_a_port_hiding_an_inherited_parameter_and_a_changed_kind_are_refused():
    from mechatron.library.electrical import Pin, Resistor
    with pytest.raises(TypeError, match=r"'R' is declared as a port \(Pin\) in Pinned, "
                                        r"which would hide the Parameter"):
        class Pinned(Resistor):
            R = Pin(doc="A pin called R")
    with pytest.raises(TypeError, match=r"'R' is declared as a Variable .* hide the "
                                        r"Parameter \(parameter\) 'R' declared in Resistor"):
        class Varied(Resistor):
            R = mt.Variable("Ohm", doc="A resistance that varies")


def test_a_parameter_declared_again_with_a_new_default_is_allowed():
    from mechatron.library.electrical import Resistor

    class Big(Resistor):
        R = mt.Parameter("Ohm", default=1e6, doc="Resistance")

    assert type(Big())._declarations["R"].default == 1e6
