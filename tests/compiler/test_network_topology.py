"""Network topologies that are higher index (not singular) compile by index reduction and
follow their analytic solutions; the truly singular ones are refused with a message that
names the loop, the cut set or the floating node.

A loop of voltage sources and capacitors fixes the capacitor voltages; a cut set of current
sources and inductors fixes the inductor currents. Both hide a constraint among states that
the incidence of the equations does not show (issue 15, point 3).
"""

import itertools

import numpy as np
import pytest

import mechatron as mt
from mechatron.errors import StructuralError
from mechatron.library import electrical as el
from mechatron.library import electromechanical as em
from mechatron.library import rotational as rot

SIM = dict(rtol=1e-10, atol=1e-12)


# -- the reproduction of the issue: a current source feeding R || C, then an inductor ------
I_SRC, R, C, L = 1.0, 2.0, 1e-3, 1e-3


def forced_inductor(flips, order):
    """DC current source from the reference into node 1, R and C in parallel from node 1
    to node 2, inductor from node 2 to the reference; ``flips`` swaps a part's pins."""
    parts = {"src": el.DCCurrentSource(I=I_SRC), "r": el.Resistor(R=R),
             "c": el.Capacitor(C=C), "l": el.Inductor(L=L), "g": el.ElectricalReference()}
    m = mt.System("forced")
    made = {k: m.add(k, parts[k]) for k in order}

    def pins(k):
        p, n = made[k].p, made[k].n
        return (n, p) if flips[k] else (p, n)

    sp, sn = pins("src")
    rp, rn = pins("r")
    cp, cn = pins("c")
    lp, ln = pins("l")
    m.connect(made["g"].port, sp)
    m.connect(sn, rp, cp)
    m.connect(rn, cn, lp)
    m.connect(ln, made["g"].port)
    return m


ORIENTATIONS = [dict(zip(("src", "r", "c", "l"), f))
                for f in itertools.product([False, True], repeat=4)]


ORDERS = [("src", "r", "c", "l", "g"), ("g", "l", "c", "r", "src")]


@pytest.mark.parametrize("order", ORDERS)
@pytest.mark.parametrize("flips", ORIENTATIONS,
                         ids=["".join("x" if v else "-" for v in f.values())
                              for f in ORIENTATIONS])
def test_inductor_after_a_current_source_compiles_in_every_orientation(flips, order):
    cm = mt.compile_model(forced_inductor(flips, order))
    assert cm.state_names == ["c.v"], "the inductor current is fixed by the source"
    assert cm.report["differentiated_equations"]
    res = mt.simulate(cm, 0.01, **SIM)
    t = res.t
    s = {k: -1.0 if v else 1.0 for k, v in flips.items()}
    i_in = s["src"] * I_SRC          # current into node 1 (out of the source's n pin)
    v12 = i_in * R * (1 - np.exp(-t / (R * C)))
    np.testing.assert_allclose(s["c"] * res["c.v"], v12, atol=1e-8)
    np.testing.assert_allclose(s["r"] * res["r.i"], v12 / R, atol=1e-8)
    np.testing.assert_allclose(s["c"] * res["c.i"], i_in * np.exp(-t / (R * C)), atol=1e-8)
    np.testing.assert_allclose(s["l"] * res["l.i"], i_in, atol=1e-10)
    np.testing.assert_allclose(res["l.v"], 0.0, atol=1e-10)


# -- a capacitor directly across a voltage source, a second one in parallel ----------------
def test_two_capacitors_directly_across_a_sine_source_carry_C_dv_dt():
    amp, f = 2.0, 5.0
    m = mt.System("vcc")
    v = m.add("v", el.ACVoltageSource(V_amp=amp, f=f, V_offset=0.5))
    c1 = m.add("c1", el.Capacitor(C=1e-3))
    c2 = m.add("c2", el.Capacitor(C=3e-3))
    g = m.add("g", el.ElectricalReference())
    m.connect(v.p, c1.p, c2.n)                 # c2 the other way round
    m.connect(v.n, c1.n, c2.p, g.port)
    cm = mt.compile_model(m)
    assert cm.nx == 0, "both capacitor voltages are fixed by the source"
    res = mt.simulate(cm, 0.3, **SIM)
    w = 2 * np.pi * f
    u = 0.5 + amp * np.sin(w * res.t)
    du = amp * w * np.cos(w * res.t)
    np.testing.assert_allclose(res["c1.v"], u, atol=1e-10)
    np.testing.assert_allclose(res["c2.v"], -u, atol=1e-10)
    np.testing.assert_allclose(res["c1.i"], 1e-3 * du, atol=1e-9)
    np.testing.assert_allclose(res["c2.i"], -3e-3 * du, atol=1e-9)
    # the source delivers both currents: i flows from p to n through it
    np.testing.assert_allclose(res["v.i"], -4e-3 * du, atol=1e-9)


