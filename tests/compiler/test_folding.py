"""Subsystem ports folded into the nodes they join (mechatron.compiler.folding): the same
model, names, states and logged values as with every port written out as unknowns, on
hierarchies two and three levels deep, the database's subsystem models, open ports, a
port read by an equation, and a loop of ports that cannot be folded."""

import numpy as np
import pytest

import mechatron as mt
import mechatron.compiler.flatten as fl
from mechatron.compiler.flatten import flatten
from mechatron.library import electrical as el
from mechatron.library import electromechanical as em
from mechatron.library import rotational as rot
from mechatron.library.electrical.interfaces import OnePort
from tests.compiler.test_hierarchy import Pair, Stage


def unfolded(monkeypatch, build):
    """``build()`` compiled with no port folded (every port variable an unknown)."""
    with monkeypatch.context() as m:
        m.setattr(fl, "plan_subsystems", lambda model, elements: ({}, {}))
        return mt.compile_model(build())


def deep_ladder():
    m = mt.System("deep")
    src = m.add("src", el.DCVoltageSource(V=2.0))
    g = m.add("g", el.ElectricalReference())
    a = m.add("a", Pair(R=1.0, C=1.0))
    b = m.add("b", Pair(R=0.5, C=2.0))
    m.connect(src.p, a.p)
    m.connect(a.n, b.p)
    m.connect(b.gnd, g.port, a.gnd, src.n)     # drawn in another order
    return m


class Drive(mt.Component):
    """A DC motor with its rotor inertia: pins, a shaft and a support, wired inside."""

    p = el.Pin()
    n = el.Pin()
    flange = rot.Flange()
    support = rot.Flange()
    R = el.Resistor(R=0.5)
    L = el.Inductor(L=1e-2)
    emf = em.RotationalEMF(k=0.1)
    J = rot.Inertia(J=1e-3)

    def equations(self):
        return [mt.connect(self.p, self.R.p), mt.connect(self.R.n, self.L.p),
                mt.connect(self.L.n, self.emf.p), mt.connect(self.emf.n, self.n),
                mt.connect(self.emf.A, self.J.port, self.flange),
                mt.connect(self.emf.B, self.support)]


def two_drives():
    m = mt.System("two_drives")
    src = m.add("src", el.DCVoltageSource(V=12.0))
    g = m.add("g", el.ElectricalReference())
    fixed = m.add("fixed", rot.RotationalReference())
    d1 = m.add("d1", Drive())
    d2 = m.add("d2", Drive())
    spring = m.add("k", rot.RotationalSpring(k=20.0))
    load = m.add("load", rot.RotationalDamper(D=0.01))
    m.connect(src.p, d1.p, d2.p)
    m.connect(d1.n, d2.n, src.n, g.port)
    m.connect(d1.flange, spring.A)
    m.connect(spring.B, d2.flange, load.A)      # d2's flange: a port of three members
    m.connect(load.B, fixed.port, d1.support, d2.support)
    return m


def assert_same(folded, plain, t_end, tol=1e-9, **options):
    """The same names, units, states and flat counts, and every logged value within
    ``tol`` of its signal's scale, integrated with ``options``."""
    assert folded.names == plain.names
    assert folded.units == plain.units
    assert sorted(folded.state_names) == sorted(plain.state_names)
    for key in ("variables", "equations"):
        # as many in the flat model; after alias elimination, folding leaves at most as
        # many (a port's through variable in a sum of three or more is gone with it)
        assert folded.report[key]["flat"] == plain.report[key]["flat"]
        assert folded.report[key]["after_alias"] <= plain.report[key]["after_alias"]
    options = {"rtol": 1e-10, "atol": 1e-12, **options}
    a = mt.simulate(folded, t_end, log="all", **options)
    b = mt.simulate(plain, t_end, log="all", **options)
    np.testing.assert_allclose(a.t, b.t)
    for name in plain.names:
        scale = max(1.0, float(np.max(np.abs(b[name]))))
        np.testing.assert_allclose(a[name], b[name], rtol=0, atol=tol * scale,
                                   err_msg=name)


@pytest.mark.parametrize("build,t_end", [(deep_ladder, 5.0), (two_drives, 0.2)],
                         ids=["three_levels", "drive_used_twice"])
