"""The PWM-fed DC motor's ``inputs`` variant: duty cycle and load torque from outside."""

import numpy as np
import pytest

import mechatron as mt

ENTRY = mt.models.get("dc_motor_pwm")


def test_the_inputs_variant_driven_by_the_fixed_duty_is_the_switched_drive():
    """Duty input at the fixed duty, no load: the ``switched`` drive to 1e-9 (the same
    PWM block latches the same value at the same ticks)."""
    t = np.linspace(0, 0.02, 101)
    kw = dict(t_out=t, rtol=1e-11, atol=1e-13)
    ref = mt.simulate(ENTRY.build("switched", duty=0.3), 0.02, **kw)
    cm = mt.compile_model(ENTRY.build("inputs"))
    assert cm.input_names == ["duty", "tau_load"]
    res = mt.simulate(cm, 0.02, inputs={"duty": 0.3, "tau_load": 0.0}, **kw)
    for path in ENTRY.output_paths("inputs").values():
        np.testing.assert_allclose(res[path], ref[path], rtol=0,
                                   atol=1e-9 * np.abs(ref[path]).max())


def test_a_load_torque_input_lowers_the_mean_current_balance():
    """Over whole periods in the periodic steady state the mean torque balance holds:
    k mean(i) = B mean(w) + T, so the charge over the last 100 periods is
    (B mean(w) + T) / k times their length."""
    p = ENTRY.values()
    T = 0.01
    period = 1 / p["f_pwm"]
    t_end = 0.1
    t = np.linspace(t_end - 100 * period, t_end, 20001)
    res = mt.simulate(ENTRY.build("inputs"), t_end, rtol=1e-10, atol=1e-12, t_out=t,
                      inputs={"duty": 0.6, "tau_load": T})
    q = res["charge.y"][-1] - res["charge.y"][0]
    w_mean = np.trapezoid(res["j.w"], t) / (t[-1] - t[0])
    assert q / (t[-1] - t[0]) == pytest.approx((p["B"] * w_mean + T) / p["k"], rel=1e-5)
