"""Thermal components against analytic solutions and the first law."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import thermal as th

SIGMA = 5.670374419e-8
TOL = dict(rtol=1e-10, atol=1e-10)


def rc_network(element, C=10.0, T0=400.0, Ta=300.0):
    """Heat capacitor (T0) -> element -> fixed temperature Ta."""
    m = mt.System("rc")
    c = m.add("c", th.HeatCapacitor(C=C, T=T0))
    e = m.add("e", element)
    f = m.add("amb", th.FixedTemperature(T=Ta))
    m.connect(c.port, e.A)
    m.connect(e.B, f.port)
    return m


@pytest.mark.parametrize("element, G", [
    (th.ThermalConductor(G=2.0), 2.0),
    (th.ThermalResistor(R=0.25), 4.0),
    (th.ConvectiveHeatTransfer(h=25.0, area=0.04), 1.0),
])
def test_rc_network_decays_with_time_constant_C_over_G(element, G):
    C, T0, Ta = 10.0, 400.0, 300.0
    t = np.linspace(0, 3 * C / G, 7)
    res = mt.simulate(rc_network(element, C, T0, Ta), t[-1], t_out=t, **TOL)
    np.testing.assert_allclose(res["c.T"], Ta + (T0 - Ta) * np.exp(-G * t / C), rtol=1e-8)
    # heat flow from A to B through the element is G dT, and leaves the capacitor
    np.testing.assert_allclose(res["e.Q"], G * (res["c.T"] - Ta), rtol=1e-8)
    np.testing.assert_allclose(res["c.port.Q"], -res["e.Q"], rtol=1e-12)


def test_controlled_convection_takes_its_conductance_from_a_signal():
    m = rc_network(th.ControlledConvectiveHeatTransfer())
    k = m.add("gc", blocks.Constant(value=5.0))
    m.connect(k.y, m.e.Gc)
    t = np.linspace(0, 4, 5)
    res = mt.simulate(m, 4.0, t_out=t, **TOL)
    np.testing.assert_allclose(res["c.T"], 300 + 100 * np.exp(-0.5 * t), rtol=1e-8)


def test_radiation_to_ambient_settles_at_the_radiative_equilibrium():
    """Q_in = sigma Gr (T^4 - Ta^4) at equilibrium."""
    Q, Gr, Ta, C = 50.0, 0.02, 300.0, 5.0
    m = mt.System("rad")
    s = m.add("src", th.HeatFlowSource(Q_flow=Q))
    c = m.add("c", th.HeatCapacitor(C=C, T=Ta))
    r = m.add("r", th.BodyRadiation(Gr=Gr))
    a = m.add("amb", th.FixedTemperature(T=Ta))
    m.connect(s.port, c.port, r.A)
    m.connect(r.B, a.port)
    res = mt.simulate(m, 500.0, **TOL)
    T_eq = (Ta ** 4 + Q / (SIGMA * Gr)) ** 0.25
    assert res.final("c.T") == pytest.approx(T_eq, rel=1e-7)
    # the radiated heat obeys Stefan-Boltzmann at every instant
    np.testing.assert_allclose(res["r.Q"], SIGMA * Gr * (res["c.T"] ** 4 - Ta ** 4),
                               rtol=1e-10, atol=1e-12)
    # at the start the mass warms at Q/C (nothing radiated yet)
    assert res["r.Q"][0] == pytest.approx(0.0, abs=1e-9)


def test_heat_flow_sources_warm_a_mass_at_Q_over_C():
    m = mt.System("heat")
    s = m.add("src", th.HeatFlowSource(Q_flow=30.0))
    ps = m.add("psrc", th.PrescribedHeatFlow())
    ramp = m.add("ramp", blocks.Ramp(slope=2.0))
    c = m.add("c", th.HeatCapacitor(C=6.0, T=300.0))
    m.connect(ramp.y, ps.Q_in)
    m.connect(s.port, ps.port, c.port)
    t = np.linspace(0, 3, 7)
    res = mt.simulate(m, 3.0, t_out=t, **TOL)
    # C dT/dt = 30 + 2 t
    np.testing.assert_allclose(res["c.T"], 300 + (30 * t + t ** 2) / 6.0, rtol=1e-10)


def test_prescribed_temperature_drives_a_first_order_lag_exactly():
    """T' = (Ts(t) - T)/tau with Ts = a t: T = a (t - tau (1 - exp(-t/tau)))."""
    C, G, a = 4.0, 2.0, 3.0
    tau = C / G
    m = mt.System("lag")
    ramp = m.add("ramp", blocks.Ramp(slope=a))
    src = m.add("src", th.PrescribedTemperature())
    g = m.add("g", th.ThermalConductor(G=G))
    c = m.add("c", th.HeatCapacitor(C=C, T=0.0))
    m.connect(ramp.y, src.T_in)
    m.connect(src.port, g.A)
    m.connect(g.B, c.port)
    t = np.linspace(0, 6, 13)
    res = mt.simulate(m, 6.0, t_out=t, **TOL)
    np.testing.assert_allclose(res["c.T"], a * (t - tau * (1 - np.exp(-t / tau))),
                               rtol=1e-8, atol=1e-9)


