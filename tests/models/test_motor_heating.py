"""Motor winding heating: the multi-domain network balances its energy, and the final
state is the closed-form steady state."""

import numpy as np
import pytest
from scipy.integrate import simpson

import mechatron as mt
from mechatron.models.motor_heating import steady_state

ENTRY = mt.models.get("motor_heating")


def _integral(t_parts, y_parts):
    return sum(simpson(y, x=t) for t, y in zip(t_parts, y_parts))


def test_energy_balance_across_three_domains():
    p = ENTRY.values()
    t_stop = 300.0
    # a fine grid over the electrical and mechanical transients, then a coarser one
    parts = [np.linspace(0, 0.05, 20001), np.linspace(0.05, 5, 20001),
             np.linspace(5, t_stop, 20001)]
    res = mt.simulate(ENTRY.build("acausal"), t_stop, rtol=1e-11, atol=1e-12,
                      t_out=np.unique(np.concatenate(parts)))

    def seg(name):
        y = res[name]
        return [y[np.searchsorted(res.t, t[0]):np.searchsorted(res.t, t[-1]) + 1]
                for t in parts]

    i, w, T = seg("inductor.i"), seg("inertia.w"), seg("mass.T")
    supplied = _integral(parts, [p["V"] * x for x in i])
    heat_out = _integral(parts, [p["G"] * (x - p["T_amb"]) for x in T])
    viscous = _integral(parts, [p["B"] * x ** 2 for x in w])
    load = _integral(parts, [p["T_L"] * x for x in w])
    stored = (0.5 * p["L"] * res.final("inductor.i") ** 2
              + 0.5 * p["J"] * res.final("inertia.w") ** 2
              + p["C"] * (res.final("mass.T") - p["T_amb"]))
    assert supplied == pytest.approx(stored + heat_out + viscous + load, rel=1e-6)


def test_a_hotter_winding_slows_the_motor():
    cold = steady_state(**ENTRY.values(alpha=0.0))
    hot = steady_state(**ENTRY.values())
    assert hot["T"] > cold["T"] > 293.15
    assert hot["w"] < cold["w"]
