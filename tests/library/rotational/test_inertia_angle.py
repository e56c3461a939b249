"""``Inertia.phi`` and ``Mass.s`` (MSL's): states only when asked for, so the models that
do not use them compile to the same size; when asked, the angle and the position of a
body under a constant load follow the kinematics exactly."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import rotational as rot
from mechatron.library import translational as tr


def spun(inertia):
    m = mt.System("spin")
    m.add("j", inertia)
    m.add("tq", rot.ConstantTorque(T=2.0))
    m.add("fixed", rot.RotationalReference())
    m.connect(m.tq.A, m.j.port)
    m.connect(m.tq.B, m.fixed.port)
    return m


def pushed(mass):
    m = mt.System("push")
    m.add("m", mass)
    m.add("f", tr.ConstantForce(F=3.0))
    m.add("fixed", tr.TranslationalReference())
    m.connect(m.f.A, m.m.port)
    m.connect(m.f.B, m.fixed.port)
    return m


def test_the_angle_is_a_state_only_when_asked_for():
    assert type(rot.Inertia()) is rot.Inertia
    assert type(rot.Inertia(use_phi=True)) is rot.InertiaWithAngle
    assert type(rot.Inertia(phi=1.0)) is rot.InertiaWithAngle
    plain = mt.compile_model(spun(rot.Inertia(J=0.5, w=1.0)))
    angled = mt.compile_model(spun(rot.Inertia(J=0.5, w=1.0, use_phi=True)))
    assert plain.state_names == ["j.w"]
    assert sorted(angled.state_names) == ["j.phi", "j.w"]


def test_angle_of_a_uniformly_accelerated_inertia():
    t = np.linspace(0.0, 2.0, 21)
    res = mt.simulate(spun(rot.Inertia(J=0.5, w=1.0, phi=0.3)), 2.0, t_out=t, rtol=1e-10,
                      atol=1e-12)
    # torque 2 N*m on 0.5 kg*m^2: alpha = 4 rad/s^2
    np.testing.assert_allclose(res["j.phi"], 0.3 + 1.0 * t + 2.0 * t ** 2, rtol=1e-9)


def test_position_of_a_uniformly_accelerated_mass():
    assert type(tr.Mass()) is tr.Mass
    assert type(tr.Mass(s=0.0)) is tr.MassWithPosition
    assert mt.compile_model(pushed(tr.Mass(m=2.0, v=0.5))).state_names == ["m.v"]
    t = np.linspace(0.0, 1.0, 11)
    res = mt.simulate(pushed(tr.Mass(m=2.0, v=0.5, use_s=True)), 1.0, t_out=t, rtol=1e-10,
                      atol=1e-12)
    np.testing.assert_allclose(res["m.s"], 0.5 * t + 0.75 * t ** 2, rtol=1e-9, atol=1e-12)
    with pytest.raises(TypeError, match="unexpected keyword 'x'"):
        tr.Mass(x=1.0)
