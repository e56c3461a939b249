"""Translational components against analytic answers: hard stop, preloaded spring,
Stribeck friction, motion sources and sensors."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import translational as tr

TOL = dict(rtol=1e-10, atol=1e-12)


def grounded(name):
    m = mt.System(name)
    g = m.add("g", tr.TranslationalReference())
    return m, g


@pytest.mark.parametrize("F", [40.0, -25.0])
def test_hard_stop_penetration_at_rest_is_F_over_k(F):
    k, upper, lower = 1e6, 0.01, -0.02
    m, g = grounded("stop")
    mass = m.add("mass", tr.Mass(m=0.5))
    src = m.add("src", tr.ConstantForce(F=F))
    hs = m.add("hs", tr.TranslationalHardStop(upper=upper, lower=lower, k=k, d=200.0))
    m.connect(src.A, mass.port, hs.A)
    m.connect(src.B, hs.B, g.port)
    res = mt.simulate(m, 1.0, **TOL)
    bound = upper if F > 0 else lower
    assert res.final("hs.x") == pytest.approx(bound + F / k, abs=1e-10)
    assert res.final("mass.v") == pytest.approx(0.0, abs=1e-8)
    assert (np.sign(F) * res["hs.f"] >= -1e-9).all()          # it only pushes back


def test_preloaded_spring_force_and_equilibrium():
    """At the installed length the spring carries F_pre (read by a force sensor in
    series); under a constant pull F a damped mass settles at x = (F - F_pre) / k."""
    k, F_pre, F = 2000.0, 30.0, 50.0
    m, g = grounded("preload")
    mass = m.add("mass", tr.Mass(m=1.0))
    src = m.add("src", tr.ConstantForce(F=F))
    spring = m.add("spring", tr.PreloadedSpring(k=k, F_pre=F_pre))
    fs = m.add("fs", tr.ForceSensor())
    dmp = m.add("dmp", tr.TranslationalDamper(b=60.0))
    m.connect(src.A, mass.port, spring.A, dmp.A)
    m.connect(spring.B, fs.A)
    m.connect(fs.B, src.B, dmp.B, g.port)
    res = mt.simulate(m, 2.0, t_out=np.linspace(0, 2.0, 201), **TOL)
    assert res["fs.F"][0] == pytest.approx(F_pre, rel=1e-12)
    assert res.final("spring.x") == pytest.approx((F - F_pre) / k, rel=1e-8)
    assert res.final("fs.F") == pytest.approx(F, rel=1e-8)


def stribeck(v, F_brk, v_brk, F_C, b):
    """Simscape's translational friction law, written independently with NumPy."""
    v_st, v_c = v_brk * np.sqrt(2), v_brk / 10
    return (np.sqrt(2 * np.e) * (F_brk - F_C) * np.exp(-(v / v_st) ** 2) * v / v_st
            + F_C * np.tanh(v / v_c) + b * v)


@pytest.mark.parametrize("v", [-0.3, -0.1, 0.01, 0.1, 0.5])
def test_stribeck_friction_at_imposed_velocities(v):
    F_brk, v_brk, F_C, b = 25.0, 0.1, 20.0, 100.0
    m, g = grounded("friction")
    c = m.add("c", blocks.Constant(value=v))
    vs = m.add("vs", tr.IdealVelocitySource())
    fr = m.add("fr", tr.TranslationalFriction(F_brk=F_brk, v_brk=v_brk, F_C=F_C, b=b))
    m.connect(c.y, vs.v_ref)
    m.connect(vs.A, fr.A)
    m.connect(vs.B, fr.B, g.port)
    res = mt.simulate(m, 0.1, **TOL)
    assert res.final("fr.f") == pytest.approx(stribeck(v, F_brk, v_brk, F_C, b), rel=1e-12)
    if v == v_brk:   # the breakaway force is reached at v_brk (tanh(10) ~ 1 - 4e-9)
        assert res.final("fr.f") == pytest.approx(F_brk + b * v_brk, rel=1e-8)
    assert res.final("fr.f") * v > 0                           # always dissipative


def test_velocity_source_and_sensors_read_analytic_motion():
    M, amp, f = 2.0, 0.4, 1.2
    om = 2 * np.pi * f
    m, g = grounded("vsrc")
    s = m.add("s", blocks.Sine(amplitude=amp, f=f))
    vs = m.add("vs", tr.IdealVelocitySource())
    fs = m.add("fs", tr.ForceSensor())
    mass = m.add("mass", tr.Mass(m=M))
    pos = m.add("pos", tr.PositionSensor())
    vel = m.add("vel", tr.VelocitySensor())
    acc = m.add("acc", tr.AccelerationSensor())
    pw = m.add("pw", tr.TranslationalPowerSensor())
    m.connect(s.y, vs.v_ref)
    m.connect(vs.A, fs.A)
    m.connect(fs.B, pw.A)
    m.connect(pw.B, mass.port, pos.A, vel.A, acc.A)
    m.connect(vs.B, pos.B, vel.B, acc.B, g.port)
    t = np.linspace(0, 1.0, 51)
    res = mt.simulate(m, 1.0, t_out=t, **TOL)
    v = amp * np.sin(om * t)
    a = amp * om * np.cos(om * t)
    np.testing.assert_allclose(res["vel.V"], v, atol=1e-10)
    np.testing.assert_allclose(res["pos.X"], amp / om * (1 - np.cos(om * t)), atol=1e-8)
    np.testing.assert_allclose(res["acc.a"], a, atol=1e-8)
    np.testing.assert_allclose(res["fs.F"], M * a, atol=1e-8)
    np.testing.assert_allclose(res["pw.P"], M * a * v, atol=1e-8)


def test_position_source_imposes_x_and_velocity_is_its_derivative():
    M, amp, f = 0.5, 0.05, 3.0
    om = 2 * np.pi * f
    m, g = grounded("xsrc")
    s = m.add("s", blocks.Sine(amplitude=amp, f=f))
    xs = m.add("xs", tr.IdealPositionSource())
    mass = m.add("mass", tr.Mass(m=M))
    m.connect(s.y, xs.x_ref)
    m.connect(xs.A, mass.port)
    m.connect(xs.B, g.port)
    t = np.linspace(0, 0.5, 26)
    res = mt.simulate(m, 0.5, t_out=t, **TOL)
    np.testing.assert_allclose(res["xs.x"], amp * np.sin(om * t), atol=1e-12)
    np.testing.assert_allclose(res["mass.v"], amp * om * np.cos(om * t), atol=1e-8)
    # the source pushes the mass with M dv/dt: xs.f = -M a (its A.f is the reaction)
    np.testing.assert_allclose(res["xs.f"], M * amp * om ** 2 * np.sin(om * t), atol=1e-6)
