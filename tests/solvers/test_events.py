"""Events: relations become modes whose switching instants the solver locates."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import electrical as el

A, F, VF, R, RON, GOFF = 5.0, 50.0, 0.6, 100.0, 0.01, 1e-8


def rectifier():
    m = mt.System("rectifier")
    s = m.add("sine", blocks.Sine(amplitude=A, f=F))
    v = m.add("src", el.ControlledVoltageSource())
    d = m.add("d", el.Diode(Vf=VF, Ron=RON, Goff=GOFF))
    r = m.add("r", el.Resistor(R=R))
    g = m.add("g", el.ElectricalReference())
    m.connect(s.y, v.u)
    m.connect(v.p, d.p)
    m.connect(d.n, r.p)
    m.connect(r.n, v.n, g.port)
    return m


def switching_times():
    # blocking: v_d = Vs/(1 + R*Goff); the diode switches where v_d = Vf
    vs = VF * (1 + R * GOFF)
    t_on = np.arcsin(vs / A) / (2 * np.pi * F)
    t_off = 1 / (2 * F) - t_on
    return t_on, t_off


@pytest.mark.parametrize("which", ["on", "off"])
def test_diode_switching_instants_are_located_to_1e_9_s(which):
    t_on, t_off = switching_times()
    cm = mt.compile_model(rectifier())
    t_stop = (t_on + t_off) / 2 if which == "on" else (t_off + 1 / F) / 2
    res = mt.simulate(cm, t_stop, rtol=1e-10, atol=1e-12)
    expected = t_on if which == "on" else t_off
    assert abs(res.event_times["d"] - expected) < 1e-9
    assert res.stats.events == {"d": 1 if which == "on" else 2}


def test_rectified_current_follows_the_conducting_branch():
    t_on, t_off = switching_times()
    res = mt.simulate(rectifier(), 1 / F, rtol=1e-10, atol=1e-12,
                      t_out=np.linspace(0, 1 / F, 2001))
    vs = A * np.sin(2 * np.pi * F * res.t)
    conducting = (res.t > t_on + 1e-6) & (res.t < t_off - 1e-6)
    i_on = (vs - VF + GOFF * VF * RON) / (R + RON)
    np.testing.assert_allclose(res["r.i"][conducting], i_on[conducting], rtol=1e-9)
    blocking = (res.t < t_on - 1e-6) | (res.t > t_off + 1e-6)
    np.testing.assert_allclose(res["r.i"][blocking],
                               GOFF * vs[blocking] / (1 + R * GOFF), atol=1e-15)
    assert set(np.unique(res["d.on"])) == {0.0, 1.0}


def test_pulse_source_edges_are_events():
    m = mt.System("pulse")
    p = m.add("p", blocks.Pulse(amplitude=1.0, period=1e-3, width=0.25, delay=0.0))
    v = m.add("src", el.ControlledVoltageSource())
    r = m.add("r", el.Resistor(R=1.0))
    c = m.add("c", el.Capacitor(C=1e-4))
    g = m.add("g", el.ElectricalReference())
    m.connect(p.y, v.u)
    m.connect(v.p, r.p)
    m.connect(r.n, c.p)
    m.connect(c.n, v.n, g.port)
    res = mt.simulate(m, 10e-3, rtol=1e-9, atol=1e-12)
    # two edges per period over 10 periods (the first rising edge is at t = 0)
    assert sum(res.stats.events.values()) in (19, 20)
    # the capacitor integrates the duty cycle: its mean charge current is zero, and the
    # exact solution of this linear circuit piecewise gives the final value
    tau = 1e-4
    v_c = 0.0
    for k in range(10):
        v_c = 1 + (v_c - 1) * np.exp(-0.25e-3 / tau)
        v_c = v_c * np.exp(-0.75e-3 / tau)
    assert abs(res.final("c.v") - v_c) < 1e-7


def test_sundials_solvers_refuse_models_with_events_instead_of_missing_them():
    with pytest.raises(mt.errors.SimulationError, match=r"cannot locate the events of .*d.*"
                                                        r"rosenbrock"):
        mt.simulate(rectifier(), 0.01, solver="cvodes")


def test_logged_values_equal_a_direct_evaluation_across_chunks():
    from mechatron.solvers.logging import chunk_size
    cm = mt.compile_model(rectifier())
    t = np.linspace(0, 1 / F, 3 * chunk_size(len(cm.names)) + 5)
    res = mt.simulate(cm, 1 / F, rtol=1e-10, atol=1e-12, t_out=t)
    vs = A * np.sin(2 * np.pi * F * res.t)
    np.testing.assert_allclose(res["sine.y"], vs, atol=1e-12)
    np.testing.assert_allclose(res["src.v"], vs, atol=1e-12)
