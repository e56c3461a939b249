"""Semiconductors and switches against their analytic characteristics: the exponential
diode's I-V (with and without a series resistor), the ideal switch, the MOSFETs' static
characteristics with their body diodes, and a PWM-driven MOSFET half-bridge against the
exact piecewise-exponential solution of its RL load."""

import numpy as np
import pytest
from scipy.optimize import brentq

import mechatron as mt
from mechatron.core import Input, Variable, der
from mechatron.library import blocks
from mechatron.library import electrical as el

KB, QE = 1.380649e-23, 1.602176634e-19


class Integrator(mt.Component):
    """Test-only: ``der(y) == u`` from y(0) = 0."""

    u = Input("1", doc="Integrand")
    y = Variable("1", start=0.0, doc="Integral of u")

    def equations(self):
        return [der(self.y) == self.u]


def shockley(v, i_s, n, temp, g_par, x_max=np.inf):
    vt = KB * temp / QE
    x = np.asarray(v, dtype=float) / (n * vt)
    core = np.exp(np.minimum(x, x_max)) * (1 + np.maximum(x - x_max, 0))
    return i_s * (core - 1) + g_par * v


def swept_diode(diode, v0, slope):
    m = mt.System("sweep")
    ramp = m.add("ramp", blocks.Ramp(initial=v0, slope=slope, start=0.0))
    src = m.add("src", el.ControlledVoltageSource())
    m.add("d", diode)
    g = m.add("g", el.ElectricalReference())
    m.connect(ramp.y, src.u)
    m.connect(src.p, diode.p)
    m.connect(diode.n, src.n, g.port)
    return m


# -- exponential diode ----------------------------------------------------------------------

def test_exponential_diode_follows_shockley_equation_over_a_voltage_sweep():
    I_S, N, T, G = 2e-14, 1.5, 320.0, 1e-9
    d = el.ExponentialDiode(I_s=I_S, N=N, T=T, G_par=G)
    res = mt.simulate(swept_diode(d, -1.0, 1.8), 1.0, t_out=np.linspace(0, 1, 201))
    v = res["d.v"]
    np.testing.assert_allclose(v, -1.0 + 1.8 * res.t, atol=1e-12)
    np.testing.assert_allclose(res["d.i"], shockley(v, I_S, N, T, G), rtol=1e-12,
                               atol=1e-20)
    assert res.final("d.V_t") == pytest.approx(KB * T / QE, rel=1e-14)
    # forward: a decade of current per N*V_t*ln(10) of voltage
    vt = KB * T / QE
    i1 = shockley(0.5, I_S, N, T, 0)
    assert shockley(0.5 + N * vt * np.log(10), I_S, N, T, 0) == pytest.approx(10 * i1,
                                                                             rel=1e-9)


def test_exponential_diode_continues_linearly_above_x_max():
    I_S, N, T, X_MAX = 1e-14, 1.0, 300.0, 20.0
    d = el.ExponentialDiode(I_s=I_S, N=N, T=T, G_par=0.0, x_max=X_MAX)
    res = mt.simulate(swept_diode(d, 0.0, 1.0), 1.0, t_out=np.linspace(0, 1, 101))
    vt = KB * T / QE
    v_knee = X_MAX * vt
    above = res["d.v"] > v_knee
    assert above.sum() > 40
    tangent = I_S * (np.exp(X_MAX) * (1 + (res["d.v"] - v_knee) / vt) - 1)
    np.testing.assert_allclose(res["d.i"][above], tangent[above], rtol=1e-12)


@pytest.mark.parametrize("vs", [0.3, 0.8, 2.0, 10.0, -5.0])
def test_exponential_diode_in_series_with_resistor_solves_the_implicit_equation(vs):
    I_S, N, T, R = 1e-12, 1.2, 300.15, 100.0
    m = mt.System("dr")
    src = m.add("src", el.DCVoltageSource(V=vs))
    r = m.add("r", el.Resistor(R=R))
    d = m.add("d", el.ExponentialDiode(I_s=I_S, N=N, T=T, G_par=0.0))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, r.p)
    m.connect(r.n, d.p)
    m.connect(d.n, src.n, g.port)
    res = mt.simulate(m, 1e-3, rtol=1e-10, atol=1e-14)
    # independent: bracket the diode voltage with SciPy
    vd = brentq(lambda x: x + R * shockley(x, I_S, N, T, 0.0) - vs, -abs(vs) - 1, abs(vs) + 1,
                xtol=1e-15, rtol=1e-14)
    assert res.final("d.v") == pytest.approx(vd, rel=1e-9, abs=1e-12)
    assert res.final("r.i") == pytest.approx((vs - vd) / R, rel=1e-8, abs=1e-18)