def test_folded_ports_give_the_model_of_the_written_out_ports(build, t_end, monkeypatch):
    flat = flatten(build())
    assert flat.folded, "nothing was folded"
    # no variable of a folded port is an unknown of the flat model
    for path in flat.folded.ports:
        assert not [n for n in flat.variables if n.startswith(path + ".")]
    assert_same(mt.compile_model(build()), unfolded(monkeypatch, build), t_end)


@pytest.mark.parametrize("name,variant", [("two_axis", "acausal"), ("bldc_motor", None),
                                          ("two_axis", "inputs")])
def test_database_subsystem_models_are_unchanged_by_folding(name, variant, monkeypatch):
    """The ``inputs`` variant of two_axis connects a brake to ``axis.load.port``, a part
    inside each axis: those axes are then wired connect by connect."""
    entry = mt.models.get(name)
    kwargs = {"variant": variant} if variant else {}

    def build():
        return entry.build(**kwargs)

    assert bool(flatten(build()).folded) == (variant != "inputs")
    assert_same(mt.compile_model(build()), unfolded(monkeypatch, build),
                min(entry.experiment.t_stop, 0.05), solver=entry.experiment.solver)


class TimedStage(Stage):
    """A stage whose class writes equations (none beyond its parent's connects) and
    declares a time scale: its time constant."""

    def equations(self):
        return []

    def time_scales(self):
        return [self.R * self.C]


def timed_stages():
    m = mt.System("timed")
    src = m.add("src", el.DCVoltageSource(V=1.0))
    g = m.add("g", el.ElectricalReference())
    a = m.add("a", TimedStage(R=1.0, C=2.0))
    b = m.add("b", TimedStage(R=3.0, C=0.5))
    c = m.add("c", Stage(R=1.0, C=1.0))       # no time scale of its own
    m.connect(src.p, a.p)
    m.connect(a.n, b.p)
    m.connect(b.n, c.p)
    m.connect(src.n, g.port, a.gnd, b.gnd, c.gnd)
    return m


def test_a_planned_subsystem_keeps_the_time_scales_its_class_declares(monkeypatch):
    """Each instance's time scales, read as when its ports are written out: variable-step
    solvers keep their steps below half the smallest."""
    assert {"a.p", "b.p", "c.p"} <= set(flatten(timed_stages()).folded.ports)
    folded = mt.compile_model(timed_stages())
    plain = unfolded(monkeypatch, timed_stages)
    got = np.asarray(folded.f_scales(folded.p0)).ravel()
    np.testing.assert_allclose(sorted(got), [1.5, 2.0], rtol=1e-15)
    np.testing.assert_array_equal(got, np.asarray(plain.f_scales(plain.p0)).ravel())


def test_port_flows_balance_across_the_folded_node():
    res = mt.simulate(two_drives(), 0.2, log="all", rtol=1e-10, atol=1e-12)
    # what flows into a drive's pin flows on through its resistor; at the shared shaft
    # node the torques of spring, drive and load sum to zero
    np.testing.assert_allclose(res["d1.p.i"], res["d1.R.i"], atol=1e-12)
    np.testing.assert_allclose(res["d1.n.i"], -res["d1.R.i"], atol=1e-12)
    np.testing.assert_allclose(res["k.B.tau"] + res["d2.flange.tau"] + res["load.A.tau"],
                               0.0, atol=1e-9)
    np.testing.assert_allclose(res["d2.flange.w"], res["load.A.w"], atol=1e-12)


def test_an_open_port_of_a_folded_subsystem_carries_nothing(monkeypatch):
    def build():
        m = mt.System("open")
        src = m.add("src", el.DCVoltageSource(V=1.0))
        g = m.add("g", el.ElectricalReference())
        s = m.add("s", Stage())
        m.connect(src.p, s.p)
        m.connect(src.n, g.port, s.gnd)
        return m                            # s.n open

    res = mt.simulate(build(), 1.0, log="all")
    np.testing.assert_allclose(res["s.n.i"], 0.0, atol=1e-15)
    np.testing.assert_allclose(res["s.n.v"], res["s.c.v"], atol=1e-15)
    assert_same(mt.compile_model(build()), unfolded(monkeypatch, build), 1.0)


class Branch(OnePort):
    """A two-pin branch whose voltage the model's equations give."""


