"""Multibody components, one small mechanism each, against analytic answers and
independent 1-D models."""

import math

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import multibody as mb
from mechatron.library import rotational as rot
from mechatron.library.multibody import mechanisms as mech
from mechatron.library.multibody.parts import G_STANDARD   # the bodies' default g

TIGHT = dict(rtol=1e-12, atol=1e-12)


def test_incline_prismatic_matches_the_1d_translational_model():
    t = np.linspace(0.0, 5.0, 2001)
    r3 = mt.simulate(mech.incline(), 5.0, t_out=t, **TIGHT)
    r1 = mt.simulate(mech.incline_1d(), 5.0, t_out=t, **TIGHT)
    assert np.max(np.abs(r3["joint.s"] - r1["spring.x"])) < 1e-8
    assert np.max(np.abs(r3["joint.v"] - r1["mass.v"])) < 1e-8
    # the mass moves along the 60 degree line; the normal force carries m g cos(60)
    ang = math.radians(60)
    s = r3["joint.s"]
    np.testing.assert_allclose(r3["mass.frame.x"], s * math.cos(ang), atol=1e-12)
    np.testing.assert_allclose(r3["mass.frame.y"], s * math.sin(ang), atol=1e-12)
    normal = -r3["mass.frame.fx"] * -math.sin(ang) - r3["mass.frame.fy"] * math.cos(ang)
    np.testing.assert_allclose(-normal, 2.0 * G_STANDARD * math.cos(ang), rtol=1e-9)


def test_incline_settles_at_the_static_deflection():
    res = mt.simulate(mech.incline(d=20.0), 20.0, **TIGHT)
    assert res.final("joint.s") == pytest.approx(-2.0 * G_STANDARD * math.sin(math.radians(60))
                                                 / 50.0, abs=1e-9)


def hanging(element, m=1.0, y0=-1.2, g=9.81):
    """A body hanging from a fixed point by a line-force element, released at y0."""
    s = mt.System("hanging")
    top = s.add("top", mb.Fixed())
    el = s.add("el", element)
    body = s.add("body", mb.Body(m=m, J=0.1, g=g, y=y0))
    s.connect(top.frame, el.frame_a)
    s.connect(el.frame_b, body.frame_a)
    return s


def test_spring_hanging_body_oscillates_at_sqrt_k_over_m():
    k, m, L0, y0 = 40.0, 2.0, 1.0, -1.2
    t = np.linspace(0.0, 3.0, 601)
    res = mt.simulate(hanging(mb.Spring(k=k, L0=L0), m=m, y0=y0), 3.0, t_out=t, **TIGHT)
    y_eq = -(L0 + m * 9.81 / k)
    y = y_eq + (y0 - y_eq) * np.cos(math.sqrt(k / m) * t)
    np.testing.assert_allclose(res["body.y"], y, atol=1e-9)
    np.testing.assert_allclose(res["body.x"], 0.0, atol=1e-12)
    e = res["body.E_kin"] + res["body.E_pot"] + res["el.E"]
    assert np.max(np.abs(e - e[0])) < 1e-9 * abs(e[0])


def test_spring_damper_hanging_body_is_a_damped_oscillator():
    k, d, m, L0, y0 = 40.0, 3.0, 2.0, 1.0, -1.2
    t = np.linspace(0.0, 3.0, 601)
    res = mt.simulate(hanging(mb.SpringDamper(k=k, d=d, L0=L0), m=m, y0=y0), 3.0,
                      t_out=t, **TIGHT)
    y_eq = -(L0 + m * 9.81 / k)
    zeta = d / (2 * math.sqrt(k * m))
    wn = math.sqrt(k / m)
    wd = wn * math.sqrt(1 - zeta ** 2)
    y = y_eq + (y0 - y_eq) * np.exp(-zeta * wn * t) * (
        np.cos(wd * t) + zeta * wn / wd * np.sin(wd * t))
    np.testing.assert_allclose(res["body.y"], y, atol=1e-9)


def test_damper_alone_lets_the_body_fall_at_terminal_speed():
    d, m = 5.0, 1.0
    res = mt.simulate(hanging(mb.Damper(d=d), m=m, y0=-1.0), 3.0, **TIGHT)
    tau = m / d
    v = -9.81 * tau * (1 - np.exp(-res.t / tau))
    np.testing.assert_allclose(res["body.vy"], v, atol=1e-9)


def test_world_force_and_torque_accelerate_a_free_body():
    s = mt.System("free")
    body = s.add("body", mb.Body(m=2.0, J=0.5, g=0.0))
    fx = s.add("fx", blocks.Constant(value=3.0))
    fy = s.add("fy", blocks.Constant(value=-1.0))
    tq = s.add("tq", blocks.Constant(value=0.25))
    force = s.add("force", mb.WorldForce())
    torque = s.add("torque", mb.WorldTorque())
    s.connect(fx.y, force.fx_in)
    s.connect(fy.y, force.fy_in)
    s.connect(tq.y, torque.tau_in)
    s.connect(body.frame_a, force.frame, torque.frame)
    res = mt.simulate(s, 2.0, **TIGHT)
    t = res.t
    np.testing.assert_allclose(res["body.x"], 3.0 / 2.0 * t ** 2 / 2, atol=1e-10)
    np.testing.assert_allclose(res["body.y"], -1.0 / 2.0 * t ** 2 / 2, atol=1e-10)
    np.testing.assert_allclose(res["body.frame_a.phi"], 0.25 / 0.5 * t ** 2 / 2, atol=1e-10)