# -- ideal switch ---------------------------------------------------------------------------

def test_ideal_switch_closes_at_the_control_step_and_charges_the_capacitor():
    V, R, C, RON, T_ON = 10.0, 100.0, 1e-6, 0.5, 2e-4
    m = mt.System("sw")
    step = m.add("step", blocks.Step(t_step=T_ON, initial=0.0, final=1.0))
    src = m.add("src", el.DCVoltageSource(V=V))
    sw = m.add("sw", el.IdealSwitch(R_on=RON, G_off=0.0, threshold=0.5))
    r = m.add("r", el.Resistor(R=R))
    c = m.add("c", el.Capacitor(C=C))
    g = m.add("g", el.ElectricalReference())
    m.connect(step.y, sw.control)
    m.connect(src.p, sw.p)
    m.connect(sw.n, r.p)
    m.connect(r.n, c.p)
    m.connect(c.n, src.n, g.port)
    t = np.linspace(0, 1e-3, 401)
    res = mt.simulate(m, 1e-3, rtol=1e-10, atol=1e-13, t_out=t)
    tau = (R + RON) * C
    expected = np.where(t > T_ON, V * (1 - np.exp(-(t - T_ON) / tau)), 0.0)
    np.testing.assert_allclose(res["c.v"], expected, atol=1e-8)
    away = np.abs(t - T_ON) > 1e-9   # at the edge itself the log may hold either side
    np.testing.assert_array_equal(res["sw.closed"][away], (t[away] > T_ON).astype(float))


def test_ideal_switch_open_and_closed_resistances():
    V, R, RON, GOFF = 5.0, 10.0, 0.2, 1e-3
    m = mt.System("sw")
    pulse = m.add("ctl", blocks.Pulse(amplitude=2.0, period=2e-3, width=0.5))
    src = m.add("src", el.DCVoltageSource(V=V))
    sw = m.add("sw", el.IdealSwitch(R_on=RON, G_off=GOFF, threshold=1.0))
    r = m.add("r", el.Resistor(R=R))
    g = m.add("g", el.ElectricalReference())
    m.connect(pulse.y, sw.control)
    m.connect(src.p, sw.p)
    m.connect(sw.n, r.p)
    m.connect(r.n, src.n, g.port)
    res = mt.simulate(m, 3e-3, t_out=np.array([0.5e-3, 1.5e-3, 2.5e-3]))
    i_open = V * GOFF / (1 + R * GOFF)
    i_closed = V / (R + RON)
    np.testing.assert_allclose(res["r.i"], [i_closed, i_open, i_closed], rtol=1e-12)


# -- MOSFETs: static characteristics --------------------------------------------------------

def mosfet_sweep(fet, v_gate, v0, slope):
    m = mt.System("fet")
    ramp = m.add("ramp", blocks.Ramp(initial=v0, slope=slope))
    src = m.add("vds", el.ControlledVoltageSource())
    m.add("q", fet)
    vg = m.add("vg", el.DCVoltageSource(V=v_gate))
    g = m.add("g", el.ElectricalReference())
    m.connect(ramp.y, src.u)
    m.connect(src.p, fet.p)
    m.connect(vg.p, fet.gate)
    m.connect(fet.n, src.n, vg.n, g.port)
    return m


@pytest.mark.parametrize("kind,v_gate,channel_on", [("N", 10.0, True), ("N", 0.0, False),
                                                    ("N", 1.9, False), ("P", -10.0, True),
                                                    ("P", 0.0, False), ("P", -1.9, False)])
def test_mosfet_static_characteristic_with_body_diode(kind, v_gate, channel_on):
    RON, GOFF, VF, RD = 0.05, 1e-4, 0.7, 0.02
    cls = el.NMOSFET if kind == "N" else el.PMOSFET
    fet = cls(R_on=RON, G_off=GOFF, V_f=VF, R_d=RD)
    res = mt.simulate(mosfet_sweep(fet, v_gate, -2.0, 4.0), 1.0,
                      t_out=np.linspace(0, 1, 401))
    v = res["q.v"]
    np.testing.assert_allclose(v, -2.0 + 4.0 * res.t, atol=1e-12)
    channel = v / RON if channel_on else GOFF * v
    if kind == "N":   # body diode from source (n) to drain (p)
        diode = np.where(-v > VF, (-v - VF) / RD, 0.0)
        expected = channel - diode
    else:             # body diode from drain (p) to source (n)
        diode = np.where(v > VF, (v - VF) / RD, 0.0)
        expected = channel + diode
    np.testing.assert_allclose(res["q.i"], expected, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res["q.i_d"], diode, rtol=1e-10, atol=1e-12)
    assert set(np.unique(res["q.on"])) == {1.0 if channel_on else 0.0}
    assert res["q.gate.i"].max() == 0.0 and res["q.gate.i"].min() == 0.0
    # the body diode turns on where the ramp crosses its forward voltage (an event)
    assert res.stats.events.get("q") == 1