def test_capacitors_in_series_across_a_source_share_its_voltage_by_their_start_values():
    """V, C1 and C2 in a loop, a resistor across C2: one state; the loop fixes
    v1 + v2 = V, so C1 charges as C2 discharges through R (tau = R (C1 + C2))."""
    m = mt.System("vcc_series")
    v = m.add("v", el.DCVoltageSource(V=3.0))
    c1 = m.add("c1", el.Capacitor(C=1e-3, v=1.0))
    c2 = m.add("c2", el.Capacitor(C=2e-3, v=2.0))
    r = m.add("r", el.Resistor(R=10.0))
    g = m.add("g", el.ElectricalReference())
    m.connect(v.p, c1.p)
    m.connect(c1.n, c2.p, r.p)
    m.connect(v.n, c2.n, r.n, g.port)
    cm = mt.compile_model(m)
    assert cm.nx == 1
    res = mt.simulate(cm, 0.2, **SIM)
    tau = 10.0 * 3e-3
    v2 = 2.0 * np.exp(-res.t / tau)
    np.testing.assert_allclose(res["c2.v"], v2, atol=1e-8)
    np.testing.assert_allclose(res["c1.v"] + res["c2.v"], 3.0, atol=1e-10)


# -- two inductors in series driven by a current source ------------------------------------
def test_two_inductors_in_series_with_a_sine_current_source_carry_its_current():
    amp, f, l1, l2 = 1.5, 4.0, 1e-3, 2e-3
    m = mt.System("ll")
    i = m.add("i", el.ACCurrentSource(I_amp=amp, f=f, I_offset=0.2))
    a = m.add("l1", el.Inductor(L=l1))
    b = m.add("l2", el.Inductor(L=l2))
    g = m.add("g", el.ElectricalReference())
    m.connect(g.port, i.p)
    m.connect(i.n, a.p)
    m.connect(a.n, b.n)                        # l2 reversed
    m.connect(b.p, g.port)
    cm = mt.compile_model(m)
    assert cm.nx == 0, "both inductor currents are fixed by the source"
    res = mt.simulate(cm, 0.5, **SIM)
    w = 2 * np.pi * f
    cur = 0.2 + amp * np.sin(w * res.t)
    dcur = amp * w * np.cos(w * res.t)
    np.testing.assert_allclose(res["l1.i"], cur, atol=1e-10)
    np.testing.assert_allclose(res["l2.i"], -cur, atol=1e-10)
    np.testing.assert_allclose(res["l1.v"], l1 * dcur, atol=1e-9)
    np.testing.assert_allclose(res["l2.v"], -l2 * dcur, atol=1e-9)
    # the source's voltage p - n is minus the drop across both inductors
    np.testing.assert_allclose(res["i.v"], -(l1 + l2) * dcur, atol=1e-9)


def test_inductor_in_series_with_a_current_source_then_a_second_one_across_a_resistor():
    m = mt.System("ll_r")
    i = m.add("i", el.DCCurrentSource(I=1.5))
    a = m.add("l1", el.Inductor(L=1e-3))
    b = m.add("l2", el.Inductor(L=2e-3))
    r = m.add("r", el.Resistor(R=3.0))
    g = m.add("g", el.ElectricalReference())
    m.connect(g.port, i.p)
    m.connect(i.n, a.p)
    m.connect(a.n, b.p, r.p)
    m.connect(b.n, r.n, g.port)
    cm = mt.compile_model(m)
    assert cm.state_names == ["l2.i"]
    res = mt.simulate(cm, 5e-3, **SIM)
    np.testing.assert_allclose(res["l1.i"], 1.5, atol=1e-10)
    np.testing.assert_allclose(res["l2.i"], 1.5 * (1 - np.exp(-3.0 * res.t / 2e-3)),
                               atol=1e-8)


