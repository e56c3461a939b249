"""Energy balance of a translational network: the energy a force source puts in equals
what the damper and the Stribeck friction dissipate plus what the masses and the
(preloaded) springs store, each power integrated by an extra state ``der(E) = P``."""

import pytest

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import translational as tr


class EnergyMeter(mt.Component):
    """Test-only integrator of a power: ``der(E) == P``; ``P`` is set by an equation of
    the model."""

    E = mt.Variable("J", start=0.0, doc="Energy, integral of P")
    P = mt.Variable("W", doc="Power being integrated")

    def equations(self):
        return [mt.der(self.E) == self.P]


def test_input_energy_equals_dissipated_plus_stored():
    m1, m2, k1, k2, F_pre = 1.0, 0.5, 400.0, 900.0, 15.0
    m = mt.System("chain")
    g = m.add("g", tr.TranslationalReference())
    s = m.add("s", blocks.Sine(amplitude=40.0, f=1.3, offset=5.0))
    src = m.add("src", tr.IdealForceSource())
    pw = m.add("pw", tr.TranslationalPowerSensor())
    mass1 = m.add("mass1", tr.Mass(m=m1))
    spring = m.add("spring", tr.TranslationalSpring(k=k1))
    mass2 = m.add("mass2", tr.Mass(m=m2))
    pre = m.add("pre", tr.PreloadedSpring(k=k2, F_pre=F_pre))
    dmp = m.add("dmp", tr.TranslationalDamper(b=3.0))
    fr = m.add("fr", tr.TranslationalFriction(F_brk=8.0, v_brk=0.05, F_C=6.0, b=1.0))
    e_in = m.add("e_in", EnergyMeter())
    e_loss = m.add("e_loss", EnergyMeter())
    m.connect(s.y, src.f_in)
    m.connect(src.A, pw.A)
    m.connect(pw.B, mass1.port, spring.A, fr.A)
    m.connect(spring.B, mass2.port, pre.A, dmp.A)
    m.connect(src.B, fr.B, pre.B, dmp.B, g.port)
    m.add_equation(lambda: e_in.P == pw.P)
    m.add_equation(lambda: e_loss.P == dmp.f * dmp.v + fr.f * fr.v)
    res = mt.simulate(m, 4.0, rtol=1e-10, atol=1e-12)
    x2 = res.final("pre.x")
    stored = (0.5 * m1 * res.final("mass1.v") ** 2 + 0.5 * m2 * res.final("mass2.v") ** 2
              + 0.5 * k1 * res.final("spring.x") ** 2
              + F_pre * x2 + 0.5 * k2 * x2 ** 2)       # work done on the preloaded spring
    e_in_final = res.final("e_in.E")
    assert e_in_final > 1.0
    assert res.final("e_loss.E") > 0.1 * e_in_final
    assert res.final("e_loss.E") + stored == pytest.approx(e_in_final, rel=1e-6)
