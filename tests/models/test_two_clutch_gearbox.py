"""The two-clutch gearbox: the analytic steady state in each gear, the clutch modes of a
power-shift, and the energy balance across it (clutch slip losses included)."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.models.two_clutch_gearbox import ENTRY, steady_state


@pytest.fixture(scope="module")
def run():
    t = np.linspace(0.0, 4.0, 40001)
    return mt.simulate(ENTRY.build(), 4.0, t_out=t, rtol=1e-10, atol=1e-12)


def test_steady_state_in_each_gear(run):
    p = ENTRY.values()
    before = np.searchsorted(run.t, p["t_shift"]) - 1
    g1 = steady_state(**p, ratio=p["r1"])
    assert run["motor.inertia.w"][before] == pytest.approx(g1["w_m"], rel=1e-6)
    assert run["load.w"][before] == pytest.approx(g1["w_L"], rel=1e-6)
    # gear 1 locked, gear 2 open: clutch 1 stuck, clutch 2 slipping forward
    assert run["clutch1.mode"][before] == 0 and run["clutch2.mode"][before] == 1
    g2 = steady_state(**p, ratio=p["r2"])
    assert run.final("load.w") == pytest.approx(g2["w_L"], rel=1e-6)
    # after the shift: clutch 2 stuck, clutch 1 open and slipping backwards
    assert run["clutch2.mode"][-1] == 0 and run["clutch1.mode"][-1] == -1
    # the load's angle (MSL's Inertia.phi) is the integral of its speed
    phi = np.concatenate([[0.0], np.cumsum(np.diff(run.t) * 0.5 * (run["load.w"][1:]
                                                                  + run["load.w"][:-1]))])
    np.testing.assert_allclose(run["load.phi"], phi, atol=1e-6 * phi[-1])


def test_energy_balance_across_the_shift(run):
    p = ENTRY.values()
    t, i = run.t, run["motor.inductor.i"]
    w_m, w_L = run["motor.inertia.w"], run["load.w"]

    def integral(y):
        return np.trapezoid(y, t)
    supplied = integral(p["V"] * i)
    copper = integral(p["R"] * i ** 2)
    friction = integral(p["B_v"] * w_m ** 2 + p["D_L"] * w_L ** 2)
    slip = integral(run["clutch1.tau"] * run["clutch1.w"]
                    + run["clutch2.tau"] * run["clutch2.w"])
    kinetic = 0.5 * p["J"] * w_m[-1] ** 2 + 0.5 * p["J_L"] * w_L[-1] ** 2
    magnetic = 0.5 * p["L"] * i[-1] ** 2
    assert slip > 0.05 * kinetic                 # the shift dissipates in clutch 2
    assert supplied == pytest.approx(copper + friction + slip + kinetic + magnetic,
                                     rel=2e-6)