def test_sensors_read_without_disturbing_the_network():
    C, G, T0, Ta = 10.0, 2.0, 400.0, 300.0
    m = mt.System("sensed")
    c = m.add("c", th.HeatCapacitor(C=C, T=T0))
    hs = m.add("qs", th.HeatFlowSensor())
    g = m.add("g", th.ThermalConductor(G=G))
    f = m.add("amb", th.FixedTemperature(T=Ta))
    ts = m.add("ts", th.TemperatureSensor())
    rs = m.add("rs", th.RelativeTemperatureSensor())
    m.connect(c.port, hs.A, ts.port, rs.A)
    m.connect(hs.B, g.A)
    m.connect(g.B, f.port, rs.B)
    t = np.linspace(0, 10, 6)
    res = mt.simulate(m, 10.0, t_out=t, **TOL)
    T = Ta + (T0 - Ta) * np.exp(-G * t / C)
    np.testing.assert_allclose(res["ts.T"], T, rtol=1e-8)
    np.testing.assert_allclose(res["rs.T_rel"], T - Ta, rtol=1e-7)
    np.testing.assert_allclose(res["qs.Q_flow"], G * (T - Ta), rtol=1e-7)


def test_thermal_reference_is_absolute_zero():
    """A mass cooled through G towards the reference: T = T0 exp(-G t/C)."""
    m = mt.System("to_zero")
    c = m.add("c", th.HeatCapacitor(C=1.0, T=100.0))
    g = m.add("g", th.ThermalConductor(G=0.5))
    z = m.add("z", th.ThermalReference())
    m.connect(c.port, g.A)
    m.connect(g.B, z.port)
    t = np.linspace(0, 4, 5)
    res = mt.simulate(m, 4.0, t_out=t, **TOL)
    np.testing.assert_allclose(res["c.T"], 100 * np.exp(-0.5 * t), rtol=1e-8)


class HeatMeter(th.TwoPort):
    """Test-only series meter integrating the heat passed from A to B: ``dE/dt = Q``."""

    E = mt.Variable("J", start=0.0, doc="Heat passed from A to B")

    def equations(self):
        return [self.dT == 0, mt.der(self.E) == self.Q]


def test_first_law_heat_in_equals_heat_stored_plus_heat_rejected():
    """Pulsating heater -> mass 1 -> conductor -> mass 2 -> convection + radiation to
    ambient: the integrated heater input equals the internal energy change of both masses
    plus the heat that reached ambient, to 1e-6."""
    C1, C2, T0, Ta = 50.0, 80.0, 300.0, 290.0
    m = mt.System("first_law")
    sine = m.add("sine", blocks.Sine(amplitude=40.0, offset=60.0, f=0.01))
    src = m.add("src", th.PrescribedHeatFlow())
    e_in = m.add("e_in", HeatMeter())
    c1 = m.add("c1", th.HeatCapacitor(C=C1, T=T0))
    g = m.add("g", th.ThermalConductor(G=3.0))
    c2 = m.add("c2", th.HeatCapacitor(C=C2, T=T0))
    conv = m.add("conv", th.ConvectiveHeatTransfer(h=15.0, area=0.1))
    rad = m.add("rad", th.BodyRadiation(Gr=0.05))
    e_out = m.add("e_out", HeatMeter())
    amb = m.add("amb", th.FixedTemperature(T=Ta))
    m.connect(sine.y, src.Q_in)
    m.connect(src.port, e_in.A)
    m.connect(e_in.B, c1.port, g.A)
    m.connect(g.B, c2.port, conv.A, rad.A)
    m.connect(conv.B, rad.B, e_out.A)
    m.connect(e_out.B, amb.port)
    res = mt.simulate(m, 300.0, **TOL)
    heat_in = res.final("e_in.E")
    stored = C1 * (res.final("c1.T") - T0) + C2 * (res.final("c2.T") - T0)
    rejected = res.final("e_out.E")
    assert heat_in > 1e4 and stored > 0 and rejected > 0
    assert stored + rejected == pytest.approx(heat_in, rel=1e-6)
