"""Electrical sources against analytic answers: AC sources into RC circuits (whole
response, steady-state amplitude and phase), the four linear controlled sources, the
signal-controlled current source, and the PWM sources' switching instants and mean."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.core import Input, Variable, der
from mechatron.library import blocks
from mechatron.library import electrical as el


class Integrator(mt.Component):
    """Test-only: ``der(y) == u`` from y(0) = 0."""

    u = Input("1", doc="Integrand")
    y = Variable("1", start=0.0, doc="Integral of u")

    def equations(self):
        return [der(self.y) == self.u]


def first_order_sine(t, a, b, w, ph, y0=0.0):
    """Exact solution of y' = a y + b sin(w t + ph), y(0) = y0."""
    c = -b * w / (w ** 2 + a ** 2)
    s = -a * b / (w ** 2 + a ** 2)
    ss = lambda tt: s * np.sin(w * tt + ph) + c * np.cos(w * tt + ph)  # noqa: E731
    return ss(t) + (y0 - ss(0.0)) * np.exp(a * t), np.hypot(s, c), np.arctan2(c, s)


# -- AC sources -----------------------------------------------------------------------------

def test_ac_voltage_source_into_rc_amplitude_phase_and_transient():
    VA, F, PH, VOFF, R, C = 3.0, 200.0, 0.4, 0.5, 1e3, 1e-6
    m = mt.System("rc")
    src = m.add("src", el.ACVoltageSource(V_amp=VA, f=F, phase=PH, V_offset=VOFF))
    r = m.add("r", el.Resistor(R=R))
    c = m.add("c", el.Capacitor(C=C))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, r.p)
    m.connect(r.n, c.p)
    m.connect(c.n, src.n, g.port)
    t = np.linspace(0, 20e-3, 2001)
    res = mt.simulate(m, t[-1], rtol=1e-10, atol=1e-12, t_out=t)
    tau, w = R * C, 2 * np.pi * F
    np.testing.assert_allclose(res["src.v"], VOFF + VA * np.sin(w * t + PH), atol=1e-12)
    y_sine, amp, phase = first_order_sine(t, -1 / tau, VA / tau, w, PH)
    y_dc = VOFF * (1 - np.exp(-t / tau))
    np.testing.assert_allclose(res["c.v"], y_sine + y_dc, atol=1e-8)
    # the textbook steady state: |H| = 1/sqrt(1 + (w tau)^2), angle -atan(w tau)
    assert amp == pytest.approx(VA / np.sqrt(1 + (w * tau) ** 2), rel=1e-12)
    assert phase == pytest.approx(-np.arctan(w * tau), rel=1e-12)
    # and the simulated last period has that amplitude and phase (least squares fit)
    last = t >= t[-1] - 1 / F
    basis = np.column_stack([np.sin(w * t[last] + PH), np.cos(w * t[last] + PH),
                             np.ones(last.sum())])
    coef, *_ = np.linalg.lstsq(basis, res["c.v"][last], rcond=None)
    assert np.hypot(coef[0], coef[1]) == pytest.approx(
        VA / np.sqrt(1 + (w * tau) ** 2), rel=1e-6)
    assert np.arctan2(coef[1], coef[0]) == pytest.approx(-np.arctan(w * tau), abs=1e-6)
    assert coef[2] == pytest.approx(VOFF, rel=1e-6)


def test_ac_current_source_into_parallel_rc():
    IA, F, PH, IOFF, R, C = 2e-3, 1e3, -0.3, 1e-3, 500.0, 0.5e-6
    m = mt.System("rc_par")
    src = m.add("src", el.ACCurrentSource(I_amp=IA, f=F, phase=PH, I_offset=IOFF))
    r = m.add("r", el.Resistor(R=R))
    c = m.add("c", el.Capacitor(C=C))
    g = m.add("g", el.ElectricalReference())
    # the source pushes its current out of n into the node
    m.connect(src.n, r.p, c.p)
    m.connect(src.p, r.n, c.n, g.port)
    t = np.linspace(0, 5e-3, 1001)
    res = mt.simulate(m, t[-1], rtol=1e-10, atol=1e-12, t_out=t)
    tau, w = R * C, 2 * np.pi * F
    y, amp, _ = first_order_sine(t, -1 / tau, IA / C, w, PH)
    y += IOFF * R * (1 - np.exp(-t / tau))
    np.testing.assert_allclose(res["c.v"], y, atol=1e-8)
    np.testing.assert_allclose(res["src.i"], IOFF + IA * np.sin(w * t + PH), atol=1e-15)
    assert amp == pytest.approx(IA * R / np.sqrt(1 + (w * tau) ** 2), rel=1e-12)


