"""Drive sensors on a shaft turning at constant speed: the incremental encoder's counts,
quantized angle and speed at each read-out against floor(phi cpr / 2 pi) computed here;
the Hall sensors' six states per electrical revolution and their edges."""

import numpy as np

import mechatron as mt
from mechatron.library import rotational as rot


def spinning(sensor, w0):
    m = mt.System("shaft")
    j = m.add("j", rot.Inertia(J=1e-3, w=w0))
    m.add("s", sensor)
    g = m.add("g", rot.RotationalReference())
    m.connect(j.port, sensor.A)
    m.connect(sensor.B, g.port)
    return m


def test_incremental_encoder_counts_angle_and_speed():
    W0, CPR, TS = 37.3, 1000, 1e-3
    n = 40
    t = (np.arange(n) + 0.5) * TS           # between read-outs: the values of tick k
    res = mt.simulate(spinning(rot.IncrementalEncoder(cpr=CPR, Ts=TS), W0), n * TS,
                      t_out=t, rtol=1e-11, atol=1e-13)
    tk = np.arange(n) * TS
    counts = np.floor(W0 * tk * CPR / (2 * np.pi))
    np.testing.assert_array_equal(res["s.count"], counts)
    np.testing.assert_allclose(res["s.Phi"], 2 * np.pi * counts / CPR, rtol=1e-14)
    speed = np.diff(np.concatenate([[0.0], counts])) * 2 * np.pi / (CPR * TS)
    np.testing.assert_allclose(res["s.W"], speed, rtol=1e-12, atol=1e-12)
    # quantization: angle error within one count, speed within one count per period
    assert np.all((W0 * tk - res["s.Phi"] >= -1e-12)
                  & (W0 * tk - res["s.Phi"] < 2 * np.pi / CPR))
    assert np.all(np.abs(res["s.W"][1:] - W0) <= 2 * np.pi / (CPR * TS))
    # it takes no torque: the shaft keeps its speed
    np.testing.assert_allclose(res["j.w"], W0, rtol=1e-12)


def test_hall_sensors_six_states_per_electrical_revolution():
    W0, P, TH0 = 10.0, 4, 0.3
    period = 2 * np.pi / (P * W0)             # one electrical revolution
    n_rev = 3
    # the middle of each sixth, where no edge is near
    edges = (np.arange(-1, 6 * n_rev + 2) * np.pi / 3 - TH0) / (P * W0)
    mids = 0.5 * (edges[:-1] + edges[1:])
    mids = mids[(mids > 0) & (mids < n_rev * period)]
    res = mt.simulate(spinning(rot.HallSensor(p=P, theta_0=TH0), W0), n_rev * period,
                      t_out=mids, rtol=1e-11, atol=1e-13)
    theta = P * W0 * mids + TH0
    for name, shift in (("h_a", 0.0), ("h_b", -2 * np.pi / 3), ("h_c", 2 * np.pi / 3)):
        np.testing.assert_array_equal(res[f"s.{name}"], (np.sin(theta + shift) > 0) * 1.0)
    states = {(a, b, c) for a, b, c in zip(res["s.h_a"], res["s.h_b"], res["s.h_c"])}
    assert len(states) == 6 and (0, 0, 0) not in states and (1, 1, 1) not in states
