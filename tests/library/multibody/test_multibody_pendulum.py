"""Open chains against equation models: the double pendulum (seed eqs. 14-15) and a
compound pendulum, with energy conservation."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechatron as mt
from mechatron.library import multibody as mb
from mechatron.library.multibody import mechanisms as mech
from mechatron.library.multibody.parts import G_STANDARD   # the bodies' default g
from mechatron.library.multibody.reference import (double_pendulum_energy,
                                                   double_pendulum_rhs)

T_END = 10.0
TIGHT = dict(rtol=1e-12, atol=1e-12)


@pytest.fixture(scope="module")
def pendulum_run():
    cm = mt.compile_model(mech.double_pendulum())
    return cm, mt.simulate(cm, T_END, **TIGHT)


def test_double_pendulum_selects_the_joint_angles_as_states(pendulum_run):
    cm, _ = pendulum_run
    assert sorted(cm.state_names) == ["j1.q", "j1.w", "j2.q", "j2.w"]
    assert cm.report["differentiated_equations"], "the rod constraints are differentiated"


def test_double_pendulum_matches_the_lagrange_equations(pendulum_run):
    _, res = pendulum_run
    sol = solve_ivp(double_pendulum_rhs, (0.0, T_END), [math.pi / 2, 0.0, 0.0, 0.0],
                    t_eval=res.t, method="DOP853", rtol=1e-13, atol=1e-13)
    a1 = res["j1.q"]
    a2 = res["j1.q"] + res["j2.q"]          # joint 2 is relative
    assert np.max(np.abs(a1 - sol.y[0])) < 1e-6
    assert np.max(np.abs(a2 - sol.y[1])) < 1e-6
    # positions follow the angles
    np.testing.assert_allclose(res["m2.frame.x"], np.sin(a1) + np.sin(a2), atol=1e-9)
    np.testing.assert_allclose(res["m2.frame.y"], -np.cos(a1) - np.cos(a2), atol=1e-9)


def test_double_pendulum_matches_the_equation_model_component(pendulum_run):
    _, res = pendulum_run
    eq = mt.simulate(mech.DoublePendulumLagrange(), T_END, t_out=res.t, **TIGHT)
    assert np.max(np.abs(res["j1.q"] - eq["a1"])) < 1e-6
    assert np.max(np.abs(res["j1.q"] + res["j2.q"] - eq["a2"])) < 1e-6


def test_double_pendulum_conserves_energy(pendulum_run):
    _, res = pendulum_run
    e = res["m1.E_kin"] + res["m2.E_kin"] + res["m1.E_pot"] + res["m2.E_pot"]
    e0 = double_pendulum_energy(math.pi / 2, 0.0, 0.0, 0.0)
    assert e[0] == pytest.approx(e0, abs=1e-12)
    assert np.max(np.abs(e - e0)) / abs(e0) < 1e-8


def test_compound_pendulum_small_oscillation_period():
    """A rigid body (m, J about its centre, centre at distance l below the pivot):
    omega^2 = m g l / (J + m l^2) for small angles; the period is checked against the
    log's zero crossings of the angle."""
    m_, j_, l_, q0 = 2.0, 0.05, 0.4, 1e-3
    s = mt.System("compound")
    w = s.add("world", mb.World())
    joint = s.add("joint", mb.Revolute(q=q0))
    body = s.add("body", mb.Body(m=m_, J=j_, rcm_y=-l_))
    s.connect(w.frame, joint.frame_a)
    s.connect(joint.frame_b, body.frame_a)
    omega = math.sqrt(m_ * G_STANDARD * l_ / (j_ + m_ * l_ ** 2))
    t = np.linspace(0.0, 3.0, 3001)
    res = mt.simulate(s, 3.0, t_out=t, rtol=1e-11, atol=1e-13)
    # the small-angle solution q0 cos(omega t); the nonlinearity is O(q0^3)
    np.testing.assert_allclose(res["joint.q"], q0 * np.cos(omega * t), atol=1e-8)
    # the body's centre of mass hangs at distance l from the pivot
    np.testing.assert_allclose(np.hypot(res["body.x"], res["body.y"]), l_, atol=1e-12)


def test_rod_tension_from_the_force_sensor_is_m_g_cos_plus_m_l_w2():
    """Single pendulum with a ForceSensor between rod and mass: the sensor measures the
    force the rod exerts on the mass; along the rod it is the tension
    T = m g cos(a) + m l w^2 (Newton's law in the radial direction)."""
    m_, l_ = 1.5, 0.8
    s = mt.System("sensed")
    w = s.add("world", mb.World())
    joint = s.add("joint", mb.Revolute(q=1.0))
    rod = s.add("rod", mb.RigidTransform(ry=-l_))
    fs = s.add("fs", mb.ForceSensor())
    mass = s.add("mass", mb.PointMass(m=m_))
    pos = s.add("pos", mb.PositionSensor())
    vel = s.add("vel", mb.VelocitySensor())
    acc = s.add("acc", mb.AccelerationSensor())
    s.connect(w.frame, joint.frame_a)
    s.connect(joint.frame_b, rod.frame_a)
    s.connect(rod.frame_b, fs.frame_a)
    s.connect(fs.frame_b, mass.frame, pos.frame, vel.frame, acc.frame)
    res = mt.simulate(s, 2.0, rtol=1e-11, atol=1e-12)
    a, wq = res["joint.q"], res["joint.w"]
    tension = m_ * G_STANDARD * np.cos(a) + m_ * l_ * wq ** 2
    # unit vector from the mass to the pivot: (-sin a, cos a)
    along = res["fs.fx"] * -np.sin(a) + res["fs.fy"] * np.cos(a)
    np.testing.assert_allclose(along, tension, atol=1e-8)
    across = res["fs.fx"] * np.cos(a) + res["fs.fy"] * np.sin(a)
    assert np.max(np.abs(across)) < 1e-8, "a massless rod pulls only along itself"
    np.testing.assert_allclose(res["pos.x"], l_ * np.sin(a), atol=1e-10)
    np.testing.assert_allclose(res["pos.y"], -l_ * np.cos(a), atol=1e-10)
    np.testing.assert_allclose(res["vel.vx"], l_ * np.cos(a) * wq, atol=1e-9)
    # tangential + centripetal acceleration, with a'' = -g/l sin a
    alpha = -G_STANDARD / l_ * np.sin(a)
    ax = l_ * (np.cos(a) * alpha - np.sin(a) * wq ** 2)
    ay = l_ * (np.sin(a) * alpha + np.cos(a) * wq ** 2)
    np.testing.assert_allclose(res["acc.ax"], ax, atol=1e-8)
    np.testing.assert_allclose(res["acc.ay"], ay, atol=1e-8)
