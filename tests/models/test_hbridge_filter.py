"""The seed's PWM-to-analog RC filter: its cut-off frequency, the mean and the ripple of
its output against the analytic periodic steady state of an RC driven by a square wave,
and the motor behind the H-bridge turning at the speed of the mean voltage."""

import math

import numpy as np
import pytest
from scipy.integrate import trapezoid

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.models.hbridge_filter import cutoff_frequency, filter_ripple

ENTRY = mt.models.get("hbridge_rc_filter")


def test_cutoff_frequency_is_the_seeds_530_hz():
    p = ENTRY.values()
    assert cutoff_frequency(p["R_f"], p["C_f"]) == pytest.approx(530.5, abs=0.05)


def test_filter_attenuates_a_sine_at_the_cutoff_by_3_db_and_45_degrees():
    p = ENTRY.values()
    fc = cutoff_frequency(p["R_f"], p["C_f"])
    m = mt.System("rc")
    src = m.add("src", el.ACVoltageSource(V_amp=1.0, f=fc))
    r = m.add("r", el.Resistor(R=p["R_f"]))
    c = m.add("c", el.Capacitor(C=p["C_f"], v=0.0))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, r.p)
    m.connect(r.n, c.p)
    m.connect(src.n, c.n, g.port)
    periods = 20                                   # the start transient decays as e^-2pi
    t = np.linspace((periods - 1) / fc, periods / fc, 2001)
    res = mt.simulate(m, periods / fc, rtol=1e-10, atol=1e-12, t_out=t)
    w = 2 * math.pi * fc
    basis = np.column_stack([np.sin(w * t), np.cos(w * t)])
    (a, b), *_ = np.linalg.lstsq(basis, res["c.v"], rcond=None)
    assert math.hypot(a, b) == pytest.approx(1 / math.sqrt(2), rel=1e-6)
    assert math.atan2(b, a) == pytest.approx(-math.pi / 4, abs=1e-6)


def _last_period(D):
    p = ENTRY.values(D=D)
    T, t_stop = 1 / p["f"], ENTRY.experiment.t_stop
    t = np.concatenate([np.linspace(0, t_stop - 2 * T, 50),
                        np.linspace(t_stop - T, t_stop, 2001)])
    res = mt.simulate(ENTRY.build("acausal", D=D), t_stop, solver="rk45", rtol=1e-9,
                      atol=1e-11, t_out=t)
    k = int(np.searchsorted(t, t_stop - T))
    return p, t[k:], {name: res[name][k:] for name in ("c_f.v", "motor.inertia.w", "pwm.v")}


@pytest.fixture(scope="module", params=[0.3, 0.7])
def steady(request):
    return _last_period(request.param)


def test_mean_output_is_duty_times_amplitude(steady):
    p, t, y = steady
    period = t[-1] - t[0]
    assert trapezoid(y["pwm.v"], t) / period == pytest.approx(p["D"] * p["V_pwm"],
                                                               rel=1e-3)
    assert trapezoid(y["c_f.v"], t) / period == pytest.approx(p["D"] * p["V_pwm"],
                                                               rel=1e-6)


def test_ripple_matches_the_periodic_steady_state_of_an_rc(steady):
    p, t, y = steady
    ref = filter_ripple(p["V_pwm"], p["D"], p["f"], p["R_f"], p["C_f"])
    v = y["c_f.v"]
    assert v.max() == pytest.approx(ref["high"], rel=1e-7)    # at the falling edge
    assert v.min() == pytest.approx(ref["low"], rel=1e-7)     # at the rising edges
    assert v.max() - v.min() == pytest.approx(ref["ripple"], rel=1e-6)
    k = int(np.argmax(v))
    assert t[k] - t[0] == pytest.approx(p["D"] / p["f"], abs=0.2e-6)
    # a first-order filter at ~10 f_c leaves a large ripple: the reason the seed's
    # choice is a compromise between ripple and delay
    assert ref["ripple"] > 0.1 * p["V_pwm"] * min(p["D"], 1 - p["D"])


def test_motor_turns_at_the_speed_of_the_mean_bridge_voltage(steady):
    # the drive is linear, so its periodic mean is the DC response to the mean input
    p, t, y = steady
    V = p["V_bus"] * p["D"]
    w_dc = p["k"] * V / (p["R"] * p["B"] + p["k"] ** 2)
    assert trapezoid(y["motor.inertia.w"], t) / (t[-1] - t[0]) == pytest.approx(w_dc, rel=1e-6)


def test_the_inputs_variant_driven_by_the_fixed_duty_is_the_circuit():
    """The duty cycle input at the fixed source's duty and no load: the modulator latches
    it each period and switches at the same edges, so the ``acausal`` circuit to 1e-9."""
    t = np.linspace(0, 0.01, 201)
    kw = dict(solver="rk45", rtol=1e-11, atol=1e-13, t_out=t)
    ref = mt.simulate(ENTRY.build("acausal", D=0.7), 0.01, **kw)
    cm = mt.compile_model(ENTRY.build("inputs"))
    assert cm.input_names == ["D", "tau_load"]
    res = mt.simulate(cm, 0.01, inputs={"D": 0.7, "tau_load": 0.0}, **kw)
    for path in ENTRY.output_paths("inputs").values():
        np.testing.assert_allclose(res[path], ref[path], rtol=0,
                                   atol=1e-9 * np.abs(ref[path]).max())


def test_a_load_torque_input_lowers_the_mean_speed_as_the_dc_response():
    """The drive is linear: its periodic mean speed under a load torque T is the DC
    response (k V_bus D - R T) / (R B + k^2)."""
    p = ENTRY.values()
    D, T = 0.7, 0.005
    period, t_stop = 1 / p["f"], ENTRY.experiment.t_stop
    t = np.linspace(t_stop - period, t_stop, 2001)
    res = mt.simulate(ENTRY.build("inputs"), t_stop, solver="rk45", rtol=1e-9, atol=1e-11,
                      t_out=t, inputs={"D": D, "tau_load": T})
    w_dc = (p["k"] * p["V_bus"] * D - p["R"] * T) / (p["R"] * p["B"] + p["k"] ** 2)
    mean = trapezoid(res["motor.inertia.w"], t) / period
    assert mean == pytest.approx(w_dc, rel=1e-6)
