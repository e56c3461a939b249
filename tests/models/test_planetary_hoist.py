"""The planetary hoist: its steady lifting speed (the database test checks the final
values against the analytic steady state), the planetary set's kinematics, and the energy
balance of the whole drive: electrical energy in = copper, friction and rope losses +
potential, kinetic and spring energy gained."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.models.planetary_hoist import ENTRY, steady_state


def test_hoist_kinematics_and_energy_balance():
    p = ENTRY.values()
    t = np.linspace(0, 2.0, 40001)
    res = mt.simulate(ENTRY.build("acausal"), 2.0, t_out=t, rtol=1e-10, atol=1e-12)
    n = 1 + p["ratio"]
    # ring held: the carrier turns n times slower than the sun; the drum winds r w_c
    np.testing.assert_allclose(res["gear.carrier.w"], res["motor.inertia.w"] / n,
                               atol=1e-9)
    np.testing.assert_allclose(res["drum.T.v"], p["r"] * res["gear.carrier.w"], atol=1e-12)
    i, w, vm, L_r = (res["motor.inductor.i"], res["motor.inertia.w"], res["load.v"],
                     res["rope.s_rel"])
    v_supply = res["supply.v"]

    def integral(y):
        return np.trapezoid(y, t)
    h = np.concatenate([[0.0], np.cumsum(np.diff(t) * 0.5 * (vm[1:] + vm[:-1]))])
    rate = res["drum.T.v"] - vm
    supplied = integral(v_supply * i)
    lost = integral(p["R"] * i ** 2 + p["B"] * w ** 2 + p["d"] * rate ** 2)
    stretch = L_r - p["L_0"]
    gained = (0.5 * p["L"] * i[-1] ** 2 + 0.5 * p["J"] * w[-1] ** 2
              + 0.5 * p["m"] * vm[-1] ** 2 + p["m"] * p["g"] * h[-1]
              + 0.5 * p["c"] * (stretch[-1] ** 2 - stretch[0] ** 2))
    assert supplied == pytest.approx(lost + gained, rel=1e-6)
    # and it lifts: at the end the load rises at the steady speed
    assert vm[-1] == pytest.approx(steady_state(**p)["v_m"], rel=1e-6)
    assert h[-1] > 1.0
