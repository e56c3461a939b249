"""Physical signals: math with units, converters, and the unit check on connections."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.errors import UnitError
from mechatron.library import blocks
from mechatron.library import electrical as el
from mechatron.library import physical_signals as ps
from mechatron.library import rotational as rot
from mechatron.library import thermal as th

TOL = dict(rtol=1e-10, atol=1e-12)


def resistor_driven_by(block, R=2.0):
    """block.y -> controlled voltage source -> resistor R."""
    m = mt.System("drive")
    b = m.add("b", block)
    src = m.add("src", el.ControlledVoltageSource())
    r = m.add("r", el.Resistor(R=R))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, r.p)
    m.connect(r.n, src.n, g.port)
    return m, b, src


def test_signal_to_physical_scales_the_signal_to_SI():
    m, conv, src = resistor_driven_by(ps.SignalToPhysical(unit="mV"))
    k = m.add("k", blocks.Constant(value=500.0))
    m.connect(k.y, conv.u)
    m.connect(conv.y, src.u)
    res = mt.simulate(m, 1e-3, **TOL)
    assert res.final("r.v") == pytest.approx(0.5, rel=1e-14)
    assert res.final("r.i") == pytest.approx(0.25, rel=1e-14)


def test_a_unit_mismatch_across_a_signal_connection_is_an_error():
    m, conv, src = resistor_driven_by(ps.SignalToPhysical(unit="A"))
    k = m.add("k", blocks.Constant(value=1.0))
    m.connect(k.y, conv.u)
    m.connect(conv.y, src.u)
    with pytest.raises(UnitError, match=r"'b\.y' \(A\) to 'src\.u' \(V\).*dimension"):
        mt.compile_model(m)


def test_physical_signal_math_rejects_mixed_units():
    m = mt.System("mixed")
    a = m.add("a", ps.PSConstant(unit="N", value=2.0))
    v = m.add("v", ps.PSConstant(unit="V", value=1.0))
    add = m.add("plus", ps.PSAdd(unit="N"))
    out = m.add("out", ps.PhysicalToSignal(unit="N"))
    m.connect(a.y, add.u1)
    m.connect(v.y, add.u2)
    m.connect(add.y, out.u)
    with pytest.raises(UnitError, match=r"'v\.y' \(V\) to 'plus\.u2' \(N\)"):
        mt.compile_model(m)


def test_physical_to_signal_reads_rad_per_s_as_rpm_and_checks_the_dimension():
    m = mt.System("rpm")
    tq = m.add("tq", blocks.Constant(value=0.5))
    src = m.add("src", rot.IdealTorqueSource())
    j = m.add("j", rot.Inertia(J=0.1, w=0.0))
    ground = m.add("ground", rot.RotationalReference())
    sensor = m.add("sensor", rot.AngularVelocitySensor())
    rpm = m.add("rpm", ps.PhysicalToSignal(unit="rpm"))
    m.connect(tq.y, src.tau_in)
    m.connect(src.A, j.port, sensor.A)
    m.connect(src.B, sensor.B, ground.port)
    m.connect(sensor.W, rpm.u)
    t = np.linspace(0, 2, 5)
    res = mt.simulate(m, 2.0, t_out=t, **TOL)
    np.testing.assert_allclose(res["rpm.y"], 5.0 * t * 60 / (2 * np.pi), rtol=1e-10)
    bad = m.add("bad", ps.PhysicalToSignal(unit="A"))
    m.connect(sensor.W, bad.u)
    with pytest.raises(UnitError, match=r"sensor\.W.*bad\.u"):
        mt.compile_model(m)


def test_offset_units_and_bad_unit_keywords_are_rejected():
    with pytest.raises(UnitError, match="degC.*offset"):
        ps.SignalToPhysical(unit="degC")
    with pytest.raises(UnitError, match="unknown unit"):
        ps.PSAdd(unit="furlongs per blorp")
    with pytest.raises(TypeError, match="unit must be a string"):
        ps.PSAdd(unit=5)
    with pytest.raises(TypeError, match="unexpected keyword 'units'"):
        ps.PSAdd(units="N")


def test_gain_takes_a_quantity_in_unit_out_per_unit_in():
    m = mt.System("gain")
    c = m.add("c", ps.PSConstant(unit="A", value=4.0))
    g = m.add("g", ps.PSGain(unit_in="A", unit_out="N", K="2.5 N/A"))
    out = m.add("out", ps.PhysicalToSignal(unit="kN"))
    m.connect(c.y, g.u)
    m.connect(g.y, out.u)
    res = mt.simulate(m, 1e-3, **TOL)
    assert res.final("g.y") == pytest.approx(10.0, rel=1e-15)
    assert res.final("out.y") == pytest.approx(0.01, rel=1e-15)
    bad = ps.PSGain(unit_in="A", unit_out="N", K="2 V")
    m2 = mt.System("bad_gain")
    m2.add("c", ps.PSConstant(unit="A"))
    m2.add("g", bad)
    m2.connect(m2.c.y, m2.g.u)
    with pytest.raises(UnitError, match=r"g\.K"):
        mt.compile_model(m2)


def test_units_of_derived_outputs():
    def unit(block, name):
        return mt.units.dimensionality(type(block)._declarations[name].unit)

    assert unit(ps.PSProduct(unit1="V", unit2="A"), "y") == mt.units.dimensionality("W")
    assert unit(ps.PSIntegrator(unit="A"), "y") == mt.units.dimensionality("C")
    assert unit(ps.PSGain(unit_in="m", unit_out="N"), "K") == mt.units.dimensionality("N/m")
    assert unit(ps.PSGain(unit_in="V"), "y") == mt.units.dimensionality("V")
    # one specialised class per unit set, with the base's name
    assert type(ps.PSAdd(unit="N")) is type(ps.PSAdd(unit="N"))
    assert type(ps.PSAdd(unit="N")).__name__ == "PSAdd"
    assert isinstance(ps.PSAdd(unit="N"), ps.PSAdd)


def test_add_subtract_product_saturation_integrator():
    m = mt.System("math")
    sine = m.add("sine", blocks.Sine(amplitude=3.0, f=1.0))
    s2p = m.add("s2p", ps.SignalToPhysical(unit="N"))
    c = m.add("c", ps.PSConstant(unit="N", value=0.5))
    add = m.add("plus", ps.PSAdd(unit="N"))
    sub = m.add("minus", ps.PSSubtract(unit="N"))
    prod = m.add("prod", ps.PSProduct(unit1="N", unit2="N"))
    sat = m.add("sat", ps.PSSaturation(unit="N", upper=2.0, lower=-1.0))
    integ = m.add("int", ps.PSIntegrator(unit="N", y=0.25))
    m.connect(sine.y, s2p.u)
    m.connect(s2p.y, add.u1, sub.u1, prod.u1, sat.u, integ.u)
    m.connect(c.y, add.u2, sub.u2, prod.u2)
    t = np.linspace(0, 1, 41)
    res = mt.simulate(m, 1.0, t_out=t, **TOL)
    u = 3.0 * np.sin(2 * np.pi * t)
    np.testing.assert_allclose(res["plus.y"], u + 0.5, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res["minus.y"], u - 0.5, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res["prod.y"], 0.5 * u, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res["sat.y"], np.clip(u, -1.0, 2.0), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res["int.y"], 0.25 + 3.0 * (1 - np.cos(2 * np.pi * t))
                               / (2 * np.pi), rtol=1e-8, atol=1e-9)


def test_electrical_power_as_a_physical_signal_heats_a_thermal_mass():
    """v (V) * i (A) -> W -> prescribed heat flow: Joule heating, T = T0 + V^2/R t / C."""
    V, R, C, T0 = 12.0, 6.0, 40.0, 300.0
    m = mt.System("joule")
    src = m.add("src", el.DCVoltageSource(V=V))
    r = m.add("r", el.Resistor(R=R))
    am = m.add("am", el.CurrentSensor())
    vm = m.add("vm", el.VoltageSensor())
    g = m.add("g", el.ElectricalReference())
    p = m.add("p", ps.PSProduct(unit1="V", unit2="A"))
    heat = m.add("heat", th.PrescribedHeatFlow())
    mass = m.add("mass", th.HeatCapacitor(C=C, T=T0))
    m.connect(src.p, am.p)
    m.connect(am.n, r.p, vm.p)
    m.connect(r.n, vm.n, src.n, g.port)
    m.connect(vm.V, p.u1)
    m.connect(am.I, p.u2)
    m.connect(p.y, heat.Q_in)
    m.connect(heat.port, mass.port)
    t = np.linspace(0, 10, 6)
    res = mt.simulate(m, 10.0, t_out=t, **TOL)
    np.testing.assert_allclose(res["mass.T"], T0 + V ** 2 / R * t / C, rtol=1e-12)
    # the product's unit is W; feeding it into a temperature input is refused
    bad = m.add("bad", th.PrescribedTemperature())
    m.connect(p.y, bad.T_in)
    m.connect(bad.port, mass.port)
    with pytest.raises(UnitError, match=r"p\.y.*bad\.T_in"):
        mt.compile_model(m)
