"""The two-axis table: one motor-and-load subsystem used twice, three levels deep, against
the per-axis equations and the analytic final values (the database walk checks the
default experiment too)."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.core.balance import check_balance
from mechatron.models.two_axis import MotorAxis

ENTRY = mt.models.get("two_axis")


def test_axes_follow_their_own_equations_and_parameters():
    t = np.linspace(0, 0.1, 51)
    sub = mt.simulate(ENTRY.build("acausal", V_y=-6.0, J_load=2e-5), 0.1, t_out=t,
                      rtol=1e-11, atol=1e-13)
    ode = mt.simulate(ENTRY.build("ode", V_y=-6.0, J_load=2e-5), 0.1, t_out=t,
                      rtol=1e-11, atol=1e-13)
    for label, path in ENTRY.output_paths("acausal").items():
        np.testing.assert_allclose(sub[path], ode[ENTRY.output_paths("ode")[label]],
                                   atol=1e-9 * max(1.0, np.abs(ode[label]).max()))
    assert sub.final("y.load.w") < 0 < sub.final("x.load.w")


def test_the_rigid_shaft_keeps_one_state_per_axis_and_the_axis_is_balanced():
    cm = mt.compile_model(ENTRY.build("acausal"))
    assert len(cm.state_names) == 4           # i and one shaft speed per axis
    assert check_balance(MotorAxis).balanced


def test_a_load_torque_taken_from_the_axis_parameters():
    # the axis passes J and J_load on: doubling the load inertia doubles nothing but the
    # mechanical time constant, so the final speed stays and the early speed drops
    a = mt.simulate(ENTRY.build("acausal"), 2e-3, rtol=1e-10, atol=1e-12)
    b = mt.simulate(ENTRY.build("acausal", J_load=4e-5), 2e-3, rtol=1e-10, atol=1e-12)
    assert b.final("x.load.w") < a.final("x.load.w")
    assert b.final("x.motor.inertia.w") == b.final("x.load.w")
