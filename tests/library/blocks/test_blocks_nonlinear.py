"""Nonlinear blocks: switching instants against analytic solutions, staircases and
limits against NumPy, and chattering detection."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import thermal as th

C, G, TA, P, T_LO, T_HI = 10.0, 10.0, 293.15, 500.0, 300.0, 305.0


def thermostat(T0=TA):
    m = mt.System("thermostat")
    mass = m.add("mass", th.HeatCapacitor(C=C, T=T0))
    cond = m.add("cond", th.ThermalConductor(G=G))
    amb = m.add("amb", th.FixedTemperature(T=TA))
    heat = m.add("heater", th.PrescribedHeatFlow())
    sens = m.add("sensor", th.TemperatureSensor())
    # on above T_HI means heater off (0 W); off below T_LO means heater on (P)
    relay = m.add("relay", blocks.Relay(on_point=T_HI, off_point=T_LO, on_value=0.0,
                                        off_value=P))
    m.connect(mass.port, cond.A, heat.port, sens.port)
    m.connect(cond.B, amb.port)
    m.connect(sens.T, relay.u)
    m.connect(relay.y, heat.Q_in)
    return m


def switching_times(n):
    """C dT/dt = Q - G (T - TA): exponential segments towards TA + P/G (heating) and TA
    (cooling), tau = C/G; each switching time from the logarithm of the ratio."""
    tau, t_hot = C / G, TA + P / G
    first = tau * np.log((t_hot - TA) / (t_hot - T_HI))
    cool = tau * np.log((T_HI - TA) / (T_LO - TA))
    heat = tau * np.log((t_hot - T_LO) / (t_hot - T_HI))
    steps = [first] + [cool if k % 2 == 0 else heat for k in range(n - 1)]
    return np.cumsum(steps)


def test_relay_thermostat_switches_at_the_analytic_times():
    cm = mt.compile_model(thermostat())
    times = switching_times(5)
    for k in range(4):
        res = mt.simulate(cm, (times[k] + times[k + 1]) / 2, rtol=1e-12, atol=1e-10)
        assert abs(res.event_times["relay"] - times[k]) < 1e-9
        heater_on = k % 2 == 1
        assert res.final("heater.Q_in") == (P if heater_on else 0.0)
    # the temperature stays in the hysteresis band after the first switch
    res = mt.simulate(cm, times[4], rtol=1e-10, atol=1e-10,
                      t_out=np.linspace(times[0] + 1e-6, times[4], 500))
    assert T_LO - 1e-6 <= res["mass.T"].min() and res["mass.T"].max() <= T_HI + 1e-6


def test_relay_starts_on_when_its_input_is_above_the_on_point():
    res = mt.simulate(thermostat(T0=310.0), 0.01, rtol=1e-10)
    assert res["relay.q"][0] == 1.0 and res["heater.Q_in"][0] == 0.0


def sine_through(block, f=1.0, amp=2.0, t=np.linspace(0, 1, 1001)):
    m = mt.System("nl")
    s = m.add("s", blocks.Sine(amplitude=amp, f=f))
    m.add("b", block)
    m.connect(s.y, block.u)
    return mt.simulate(m, t[-1], t_out=t, rtol=1e-10, atol=1e-12), amp * np.sin(
        2 * np.pi * f * t)


def test_saturation_and_dead_zone_follow_their_static_curves():
    res, u = sine_through(blocks.Saturation(lower=-0.5, upper=1.2))
    np.testing.assert_allclose(res["b.y"], np.clip(u, -0.5, 1.2), atol=1e-12)
    res, u = sine_through(blocks.DeadZone(start=-0.3, end=0.7))
    expect = np.where(u > 0.7, u - 0.7, np.where(u < -0.3, u + 0.3, 0.0))
    np.testing.assert_allclose(res["b.y"], expect, atol=1e-12)
    assert res.stats.events["b"] == 4      # enter/leave each side once per period


def test_quantizer_is_a_staircase_with_an_event_per_step():
    t = np.linspace(0, 1, 2001)
    res, u = sine_through(blocks.Quantizer(q=0.25), t=t)
    # away from the thresholds (n + 1/2) q the output is q round(u / q)
    frac = np.abs(u / 0.25 - np.floor(u / 0.25) - 0.5)
    away = frac > 1e-6
    np.testing.assert_allclose(res["b.y"][away], 0.25 * np.floor(u[away] / 0.25 + 0.5),
                               atol=1e-12)
    # levels -8 .. 8 over a period of amplitude 2: 8 up, 16 down, 8 up; t = 1 ends on the
    # threshold at 0
    assert res.stats.events["b"] >= 31


def test_round_converts_to_integer_signal():
    res, u = sine_through(blocks.Round(), amp=3.0)
    assert set(np.unique(res["b.y"])) <= {-3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0}
    away = np.abs(u - np.floor(u) - 0.5) > 1e-6
    np.testing.assert_allclose(res["b.y"][away], np.floor(u[away] + 0.5), atol=0)


def test_rate_limiter_ramps_at_the_limit_after_a_step():
    m = mt.System("rl")
    s = m.add("s", blocks.Step(t_step=0.1, final=1.0))
    rl = m.add("rl", blocks.RateLimiter(rising=2.0, falling=-1.0, T=1e-3))
    m.connect(s.y, rl.u)
    t = np.linspace(0, 1, 1001)
    res = mt.simulate(m, 1.0, t_out=t, rtol=1e-10, atol=1e-12)
    # slope 2 until (u - y)/T < 2, i.e. y = 1 - 2T; then exponential with time constant T
    t_knee = 0.1 + (1 - 2e-3) / 2.0
    ramp = (t > 0.1) & (t < t_knee)
    np.testing.assert_allclose(res["rl.y"][ramp], 2.0 * (t[ramp] - 0.1), atol=1e-9)
    tail = t > t_knee
    np.testing.assert_allclose(res["rl.y"][tail],
                               1 - 2e-3 * np.exp(-(t[tail] - t_knee) / 1e-3), atol=1e-9)


def test_backlash_holds_its_output_while_the_input_turns_inside_the_play():
    res, u = sine_through(blocks.Backlash(width=0.4, T=1e-5), amp=1.0,
                          t=np.linspace(0, 1, 4001))
    y = res["b.y"]
    # dragged: y = u -/+ width/2 (lag T u' <= 1e-4); at rest after each turn until the
    # input has crossed the play (u = max - 0.4 at the top)
    t = res.t
    up = (t > 0.1) & (t < 0.25 - 1e-3)
    np.testing.assert_allclose(y[up], u[up] - 0.2, atol=1e-4)
    t_release = 0.5 - np.arcsin(0.6) / (2 * np.pi)          # u = 1 - 0.4 on the way down
    held = (t > 0.25 + 1e-3) & (t < t_release - 1e-3)
    np.testing.assert_allclose(y[held], 0.8, atol=1e-4)
    down = (t > t_release + 1e-2) & (t < 0.75 - 1e-3)
    np.testing.assert_allclose(y[down], u[down] + 0.2, atol=1e-4)


def test_chattering_of_an_ideal_relay_in_a_loop_names_the_component():
    # x' = -sign(x) with the ideal relay of blocks.Sign: after x reaches 0 at t = 1 every
    # switch drives x straight back: a sliding mode (infinitely many events)
    m = mt.System("chatter")
    sw = m.add("ideal_relay", blocks.Sign())
    g = m.add("g", blocks.Gain(k=-1.0))
    i = m.add("integ", blocks.Integrator(y=1.0))
    m.connect(i.y, sw.u)
    m.connect(sw.y, g.u)
    m.connect(g.y, i.u)
    with pytest.raises(mt.errors.SimulationError,
                       match=r"chattering at t = 1 s: events at 'ideal_relay'") as err:
        mt.simulate(m, 2.0)
    assert err.value.path == "ideal_relay"


def test_relay_with_hysteresis_in_the_same_loop_does_not_chatter():
    m = mt.System("osc")
    rl = m.add("relay", blocks.Relay(on_point=0.1, off_point=-0.1, on_value=-1.0,
                                     off_value=1.0))
    i = m.add("integ", blocks.Integrator(y=0.0))
    m.connect(i.y, rl.u)
    m.connect(rl.y, i.u)
    res = mt.simulate(m, 2.0, rtol=1e-10, atol=1e-12)
    # a triangle between -0.1 and 0.1 with slope 1: a switch every 0.2 s after the first
    # at t = 0.1
    assert res.stats.events["relay"] >= 9
    assert abs(res.event_times["relay"] - 1.9) < 1e-9