# -- MOSFET half-bridge ---------------------------------------------------------------------

VDC, RL, LL, FSW, DUTY, RON, GOFF, VG = 24.0, 2.0, 1e-3, 10e3, 0.3, 0.01, 1e-6, 10.0
DELAY = 0.25 / FSW


def half_bridge(high_side, i_start=0.0):
    """Two MOSFETs switched complementarily by one PWM source (the low-side gate is the
    inverted high-side gate drive, through a VCVS and a bias), an RL load from the
    switch node to ground."""
    m = mt.System("half_bridge")
    src = m.add("vdc", el.DCVoltageSource(V=VDC))
    lo = m.add("lo", el.NMOSFET(R_on=RON, G_off=GOFF))
    r = m.add("r", el.Resistor(R=RL))
    ind = m.add("l", el.Inductor(L=LL, i=i_start))
    meter = m.add("meter", el.CurrentSensor())
    q = m.add("q", Integrator())
    drv = m.add("drv", el.VoltageControlledVoltageSource(gain=-1.0 if high_side == "N"
                                                         else 1.0))
    bias = m.add("bias", el.DCVoltageSource(V=VG))
    g = m.add("g", el.ElectricalReference())
    if high_side == "N":   # gate driven +VG against the switch node (bootstrap driver)
        hi = m.add("hi", el.NMOSFET(R_on=RON, G_off=GOFF))
        gh = m.add("gh", el.PWMVoltageSource(V_on=VG, f=FSW, duty=DUTY, delay=DELAY))
        m.connect(src.p, hi.p)
        m.connect(hi.n, gh.n, drv.n1)
        sw_node = hi.n
    else:                  # P-channel: source at VDC, gate pulled VG below it
        hi = m.add("hi", el.PMOSFET(R_on=RON, G_off=GOFF))
        gh = m.add("gh", el.PWMVoltageSource(V_on=-VG, f=FSW, duty=DUTY, delay=DELAY))
        m.connect(src.p, hi.n, gh.n, drv.n1)
        sw_node = hi.p
    m.connect(gh.p, hi.gate, drv.p1)
    m.connect(bias.p, drv.n2)
    m.connect(drv.p2, lo.gate)
    m.connect(sw_node, lo.p, r.p)
    m.connect(r.n, meter.p)
    m.connect(meter.n, ind.p)
    m.connect(meter.I, q.u)
    m.connect(ind.n, lo.n, bias.n, src.n, g.port)
    return m


def thevenin():
    """The load sees the Thevenin source (Vth, Rth) of the two switch conductances; Rth
    is the same in both states."""
    g_on = 1 / RON
    rth = 1 / (g_on + GOFF)
    return VDC * g_on * rth, VDC * GOFF * rth, rth      # high side on / low side on


def periodic_start():
    """Load current at t = 0 on the periodic steady state (t = 0 lies (1 - 0.25) periods
    after a rising edge, in the low-side-on state)."""
    v_a, v_b, rth = thevenin()
    tau = LL / (RL + rth)
    i_a, i_b = v_a / (RL + rth), v_b / (RL + rth)
    e_a, e_b = np.exp(-DUTY / FSW / tau), np.exp(-(1 - DUTY) / FSW / tau)
    i_rise = (i_b * (1 - e_b) + i_a * (1 - e_a) * e_b) / (1 - e_a * e_b)
    return i_b + (i_rise - i_b) * np.exp(DELAY / tau)


def exact_half_bridge(t_eval, i_start=0.0):
    """i' = (Vth(t) - (R + Rth) i)/L solved exactly interval by interval. Returns
    (i, v_switch_node, integral of i, averaged mean current) at the sorted times."""
    v_a, v_b, rth = thevenin()
    tau = LL / (RL + rth)
    edges = []
    k = 0
    while DELAY + k / FSW < t_eval[-1] + 1 / FSW:
        edges += [DELAY + k / FSW, DELAY + (k + DUTY) / FSW]
        k += 1
    out_i, out_v, out_q = [], [], []
    t0, i0, q0, state_on = 0.0, i_start, 0.0, False
    bounds = [e for e in edges]
    j = 0
    for te in t_eval:
        while j < len(bounds) and bounds[j] <= te:
            v_src = v_a if state_on else v_b
            i_inf = v_src / (RL + rth)
            dt = bounds[j] - t0
            q0 += i_inf * dt + (i0 - i_inf) * tau * (1 - np.exp(-dt / tau))
            i0 = i_inf + (i0 - i_inf) * np.exp(-dt / tau)
            t0, state_on = bounds[j], not state_on
            j += 1
        v_src = v_a if state_on else v_b
        i_inf = v_src / (RL + rth)
        dt = te - t0
        i = i_inf + (i0 - i_inf) * np.exp(-dt / tau)
        out_i.append(i)
        out_v.append(v_src - rth * i)
        out_q.append(q0 + i_inf * dt + (i0 - i_inf) * tau * (1 - np.exp(-dt / tau)))
    mean = (DUTY * v_a + (1 - DUTY) * v_b) / (RL + rth)
    return np.array(out_i), np.array(out_v), np.array(out_q), mean