def test_spring_in_series_with_a_torque_source_is_a_cut_set_and_compiles():
    """ConstantTorque -> spring s1 -> inertia with a damper to the reference: the spring
    carries the source torque (its deflection is fixed), the inertia spins up as
    J dw/dt = T - D w."""
    T, k, J, D = 2.0, 50.0, 0.1, 0.5
    m = mt.System("torque_spring")
    ref = m.add("ref", rot.RotationalReference())
    src = m.add("src", rot.ConstantTorque(T=T))
    s1 = m.add("s1", rot.RotationalSpring(k=k))
    j = m.add("j", rot.Inertia(J=J))
    d = m.add("d", rot.RotationalDamper(D=D))
    m.connect(ref.port, src.B, d.B)
    m.connect(src.A, s1.A)
    m.connect(s1.B, j.port, d.A)
    cm = mt.compile_model(m)
    assert cm.state_names == ["j.w"]
    res = mt.simulate(cm, 1.0, **SIM)
    np.testing.assert_allclose(res["j.w"], T / D * (1 - np.exp(-D * res.t / J)), atol=1e-8)
    # the source's tau = -T enters it at A, so T enters the spring at its A
    np.testing.assert_allclose(res["s1.tau"], T, atol=1e-10)
    np.testing.assert_allclose(res["s1.phi"], T / k, atol=1e-10)


# -- cut sets closed through a parameter: transformer, gear, gyrator -----------------------
def transformer_cut_set(flip_l, order):
    """DC current source I into the primary of an ideal transformer (ratio N); on the
    secondary, R || C in series with an inductor: the inductor carries N * I, fixed by
    the source through the ratio, a parameter."""
    parts = {"i": el.DCCurrentSource(I=I_SRC), "x": el.IdealTransformer(N=2.0),
             "r": el.Resistor(R=R), "c": el.Capacitor(C=C), "l": el.Inductor(L=L),
             "g": el.ElectricalReference(), "g2": el.ElectricalReference()}
    m = mt.System("transformer_cut_set")
    made = {k: m.add(k, parts[k]) for k in order}
    i, x, r, c, ind, g, g2 = (made[k] for k in "i x r c l g g2".split())
    lp, ln = (ind.n, ind.p) if flip_l else (ind.p, ind.n)
    m.connect(g.port, i.p)
    m.connect(i.n, x.p1)
    m.connect(x.n1, g.port)
    m.connect(x.p2, r.p, c.p)
    m.connect(r.n, c.n, lp)
    m.connect(ln, x.n2, g2.port)
    return m


@pytest.mark.parametrize("flip_l, order", [
    (False, "i x r c l g g2".split()),
    (True, "l c r g2 x g i".split()),
    (True, "i x r c l g g2".split()),
])
def test_inductor_forced_through_an_ideal_transformer(flip_l, order):
    """The secondary current is N I (power balance of the ideal transformer); it charges
    R || C: v = N I R (1 - exp(-t / (R C))); the inductor current is constant, so its
    voltage is 0 and the primary voltage is N times the capacitor's."""
    N = 2.0
    cm = mt.compile_model(transformer_cut_set(flip_l, order))
    assert cm.state_names == ["c.v"]
    res = mt.simulate(cm, 0.01, **SIM)
    sign = -1.0 if flip_l else 1.0
    np.testing.assert_allclose(sign * res["l.i"], N * I_SRC, atol=1e-10)
    v = N * I_SRC * R * (1 - np.exp(-res.t / (R * C)))
    np.testing.assert_allclose(res["c.v"], v, atol=1e-8)
    np.testing.assert_allclose(res["l.v"], 0.0, atol=1e-8)
    np.testing.assert_allclose(res["x.v1"], N * v, atol=1e-8)
    # lossless: the power the source delivers is what R dissipates plus what C stores
    np.testing.assert_allclose(res["x.v1"] * I_SRC,
                               res["r.v"] ** 2 / R + res["c.v"] * res["c.i"], atol=1e-7)


