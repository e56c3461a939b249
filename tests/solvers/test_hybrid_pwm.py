"""A 10 kHz PWM driving the DC motor for 1 s: 20,000 switching events handled inside the
integrator (no Python per event); the mean current equals the averaged model's."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import blocks
from mechatron.models.dc_motor_pwm import pwm_motor

V, R, L, K, J, B = 19.2, 7.1, 3.408e-4, 0.151, 4.8e-6, 1.236e-4
F_PWM, DUTY = 10e3, 0.5


def motor(averaged: bool) -> mt.System:
    return pwm_motor(averaged, V=V, R=R, L=L, k=K, J=J, B=B, duty=DUTY, f_pwm=F_PWM)


@pytest.fixture(scope="module")
def runs():
    pwm = mt.simulate(motor(False), 1.0, t_out=np.linspace(0, 1, 101))
    avg = mt.simulate(motor(True), 1.0, t_out=np.linspace(0, 1, 101), rtol=1e-9,
                      atol=1e-12)
    return pwm, avg


def test_pwm_switches_twice_per_period_for_a_second(runs):
    pwm, _ = runs
    # 20,000 switching edges (10,000 falling edges and 9,999 rising ones after the one at
    # t = 0) plus 10,000 sample ticks that latch the duty: every one an event of 'pwm'
    n = int(F_PWM)
    assert pwm.stats.events == {"pwm": n + n + (n - 1)}
    assert pwm.stats.solver == "erk"


def test_mean_current_equals_the_averaged_models_within_one_percent(runs):
    pwm, avg = runs
    mean_pwm, mean_avg = pwm.final("charge.y"), avg.final("charge.y")   # over 1 s
    assert mean_avg > 0.05
    assert mean_pwm == pytest.approx(mean_avg, rel=1e-2)
    # the speed (a low-pass of the current) agrees as well, and reaches the analytic
    # steady state of the averaged drive k DUTY V / (R B + k^2)
    assert pwm.final("j.w") == pytest.approx(avg.final("j.w"), rel=1e-2)
    assert avg.final("j.w") == pytest.approx(K * DUTY * V / (R * B + K ** 2), rel=1e-4)


def test_pwm_duty_is_latched_each_period():
    m = mt.System("pwm_ramp")
    duty = m.add("duty", blocks.Ramp(slope=250.0))      # 0 -> 1 over 4 ms
    pwm = m.add("pwm", blocks.PWM(Ts=1e-3))
    m.connect(duty.y, pwm.u)
    t = np.linspace(0, 5e-3, 50001)
    res = mt.simulate(m, 5e-3, t_out=t)
    # period k is on for duty(t_k) * Ts = 0.25 k ms (clamped to a full period)
    for k in range(5):
        inside = (t >= k * 1e-3) & (t < (k + 1) * 1e-3)
        on_time = np.sum(res["pwm.y"][inside] > 0.5) * (t[1] - t[0])
        assert on_time == pytest.approx(min(0.25 * k, 1.0) * 1e-3, abs=2e-7)
