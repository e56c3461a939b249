"""Speed and position control of the seed's DC motor: the current stays within its 3 A
limit, the loops settle on the reference, and the closed loop matches an independent
SciPy implementation of the same equations."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechatron as mt
from mechatron.models.dc_motor_control import DCMotorSpeedPIVoltage

R, L, K, J, B = 7.1, 3.408e-4, 0.151, 4.8e-6, 1.236e-4


def run(name, **params):
    entry = mt.models.get(name)
    t = np.linspace(0, entry.experiment.t_stop, 4001)
    res = mt.simulate(entry.build(**params), entry.experiment.t_stop, rtol=1e-9,
                      atol=1e-11, t_out=t)
    return entry, res


@pytest.mark.parametrize("w_set", [100.0, -140.0])
def test_speed_loop_limits_the_current_and_settles(w_set):
    entry, res = run("dc_motor_speed_pi", w_set=w_set)
    assert np.max(np.abs(res["i"])) <= 3.0
    assert res.final("w") == pytest.approx(w_set, rel=1e-4)
    # the last 20 ms stay within 0.1% of the reference
    late = res.t > res.t[-1] - 0.02
    assert np.max(np.abs(res["w"][late] - w_set)) < 1e-3 * abs(w_set)


def test_a_large_step_saturates_the_current_reference():
    """A stiff loop asks for far more than 3 A: the limiter is active (the reference sits
    at the limit) and the current stays within it."""
    entry, res = run("dc_motor_speed_pi", w_set=150.0, Kp=0.08, V_max=60.0)
    assert np.max(np.abs(res["i_ref"])) == pytest.approx(3.0, rel=1e-3)
    assert np.max(np.abs(res["i"])) <= 3.0
    assert res.final("w") == pytest.approx(150.0, rel=0.05)


def test_position_loop_settles_on_one_turn():
    entry, res = run("dc_motor_position_pi")
    assert np.max(np.abs(res["i"])) <= 3.0
    assert res.final("phi") == pytest.approx(2 * np.pi, rel=1e-4)
    assert abs(res.final("w")) < 0.01
    assert np.max(res["w"]) <= 150.0 * 1.001          # the speed reference limit


def test_voltage_structure_against_scipy():
    """The seed's PI-to-voltage loop, re-implemented by hand with solve_ivp (BDF)."""
    Kp, Ki, V_max, T_aw, w_set = 0.05, 5.0, 24.0, 2e-3, 100.0

    def sat(x, a):
        e = 1e-3 * a
        return 0.5 * (np.sqrt((x + a) ** 2 + e ** 2) - np.sqrt((x - a) ** 2 + e ** 2))

    def rhs(t, y):
        i, w, x = y
        u = Kp * (w_set - w) + Ki * x
        v = sat(u, V_max)
        return [(v - R * i - K * w) / L, (K * i - B * w) / J,
                (w_set - w) + (v - u) / (Kp * T_aw)]
    t = np.linspace(0, 0.05, 501)
    ref = solve_ivp(rhs, (0, 0.05), [0, 0, 0], method="BDF", t_eval=t, rtol=1e-10,
                    atol=1e-12)
    res = mt.simulate(DCMotorSpeedPIVoltage(), 0.05, rtol=1e-10, atol=1e-12, t_out=t)
    np.testing.assert_allclose(res["w"], ref.y[1], rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(res["i"], ref.y[0], rtol=1e-6, atol=1e-7)