@pytest.mark.parametrize("high_side", ["N", "P"])
def test_mosfet_half_bridge_matches_exact_and_averaged_solution(high_side):
    """From rest: the whole waveform against the exact solution. From the periodic steady
    state (its analytic start current): the mean load current over every period equals
    the averaged value (D Vth_on + (1 - D) Vth_off)/(R + Rth) ~ D VDC/(R + R_on)."""
    n_per = 20
    t_stop = DELAY + n_per / FSW
    # sample inside the intervals (away from the edges) plus whole-period marks
    frac = np.array([0.1, 0.2, 0.45, 0.6, 0.9])
    t_in = np.concatenate([DELAY + (k + frac) / FSW for k in range(n_per)])
    marks = DELAY + np.arange(n_per + 1) / FSW
    t_out = np.unique(np.concatenate([[0.0], t_in, marks]))
    for i_start in (0.0, periodic_start()):
        res = mt.simulate(half_bridge(high_side, i_start), t_stop, rtol=1e-10, atol=1e-12,
                          t_out=t_out)
        i_ex, v_ex, q_ex, mean = exact_half_bridge(res.t, i_start)
        inside = np.isin(res.t, t_in)
        np.testing.assert_allclose(res["l.i"], i_ex, rtol=1e-7, atol=1e-9)
        np.testing.assert_allclose(res["r.p.v"][inside], v_ex[inside], rtol=1e-7,
                                   atol=1e-7)
        np.testing.assert_allclose(res["q.y"], q_ex, rtol=1e-7, atol=1e-12)
        # complementary switching: exactly one channel conducts at every sample
        np.testing.assert_array_equal(res["hi.on"][inside] + res["lo.on"][inside], 1.0)
        assert res.stats.events["gh"] == 2 * n_per   # the rise at t_stop is not reached
    # periodic steady state: the mean over each period is the averaged value
    q_marks = res["q.y"][np.isin(res.t, marks)]
    np.testing.assert_allclose(np.diff(q_marks) * FSW, mean, rtol=1e-6)
    # which is D * VDC / (R + R_on) up to the off-conductance leakage
    assert mean == pytest.approx(DUTY * VDC / (RL + RON), rel=1e-4)


def test_buck_converter_freewheeling_diode_takes_over_the_inductor_current():
    VIN, F, D = 24.0, 10e3, 0.3
    m = mt.System("buck")
    src = m.add("vdc", el.DCVoltageSource(V=VIN))
    hi = m.add("hi", el.NMOSFET(R_on=RON, G_off=GOFF))
    gh = m.add("gh", el.PWMVoltageSource(V_on=VG, f=F, duty=D, delay=DELAY))
    d = m.add("d", el.Diode(Vf=0.7, Ron=0.01, Goff=1e-8))
    r = m.add("r", el.Resistor(R=RL))
    ind = m.add("l", el.Inductor(L=LL))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, hi.p)
    m.connect(hi.n, d.n, r.p, gh.n)
    m.connect(gh.p, hi.gate)
    m.connect(r.n, ind.p)
    m.connect(ind.n, d.p, src.n, g.port)
    t_off = DELAY + D / F
    eps = 1e-10
    res = mt.simulate(m, 3 / F, rtol=1e-9, atol=1e-12,
                      t_out=np.array([0.0, t_off - eps, t_off + eps, t_off + 0.3 / F]))
    # the inductor current is continuous across the turn-off (it can change by at most
    # 2 eps max|di/dt| = 2 eps VIN / L), the diode conducts it and clamps the switch node
    # one forward drop (plus R_on i) below ground
    assert res["l.i"][1] > 0.1
    assert abs(res["l.i"][2] - res["l.i"][1]) <= 2 * eps * VIN / LL
    assert res["d.on"][3] == 1.0
    assert res["r.p.v"][3] == pytest.approx(-(0.7 + 0.01 * res["l.i"][3]), rel=1e-3)
