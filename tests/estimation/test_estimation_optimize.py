"""Response optimization of the speed PI loop, verified by an independent simulation."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from mechatron.estimation.optimize import (DesignVariable, ResponseProblem, SignalBound,
                                           StepResponse, optimize_response, step_metrics,
                                           verify)
from mechatron.models.dc_motor_control import DCMotorSpeedPIVoltage

R, L, K, J, B = 7.1, 3.408e-4, 0.151, 4.8e-6, 1.236e-4


def test_step_metrics_of_a_first_order_response():
    tau = 0.01
    t = np.linspace(0, 0.2, 200001)
    m = step_metrics(t, 5 * (1 - np.exp(-t / tau)), 0.0, 5.0)
    assert m["rise_time_s"] == pytest.approx(tau * math.log(9), rel=1e-4)
    assert m["settling_time_s"] == pytest.approx(tau * math.log(50), rel=1e-4)
    assert m["overshoot_pct"] == 0.0


def test_envelope_of_a_negative_step():
    req = StepResponse("w", -10.0, initial=0.0, rise_time=1.0, rise_pct=80,
                       overshoot_pct=5, settling_time=2.0, settling_pct=2)
    s, lo, hi = req.envelope(np.array([0.5, 1.5, 2.5]))
    assert s == -1
    np.testing.assert_allclose(lo, [-np.inf, 8.0, 9.8])
    np.testing.assert_allclose(hi, [10.5, 10.5, 10.2])


def scipy_loop(Kp, Ki, t):
    """The PI-to-voltage loop of the seed written by hand, integrated by SciPy (BDF)."""
    V_max, T_aw, w_set = 24.0, 2e-3, 100.0

    def sat(x, a):
        e = 1e-3 * a
        return 0.5 * (np.sqrt((x + a) ** 2 + e ** 2) - np.sqrt((x - a) ** 2 + e ** 2))

    def rhs(_, y):
        i, w, x = y
        u = Kp * (w_set - w) + Ki * x
        v = sat(u, V_max)
        return [(v - R * i - K * w) / L, (K * i - B * w) / J,
                (w_set - w) + (v - u) / (Kp * T_aw)]
    sol = solve_ivp(rhs, (t[0], t[-1]), [0, 0, 0], method="BDF", t_eval=t, rtol=1e-9,
                    atol=1e-11)
    return sol.y[0], sol.y[1]


def test_speed_pi_meets_overshoot_settling_and_current_limit():
    reqs = [StepResponse("w", 100.0, rise_time=0.01, overshoot_pct=5, settling_time=0.025),
            SignalBound("i", -3.0, 3.0)]
    design = [DesignVariable("Kp", 0.05, 1e-4, 1.0), DesignVariable("Ki", 5.0, 0.0, 200.0)]
    prob = ResponseProblem(DCMotorSpeedPIVoltage(), design, reqs, t_stop=0.05,
                           n_points=1001)
    res = optimize_response(prob)
    assert res.success, res.message
    assert res.max_violation_initial > 0 and res.max_violation == 0
    # independent check 1: mechatron.simulate (CVODES) on a fine grid
    check = verify(prob, res.values)
    assert check["all_met"], check["rows"]
    # independent check 2: the equations by hand in SciPy
    t = np.unique(np.concatenate([np.linspace(0, 0.002, 4001), np.linspace(0, 0.05, 5001)]))
    i0, w0 = scipy_loop(0.05, 5.0, t)
    i1, w1 = scipy_loop(res.parameters["Kp"], res.parameters["Ki"], t)
    before = step_metrics(t, w0, 0.0, 100.0)
    after = step_metrics(t, w1, 0.0, 100.0)
    assert after["overshoot_pct"] < 5.0
    assert after["settling_time_s"] < before["settling_time_s"]
    assert after["settling_time_s"] <= 0.025
    assert np.max(np.abs(i1)) <= 3.0
    assert len(res.history) >= 3
