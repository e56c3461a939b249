"""Every error path: the exception type and a message naming the instance paths."""

import pytest

import mechatron as mt
from mechatron.errors import (ConnectError, ModelError, ParameterError, StructuralError,
                              UnitError)
from mechatron.library import electrical as el
from mechatron.library import rotational as rot


def rc(ground=True):
    m = mt.System("rc")
    src = m.add("src", el.DCVoltageSource(V=1.0))
    r1 = m.add("r1", el.Resistor(R=1.0))
    c1 = m.add("c1", el.Capacitor(C=1.0))
    m.connect(src.p, r1.p)
    m.connect(r1.n, c1.p)
    if ground:
        g = m.add("g", el.ElectricalReference())
        m.connect(src.n, c1.n, g.port)
    else:
        m.connect(src.n, c1.n)
    return m


def test_network_without_reference():
    with pytest.raises(ModelError, match=r"electrical network of c1, r1, src has no "
                                         r"reference.*ElectricalReference|reference missing"):
        mt.compile_model(rc(ground=False))


def _networks(order):
    """A grounded RC circuit; a loop of a source, a resistor and a converter's pins with
    no electrical reference, the converter's frame held by a rotational reference; a
    loop of a source and a resistor alone. Parts are added in ``order``."""
    from mechatron.library import electromechanical as em

    m = mt.System("nets")
    parts = {"src": el.DCVoltageSource(V=1.0), "r1": el.Resistor(R=1.0),
             "c1": el.Capacitor(C=1.0), "g": el.ElectricalReference(),
             "src2": el.DCVoltageSource(V=2.0), "r2": el.Resistor(R=2.0),
             "emf": em.RotationalEMF(k=0.5), "j": rot.Inertia(J=1.0),
             "frame": rot.RotationalReference(),
             "src3": el.DCVoltageSource(V=3.0), "r3": el.Resistor(R=3.0)}
    p = {name: m.add(name, parts[name]) for name in order}
    m.connect(p["src"].p, p["r1"].p)
    m.connect(p["r1"].n, p["c1"].p)
    m.connect(p["src"].n, p["c1"].n, p["g"].port)
    m.connect(p["src2"].p, p["r2"].p)
    m.connect(p["r2"].n, p["emf"].p)
    m.connect(p["emf"].n, p["src2"].n)
    m.connect(p["emf"].A, p["j"].port)
    m.connect(p["emf"].B, p["frame"].port)
    m.connect(p["src3"].p, p["r3"].p)
    m.connect(p["r3"].n, p["src3"].n)
    return m


@pytest.mark.parametrize("order", [
    ["src", "r1", "c1", "g", "src2", "r2", "emf", "j", "frame", "src3", "r3"],
    ["r3", "frame", "emf", "r2", "g", "c1", "src3", "src2", "j", "r1", "src"]])
def test_each_network_without_reference_is_named_once(order):
    """Networks are joined through the components whose ports of one domain they meet:
    the converter joins its two pins, and its two flanges, not its pins with its
    flanges, so the rotational reference on its frame does not ground its circuit. The
    circuit with its reference passes; each loop without one is reported once, with
    its own parts only, in the order of its first node, whatever order the parts were
    added in."""
    with pytest.raises(ModelError) as info:
        mt.compile_model(_networks(order))
    found = [p for p in info.value.problems if "has no reference" in p]
    assert len(found) == 2
    assert found[0].startswith("electrical network of emf, r2, src2 has no reference")
    assert found[1].startswith("electrical network of r3, src3 has no reference")


def test_unconnected_port_is_named():
    m = rc()
    m.add("r2", el.Resistor(R=2.0))
    m.connect(m.r2.p, m.r1.n)
    with pytest.raises(ModelError, match=r"port 'r2.n' \(electrical\) is not connected"):
        mt.compile_model(m)


def test_two_voltage_sources_in_parallel_are_overdetermined():
    m = rc()
    v2 = m.add("v2", el.DCVoltageSource(V=2.0))
    m.connect(v2.p, m.src.p)
    m.connect(v2.n, m.src.n)
    with pytest.raises(StructuralError, match=r"equations for .* unknowns.*"
                                              r"Potential extra equation.*(src|v2)") as info:
        mt.compile_model(m)
    assert any("v2" in e or "src" in e for e in info.value.equations)


def test_ports_of_different_domains():
    m = rc()
    j = m.add("j", rot.Inertia(J=1.0))
    m.connect(j.port, m.r1.p)
    with pytest.raises(ConnectError, match=r"cannot connect 'j.port' \(rotational\) with "
                                           r"'r1.p' \(electrical\): ports belong to "
                                           r"different domains"):
        mt.compile_model(m)


def test_mass_given_for_a_resistance():
    m = rc()
    m.r1._values["R"] = "3 kg"
    with pytest.raises(UnitError, match=r"r1.R: expected a value in Ohm.*got 3 kg"):
        mt.compile_model(m)


def test_negative_resistance():
    m = rc()
    m.r1._values["R"] = -5
    with pytest.raises(ParameterError, match=r"Resistor 'r1': R must be >= 0, got -5"):
        mt.compile_model(m)


def test_all_value_problems_are_reported_at_once():
    m = rc()
    m.r1._values["R"] = -1.0
    m.c1._values["C"] = "2 m"
    with pytest.raises(ParameterError) as info:
        mt.compile_model(m)
    assert len(info.value.problems) == 2
    assert "r1" in str(info.value) and "c1.C" in str(info.value)


def test_unknown_keyword_lists_the_valid_names():
    with pytest.raises(TypeError, match=r"Resistor\(\) got an unexpected keyword 'Rr'. "
                                        r"Valid names: R"):
        el.Resistor(Rr=1.0)


def test_underdetermined_names_unmatched_variables_and_hint():
    class Floating(mt.Component):
        x = mt.Variable("m")
        y = mt.Variable("m")

        def equations(self):
            return [self.x == 2 * self.y + 0 * mt.der(self.x) * 0]

    with pytest.raises(StructuralError, match=r"1 equations for 2 unknowns|unknowns"):
        mt.compile_model(Floating())


def test_an_expression_that_is_not_an_equation():
    class Broken(mt.Component):
        x = mt.Variable("m")

        def equations(self):
            return [self.x - 1]

    with pytest.raises(ModelError, match=r"equation 1 of Broken is not an equation.*=="):
        mt.compile_model(Broken())


def test_signal_input_left_unconnected():
    m = mt.System("m")
    m.add("src", el.ControlledVoltageSource())
    m.add("g", el.ElectricalReference())
    m.connect(m.src.p, m.src.n, m.g.port)
    with pytest.raises(ModelError, match=r"signal input 'src.u' is not connected"):
        mt.compile_model(m)


def test_cli_errors_are_one_line(capsys):
    from mechatron.cli import main
    code = main(["simulate", "dc_motor", "--set", "R=3 kg"])
    err = capsys.readouterr().err
    assert code == 2
    assert "Traceback" not in err
    assert err.strip().count("\n") == 0 and "R" in err
