"""The geared drive with backlash (``geared_drive``): analytic steady states on both
flanks, the dead band crossed when the motor reverses, and free flight of the load in the
gap (its own friction-and-load-torque dynamics, solved in closed form)."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.models.geared_drive import ENTRY, steady_state

P = ENTRY.values()
T_STOP = ENTRY.experiment.t_stop


@pytest.fixture(scope="module", params=["acausal", "equation"])
def run(request):
    t = np.unique(np.concatenate([np.linspace(0.0, T_STOP, 5001),
                                  np.linspace(P["t_rev"], P["t_rev"] + 0.01, 20001)]))
    res = mt.simulate(ENTRY.build(request.param), T_STOP, rtol=1e-10, atol=1e-12,
                      t_out=t)
    return res, ENTRY.output_paths(request.param)


def at(res, path, t):
    return float(np.interp(t, res.t, res[path]))


@pytest.mark.parametrize("when, sign", [("before", 1.0), ("end", -1.0)])
def test_steady_state_on_each_flank_is_analytic(run, when, sign):
    res, out = run
    t = P["t_rev"] - 1e-6 if when == "before" else T_STOP
    ref = steady_state(**dict(P, V=sign * P["V"]))
    for label in ("w_m", "i", "w_L", "tau", "phi"):
        assert at(res, out[label], t) == pytest.approx(ref[label], rel=1e-6), label
    # the teeth touch on the flank the transmitted torque asks for
    assert np.sign(ref["phi"]) == np.sign(ref["tau"]) == sign


def test_load_falls_behind_by_the_dead_band_when_the_motor_reverses(run):
    res, out = run
    fwd = steady_state(**P)
    rev = steady_state(**dict(P, V=-P["V"]))
    lag = at(res, out["phi"], P["t_rev"] - 1e-6) - res[out["phi"]][-1]
    assert lag == pytest.approx(P["b"] + (fwd["tau"] - rev["tau"]) / P["k_c"], rel=1e-6)
    assert lag > P["b"]


def test_load_flies_freely_across_the_gap(run):
    """After the reversal the teeth separate; while no torque is transmitted the load
    obeys J_L dw/dt = -b_L w - T_L, so w(t) = (w0 + T_L/b_L) exp(-b_L (t - t0)/J_L) -
    T_L/b_L; the flight ends when the other flank is reached, phi = -b/2."""
    res, out = run
    t, tau, phi, w_L = res.t, res[out["tau"]], res[out["phi"]], res[out["w_L"]]
    after = t > P["t_rev"]
    free = after & (tau == 0.0)
    assert free.any()
    first = np.argmax(free)
    last = first + np.argmin(free[first:])          # first contact sample after the flight
    assert last - first > 20
    flight = slice(first, last)
    assert phi[first] >= P["b"] / 2 - 1e-9          # contact was lost on the driving flank
    assert phi[last] == pytest.approx(-P["b"] / 2, abs=5e-5)   # the grid's resolution
    assert phi[last - 1] > -P["b"] / 2               # met the other flank, not earlier
    c = P["T_L"] / P["b_L"]
    t0, w0 = t[first], w_L[first]
    analytic = (w0 + c) * np.exp(-P["b_L"] * (t[flight] - t0) / P["J_L"]) - c
    np.testing.assert_allclose(w_L[flight], analytic, rtol=1e-7, atol=1e-9)
    # the reversed torque brakes the motor at once: the gear output falls behind the
    # load, which runs on forward; by the end of the flight the motor runs backward
    w_gear = res[out["w_m"]] / P["N"]
    assert w_gear[first] < w_L[first] and w_L[first] > 0
    assert w_gear[last] < 0
