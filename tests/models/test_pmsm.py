"""PMSM with field-oriented control: current limit, anti-windup and the power balance."""

import numpy as np
import pytest

import mechatron as mt

ENTRY = mt.models.get("pmsm_foc")


@pytest.fixture(scope="module")
def run():
    t = np.linspace(0, 0.2, 4001)
    return mt.simulate(ENTRY.build("dq"), 0.2, rtol=1e-9, atol=1e-10, t_out=t)


def test_acceleration_at_the_current_limit(run):
    p = ENTRY.values()
    i_q, w, t = run["i_q"], run["w"], run.t
    assert np.max(run["iq_ref"]) <= p["i_max"] + 1e-12
    # while the speed PI is saturated the rotor accelerates at the limit torque
    torque = 1.5 * p["p"] * p["psi"] * p["i_max"]
    # saturated (i_q_ref at the limit), after the current loop's 2 ms transient
    mid = (run["iq_ref"] >= p["i_max"] - 1e-12) & (t > 2e-3)
    assert np.count_nonzero(mid) > 20
    accel = np.gradient(w, t)[mid]
    expected = (torque - p["T_load"] - p["B"] * w[mid]) / p["J"]
    np.testing.assert_allclose(accel, expected, rtol=2e-3)
    assert np.allclose(i_q[mid], p["i_max"], rtol=2e-3)


def test_anti_windup_limits_the_integrator_and_the_overshoot(run):
    # back-calculation bleeds the integrator while the speed PI is at the limit
    plain = mt.simulate(ENTRY.build("dq", K_aw=0.0), 0.2, rtol=1e-9, atol=1e-10,
                        t_out=run.t)
    assert np.max(run["x_w"]) < np.max(plain["x_w"])
    assert np.max(run["w"]) < np.max(plain["w"])


def test_steady_state_power_balance():
    p = ENTRY.values()
    res = mt.simulate(ENTRY.build("abc"), 1.0, rtol=1e-9, atol=1e-10)
    i_q, v_q, w, v_d = (res.final(k) for k in ("i_q", "v_q", "w", "v_d"))
    electrical = 1.5 * (v_d * res.final("i_d") + v_q * i_q)      # amplitude-invariant dq
    copper = 1.5 * p["R"] * (res.final("i_d") ** 2 + i_q ** 2)
    mechanical = (p["B"] * w + p["T_load"]) * w
    assert electrical == pytest.approx(copper + mechanical, rel=1e-8)