def test_signal_controlled_current_source_drives_a_resistor():
    m = mt.System("ccs")
    sine = m.add("sine", blocks.Sine(amplitude=0.2, f=50.0, offset=0.1))
    src = m.add("src", el.ControlledCurrentSource())
    r = m.add("r", el.Resistor(R=33.0))
    g = m.add("g", el.ElectricalReference())
    m.connect(sine.y, src.u)
    m.connect(src.n, r.p)
    m.connect(r.n, src.p, g.port)
    res = mt.simulate(m, 0.04, t_out=np.linspace(0, 0.04, 81))
    u = 0.1 + 0.2 * np.sin(2 * np.pi * 50 * res.t)
    np.testing.assert_allclose(res["r.i"], u, atol=1e-14)
    np.testing.assert_allclose(res["r.p.v"], 33.0 * u, atol=1e-12)


# -- linear controlled sources --------------------------------------------------------------

def controlled(cls, value, v_in=2.0, r_in=10.0, r_load=50.0):
    """Port 1 driven by ``v_in`` through ``r_in``; port 2 loaded by ``r_load``."""
    m = mt.System("ctl")
    src = m.add("src", el.DCVoltageSource(V=v_in))
    rin = m.add("rin", el.Resistor(R=r_in))
    key = {"VoltageControlledVoltageSource": "gain", "CurrentControlledCurrentSource": "gain",
           "VoltageControlledCurrentSource": "G",
           "CurrentControlledVoltageSource": "R_m"}[cls.__name__]
    x = m.add("x", cls(**{key: value}))
    rl = m.add("rl", el.Resistor(R=r_load))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, rin.p)
    m.connect(rin.n, x.p1)
    m.connect(x.p2, rl.p)
    m.connect(src.n, x.n1, x.n2, rl.n, g.port)
    return mt.simulate(m, 1e-3, t_out=np.array([0.0, 1e-3]))


def test_voltage_controlled_voltage_source():
    res = controlled(el.VoltageControlledVoltageSource, -3.5)
    assert res.final("x.i1") == 0.0
    assert res.final("x.v1") == pytest.approx(2.0, rel=1e-14)
    assert res.final("rl.v") == pytest.approx(-7.0, rel=1e-14)


def test_voltage_controlled_current_source():
    res = controlled(el.VoltageControlledCurrentSource, 0.02)
    assert res.final("x.i1") == 0.0
    # i2 = G v1 flows from p2 through the source to n2, so out of p2 ... into the load
    # at its n: the load current from p to n is -G v1
    assert res.final("x.i2") == pytest.approx(0.04, rel=1e-14)
    assert res.final("rl.i") == pytest.approx(-0.04, rel=1e-14)
    assert res.final("rl.v") == pytest.approx(-0.04 * 50.0, rel=1e-14)


def test_current_controlled_voltage_source():
    res = controlled(el.CurrentControlledVoltageSource, 7.0)
    assert res.final("x.v1") == 0.0
    assert res.final("x.i1") == pytest.approx(2.0 / 10.0, rel=1e-14)
    assert res.final("rl.v") == pytest.approx(7.0 * 0.2, rel=1e-14)


def test_current_controlled_current_source():
    res = controlled(el.CurrentControlledCurrentSource, 4.0)
    assert res.final("x.v1") == 0.0
    assert res.final("x.i2") == pytest.approx(4.0 * 0.2, rel=1e-14)
    assert res.final("rl.i") == pytest.approx(-0.8, rel=1e-14)


# -- PWM sources ----------------------------------------------------------------------------

def pwm_circuit(source, r=1.0, c=1e-5):
    m = mt.System("pwm")
    m.add("pwm", source)
    res_ = m.add("r", el.Resistor(R=r))
    cap = m.add("c", el.Capacitor(C=c))
    meter = m.add("vm", el.VoltageSensor())
    avg = m.add("avg", Integrator())
    g = m.add("g", el.ElectricalReference())
    m.connect(source.p, res_.p, meter.p)
    m.connect(res_.n, cap.p)
    m.connect(meter.V, avg.u)
    m.connect(source.n, cap.n, meter.n, g.port)
    return m