def test_transformer_ratio_stays_a_tunable_parameter():
    """The reduced equation keeps N symbolic: a new ratio changes the forced current
    without recompiling."""
    cm = mt.compile_model(transformer_cut_set(False, "i x r c l g g2".split()))
    res = mt.simulate(cm, 0.01, params={"x.N": 0.5}, **SIM)
    np.testing.assert_allclose(res["l.i"], 0.5 * I_SRC, atol=1e-10)
    np.testing.assert_allclose(res["c.v"], 0.5 * I_SRC * R * (1 - np.exp(-res.t / (R * C))),
                               atol=1e-8)


def gyrator_cut_set(k1, k2, gear_ratio=None):
    """The transformer of `transformer_cut_set` built from two gyrators: a current
    source drives RotationalEMF e1, whose flange turns e2 (directly, or through an
    IdealGear), which feeds R || C and the inductor. e1 turns I into the torque k1 I,
    the gear multiplies it by its ratio, e2 turns it back into a current, so the
    inductor carries k1 * ratio / k2 * I: a cut set closed across two domains through
    three parameters."""
    m = mt.System("gyrator_cut_set")
    g = m.add("g", el.ElectricalReference())
    g2 = m.add("g2", el.ElectricalReference())
    i = m.add("i", el.DCCurrentSource(I=I_SRC))
    e1 = m.add("e1", em.RotationalEMF(k=k1))
    e2 = m.add("e2", em.RotationalEMF(k=k2))
    ref = m.add("ref", rot.RotationalReference())
    r = m.add("r", el.Resistor(R=R))
    c = m.add("c", el.Capacitor(C=C))
    ind = m.add("l", el.Inductor(L=L))
    m.connect(g.port, i.p)
    m.connect(i.n, e1.p)
    m.connect(e1.n, g.port)
    if gear_ratio is None:
        m.connect(e1.A, e2.A)
    else:
        gear = m.add("gear", rot.IdealGear(ratio=gear_ratio))
        m.connect(e1.A, gear.A)
        m.connect(gear.B, e2.A)
    m.connect(e1.B, e2.B, ref.port)
    m.connect(e2.p, r.p, c.p)
    m.connect(r.n, c.n, ind.p)
    m.connect(ind.n, e2.n, g2.port)
    return m


@pytest.mark.parametrize("gear_ratio", [None, 3.0])
def test_inductor_forced_through_gyrators_and_a_gear(gear_ratio):
    k1, k2 = 0.2, 0.5
    cm = mt.compile_model(gyrator_cut_set(k1, k2, gear_ratio))
    assert cm.state_names == ["c.v"]
    res = mt.simulate(cm, 0.01, **SIM)
    n = k1 * (gear_ratio or 1.0) / k2
    np.testing.assert_allclose(res["l.i"], n * I_SRC, atol=1e-10)
    v = n * I_SRC * R * (1 - np.exp(-res.t / (R * C)))
    np.testing.assert_allclose(res["c.v"], v, atol=1e-8)
    # torque balance on the shafts, and the back EMFs of one speed (times the ratio)
    w2 = res["e2.w"]
    np.testing.assert_allclose(res["e2.v"], k2 * w2, atol=1e-8)
    np.testing.assert_allclose(res["e1.w"], (gear_ratio or 1.0) * w2, atol=1e-8)
    # lossless: source power = R's dissipation + C's charging
    np.testing.assert_allclose(res["e1.v"] * I_SRC,
                               res["r.v"] ** 2 / R + res["c.v"] * res["c.i"], atol=1e-7)
    if gear_ratio is not None:   # the ratio stays a parameter of the compiled model
        res = mt.simulate(cm, 0.01, params={"gear.ratio": 1.5}, **SIM)
        np.testing.assert_allclose(res["l.i"], k1 * 1.5 / k2 * I_SRC, atol=1e-10)


# -- truly singular networks ---------------------------------------------------------------
def _voltage_sources_in_parallel():
    m = mt.System("vv")
    a = m.add("v1", el.DCVoltageSource(V=1.0))
    b = m.add("v2", el.DCVoltageSource(V=1.0))
    r = m.add("r", el.Resistor(R=1.0))
    g = m.add("g", el.ElectricalReference())
    m.connect(a.p, b.p, r.p)
    m.connect(a.n, b.n, r.n, g.port)
    return m


