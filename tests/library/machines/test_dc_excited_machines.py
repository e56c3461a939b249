"""Electrically excited DC machines (separately excited, series, shunt): the nominal
operating point from the data record against the analytic steady state, the start-up
transient against a hand-written SciPy model of the machine's ODEs, and the energy
balance of the separately excited one."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.library import machines
from mechatron.library import rotational as rot

# MSL's DcElectricalExcitedData defaults (the machines' defaults)
VN, IN, WN, RA, LA, JR = 100.0, 100.0, 1425 * 2 * np.pi / 60, 0.05, 0.0015, 0.15


def with_load(machine, tau_load, *, field=None):
    """Armature (and field) fed from DC sources, a constant load torque on the shaft."""
    m = mt.System("drive")
    m.add("dcm", machine)
    va = m.add("va", el.DCVoltageSource(V=VN))
    load = m.add("load", rot.ConstantTorque(T=-tau_load))   # opposes positive speed
    g = m.add("g", el.ElectricalReference())
    f = m.add("f", rot.RotationalReference())
    m.connect(va.p, machine.p)
    m.connect(va.n, machine.n, g.port)
    if field is not None:
        ve = m.add("ve", el.DCVoltageSource(V=field))
        m.connect(ve.p, machine.pe)
        m.connect(ve.n, machine.ne, g.port)
    m.connect(machine.flange, load.A)
    m.connect(machine.support, load.B, f.port)
    return m


def test_separately_excited_nominal_point_and_startup():
    RE, LE, IEN = 100.0, 1.0, 1.0
    lme = (VN - RA * IN) / (WN * IEN)
    t_nom = lme * IEN * IN
    m = with_load(machines.DCElectricalExcited(), t_nom, field=RE * IEN)
    t = np.linspace(0, 1.5, 1501)
    res = mt.simulate(m, 1.5, t_out=t, rtol=1e-10, atol=1e-10)
    assert res.final("dcm.inertia.w") == pytest.approx(WN, rel=1e-7)
    assert res.final("dcm.l_a.i") == pytest.approx(IN, rel=1e-7)
    assert res.final("dcm.l_e.i") == pytest.approx(IEN, rel=1e-7)

    def rhs(_, y):
        ia, ie, w = y
        psi = lme * ie
        return [(VN - RA * ia - psi * w) / LA, (RE * IEN - RE * ie) / LE,
                (psi * ia - t_nom) / JR]
    ref = solve_ivp(rhs, (0, 1.5), [0.0, 0.0, 0.0], t_eval=t, rtol=1e-11, atol=1e-11,
                    method="LSODA")
    np.testing.assert_allclose(res["dcm.l_a.i"], ref.y[0], atol=1e-5 * IN)
    np.testing.assert_allclose(res["dcm.l_e.i"], ref.y[1], atol=1e-8)
    np.testing.assert_allclose(res["dcm.inertia.w"], ref.y[2], atol=1e-5 * WN)
    # energy: supplied = copper losses + load work + stored (magnetic and kinetic)
    ia, ie, w = res["dcm.l_a.i"], res["dcm.l_e.i"], res["dcm.inertia.w"]
    supplied = np.trapezoid(VN * ia + RE * IEN * ie, t)
    lost = np.trapezoid(RA * ia ** 2 + RE * ie ** 2 + t_nom * w, t)
    stored = 0.5 * (LA * ia[-1] ** 2 + LE * ie[-1] ** 2 + JR * w[-1] ** 2)
    assert supplied == pytest.approx(lost + stored, rel=1e-4)


def test_series_machine_nominal_point_and_startup():
    RE, LE = 0.01, 0.0005
    lme = (VN - (RA + RE) * IN) / (WN * IN)
    t_nom = lme * IN ** 2
    m = with_load(machines.DCSeries(), t_nom)
    t = np.linspace(0, 5.0, 2001)          # speed time constant ~0.19 s here
    res = mt.simulate(m, 5.0, t_out=t, rtol=1e-10, atol=1e-10)
    assert res.final("dcm.inertia.w") == pytest.approx(WN, rel=1e-7)
    assert res.final("dcm.l_a.i") == pytest.approx(IN, rel=1e-7)
    np.testing.assert_allclose(res["dcm.l_e.i"], res["dcm.l_a.i"], atol=1e-12)

    def rhs(_, y):
        i, w = y
        return [(VN - (RA + RE) * i - lme * i * w) / (LA + LE), (lme * i ** 2 - t_nom) / JR]
    ref = solve_ivp(rhs, (0, 5.0), [0.0, 0.0], t_eval=t, rtol=1e-11, atol=1e-11,
                    method="LSODA")
    np.testing.assert_allclose(res["dcm.l_a.i"], ref.y[0], atol=1e-5 * IN)
    np.testing.assert_allclose(res["dcm.inertia.w"], ref.y[1], atol=1e-5 * WN)
    # the series machine's starting torque: with the rotor held, i = V/(R_a + R_e)
    # gives L_me i^2, far above nominal
    assert lme * (VN / (RA + RE)) ** 2 > 100 * t_nom


def test_shunt_machine_nominal_point_and_startup():
    RE, LE = 100.0, 1.0
    ie_n = VN / RE
    lme = (VN - RA * IN) * RE / (WN * VN)
    t_nom = lme * ie_n * IN
    m = with_load(machines.DCShunt(), t_nom)
    t = np.linspace(0, 1.5, 1501)
    res = mt.simulate(m, 1.5, t_out=t, rtol=1e-10, atol=1e-10)
    assert res.final("dcm.inertia.w") == pytest.approx(WN, rel=1e-7)
    assert res.final("dcm.l_a.i") == pytest.approx(IN, rel=1e-7)
    assert res.final("dcm.p.i") == pytest.approx(IN + ie_n, rel=1e-7)

    def rhs(_, y):
        ia, ie, w = y
        return [(VN - RA * ia - lme * ie * w) / LA, (VN - RE * ie) / LE,
                (lme * ie * ia - t_nom) / JR]
    ref = solve_ivp(rhs, (0, 1.5), [0.0, 0.0, 0.0], t_eval=t, rtol=1e-11, atol=1e-11,
                    method="LSODA")
    np.testing.assert_allclose(res["dcm.l_a.i"], ref.y[0], atol=1e-5 * IN)
    np.testing.assert_allclose(res["dcm.inertia.w"], ref.y[2], atol=1e-5 * WN)


def test_machine_parameters_are_tunable_and_pass_on():
    """A different nominal speed changes L_me (passed on as an expression) without
    recompiling: the machine then runs at the new nominal speed at its nominal load."""
    wn2 = 0.8 * WN
    lme2 = (VN - RA * IN) / (wn2 * 1.0)
    cm = mt.compile_model(with_load(machines.DCElectricalExcited(), lme2 * IN, field=100.0))
    res = mt.simulate(cm, 1.5, params={"dcm.w_nom": wn2}, rtol=1e-10, atol=1e-10)
    assert res.final("dcm.inertia.w") == pytest.approx(wn2, rel=1e-7)
    assert res.final("dcm.airgap.psi") == pytest.approx(lme2, rel=1e-9)
