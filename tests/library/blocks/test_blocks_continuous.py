"""Continuous blocks against scipy.signal and analytic solutions."""

import numpy as np
import pytest
from scipy import signal

import mechatron as mt
from mechatron.library import blocks

T = np.linspace(0, 5, 501)


def step_response(block, t=T, **sim):
    m = mt.System("resp")
    s = m.add("s", blocks.Step(t_step=0.0))
    m.add("g", block)
    m.connect(s.y, block.u)
    return mt.simulate(m, t[-1], t_out=t, rtol=1e-12, atol=1e-14, **sim)


@pytest.mark.parametrize("num, den", [
    ([1.0], [1.0, 1.0]),
    ([2.0, 1.0], [1.0, 0.8, 4.0]),
    ([1.0, 0.0, 3.0], [2.0, 3.0, 5.0, 1.0]),
    ([0.5, 1.0, 2.0], [1.0, 2.0, 3.0]),         # biproper: direct feedthrough
])
def test_transfer_function_step_response_matches_scipy(num, den):
    res = step_response(blocks.TransferFunction(num=num, den=den))
    _, y = signal.step((num, den), T=T)
    # the step is applied at t = 0 (the response is taken just after)
    np.testing.assert_allclose(res["g.y"][1:], y[1:], rtol=0, atol=1e-8)


def test_state_space_step_response_matches_scipy():
    a = [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-2.0, -3.5, -2.5]]
    b, c, d = [0.0, 0.5, 1.0], [1.0, -0.3, 0.2], 0.1
    res = step_response(blocks.StateSpace(A=a, B=b, C=c, D=d))
    _, y = signal.step((np.array(a), np.array(b)[:, None], np.array(c)[None, :], [[d]]),
                       T=T)
    np.testing.assert_allclose(res["g.y"][1:], y[1:], rtol=0, atol=1e-8)


def test_first_and_second_order_blocks_match_analytic_responses():
    r1 = step_response(blocks.FirstOrder(k=2.0, T=0.5))
    np.testing.assert_allclose(r1["g.y"], 2.0 * (1 - np.exp(-T / 0.5)), atol=1e-9)
    w, d = 3.0, 0.2
    r2 = step_response(blocks.SecondOrder(k=1.5, w=w, D=d))
    _, y = signal.step(([1.5 * w ** 2], [1.0, 2 * d * w, w ** 2]), T=T)
    np.testing.assert_allclose(r2["g.y"], y, atol=1e-8)


def test_filtered_derivative_of_a_ramp_approaches_its_slope():
    m = mt.System("der")
    r = m.add("r", blocks.Ramp(slope=3.0))
    d = m.add("d", blocks.Derivative(T=0.01))
    m.connect(r.y, d.u)
    res = mt.simulate(m, 0.1, t_out=np.linspace(0, 0.1, 11), rtol=1e-10, atol=1e-12)
    # u = 3t: x' = (3t - x)/T gives y = (u - x)/T = 3 (1 - exp(-t/T))
    np.testing.assert_allclose(res["d.y"], 3.0 * (1 - np.exp(-res.t / 0.01)), atol=1e-7)