def reading_model():
    """A stage fed through a source that follows half the stage's input voltage: an
    equation of the model reads the stage's pin."""
    m = mt.System("read")
    src = m.add("src", el.DCVoltageSource(V=1.0))
    g = m.add("g", el.ElectricalReference())
    b = m.add("b", Branch())
    s = m.add("s", Stage())
    probe = m.add("probe", el.Resistor(R=1e3))
    m.connect(src.p, b.p)
    m.connect(b.n, s.p)
    m.connect(s.n, probe.p)
    m.connect(src.n, g.port, s.gnd, probe.n)
    m.add_equation(lambda: b.v == 0.5 * s.p.v)     # reads the stage's pin
    return m


def test_a_port_read_by_an_equation_is_written_out(monkeypatch):
    flat = flatten(reading_model())
    folded = set(flat.folded.ports)
    assert "s.p" not in folded and {"s.n", "s.gnd"} <= folded
    # in its place of declaration, as if never folded
    names = list(flat.variables)
    assert names.index("s.p.v") < names.index("s.r.v")
    cm = mt.compile_model(reading_model())
    assert_same(cm, unfolded(monkeypatch, reading_model), 1.0)
    res = mt.simulate(cm, 1.0)
    np.testing.assert_allclose(res["s.p.v"], 1.0 / 1.5, rtol=1e-12)


class Short(mt.Component):
    """A wire between its two pins: a node of folded ports alone."""

    p = el.Pin()
    n = el.Pin()
    r = el.Resistor(R=1.0)          # a part, so that it is a subsystem

    def equations(self):
        return [mt.connect(self.p, self.n, self.r.p), mt.connect(self.r.n, self.n)]


def test_a_loop_of_ports_is_flattened_as_before(monkeypatch):
    def build():
        m = mt.System("loop")
        src = m.add("src", el.DCVoltageSource(V=1.0))
        g = m.add("g", el.ElectricalReference())
        w = m.add("w", Short())
        load = m.add("load", el.Resistor(R=2.0))
        m.connect(src.p, w.p, w.n, load.p)      # both pins on one outside node: a loop
        m.connect(src.n, g.port, load.n)
        return m

    flat = flatten(build())
    assert not flat.folded and "w.p.i" in flat.variables
    errors = []
    for compile_ in (lambda: mt.compile_model(build()),
                     lambda: unfolded(monkeypatch, build)):
        try:
            compile_()
            errors.append(None)
        except Exception as exc:   # noqa: BLE001 - both ways must end alike
            errors.append((type(exc), str(exc)))
    assert errors[0] == errors[1]


class SeriesSources(mt.Component):
    """Two current sources in series with a capacitor between them: a cut set of
    sources once the subsystem's pins close the loop through a resistor."""

    p = el.Pin()
    n = el.Pin()
    i1 = el.DCCurrentSource(I=1.0)
    i2 = el.DCCurrentSource(I=1.0)
    c = el.Capacitor(C=1.0)

    def equations(self):
        return [mt.connect(self.p, self.i1.p), mt.connect(self.i1.n, self.c.p),
                mt.connect(self.c.n, self.i2.p), mt.connect(self.i2.n, self.n)]


def test_a_singular_network_inside_a_planned_subsystem_is_named_in_physical_terms():
    m = mt.System("ii")
    s = m.add("s", SeriesSources())
    r = m.add("r", el.Resistor(R=1.0))
    g = m.add("g", el.ElectricalReference())
    m.connect(g.port, s.p, r.n)
    m.connect(s.n, r.p)
    assert flatten(m).folded
    with pytest.raises(mt.errors.StructuralError,
                       match=r"sources s\.i1 and s\.i2 form a cut set: their currents are "
                             r"not independent"):
        mt.compile_model(m)


def test_an_instance_with_attributes_of_its_own_is_written_out(monkeypatch):
    """A plan is read off the first instance of a class that has nothing beyond its
    declarations; an instance with an attribute of its own (here the first and the last
    of three) may connect differently, so its ports are written out, before and after
    the plan is made."""
    def build():
        m = mt.System("marked")
        src = m.add("src", el.DCVoltageSource(V=1.0))
        g = m.add("g", el.ElectricalReference())
        stages = [m.add(f"s{k}", Stage(R=1.0 + k, C=0.5)) for k in range(3)]
        stages[0].note = "spare"
        stages[2].note = "spare"
        node = src.p
        for s in stages:
            m.connect(node, s.p)
            m.connect(s.gnd, g.port)
            node = s.n
        m.connect(src.n, g.port)
        return m

    assert sorted(flatten(build()).folded.ports) == ["s1.gnd", "s1.n", "s1.p"]
    assert_same(mt.compile_model(build()), unfolded(monkeypatch, build), 2.0)
