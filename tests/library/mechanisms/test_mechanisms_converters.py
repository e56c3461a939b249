"""Rotational-translational converters: lead screw force-torque ratio and efficiency in
both power-flow directions, rack and pinion kinematics, wheel and axle dynamics."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import blocks, mechanisms
from mechatron.library import rotational as rot
from mechatron.library import translational as tr

TOL = dict(rtol=1e-10, atol=1e-12)


def frame(name):
    m = mt.System(name)
    gr = m.add("gr", rot.RotationalReference())
    gt = m.add("gt", tr.TranslationalReference())
    return m, gr, gt


def test_lead_screw_forward_force_is_2_pi_eta_tau_over_lead():
    """A motor torque tau turns the screw; the nut pushes a damped mass. At steady state
    the push is F = 2 pi eta tau / lead and the output power is eta times the input."""
    tau, lead, eta, b = 0.5, 4e-3, 0.85, 2000.0
    m, gr, gt = frame("screw")
    c = m.add("c", blocks.Constant(value=tau))
    src = m.add("src", rot.IdealTorqueSource())
    j = m.add("j", rot.Inertia(J=1e-4))
    ls = m.add("ls", mechanisms.LeadScrew(lead=lead, eta=eta, eta_back=0.6))
    mass = m.add("mass", tr.Mass(m=2.0))
    dmp = m.add("dmp", tr.TranslationalDamper(b=b))
    m.connect(c.y, src.tau_in)
    m.connect(src.A, j.port, ls.R)
    m.connect(ls.T, mass.port, dmp.A)
    m.connect(src.B, gr.port)
    m.connect(dmp.B, gt.port)
    res = mt.simulate(m, 2.0, **TOL)
    F = 2 * np.pi * eta * tau / lead
    assert -res.final("ls.T.f") == pytest.approx(F, rel=1e-8)
    assert res.final("mass.v") == pytest.approx(F / b, rel=1e-8)
    assert res.final("j.w") == pytest.approx(2 * np.pi * F / (b * lead), rel=1e-8)
    p_in = res.final("ls.R.tau") * res.final("j.w")
    p_out = -res.final("ls.T.f") * res.final("mass.v")
    assert p_out / p_in == pytest.approx(eta, rel=1e-8)
    assert res.final("ls.P_loss") == pytest.approx((1 - eta) * p_in, rel=1e-8)


def test_lead_screw_backdriven_torque_uses_eta_back():
    """A force F on the nut back-drives the screw against a rotational damper D: the
    torque reaching the screw is eta_back F lead / (2 pi)."""
    F, lead, eta_back, D = 100.0, 5e-3, 0.6, 0.01
    m, gr, gt = frame("backdrive")
    c = m.add("c", blocks.Constant(value=F))
    src = m.add("src", tr.IdealForceSource())
    mass = m.add("mass", tr.Mass(m=0.2))
    ls = m.add("ls", mechanisms.LeadScrew(lead=lead, eta=0.9, eta_back=eta_back))
    j = m.add("j", rot.Inertia(J=1e-5))
    dmp = m.add("dmp", rot.RotationalDamper(D=D))
    m.connect(c.y, src.f_in)
    m.connect(src.A, mass.port, ls.T)
    m.connect(src.B, gt.port)
    m.connect(ls.R, j.port, dmp.A)
    m.connect(dmp.B, gr.port)
    res = mt.simulate(m, 2.0, **TOL)
    tau = eta_back * F * lead / (2 * np.pi)
    assert res.final("j.w") == pytest.approx(tau / D, rel=1e-8)
    assert res.final("mass.v") == pytest.approx(lead / (2 * np.pi) * tau / D, rel=1e-8)
    p_in = F * res.final("mass.v")
    assert res.final("ls.P_loss") == pytest.approx((1 - eta_back) * p_in, rel=1e-8)


def test_rack_and_pinion_kinematics_and_force():
    """The pinion turns at w(t) = A sin(om t): the rack moves at r w and the pinion needs
    the torque r m dv/dt."""
    r, M, amp, f = 0.03, 4.0, 20.0, 0.8
    om = 2 * np.pi * f
    m, gr, gt = frame("rack")
    s = m.add("s", blocks.Sine(amplitude=amp, f=f))
    vs = m.add("vs", rot.IdealAngularVelocitySource())
    rp = m.add("rp", mechanisms.RackAndPinion(r=r))
    mass = m.add("mass", tr.Mass(m=M))
    pos = m.add("pos", tr.PositionSensor())
    m.connect(s.y, vs.w_ref)
    m.connect(vs.A, rp.R)
    m.connect(rp.T, mass.port, pos.A)
    m.connect(vs.B, gr.port)
    m.connect(pos.B, gt.port)
    t = np.linspace(0, 1.0, 41)
    res = mt.simulate(m, 1.0, t_out=t, **TOL)
    np.testing.assert_allclose(res["mass.v"], r * amp * np.sin(om * t), atol=1e-10)
    np.testing.assert_allclose(res["pos.X"], r * res["vs.phi"], atol=1e-10)
    np.testing.assert_allclose(res["rp.R.tau"], r * M * r * amp * om * np.cos(om * t),
                               atol=1e-8)


def test_wheel_and_axle_accelerates_a_vehicle_at_tau_over_r_m():
    tau, r, M = 30.0, 0.3, 100.0
    m = mt.System("vehicle")     # the mass is referenced implicitly: no translational ground
    gr = m.add("gr", rot.RotationalReference())
    c = m.add("c", blocks.Constant(value=tau))
    src = m.add("src", rot.IdealTorqueSource())
    wh = m.add("wh", mechanisms.WheelAndAxle(r=r))
    car = m.add("car", tr.Mass(m=M))
    m.connect(c.y, src.tau_in)
    m.connect(src.A, wh.R)
    m.connect(wh.T, car.port)
    m.connect(src.B, gr.port)
    t = np.linspace(0, 2.0, 11)
    res = mt.simulate(m, 2.0, t_out=t, **TOL)
    np.testing.assert_allclose(res["car.v"], tau / (r * M) * t, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(res["wh.R.w"], res["car.v"] / r, rtol=1e-12, atol=1e-12)
