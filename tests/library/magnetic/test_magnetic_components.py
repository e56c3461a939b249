"""Magnetic components against magnetic-circuit theory and energy conservation."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import electrical as el
from mechatron.library import magnetic as mg
from mechatron.library import translational as tr

MU0 = 4e-7 * np.pi
TOL = dict(rtol=1e-10, atol=1e-16)  # fluxes are ~1e-4 Wb


def loop(source, *elements):
    """source.B -> elements in series -> source.A, with a reference at source.A."""
    m = mt.System("magnetic_loop")
    s = m.add("src", source)
    ref = m.add("ref", mg.MagneticReference())
    prev = s.B
    for k, e in enumerate(elements):
        part = m.add(f"e{k}", e)
        m.connect(prev, part.A)
        prev = part.B
    m.connect(prev, s.A, ref.port)
    return m


def test_mmf_source_drives_flux_mmf_over_total_reluctance():
    R1, g, area, mu_r, F = 2e5, 1e-3, 4e-4, 1.0, 150.0
    m = loop(mg.MmfSource(F=F), mg.Reluctance(R=R1), mg.AirGapReluctance(
        g=g, area=area, mu_r=mu_r), mg.FluxSensor())
    res = mt.simulate(m, 1e-3, **TOL)
    R2 = g / (MU0 * mu_r * area)
    assert res.final("e2.Phi") == pytest.approx(F / (R1 + R2), rel=1e-12)
    assert res.final("e0.mmf") == pytest.approx(R1 * F / (R1 + R2), rel=1e-12)
    assert res.final("e1.mmf") == pytest.approx(R2 * F / (R1 + R2), rel=1e-12)
    # an mmf sensor in series carries no flux: the whole loop then carries none
    m = loop(mg.MmfSource(F=F), mg.Reluctance(R=R1), mg.MmfSensor())
    res = mt.simulate(m, 1e-3, **TOL)
    assert res.final("e1.F") == pytest.approx(F, rel=1e-12)
    assert res.final("e0.phi") == pytest.approx(0.0, abs=1e-18)


def test_mmf_sensor_in_parallel_reads_R_phi():
    R, Phi = 3e5, 2e-4
    m = loop(mg.FluxSource(Phi=Phi), mg.Reluctance(R=R))
    s = m.add("sens", mg.MmfSensor())
    m.connect(s.A, m.e0.A)
    m.connect(s.B, m.e0.B)
    res = mt.simulate(m, 1e-3, **TOL)
    assert res.final("sens.F") == pytest.approx(R * Phi, rel=1e-12)
    assert res.final("e0.phi") == pytest.approx(Phi, rel=1e-12)


def test_controlled_sources_follow_their_signals():
    R = 1e5
    m = loop(mg.ControlledFluxSource(), mg.Reluctance(R=R))
    ramp = m.add("ramp", blocks.Ramp(slope=1e-3))
    m.connect(ramp.y, m.src.Phi_in)
    t = np.linspace(0, 1, 5)
    res = mt.simulate(m, 1.0, t_out=t, **TOL)
    np.testing.assert_allclose(res["e0.mmf"], R * 1e-3 * t, rtol=1e-12, atol=1e-12)

    m = loop(mg.ControlledMmfSource(), mg.Reluctance(R=R))
    sine = m.add("sine", blocks.Sine(amplitude=50.0, f=2.0))
    m.connect(sine.y, m.src.F_in)
    res = mt.simulate(m, 1.0, t_out=t, **TOL)
    np.testing.assert_allclose(res["e0.phi"], 50 * np.sin(4 * np.pi * t) / R,
                               rtol=1e-9, atol=1e-14)


def test_variable_air_gap_flux_follows_mu0_A_F_over_g():
    area, F = 2e-4, 100.0
    m = loop(mg.MmfSource(F=F), mg.VariableAirGapReluctance(area=area))
    ramp = m.add("gap", blocks.Ramp(slope=1e-3, initial=0.5e-3))
    m.connect(ramp.y, m.e0.g)
    t = np.linspace(0, 2, 5)
    res = mt.simulate(m, 2.0, t_out=t, **TOL)
    np.testing.assert_allclose(res["e0.phi"], MU0 * area * F / (0.5e-3 + 1e-3 * t),
                               rtol=1e-10)


def test_eddy_current_gives_a_magnetic_time_constant_G_over_R():
    """F = G dphi/dt + R phi: phi = F/R (1 - exp(-R t / G))."""
    R, G, F = 1e4, 50.0, 10.0
    m = loop(mg.MmfSource(F=F), mg.EddyCurrent(G=G), mg.Reluctance(R=R))
    t = np.linspace(0, 3 * G / R, 7)
    res = mt.simulate(m, t[-1], t_out=t, **TOL)
    np.testing.assert_allclose(res["e1.phi"], F / R * (1 - np.exp(-R * t / G)),
                               rtol=1e-8, atol=1e-15)


def coil_circuit(N, R_mag, V=12.0, Rw=4.0):
    m = mt.System("coil")
    src = m.add("src", el.DCVoltageSource(V=V))
    r = m.add("r", el.Resistor(R=Rw))
    coil = m.add("coil", mg.ElectromagneticConverter(N=N))
    core = m.add("core", mg.Reluctance(R=R_mag))
    g = m.add("g", el.ElectricalReference())
    mref = m.add("mref", mg.MagneticReference())
    m.connect(src.p, r.p)
    m.connect(r.n, coil.p)
    m.connect(coil.n, src.n, g.port)
    m.connect(coil.B, core.A)
    m.connect(core.B, coil.A, mref.port)
    return m


def test_coil_on_a_core_is_an_inductor_N2_over_R():
    N, R_mag, V, Rw = 200, 4e6, 12.0, 4.0
    L = N ** 2 / R_mag
    t = np.linspace(0, 3 * L / Rw, 7)
    res = mt.simulate(coil_circuit(N, R_mag, V, Rw), t[-1], t_out=t, **TOL)
    i = V / Rw * (1 - np.exp(-Rw * t / L))
    np.testing.assert_allclose(res["r.i"], i, rtol=1e-8, atol=1e-12)
    # positive current drives positive flux A -> B through the coil: phi = N i / R
    np.testing.assert_allclose(res["coil.phi"], N * i / R_mag, rtol=1e-8, atol=1e-16)


def test_reluctance_force_equals_the_co_energy_derivative():
    """A constant coil current I through an actuator whose armature moves on a spring:
    at every instant F = dW'/dx at constant current, W'(x) = (N I)^2 / (2 R(x))."""
    N, I, area, x0 = 200, 0.8, 1e-4, 2e-3
    m = mt.System("actuator")
    src = m.add("src", el.DCCurrentSource(I=I))
    coil = m.add("coil", mg.ElectromagneticConverter(N=N))
    act = m.add("act", mg.ReluctanceForceActuator(area=area, x=x0))
    g = m.add("g", el.ElectricalReference())
    mref = m.add("mref", mg.MagneticReference())
    mass = m.add("mass", tr.Mass(m=0.01))
    k = m.add("k", tr.TranslationalSpring(k=5000.0))
    d = m.add("d", tr.TranslationalDamper(b=2.0))
    ground = m.add("ground", tr.TranslationalReference())
    m.connect(src.n, coil.p)
    m.connect(coil.n, src.p, g.port)
    m.connect(coil.B, act.A)
    m.connect(act.B, coil.A, mref.port)
    m.connect(act.rod, mass.port, k.A, d.A)
    m.connect(act.case, k.B, d.B, ground.port)
    res = mt.simulate(m, 0.2, **TOL)
    x = res["act.x"]

    def coenergy(xx):
        return (N * I) ** 2 / (2 * xx / (MU0 * area))

    h = 1e-9
    dW = (coenergy(x + h) - coenergy(x - h)) / (2 * h)
    np.testing.assert_allclose(res["act.F"], dW, rtol=1e-6)
    assert np.all(res["act.F"] < 0)  # attraction closes the gap
    # static equilibrium: spring force balances the magnetic pull
    x_eq = res.final("act.x")
    assert x_eq < x0
    pull = (N * I) ** 2 * MU0 * area / (2 * x_eq ** 2)
    assert 5000.0 * (x0 - x_eq) == pytest.approx(pull, rel=1e-6)


class EnergyResistor(el.Resistor):
    """Test only: a resistor integrating its loss ``dE/dt = v i``."""

    E = mt.Variable("J", start=0.0, doc="Dissipated energy")

    def equations(self):
        return [mt.der(self.E) == self.v * self.i]


class EnergySource(el.ControlledVoltageSource):
    """Test only: a voltage source integrating the energy it delivers ``-v i``."""

    E = mt.Variable("J", start=0.0, doc="Delivered energy")

    def equations(self):
        return [mt.der(self.E) == -self.v * self.i]


class EnergyEddy(mg.EddyCurrent):
    """Test only: eddy-current element integrating its loss ``mmf dphi/dt``."""

    E = mt.Variable("J", start=0.0, doc="Dissipated energy")

    def equations(self):
        return [mt.der(self.E) == self.mmf * mt.der(self.phi)]


class EnergyMmfSource(mg.ControlledMmfSource):
    """Test only: mmf source integrating the energy it delivers ``-mmf dphi/dt``."""

    E = mt.Variable("J", start=0.0, doc="Delivered energy")

    def equations(self):
        return [mt.der(self.E) == -self.mmf * mt.der(self.phi)]


def test_magnetic_energy_balance_source_equals_eddy_loss_plus_stored():
    """mmf source (sine) -> eddy current + reluctance, in parallel with a second
    reluctance: delivered energy = eddy losses + R phi^2 / 2 of both reluctances."""
    R1, R2, G = 2e4, 5e4, 3.0
    m = mt.System("mag_energy")
    sine = m.add("sine", blocks.Sine(amplitude=40.0, offset=25.0, f=150.0))
    src = m.add("src", EnergyMmfSource())
    eddy = m.add("eddy", EnergyEddy(G=G, phi=0.0))
    r1 = m.add("r1", mg.Reluctance(R=R1))
    r2 = m.add("r2", mg.Reluctance(R=R2))
    ref = m.add("ref", mg.MagneticReference())
    m.connect(sine.y, src.F_in)
    m.connect(src.B, eddy.A, r2.A)
    m.connect(eddy.B, r1.A)
    m.connect(r1.B, r2.B, src.A, ref.port)
    res = mt.simulate(m, 0.02, **TOL)
    delivered = res.final("src.E")
    energy = 0.5 * R1 * res["r1.phi"] ** 2 + 0.5 * R2 * res["r2.phi"] ** 2
    stored = energy[-1] - energy[0]   # r2 is charged at t = 0 by the source's offset
    lost = res.final("eddy.E")
    assert delivered > 0 and lost > 0 and stored > 0
    assert lost + stored == pytest.approx(delivered, rel=1e-6)


def test_electro_magneto_mechanical_energy_balance():
    """Voltage source -> winding resistance -> coil -> actuator gap + eddy loss, armature on
    spring and damper: electrical input = resistor + eddy + damper losses + magnetic,
    spring and kinetic energy at the end."""
    N, area, x0, mass_kg, k_s, b = 200, 1e-4, 2e-3, 0.01, 5000.0, 2.0
    m = mt.System("actuator_energy")
    step = m.add("v", blocks.Sine(amplitude=6.0, offset=8.0, f=20.0))
    src = m.add("src", EnergySource())
    r = m.add("r", EnergyResistor(R=12.0))
    coil = m.add("coil", mg.ElectromagneticConverter(N=N))
    eddy = m.add("eddy", EnergyEddy(G=0.5))
    act = m.add("act", mg.ReluctanceForceActuator(area=area, x=x0))
    g = m.add("g", el.ElectricalReference())
    mref = m.add("mref", mg.MagneticReference())
    mass = m.add("mass", tr.Mass(m=mass_kg, v=0.0))
    spring = m.add("k", tr.TranslationalSpring(k=k_s))
    d = m.add("d", tr.TranslationalDamper(b=b))
    ground = m.add("ground", tr.TranslationalReference())
    m.connect(step.y, src.u)
    m.connect(src.p, r.p)
    m.connect(r.n, coil.p)
    m.connect(coil.n, src.n, g.port)
    m.connect(coil.B, eddy.A)
    m.connect(eddy.B, act.A)
    m.connect(act.B, coil.A, mref.port)
    m.connect(act.rod, mass.port, spring.A, d.A)
    m.connect(act.case, spring.B, d.B, ground.port)
    t = np.linspace(0, 0.1, 20001)
    res = mt.simulate(m, 0.1, t_out=t, **TOL)
    from scipy.integrate import simpson
    damper = simpson(b * res["d.v"] ** 2, x=t)
    x, phi = res.final("act.x"), res.final("act.phi")
    magnetic = 0.5 * x / (MU0 * area) * phi ** 2
    mech = 0.5 * mass_kg * res.final("mass.v") ** 2 + 0.5 * k_s * res.final("k.x") ** 2
    total = res.final("r.E") + res.final("eddy.E") + damper + magnetic + mech
    assert res.final("act.x") < x0 and mech > 0
    assert total == pytest.approx(res.final("src.E"), rel=1e-6)
