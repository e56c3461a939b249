"""The battery-fed BLDC drive: the speed reaches its reference while the battery sags,
the charge drawn is the fall of the state of charge, the chopper conserves power, and the
chemical energy released pays for every loss and store of battery and drive."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library.electrical.battery import LI_ION_OCV
from mechatron.models.battery_bldc import ENTRY

P = ENTRY.values()
FETS = [f"leg_{k}.{side}" for k in "abc" for side in ("high", "low")]


@pytest.fixture(scope="module")
def run():
    t = np.linspace(0.0, 0.15, 15001)
    return mt.simulate(ENTRY.build(), 0.15, t_out=t, rtol=1e-8, atol=1e-10)


def test_battery_state_and_chopper(run):
    t, i = run.t, run["battery.i"]
    drawn = -np.trapezoid(i, t)                            # A*s out of the battery
    assert drawn > 0
    # to the integration error of SOC (rtol 1e-8 of 0.8), 1e-3 of its small fall
    assert run["battery.SOC"][0] - run.final("battery.SOC") == \
        pytest.approx(drawn / (3600 * P["Q"]), abs=2e-8)
    # terminal voltage: n_s OCV(SOC) + R0 i + v1, the OCV from the library's table
    soc, ocv = np.array(LI_ION_OCV).T
    v_oc = np.interp(run["battery.SOC"], soc, ocv)
    np.testing.assert_allclose(run["battery.v"], P["n_s"] * v_oc + P["R0"] * i
                               + run["battery.v1"], atol=1e-9)
    assert run.final("battery.v") < P["n_s"] * v_oc[-1]     # it sags under load
    # averaged chopper: link voltage d v_bat, power in = power out
    np.testing.assert_allclose(run["chopper.v2"], run["controller.d"] * run["chopper.v1"],
                               atol=1e-9)
    np.testing.assert_allclose(run["chopper.v1"] * run["chopper.i1"],
                               -run["chopper.v2"] * run["chopper.i2"], atol=1e-9)


def test_chemical_energy_pays_for_battery_and_drive(run):
    t = run.t
    integral = lambda y: np.trapezoid(y, t)                              # noqa: E731
    soc, ocv = np.array(LI_ION_OCV).T
    i = run["battery.i"]
    chemical = -integral(P["n_s"] * np.interp(run["battery.SOC"], soc, ocv) * i)
    v1 = run["battery.v1"]
    battery = integral(P["R0"] * i ** 2 + v1 ** 2 / P["R1"]) + 0.5 * P["C1"] * v1[-1] ** 2
    i2 = sum(run[f"motor.airgap.i_{k}"] ** 2 for k in "abc")
    w = run["motor.inertia.w"]
    drive = 0.5 * P["L"] * i2[-1] + 0.5 * P["J"] * w[-1] ** 2 + integral(
        P["R"] * i2 + sum(run[f"{q}.v"] * run[f"{q}.i"] for q in FETS)
        + P["B"] * w ** 2 + P["T_load"] * w)
    # trapezoidal quadrature across the commutation jumps of a 10 us grid (bldc_motor's)
    assert chemical == pytest.approx(battery + drive, rel=3e-4)