def _voltage_source_triangle():
    m = mt.System("vvv")
    a = m.add("v1", el.DCVoltageSource(V=1.0))
    b = m.add("v2", el.DCVoltageSource(V=1.0))
    c = m.add("v3", el.DCVoltageSource(V=2.0))
    r = m.add("r", el.Resistor(R=1.0))
    g = m.add("g", el.ElectricalReference())
    m.connect(a.p, b.n)
    m.connect(b.p, c.p, r.p)
    m.connect(a.n, c.n, r.n, g.port)
    return m


def _current_sources_in_series():
    m = mt.System("ii")
    a = m.add("i1", el.DCCurrentSource(I=1.0))
    b = m.add("i2", el.DCCurrentSource(I=1.0))
    c = m.add("c", el.Capacitor(C=1.0))
    r = m.add("r", el.Resistor(R=1.0))
    g = m.add("g", el.ElectricalReference())
    m.connect(g.port, a.p, r.n)
    m.connect(a.n, c.p)
    m.connect(c.n, b.p)
    m.connect(b.n, r.p)
    return m


def _torque_sources_in_series():
    m = mt.System("tt")
    ref = m.add("ref", rot.RotationalReference())
    a = m.add("t1", rot.ConstantTorque(T=2.0))
    b = m.add("t2", rot.ConstantTorque(T=2.0))
    d = m.add("d", rot.RotationalDamper(D=1.0))
    m.connect(ref.port, a.B, d.B)
    m.connect(a.A, b.B)
    m.connect(b.A, d.A)
    return m


def _floating_secondary():
    """An ideal transformer whose secondary circuit has no reference of its own."""
    m = mt.System("floating")
    v = m.add("v", el.DCVoltageSource(V=1.0))
    x = m.add("x", el.IdealTransformer(N=2.0))
    rp = m.add("rp", el.Resistor(R=1.0))
    r = m.add("r", el.Resistor(R=1.0))
    g = m.add("g", el.ElectricalReference())
    m.connect(v.p, rp.p)
    m.connect(rp.n, x.p1)
    m.connect(v.n, x.n1, g.port)
    m.connect(x.p2, r.p)
    m.connect(x.n2, r.n)
    return m


@pytest.mark.parametrize("build, pattern, suspects", [
    (_voltage_sources_in_parallel,
     r"model 'vv': sources v1 and v2 form a loop: their voltages are not independent\. "
     r"4 equations for 3 unknowns.*Potential extra equation.*Remove one source, or "
     r"put a resistance", {"v1", "v2"}),
    (_voltage_source_triangle,
     r"model 'vvv': sources v1, v2 and v3 form a loop: their voltages are not independent",
     {"v1", "v2", "v3"}),
    (_current_sources_in_series,
     r"model 'ii': sources i1 and i2 form a cut set: their currents are not independent\. "
     r".*give the current another path", {"i1", "i2"}),
    (_torque_sources_in_series,
     r"model 'tt': sources t1 and t2 form a cut set: their torques are not independent",
     {"t1", "t2"}),
    (_floating_secondary,
     r"model 'floating': the voltages at r\.n, r\.p are not determined: this part of the "
     r"network has no path to a reference \(a floating node\)", {"r.n.v", "r.p.v"}),
])
def test_truly_singular_networks_are_named_in_physical_terms(build, pattern, suspects):
    with pytest.raises(StructuralError, match=pattern) as info:
        mt.compile_model(build())
    message = str(info.value)
    assert "UnitDelay" not in message and "algebraic loop" not in message
    assert set(info.value.variables) == suspects
    assert info.value.equations


def test_a_loop_of_signal_blocks_still_gets_the_signal_advice():
    from mechatron.library import blocks
    m = mt.System("sig")
    r = m.add("r", blocks.Constant(value=1.0))
    s = m.add("sum", blocks.Subtract())
    k = m.add("gain", blocks.Gain(k=-1.0))
    m.connect(r.y, s.u1)
    m.connect(s.y, k.u)
    m.connect(k.y, s.u2)
    with pytest.raises(StructuralError,
                       match=r"algebraic loop through sum, gain.*UnitDelay"):
        mt.compile_model(m)