def test_integrator_limits_and_reset():
    m = mt.System("ints")
    s = m.add("s", blocks.Sine(amplitude=1.0, f=0.25))
    li = m.add("li", blocks.LimitedIntegrator(k=2.0, y_min=-0.5, y_max=0.8))
    rst = m.add("rst", blocks.Step(t_step=1.5))
    ri = m.add("ri", blocks.ResetIntegrator(k=1.0, y_reset=-1.0))
    m.connect(s.y, li.u, ri.u)
    m.connect(rst.y, ri.reset)
    t = np.linspace(0, 4, 4001)
    res = mt.simulate(m, 4.0, t_out=t, rtol=1e-10, atol=1e-12)
    # free: y = (2/(pi/2)) (1 - cos(pi t/2)) reaches 0.8 at cos = 1 - 0.2 pi
    t_hit = np.arccos(1 - 0.8 * np.pi / 4) / (np.pi / 2)
    free = t < t_hit - 1e-6
    np.testing.assert_allclose(res["li.y"][free],
                               4 / np.pi * (1 - np.cos(np.pi * t[free] / 2)), atol=1e-8)
    held = (t > t_hit + 1e-6) & (t < 2.0 - 1e-6)       # until the input turns negative
    np.testing.assert_allclose(res["li.y"][held], 0.8, atol=1e-9)
    # leaves at t = 2: y = 0.8 + (4/pi)(cos(pi*2/2) - cos(pi t/2)), down to y_min
    after = t > 2.0 + 1e-6
    expect = np.maximum(0.8 + 4 / np.pi * (-1 - np.cos(np.pi * t[after] / 2)), -0.5)
    np.testing.assert_allclose(res["li.y"][after], expect, atol=1e-8)
    # reset integrator: (2/pi)(1 - cos(pi t/2)) until 1.5 s, then -1 + the integral since
    before = t < 1.5 - 1e-9
    np.testing.assert_allclose(res["ri.y"][before],
                               2 / np.pi * (1 - np.cos(np.pi * t[before] / 2)), atol=1e-8)
    later = t > 1.5 + 1e-9
    since = np.cos(np.pi * 1.5 / 2) - np.cos(np.pi * t[later] / 2)
    np.testing.assert_allclose(res["ri.y"][later], -1 + 2 / np.pi * since, atol=1e-8)
    assert abs(res.event_times["rst"] - 1.5) < 1e-12


def pid_open_loop(kb, e0=1.0, e1=0.5, t1=2.0):
    m = mt.System("aw")
    e = m.add("e", blocks.Step(t_step=t1, initial=e0, final=-e1))
    pid = m.add("pid", blocks.PID(Kp=0.5, Ki=4.0, y_max=1.0, y_min=-10.0, Kb=kb))
    m.connect(e.y, pid.u)
    return m


def test_pid_anti_windup_keeps_the_integrator_bounded_and_recovers_on_time():
    kp, ki, y_max, e0, e1, t1 = 0.5, 4.0, 1.0, 1.0, 0.5, 2.0
    kb = 2.0
    res = mt.simulate(pid_open_loop(kb), 3.0, rtol=1e-11, atol=1e-12,
                      t_out=np.linspace(0, 3.0, 3001))
    # the output saturates at t_s = (y_max - Kp e0)/(Ki e0); from there, with a constant
    # error, dI/dt = Ki e0 + Kb (y_max - Kp e0 - I): I relaxes to I* (bounded)
    t_s = (y_max - kp * e0) / (ki * e0)
    i_star = y_max - kp * e0 + ki * e0 / kb
    sat = (res.t > t_s) & (res.t <= t1)
    i_exact = i_star + (ki * e0 * t_s - i_star) * np.exp(-kb * (res.t[sat] - t_s))
    np.testing.assert_allclose(res["pid.I"][sat], i_exact, rtol=1e-8)
    assert np.max(res["pid.I"]) <= i_star
    # after the error turns to -e1, J = I - y_max follows dJ/dt = -Ki e1 - Kb (J - Kp e1)
    # while saturated (v - y_max = J - Kp e1 > 0); the output recovers when J = Kp e1
    j0 = i_exact[-1] - y_max
    j_inf, j_exit = kp * e1 - ki * e1 / kb, kp * e1
    tau = -np.log((j_exit - j_inf) / (j0 - j_inf)) / kb
    assert res.event_times["pid"] - t1 == pytest.approx(tau, abs=1e-9)
    # without anti-windup the integrator winds up to Ki e0 t1 and recovers much later
    wound = mt.simulate(pid_open_loop(0.0), 6.0, rtol=1e-11, atol=1e-12)
    tau0 = (ki * e0 * t1 - y_max - kp * e1) / (ki * e1)
    assert wound.event_times["pid"] - t1 == pytest.approx(tau0, abs=1e-9)
    assert tau0 > 3 * tau