@pytest.mark.parametrize("duty,delay", [(0.3, 0.0), (0.72, 0.37e-3), (0.05, 0.9e-3)])
def test_pwm_source_mean_value_and_switching_instants(duty, delay):
    V_ON, V_OFF, F, N = 12.0, -2.0, 1e3, 20
    src = el.PWMVoltageSource(V_on=V_ON, V_off=V_OFF, f=F, duty=duty, delay=delay)
    # stop half-way through the pulse after the N-th period (no edge at t_stop)
    t_stop = delay + (N + 0.5 * duty) / F
    rises = delay + np.arange(N + 1) / F
    falls = delay + (np.arange(N) + duty) / F
    eps = 1e-9
    probes = np.sort(np.concatenate([rises - eps, rises + eps, falls - eps, falls + eps]))
    probes = probes[(probes > 0) & (probes < t_stop)]
    t_out = np.unique(np.concatenate([[0.0, delay, delay + N / F], probes, [t_stop]]))
    res = mt.simulate(pwm_circuit(src), t_stop, rtol=1e-10, atol=1e-12, t_out=t_out)
    # on just after each rising edge and just before each falling edge, off otherwise
    expected_on = np.zeros(t_out.size)
    for a, b in zip(rises, np.append(falls, np.inf)):
        expected_on[(t_out > a) & (t_out < b)] = 1.0
    probe = np.isin(t_out, probes)
    np.testing.assert_array_equal(res["pwm.on"][probe], expected_on[probe])
    np.testing.assert_allclose(res["pwm.v"][probe], (V_OFF + expected_on
                                                     * (V_ON - V_OFF))[probe])
    # mean over the N whole periods after the delay = V_off + duty (V_on - V_off)
    i_delay = np.searchsorted(t_out, delay)
    i_end = np.searchsorted(t_out, delay + N / F)
    mean = (res["avg.y"][i_end] - res["avg.y"][i_delay]) / (N / F)
    assert mean == pytest.approx(V_OFF + duty * (V_ON - V_OFF), rel=1e-8)
    # and before the delay the source is off
    if delay > 0:
        assert res["avg.y"][i_delay] == pytest.approx(V_OFF * delay, rel=1e-8)
    # the RC filter of the pulse train, solved exactly edge by edge
    tau = 1e-5
    v_c, t_last, level = 0.0, 0.0, V_OFF
    for tk in np.sort(np.concatenate([rises, falls])):
        v_c = level + (v_c - level) * np.exp(-(tk - t_last) / tau)
        t_last, level = tk, (V_ON if level == V_OFF else V_OFF)
    v_c = level + (v_c - level) * np.exp(-(t_stop - t_last) / tau)
    assert res.final("c.v") == pytest.approx(v_c, abs=1e-7)
    # one event per edge of the underlying pulse train in (0, t_stop) (also those masked
    # before the delay), plus the enable half-way through the off-interval before a
    # delayed first pulse
    k = np.arange(-5, N + 5)
    raw = np.concatenate([delay + k / F, delay + (k + duty) / F])
    n_edges = np.count_nonzero((raw > 0) & (raw < t_stop))
    assert res.stats.events["pwm"] == n_edges + (1 if delay > 0.5 * (1 - duty) / F else 0)


def test_controlled_pwm_source_centre_aligned_pulses():
    F, D, V_ON = 2e3, 0.4, 5.0
    m = mt.System("cpwm")
    duty = m.add("duty", blocks.Constant(value=D))
    src = m.add("pwm", el.ControlledPWMVoltageSource(V_on=V_ON, f=F))
    r = m.add("r", el.Resistor(R=10.0))
    meter = m.add("vm", el.VoltageSensor())
    avg = m.add("avg", Integrator())
    g = m.add("g", el.ElectricalReference())
    m.connect(duty.y, src.duty)
    m.connect(src.p, r.p, meter.p)
    m.connect(meter.V, avg.u)
    m.connect(src.n, r.n, meter.n, g.port)
    N = 10
    centres = np.arange(1, N) / F
    eps = 1e-9
    inside = np.concatenate([centres - D / (2 * F) + eps, centres + D / (2 * F) - eps])
    outside = np.concatenate([centres - D / (2 * F) - eps, centres + D / (2 * F) + eps])
    t_out = np.unique(np.concatenate([[0.0], inside, outside, [N / F]]))
    res = mt.simulate(m, N / F, rtol=1e-10, atol=1e-12, t_out=t_out)
    assert np.all(res["pwm.on"][np.isin(t_out, inside)] == 1.0)
    assert np.all(res["pwm.on"][np.isin(t_out, outside)] == 0.0)
    assert res.final("avg.y") / (N / F) == pytest.approx(D * V_ON, rel=1e-8)


def test_controlled_pwm_source_follows_a_varying_duty_cycle():
    """With a slow ramp of the duty cycle the pulse widths follow it: the mean over each
    period is the duty at the pulse centre times V_on (exact for a linear ramp)."""
    F, V_ON, N = 1e3, 2.0, 8
    m = mt.System("cpwm")
    duty = m.add("duty", blocks.Ramp(initial=0.1, slope=0.8 * F / N))
    src = m.add("pwm", el.ControlledPWMVoltageSource(V_on=V_ON, f=F, delay=0.5 / F))
    r = m.add("r", el.Resistor(R=1.0))
    meter = m.add("vm", el.VoltageSensor())
    avg = m.add("avg", Integrator())
    g = m.add("g", el.ElectricalReference())
    m.connect(duty.y, src.duty)
    m.connect(src.p, r.p, meter.p)
    m.connect(meter.V, avg.u)
    m.connect(src.n, r.n, meter.n, g.port)
    t_out = np.arange(N + 1) / F
    res = mt.simulate(m, N / F, rtol=1e-10, atol=1e-12, t_out=t_out)
    per_period = np.diff(res["avg.y"]) * F
    # pulse k is centred at t_c = (k + 1/2)/F where the carrier 2F|t - t_c| is zero; its
    # edges solve d(t) = 2F|t - t_c| with d(t) = d0 + s t:
    s = 0.8 * F / N
    t_c = (np.arange(N) + 0.5) / F
    t1 = (2 * F * t_c - 0.1) / (2 * F + s)
    t2 = (2 * F * t_c + 0.1) / (2 * F - s)
    np.testing.assert_allclose(per_period, V_ON * (t2 - t1) * F, rtol=1e-7)
