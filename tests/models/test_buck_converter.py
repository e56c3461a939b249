"""Buck converter: steady output D V_in less the switch losses, the textbook ripples, the
exact periodic steady state (matrix exponentials of the two phases), and the switched
mean against the state-space average."""

import numpy as np
import pytest
from scipy.integrate import trapezoid

import mechatron as mt
from mechatron.models.buck_converter import periodic_steady_state

ENTRY = mt.models.get("buck_converter")


def _sync(p):
    """The parameters of the synchronous circuit (no diode)."""
    return {k: v for k, v in p.items() if k != "V_f"}


def _last_period(D):
    """Switched and averaged runs to 100 periods; the switched one sampled finely over
    its last period."""
    p = ENTRY.values(D=D)
    T = 1 / p["f"]
    t = np.concatenate([np.linspace(0, 98 * T, 99), np.linspace(99 * T, 100 * T, 2001)])
    sw = mt.simulate(ENTRY.build("switched", D=D), 100 * T, rtol=1e-8, atol=1e-10,
                     t_out=t)
    av = mt.simulate(ENTRY.build("averaged", D=D), 100 * T, rtol=1e-10, atol=1e-12)
    k = int(np.searchsorted(t, 99 * T))
    return p, t[k:], sw["inductor.i"][k:], sw["capacitor.v"][k:], av


@pytest.fixture(scope="module", params=[0.3, 0.5, 0.75])
def steady(request):
    return _last_period(request.param)


def test_output_is_duty_times_input_less_the_switch_losses(steady):
    p, t, i, v, av = steady
    mean = trapezoid(v, t) / (t[-1] - t[0])
    lossless = p["D"] * p["V_in"]
    assert mean == pytest.approx(lossless, rel=5e-3)           # CCM: v = D V_in
    # the on-resistance of the conducting switch is in series with the load every moment
    assert mean == pytest.approx(lossless * p["R"] / (p["R"] + p["R_on"]), rel=2e-4)
    assert mean < lossless


def test_switched_mean_matches_the_state_space_average(steady):
    p, t, i, v, av = steady
    mean_v = trapezoid(v, t) / (t[-1] - t[0])
    mean_i = trapezoid(i, t) / (t[-1] - t[0])
    assert mean_v == pytest.approx(av.final("v"), rel=1e-2)    # the 1 %
    assert mean_v == pytest.approx(av.final("v"), rel=1e-6)    # what it achieves
    assert mean_i == pytest.approx(av.final("i"), rel=1e-5)
    exact = periodic_steady_state(**_sync(p))
    assert mean_v == pytest.approx(exact["v_mean"], rel=1e-7)
    assert mean_i == pytest.approx(exact["i_mean"], rel=1e-6)


def test_inductor_ripple_matches_the_textbook_formula(steady):
    p, t, i, v, av = steady
    mean = trapezoid(v, t) / (t[-1] - t[0])
    ripple = i.max() - i.min()
    textbook = (p["V_in"] - mean) * p["D"] / (p["L"] * p["f"])
    # the textbook assumes straight current segments; R_on and the load ripple bend them
    assert ripple == pytest.approx(textbook, rel=1e-2)
    exact = periodic_steady_state(**_sync(p))
    assert ripple == pytest.approx(exact["dI"], rel=1e-5)
    # and the capacitor takes the ripple current: dV = dI / (8 f C)
    assert v.max() - v.min() == pytest.approx(ripple / (8 * p["f"] * p["C"]), rel=5e-2)


def test_switched_run_reaches_the_exact_periodic_steady_state(steady):
    p, t, i, v, av = steady
    exact = periodic_steady_state(**_sync(p))
    assert i[-1] == pytest.approx(exact["i"], rel=1e-6)        # at a rising edge
    assert v[-1] == pytest.approx(exact["v"], rel=1e-7)
    k_fall = int(np.argmax(i))                                 # the falling edge
    assert t[k_fall] - t[0] == pytest.approx(p["D"] / p["f"], abs=1e-3 / p["f"])
    assert i[k_fall] == pytest.approx(exact["i_peak"], rel=1e-5)


def test_diode_buck_reaches_its_periodic_steady_state():
    p = ENTRY.values()
    T = 1 / p["f"]
    t = np.concatenate([np.linspace(0, 98 * T, 99), np.linspace(99 * T, 100 * T, 2001)])
    res = mt.simulate(ENTRY.build("diode"), 100 * T, rtol=1e-9, atol=1e-11, t_out=t)
    exact = periodic_steady_state(**p)                     # with the diode's V_f
    assert res.final("inductor.i") == pytest.approx(exact["i"], rel=1e-6)
    assert res.final("capacitor.v") == pytest.approx(exact["v"], rel=1e-7)
    k = int(np.searchsorted(t, 99 * T))
    v = res["capacitor.v"][k:]
    mean = trapezoid(v, t[k:]) / T
    assert mean == pytest.approx(exact["v_mean"], rel=1e-6)
    # CCM with a freewheeling diode: v = D V_in - (1 - D) V_f, less resistive drops
    assert mean == pytest.approx(p["D"] * p["V_in"] - (1 - p["D"]) * p["V_f"], rel=2e-3)
    # the diode conducts in every off-interval: two events per period
    assert res.stats.events.get("freewheel", 0) >= 2 * 99
    assert res["inductor.i"][k:].min() > 0                 # continuous conduction
