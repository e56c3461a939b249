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


def test_the_inputs_variant_driven_by_the_steps_is_the_table():
    """Voltage inputs at the steps' values and no load: the ``acausal`` table to 1e-9."""
    t = np.linspace(0, 0.1, 51)
    ref = mt.simulate(ENTRY.build("acausal"), 0.1, t_out=t, rtol=1e-11, atol=1e-13)
    cm = mt.compile_model(ENTRY.build("inputs"))
    assert cm.input_names == ["V_x", "tau_x", "V_y", "tau_y"]
    res = mt.simulate(cm, 0.1, t_out=t, rtol=1e-11, atol=1e-13,
                      inputs={"V_x": 19.2, "V_y": 12.0, "tau_x": 0.0, "tau_y": 0.0})
    for path in ENTRY.output_paths("inputs").values():
        np.testing.assert_allclose(res[path], ref[path], rtol=0,
                                   atol=1e-9 * np.abs(ref[path]).max())


def test_load_torque_inputs_slow_each_axis_to_the_analytic_speed():
    """Final speed under a load torque T: (k V - R T) / (R (B + D_load) + k^2)."""
    R, k, B_t = 7.1, 0.151, 1.236e-4 + 5e-5
    res = mt.simulate(ENTRY.build("inputs"), 0.5, rtol=1e-10, atol=1e-12,
                      inputs={"V_x": 12.0, "tau_x": 0.01, "V_y": -6.0, "tau_y": -0.002})
    for ax, V, T in (("x", 12.0, 0.01), ("y", -6.0, -0.002)):
        assert res.final(f"{ax}.load.w") == pytest.approx((k * V - R * T) / (R * B_t + k * k),
                                                         rel=1e-7)
