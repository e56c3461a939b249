"""Index reduction: rigidly coupled storage elements compile and match analytic answers."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import electrical as el
from mechatron.library import rotational as rot


class GearedInertias(mt.Component):
    """Two inertias rigidly coupled by an ideal gear: index 2 (w1 = ratio * w2)."""

    step = blocks.Step(t_step=0.0, final=2.0)
    src = rot.IdealTorqueSource()
    j1 = rot.Inertia(J=0.1)
    gear = rot.IdealGear(ratio=3)
    j2 = rot.Inertia(J=0.5)
    ref = rot.RotationalReference()

    def equations(self):
        return [mt.connect(self.step.y, self.src.tau_in),
                mt.connect(self.src.A, self.j1.port, self.gear.A),
                mt.connect(self.gear.B, self.j2.port),
                mt.connect(self.src.B, self.ref.port)]


def test_geared_inertias_reduce_to_one_state_and_match_reflected_inertia():
    cm = mt.compile_model(GearedInertias())
    assert cm.nx == 1
    assert cm.report["differentiated_equations"], "the gear constraint must be differentiated"
    res = mt.simulate(cm, 1.0, rtol=1e-10, atol=1e-12)
    j_eq = 0.1 + 0.5 / 3 ** 2          # inertia seen from the input flange
    w1 = 2.0 * res.t / j_eq
    np.testing.assert_allclose(res["j1.w"], w1, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(res["j2.w"], w1 / 3, rtol=1e-8, atol=1e-10)
    # the gear passes power without loss: tau_A*w_A + tau_B*w_B = 0
    p = res["gear.A.tau"] * res["gear.A.w"] + res["gear.B.tau"] * res["gear.B.w"]
    assert np.max(np.abs(p)) < 1e-8 * np.max(np.abs(res["gear.A.tau"] * res["gear.A.w"]))


def test_capacitor_directly_across_a_sine_source_has_i_equal_C_dv_dt():
    m = mt.System("capsine")
    s = m.add("sine", blocks.Sine(amplitude=2.0, f=50.0))
    v = m.add("src", el.ControlledVoltageSource())
    c = m.add("c", el.Capacitor(C=1e-3))
    g = m.add("gnd", el.ElectricalReference())
    m.connect(s.y, v.u)
    m.connect(v.p, c.p)
    m.connect(v.n, c.n, g.port)
    cm = mt.compile_model(m)
    assert cm.nx == 0, "the capacitor voltage is fixed by the source: no state"
    res = mt.simulate(cm, 0.05, rtol=1e-10, atol=1e-12)
    expected = 1e-3 * 2.0 * 2 * np.pi * 50 * np.cos(2 * np.pi * 50 * res.t)
    np.testing.assert_allclose(res["c.i"], expected, atol=1e-12)


def test_two_capacitors_in_parallel_charge_as_their_sum():
    m = mt.System("parallel")
    src = m.add("src", el.DCVoltageSource(V=1.0))
    r1 = m.add("r1", el.Resistor(R=10.0))
    c1 = m.add("c1", el.Capacitor(C=1e-3))
    c2 = m.add("c2", el.Capacitor(C=2e-3))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, r1.p)
    m.connect(r1.n, c1.p, c2.p)
    m.connect(src.n, c1.n, c2.n, g.port)
    cm = mt.compile_model(m)
    assert cm.nx == 1
    res = mt.simulate(cm, 0.1, rtol=1e-10, atol=1e-12)
    tau = 10.0 * 3e-3
    np.testing.assert_allclose(res["c1.v"], 1 - np.exp(-res.t / tau), atol=1e-8)
    np.testing.assert_allclose(res["c2.i"], 2 * res["c1.i"], atol=1e-10)
