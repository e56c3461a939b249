"""Electromechanical converters: the translational EMF (voice coil) against the matrix
exponential of its linear drive, and a multi-domain DC motor whose winding is a
heating resistor warming a thermal mass, checked for its energy balance and its
self-consistent thermal steady state."""

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq

import mechatron as mt
from mechatron.core import Variable, der
from mechatron.library import electrical as el
from mechatron.library import electromechanical as em
from mechatron.library import rotational as rot
from mechatron.library import thermal as th
from mechatron.library import translational as tr


class EnergyMeter(mt.Component):
    """Test-only: ``der(E) == P`` from E(0) = 0; the model sets ``P`` with an equation
    over other parts' variables (so the meter alone is one equation short)."""

    P = Variable("W", doc="Power")
    E = Variable("J", start=0.0, doc="Energy, integral of P")

    def equations(self):
        return [der(self.E) == self.P]


V, R, L, K, M, B = 6.0, 4.0, 2e-3, 8.0, 0.05, 2.0


def voice_coil():
    m = mt.System("voice_coil")
    src = m.add("src", el.DCVoltageSource(V=V))
    r = m.add("r", el.Resistor(R=R))
    ind = m.add("l", el.Inductor(L=L))
    emf = m.add("emf", em.TranslationalEMF(k=K))
    mass = m.add("mass", tr.Mass(m=M))
    damper = m.add("damper", tr.TranslationalDamper(b=B))
    fixed = m.add("fixed", tr.TranslationalReference())
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, r.p)
    m.connect(r.n, ind.p)
    m.connect(ind.n, emf.p)
    m.connect(emf.n, src.n, g.port)
    m.connect(emf.A, mass.port, damper.A)
    m.connect(emf.B, damper.B, fixed.port)
    return m


def test_translational_emf_drive_matches_the_matrix_exponential():
    times = np.array([0.0, 1e-4, 1e-3, 5e-3, 2e-2, 0.1])
    res = mt.simulate(voice_coil(), times[-1], rtol=1e-11, atol=1e-13, t_out=times)
    # x = [i, v]: L i' = V - R i - k v ;  m v' = k i - b v
    a = np.array([[-R / L, -K / L], [K / M, -B / M]])
    b = np.array([V / L, 0.0])
    x_inf = -np.linalg.solve(a, b)
    ref = np.array([x_inf - expm(a * t) @ x_inf for t in times])
    np.testing.assert_allclose(res["l.i"], ref[:, 0], rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(res["mass.v"], ref[:, 1], rtol=1e-8, atol=1e-12)
    # steady state: k i = b v and V = R i + k v
    assert res.final("mass.v") == pytest.approx(K * V / (R * B + K ** 2), rel=1e-6)
    # lossless conversion: v i + f v_rel = 0 at every instant; force = k i on the mass
    np.testing.assert_allclose(res["emf.v"] * res["emf.i"],
                               -res["emf.f"] * res["emf.v_rel"], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(res["emf.A.f"], -K * res["emf.i"], rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(res["emf.v"], K * res["mass.v"], rtol=1e-13, atol=1e-15)


# -- multi-domain DC motor with a self-heating winding --------------------------------------

VM, R_REF, ALPHA, T_REF, LM, KM, J, D = 12.0, 2.0, 3.93e-3, 293.15, 1e-3, 0.05, 1e-4, 1e-4
C_TH, G_TH, T_AMB = 5.0, 0.05, 293.15


def hot_motor():
    m = mt.System("hot_motor")
    src = m.add("src", el.DCVoltageSource(V=VM))
    wind = m.add("winding", el.HeatingResistor(R_ref=R_REF, alpha=ALPHA, T_ref=T_REF))
    ind = m.add("l", el.Inductor(L=LM))
    emf = m.add("emf", em.RotationalEMF(k=KM))
    rotor = m.add("rotor", rot.Inertia(J=J))
    fric = m.add("fric", rot.RotationalDamper(D=D))
    housing = m.add("housing", rot.RotationalReference())
    mass = m.add("mass", th.HeatCapacitor(C=C_TH, T=T_AMB))
    cond = m.add("cond", th.ThermalConductor(G=G_TH))
    amb = m.add("amb", th.FixedTemperature(T=T_AMB))
    g = m.add("g", el.ElectricalReference())
    e_in = m.add("e_in", EnergyMeter())
    e_amb = m.add("e_amb", EnergyMeter())
    e_fric = m.add("e_fric", EnergyMeter())
    m.connect(src.p, wind.p)
    m.connect(wind.n, ind.p)
    m.connect(ind.n, emf.p)
    m.connect(emf.n, src.n, g.port)
    m.connect(emf.A, rotor.port, fric.A)
    m.connect(emf.B, fric.B, housing.port)
    m.connect(wind.heat_port, mass.port, cond.A)
    m.connect(cond.B, amb.port)
    # energy meters: the source delivers -v i; heat to ambient; viscous loss
    m.add_equation(lambda: e_in.P == -src.v * src.i)
    m.add_equation(lambda: e_amb.P == cond.Q)
    m.add_equation(lambda: e_fric.P == fric.tau * fric.w)
    return m


def test_hot_motor_energy_balance():
    """Electrical input = kinetic + magnetic + thermal stored + heat to ambient + viscous
    loss, to 1e-6 relative, while the winding warms up and its resistance rises."""
    res = mt.simulate(hot_motor(), 60.0, rtol=1e-10, atol=1e-12)
    kinetic = 0.5 * J * res.final("rotor.w") ** 2
    magnetic = 0.5 * LM * res.final("l.i") ** 2
    thermal = C_TH * (res.final("mass.T") - T_AMB)
    out = kinetic + magnetic + thermal + res.final("e_amb.E") + res.final("e_fric.E")
    assert res.final("e_in.E") > 100.0
    assert out == pytest.approx(res.final("e_in.E"), rel=1e-6)
    # the winding warmed up and its resistance followed
    assert res.final("mass.T") > T_AMB + 2
    assert res.final("winding.R") == pytest.approx(
        R_REF * (1 + ALPHA * (res.final("mass.T") - T_REF)), rel=1e-12)
    # the winding itself stores nothing: its loss v*i all leaves as heat
    np.testing.assert_allclose(-res["winding.heat_port.Q"], res["winding.v"] * res["winding.i"],
                               rtol=1e-12, atol=1e-12)


def test_hot_motor_thermal_steady_state():
    """At steady state w = k i / D, V = (R(T) + k^2/D) i and G (T - Ta) = R(T) i^2: one
    equation in T, bracketed by SciPy."""
    def residual(temp):
        r_t = R_REF * (1 + ALPHA * (temp - T_REF))
        i = VM / (r_t + KM ** 2 / D)
        return G_TH * (temp - T_AMB) - r_t * i ** 2
    t_ss = brentq(residual, T_AMB, T_AMB + 500, xtol=1e-12)
    res = mt.simulate(hot_motor(), 4000.0, rtol=1e-10, atol=1e-12)
    assert res.final("mass.T") == pytest.approx(t_ss, rel=1e-7)
    r_t = R_REF * (1 + ALPHA * (t_ss - T_REF))
    i_ss = VM / (r_t + KM ** 2 / D)
    assert res.final("l.i") == pytest.approx(i_ss, rel=1e-6)
    assert res.final("rotor.w") == pytest.approx(KM * i_ss / D, rel=1e-6)
    # hotter winding, less current than a cold one would draw
    assert i_ss < VM / (R_REF + KM ** 2 / D)
