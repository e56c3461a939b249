"""Connection sets turned into aliases and flow sums (`compiler/flatten.py`,
`_physical_set`): each member's variable is the one of its own port, whatever the
connector classes of the set's members."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.core import Across, Component, Connector, Through
from mechatron.core.domains import ELECTRICAL
from mechatron.library import electrical as el


class ThroughFirstPin(Connector, domain=ELECTRICAL):
    """An electrical pin declaring its current before its potential (the same across
    variables as `Pin`, so the two connect)."""

    i = Through("A", doc="Current flowing into the pin")
    v = Across("V", doc="Electric potential at the pin")


class ThroughFirstResistor(Component):
    """A resistor whose pins are `ThroughFirstPin`."""

    p = ThroughFirstPin(doc="Positive pin")
    n = ThroughFirstPin(doc="Negative pin")
    R = mt.Parameter("Ohm", default=1.0, doc="Resistance")

    def equations(self):
        return [self.p.v - self.n.v == self.R * self.p.i, self.p.i + self.n.i == 0]


def rc(three_member_node: bool):
    """A source charging a capacitor through the resistor of the other pin class; with
    ``three_member_node`` its n pin joins a node of three members (a flow sum)."""
    m = mt.System("rc_mixed_pins")
    src = m.add("src", el.DCVoltageSource(V=3.0))
    g = m.add("g", el.ElectricalReference())
    r = m.add("r", ThroughFirstResistor(R=2.0))
    c = m.add("c", el.Capacitor(C=0.5))
    m.connect(src.p, r.p)
    if three_member_node:
        c2 = m.add("c2", el.Capacitor(C=0.5))
        m.connect(r.n, c.p, c2.p)
        m.connect(c2.n, g.port)
    else:
        m.connect(r.n, c.p)
    m.connect(c.n, src.n, g.port)
    return m


@pytest.mark.parametrize("three_member_node", [False, True])
def test_ports_of_two_connector_classes_connect_variable_by_variable(three_member_node):
    """v_c(t) = V (1 - exp(-t / (R C_total))) for a capacitor charged from rest."""
    V, R = 3.0, 2.0
    C = 1.0 if three_member_node else 0.5
    res = mt.simulate(rc(three_member_node), t_stop=2.0, t_out=np.linspace(0, 2, 5),
                      rtol=1e-9, atol=1e-12)
    t = np.asarray(res.t)
    expected = V * (1 - np.exp(-t / (R * C)))
    np.testing.assert_allclose(res["c.v"], expected, rtol=1e-5, atol=1e-7)
    # the current through the resistor is the capacitors' charging current
    np.testing.assert_allclose(res["r.p.i"], V / R * np.exp(-t / (R * C)),
                               rtol=1e-5, atol=1e-7)


class Wrapped(mt.Component):
    """A library resistor behind pins of the other class: each of its nodes joins a
    `ThroughFirstPin` with `Pin`s, inside and outside."""

    p = ThroughFirstPin(doc="Positive pin")
    n = ThroughFirstPin(doc="Negative pin")
    r = el.Resistor(R=2.0)

    def equations(self):
        return [mt.connect(self.p, self.r.p), mt.connect(self.r.n, self.n)]


def test_a_subsystem_port_of_another_connector_class_carries_its_own_variables():
    """The logged potential and current of each port are its own: the source voltage and
    the charging current at w.p, the capacitor voltage and the current back at w.n."""
    V, R, C = 3.0, 2.0, 0.5
    m = mt.System("wrapped")
    src = m.add("src", el.DCVoltageSource(V=V))
    g = m.add("g", el.ElectricalReference())
    w = m.add("w", Wrapped())
    c = m.add("c", el.Capacitor(C=C))
    m.connect(src.p, w.p)
    m.connect(w.n, c.p)
    m.connect(c.n, src.n, g.port)
    res = mt.simulate(m, 2.0, t_out=np.linspace(0, 2, 5), rtol=1e-9, atol=1e-12,
                      log="all")
    t = np.asarray(res.t)
    v_c = V * (1 - np.exp(-t / (R * C)))
    current = (V - v_c) / R
    np.testing.assert_allclose(res["c.v"], v_c, rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(res["w.p.v"], V, rtol=1e-12)
    np.testing.assert_allclose(res["w.p.i"], current, rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(res["w.n.v"], v_c, rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(res["w.n.i"], -current, rtol=1e-5, atol=1e-7)


def test_a_connect_of_something_not_a_port_is_named_and_its_port_left_open():
    """A connect is taken as written when it joins ports; anything else is resolved to a
    port or signal, and what is neither is reported with what to pass instead, beside
    the port it left unconnected."""
    m = mt.System("bad")
    r = m.add("r", el.Resistor(R=1.0))
    g = m.add("g", el.ElectricalReference())
    m.connect(r.p, g.port)
    m.connect(r.n, 3.0)
    with pytest.raises(mt.errors.ModelError) as err:
        mt.compile_model(m)
    assert "bad: connect() takes ports, got 3.0. Pass a port such as r1.p" in str(err.value)
    assert "port 'r.n' (electrical) is not connected" in str(err.value)
