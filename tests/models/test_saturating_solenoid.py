"""The saturating solenoid: the database test checks the final state against the static
balance (:func:`final_state`); here the energy balance of the whole actuator over the
pull-in, the saturation of the steel and the plunger's position state."""

import math

import numpy as np
import pytest

import mechatron as mt
from mechatron.library.magnetic import MU0, SOFT_MAGNETIC
from mechatron.models.saturating_solenoid import ENTRY, final_state


def test_pull_in_conserves_energy_and_saturates_the_steel():
    p = ENTRY.values()
    t = np.linspace(0.0, 0.05, 50001)
    res = mt.simulate(ENTRY.build(), 0.05, t_out=t, rtol=1e-10, atol=1e-13)
    i, x, v = res["r_coil.i"], res["gap.x"], res["plunger.v"]
    # the plunger's position (MSL's Mass.s) is the gap: both start at x0
    np.testing.assert_allclose(res["plunger.s"], x, atol=1e-12)
    assert x.min() < p["x_min"]                          # it reaches the stop

    def integral(y):
        return np.trapezoid(y, t)
    supplied = integral(p["V"] * i)
    copper = integral(p["R"] * i ** 2)
    friction = integral(res["spring.P_loss"])
    stop_loss = integral(res["stop.f"] * res["stop.v"]) - 0.5 * p["c_stop"] * \
        (np.maximum(p["x_min"] - x, 0) ** 2)[-1]          # stop work minus its stored part
    # magnetic energy: integral of the mmf over the flux, each tube (lossless tubes)
    mat = SOFT_MAGNETIC["Steel_9SMnPb28"]
    area = math.pi * p["r"] ** 2
    B = np.linspace(0.0, res.final("iron.B_flux"), 20001)
    w_iron = np.trapezoid(B / (MU0 * mat.mu_r(B)), B) * p["l_fe"] * area
    U = res.final("gap.mmf")
    w_gap = 0.5 * res.final("gap.phi") * U
    w_leak = 0.5 * res.final("leak.phi") * U
    spring = 0.5 * p["c"] * (p["x0"] - x[-1]) ** 2
    stop_stored = 0.5 * p["c_stop"] * (p["x_min"] - x[-1]) ** 2
    kinetic = 0.5 * p["m"] * v[-1] ** 2
    assert supplied == pytest.approx(copper + friction + stop_loss + w_iron + w_gap + w_leak
                                     + spring + stop_stored + kinetic, rel=1e-5)
    # deep in saturation: the steel's permeability has fallen far below its peak
    B_fe = res.final("iron.B_flux")
    assert B_fe > 1.25 * mat.B_max
    assert res.final("iron.mu_r") < 0.2 * mat.mu_r(mat.B_max)


def test_final_state_is_the_static_balance():
    p = ENTRY.values()
    f = final_state(**p)
    area = math.pi * p["r"] ** 2
    # the pull of the gap's mmf equals the spring and the stop, at rest
    assert -f["F"] == pytest.approx(p["c"] * (p["x0"] - f["x"])
                                    + p["c_stop"] * (p["x_min"] - f["x"]), rel=1e-9)
    assert -f["F"] == pytest.approx(f["phi"] ** 2 / (2 * MU0 * area), rel=1e-9)