def test_actuated_revolute_with_a_rotational_spring_is_a_torsional_oscillator():
    """No gravity; a body (J about its centre, centre at r from the axis) on a revolute
    joint whose axis carries a torsional spring: omega^2 = k / (J + m r^2)."""
    k, m, j, r, q0 = 3.0, 0.5, 0.02, 0.3, 0.4
    s = mt.System("torsion")
    w = s.add("world", mb.World())
    joint = s.add("joint", mb.ActuatedRevolute(q=q0))
    body = s.add("body", mb.Body(m=m, J=j, rcm_x=r, g=0.0))
    spring = s.add("spring", rot.RotationalSpring(k=k, phi=q0))
    ref = s.add("ref", rot.RotationalReference())
    sensor = s.add("angle", mb.RelativeAngleSensor())
    s.connect(w.frame, joint.frame_a, sensor.frame_a)
    s.connect(joint.frame_b, body.frame_a, sensor.frame_b)
    s.connect(joint.axis, spring.A)
    s.connect(spring.B, ref.port)
    t = np.linspace(0.0, 2.0, 401)
    res = mt.simulate(s, 2.0, t_out=t, **TIGHT)
    omega = math.sqrt(k / (j + m * r ** 2))
    np.testing.assert_allclose(res["joint.q"], q0 * np.cos(omega * t), atol=1e-9)
    np.testing.assert_allclose(res["angle.phi_rel"], res["joint.q"], atol=1e-12)
    np.testing.assert_allclose(res["angle.w_rel"], res["joint.w"], atol=1e-10)
    # the spring's reaction reaches the ground through frame_a: the world takes k q
    np.testing.assert_allclose(res["world.frame.tau"], k * res["joint.q"], atol=1e-9)


def test_weld_is_a_rigid_connection():
    """A pendulum whose rod is split by a weld swings like the unsplit one."""
    def pendulum(split):
        s = mt.System("p")
        w = s.add("world", mb.World())
        joint = s.add("joint", mb.Revolute(q=0.7))
        rod = s.add("rod", mb.Rod(L=0.5))
        mass = s.add("mass", mb.PointMass(m=1.0))
        s.connect(w.frame, joint.frame_a)
        if split:
            weld = s.add("weld", mb.Weld())
            s.connect(joint.frame_b, weld.frame_a)
            s.connect(weld.frame_b, rod.frame_a)
        else:
            s.connect(joint.frame_b, rod.frame_a)
        s.connect(rod.frame_b, mass.frame)
        return mt.simulate(s, 2.0, **TIGHT)
    a, b = pendulum(False), pendulum(True)
    np.testing.assert_allclose(b["joint.q"], a["joint.q"], atol=1e-10)
    # the rod along x at q = 0: a pendulum released 0.7 rad above the horizontal
    # swings down through -pi/2 (the joint angle is measured from the x-axis)
    assert np.min(a["joint.q"]) < -math.pi / 2


def test_free_prismatic_lets_a_mass_slide_down_a_frictionless_incline():
    ang = math.radians(30)
    s = mt.System("slide")
    w = s.add("world", mb.World())
    slope = s.add("slope", mb.RigidTransform(angle=ang))
    joint = s.add("joint", mb.Prismatic())
    mass = s.add("mass", mb.PointMass(m=3.0))
    s.connect(w.frame, slope.frame_a)
    s.connect(slope.frame_b, joint.frame_a)
    s.connect(joint.frame_b, mass.frame)
    res = mt.simulate(s, 1.0, **TIGHT)
    np.testing.assert_allclose(res["joint.s"], -G_STANDARD * math.sin(ang) * res.t ** 2 / 2,
                               atol=1e-10)


def test_kinetic_mechanism_gains_the_work_of_its_motor():
    """Chain of point masses driven by a torque at the first joint: the energy gained
    equals the integral of tau * w of that joint."""
    res = mt.simulate(mech.kinetic_mechanism(), 2.0, t_out=np.linspace(0, 2, 8001),
                      **TIGHT)
    e = sum(res[f"m{k}.E_kin"] + res[f"m{k}.E_pot"] for k in (1, 2, 3))
    from scipy.integrate import cumulative_simpson
    work = cumulative_simpson(2.0 * res["j1.w"], x=res.t, initial=0.0)
    assert np.max(np.abs(e - e[0] - work)) < 1e-6 * max(1.0, np.max(np.abs(work)))


def test_bad_state_select_value_is_rejected():
    with pytest.raises(ValueError, match="state_select"):
        mt.Variable("m", state_select="always!")


def test_default_gravity_is_standard_gravity():
    """A free body falls at 9.80665 m/s^2 (MSL's and Simscape Multibody's default); the
    database models that follow the thesis keep its 9.81."""
    s = mt.System("fall")
    body = s.add("body", mb.Body(m=1.0, J=0.1))
    zero = s.add("zero", blocks.Constant(value=0.0))
    force = s.add("force", mb.WorldForce())          # no force: a free fall
    s.connect(zero.y, force.fx_in, force.fy_in)
    s.connect(body.frame_a, force.frame)
    t = np.linspace(0, 1, 11)
    res = mt.simulate(s, 1.0, t_out=t, **TIGHT)
    np.testing.assert_allclose(res["body.y"], -9.80665 * t ** 2 / 2, atol=1e-12)
    assert mb.PointMass._declarations["g"].default == 9.80665
    for name in ("double_pendulum", "kinetic_mechanism"):
        entry = mt.models.get(name)
        cm = mt.compile_model(entry.build("multibody"))
        gs = {k: float(v) for k, v in zip(cm.param_names, cm.p0) if k.endswith(".g")}
        assert gs and all(v == 9.81 for v in gs.values()), (name, gs)
