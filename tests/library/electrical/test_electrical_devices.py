"""Zener diode, thyristor and bipolar transistors against their characteristics written
here: the Zener's three regions along a voltage sweep, a phase-controlled half-wave
rectifier's current period by period, and transistor bias points solved by SciPy from
the Ebers-Moll equations written independently in this file."""

import numpy as np
import pytest
from scipy.optimize import brentq

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import electrical as el

VT = 1.380649e-23 * 300.15 / 1.602176634e-19


def test_zener_characteristic_along_a_sweep():
    VZ, VF, RON, RZ, GOFF = 5.1, 0.7, 0.05, 2.0, 1e-6
    m = mt.System("z")
    src = m.add("src", el.RampVoltage(V=20.0, duration=1.0, offset=-10.0))
    rs = m.add("rs", el.Resistor(R=100.0))
    z = m.add("z", el.ZenerDiode(Vz=VZ, Vf=VF, R_on=RON, R_z=RZ, G_off=GOFF))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, rs.p)
    m.connect(rs.n, z.p)
    m.connect(src.n, z.n, g.port)
    t = np.linspace(0, 1, 1001)
    res = mt.simulate(m, 1.0, t_out=t, rtol=1e-10, atol=1e-12)
    v = res["z.v"]

    def char(u):
        if u > VF:
            return (u - VF) / RON + GOFF * VF
        if u < -VZ:
            return (u + VZ) / RZ - GOFF * VZ
        return GOFF * u
    np.testing.assert_allclose(res["z.i"], [char(u) for u in v], rtol=1e-9, atol=1e-14)
    # the series circuit solved per region: source = 100 i + v
    vs = -10.0 + 20.0 * t
    np.testing.assert_allclose(100.0 * res["z.i"] + v, vs, atol=1e-9)
    # regulation: at the start the diode is in breakdown at -Vz - R_z i
    i0 = (vs[0] + VZ - RZ * GOFF * VZ) / (100.0 + RZ)     # from 100 i + (R_z i - Vz + ...) = vs
    assert res["z.i"][0] == pytest.approx(i0, rel=1e-9)
    assert res["z.v"][0] == pytest.approx(-VZ + RZ * (i0 + GOFF * VZ), rel=1e-9)
    assert res["z.v"][-1] == pytest.approx(VF + RON * (res["z.i"][-1] - GOFF * VF), rel=1e-9)


def test_thyristor_phase_controlled_half_wave_rectifier():
    VM, F, R, ALPHA = 100.0, 50.0, 10.0, np.pi / 3
    RON, GOFF = 1e-5, 1e-5
    m = mt.System("scr")
    src = m.add("src", el.ACVoltageSource(V_amp=VM, f=F))
    th = m.add("th", el.Thyristor(R_on=RON, G_off=GOFF))
    load = m.add("load", el.Resistor(R=R))
    gate = m.add("gate", blocks.Pulse(amplitude=1.0, period=1 / F, width=0.05,
                                      delay=ALPHA / (2 * np.pi * F)))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, th.p)
    m.connect(th.n, load.p)
    m.connect(load.n, src.n, g.port)
    m.connect(gate.y, th.fire)
    n = 5
    t = np.linspace(0, n / F, 5001)
    res = mt.simulate(m, n / F, t_out=t, rtol=1e-10, atol=1e-12)
    theta = np.mod(2 * np.pi * F * t, 2 * np.pi)
    vs = VM * np.sin(2 * np.pi * F * t)
    conducting = (theta > ALPHA) & (theta < np.pi)
    expect = np.where(conducting, vs / (R + RON), GOFF * vs / (1 + GOFF * R))
    # away from the firing instants and the current zeros (events)
    away = (np.abs(theta - ALPHA) > 1e-3) & (np.abs(theta - np.pi) > 1e-3) & (theta > 1e-3)
    np.testing.assert_allclose(res["load.i"][away], expect[away], atol=1e-6)
    np.testing.assert_array_equal(res["th.on"][away], conducting[away].astype(float))
    # mean load voltage of the phase-controlled half wave, VM/(2 pi) (1 + cos alpha)
    mean = np.trapezoid(res["load.v"], t) / (n / F)
    assert mean == pytest.approx(VM / (2 * np.pi) * (1 + np.cos(ALPHA)), rel=2e-3)


# -- bipolar transistors -------------------------------------------------------------

def ebers_moll(vbe, vbc, bf=100.0, br=1.0, i_s=1e-16, gmin=1e-12):
    """Collector and base currents into an NPN (written from the textbook)."""
    ef, er = np.exp(vbe / VT) - 1, np.exp(vbc / VT) - 1
    ic = i_s * (ef - er) - i_s / br * er - gmin * vbc
    ib = i_s / bf * ef + i_s / br * er + gmin * (vbe + vbc)
    return ic, ib


def common_emitter(q, vcc, rc, vbb, rb):
    m = mt.System("ce")
    supply = m.add("vcc", el.DCVoltageSource(V=vcc))
    bias = m.add("vbb", el.DCVoltageSource(V=vbb))
    r_c = m.add("rc", el.Resistor(R=rc))
    r_b = m.add("rb", el.Resistor(R=rb))
    m.add("q", q)
    g = m.add("g", el.ElectricalReference())
    m.connect(supply.p, r_c.p)
    m.connect(r_c.n, q.C)
    m.connect(bias.p, r_b.p)
    m.connect(r_b.n, q.B)
    m.connect(q.E, supply.n, bias.n, g.port)
    return mt.simulate(m, 1e-3, t_out=np.array([0.0, 1e-3]))


@pytest.mark.parametrize("rb", [200e3, 5e3])          # forward active, saturated
def test_npn_bias_point_matches_ebers_moll(rb):
    vcc, rc, vbb = 10.0, 1e3, 2.0

    # nested bracketed solves: the collector node for a given base voltage, then the base
    def collector(vb):
        return brentq(lambda vc: (vcc - vc) / rc - ebers_moll(vb, vb - vc)[0], -1.0,
                      vcc + 1.0, xtol=1e-15, rtol=1e-15)

    vb = brentq(lambda vb: (vbb - vb) / rb - ebers_moll(vb, vb - collector(vb))[1], 0.0,
                vbb, xtol=1e-15, rtol=1e-15)
    vc = collector(vb)
    res = common_emitter(el.NPN(), vcc, rc, vbb, rb)
    assert res.final("q.B.v") == pytest.approx(vb, abs=1e-9)
    assert res.final("q.C.v") == pytest.approx(vc, abs=1e-7)
    ic, ib = res.final("q.C.i"), res.final("q.B.i")
    assert res.final("q.E.i") == pytest.approx(-(ic + ib), abs=1e-15)
    if rb > 1e5:           # forward active: the current gain is beta_F
        assert ic / ib == pytest.approx(100.0, rel=1e-5)        # G_min leaks a little
        assert vc > vb
    else:                  # saturated: the collector below the base, gain well below beta
        assert vc < vb and ic / ib < 50


def test_pnp_mirrors_the_npn():
    """The PNP in the mirrored circuit (all voltages negated) carries the negated
    currents of the NPN."""
    vcc, rc, vbb, rb = 10.0, 1e3, 2.0, 200e3
    npn = common_emitter(el.NPN(), vcc, rc, vbb, rb)
    pnp = common_emitter(el.PNP(), -vcc, rc, -vbb, rb)
    for name in ("q.B.v", "q.C.v", "q.C.i", "q.B.i", "q.E.i"):
        assert pnp.final(name) == pytest.approx(-npn.final(name), rel=1e-9, abs=1e-15)
