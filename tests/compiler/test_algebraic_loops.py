"""Algebraic loops: torn, then solved symbolically (linear) or left to the DAE solver."""

import casadi as ca
import numpy as np
import pytest
from scipy.optimize import brentq

import mechatron as mt
from mechatron.library import electrical as el


def bridge():
    """A Wheatstone bridge whose supply is a voltage source controlled by the bridge's own
    diagonal voltage (v_src = V0 + gain * v_diag): a loop through signals and the network."""
    m = mt.System("bridge")
    v0 = m.add("v0", el.DCVoltageSource(V=10.0))
    vc = m.add("vc", el.ControlledVoltageSource())
    r = [m.add(f"r{k}", el.Resistor(R=val)) for k, val in
         enumerate([100.0, 220.0, 330.0, 470.0, 1000.0], start=1)]
    sense = m.add("sense", el.VoltageSensor())
    g = m.add("g", el.ElectricalReference())
    m.connect(v0.n, g.port)
    m.connect(v0.p, vc.n)
    m.connect(vc.p, r[0].p, r[1].p)          # top node
    m.connect(r[0].n, r[2].p, r[4].p, sense.p)  # left node
    m.connect(r[1].n, r[3].p, r[4].n, sense.n)  # right node
    m.connect(r[2].n, r[3].n, g.port)
    m.connect(sense.V, vc.u)
    return m


def test_bridge_with_controlled_source_is_torn_and_matches_nodal_analysis():
    cm = mt.compile_model(bridge())
    assert cm.report["largest_block"] > 1, "the bridge is an algebraic loop"
    assert cm.nz == 0, "a linear loop is solved symbolically"
    res = mt.simulate(cm, 1e-3)
    # nodal analysis: unknowns top T, left A, right B; T = 10 + (A - B)
    g1, g2, g3, g4, g5 = (1 / x for x in (100.0, 220.0, 330.0, 470.0, 1000.0))
    a = np.array([
        [-(g1 + g3 + g5), g5, g1],                      # KCL at A with T
        [g5, -(g2 + g4 + g5), g2],                      # KCL at B with T
        [-1.0, 1.0, 1.0],                               # T - A + B = 10
    ])
    # rows 1-2: g1 (T - A) + g5 (B - A) - g3 A = 0, etc.
    va, vb, vt = np.linalg.solve(a, [0.0, 0.0, 10.0])
    assert res.final("sense.V") == pytest.approx(va - vb, rel=1e-10)
    assert res.final("r3.v") == pytest.approx(va, rel=1e-10)
    assert res.final("vc.p.v") == pytest.approx(vt, rel=1e-10)


class ExpDiode(el.OnePort):
    """A user-written Shockley diode: i = Is (exp(v/Vt) - 1); nonlinear in v."""

    Is = mt.Parameter("A", default=1e-12, doc="Saturation current")
    Vt = mt.Parameter("V", default=0.025, doc="Thermal voltage")

    def equations(self):
        return [self.i == self.Is * (ca.exp(self.v / self.Vt) - 1)]


def clamp_network() -> mt.System:
    """5 V through 1 kOhm into a diode in parallel with 10 kOhm."""
    m = mt.System("clamp")
    src = m.add("src", el.DCVoltageSource(V=5.0))
    r = m.add("r", el.Resistor(R=1000.0))
    d = m.add("d", ExpDiode())
    rl = m.add("rl", el.Resistor(R=10e3))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, r.p)
    m.connect(r.n, d.p, rl.p)
    m.connect(d.n, rl.n, src.n, g.port)
    return m


def clamp_voltage() -> float:
    """The diode's voltage in `clamp_network`, from its node's current balance."""
    def kcl(v):
        return (5.0 - v) / 1000.0 - 1e-12 * (np.exp(v / 0.025) - 1) - v / 10e3

    return brentq(kcl, 0.0, 1.0, xtol=1e-15)


def test_nonlinear_loop_is_left_to_the_dae_solver_and_solved():
    cm = mt.compile_model(clamp_network())
    assert cm.nz >= 1
    res = mt.simulate(cm, 1e-3, rtol=1e-10, atol=1e-14)
    assert res.final("d.v") == pytest.approx(clamp_voltage(), rel=1e-9)
    assert res.final("r.i") == pytest.approx(res.final("d.i") + res.final("rl.i"), rel=1e-9)
