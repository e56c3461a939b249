"""Valve-controlled hydraulic cylinder: the steady piston speed and chamber pressures are
the orifice equations' flow balance (solved by SciPy), the turbulent law fixes the ratio
of the pressure drops, and reversing the spool reverses the motion."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.models.hydraulic_cylinder import steady_motion

ENTRY = mt.models.get("hydraulic_cylinder")
STEADY_ARGS = ("P_s", "x_s", "x_max", "A_max", "area_A", "area_B", "M", "b", "F_L")


def _steady(p, direction):
    return steady_motion(**{k: p[k] for k in STEADY_ARGS}, direction=direction)


@pytest.fixture(scope="module")
def run():
    t = np.linspace(0.0, 0.5, 501)
    return mt.simulate(ENTRY.build("acausal"), 0.5, rtol=1e-9, atol=1e-10, t_out=t)


def test_open_valve_gives_the_steady_speed_of_the_flow_balance(run):
    p = ENTRY.values()
    ext = _steady(p, +1.0)
    k = int(np.searchsorted(run.t, p["t_rev"] - 0.01))      # settled, spool still at +x_s
    assert run["load.v"][k] == pytest.approx(ext["v"], rel=1e-7)
    assert run["cylinder.A.p"][k] == pytest.approx(ext["p_A"], rel=1e-7)
    assert run["cylinder.B.p"][k] == pytest.approx(ext["p_B"], rel=1e-7)
    # the chambers no longer compress: the valve's flows are area times speed
    assert run["valve.q_PA"][k] == pytest.approx(p["area_A"] * ext["v"], rel=1e-6)
    assert run["valve.q_BT"][k] == pytest.approx(p["area_B"] * ext["v"], rel=1e-6)


def test_turbulent_orifices_of_equal_area_fix_the_pressure_drop_ratio(run):
    # q = Cd a sqrt(2 dp / rho) on both open paths with q_PA / q_BT = area_A / area_B:
    # (P_s - p_A) / p_B = (area_A / area_B)^2, whatever the load (textbook result)
    p = ENTRY.values()
    k = int(np.searchsorted(run.t, p["t_rev"] - 0.01))
    ratio = (p["P_s"] - run["cylinder.A.p"][k]) / run["cylinder.B.p"][k]
    assert ratio == pytest.approx((p["area_A"] / p["area_B"]) ** 2, rel=1e-5)
    # the same in retraction, P->B and A->T open: (P_s - p_B) / p_A = (area_B/area_A)^2
    ratio = (p["P_s"] - run.final("cylinder.B.p")) / run.final("cylinder.A.p")
    assert ratio == pytest.approx((p["area_B"] / p["area_A"]) ** 2, rel=1e-5)


def test_reversing_the_spool_reverses_the_motion(run):
    p = ENTRY.values()
    ext, ret = _steady(p, +1.0), _steady(p, -1.0)
    assert ext["v"] > 0 > ret["v"]
    # the weight helps the retraction but the annulus is smaller: the speeds differ
    assert abs(ret["v"]) != pytest.approx(ext["v"], rel=1e-2)
    v, x, t = run["load.v"], run["cylinder.x"], run.t
    before, after = t < p["t_rev"], t > p["t_rev"] + 0.05
    assert np.all(v[before][1:] > 0) and np.all(v[after] < 0)
    assert run.final("load.v") == pytest.approx(ret["v"], rel=1e-7)
    assert x[np.searchsorted(t, p["t_rev"])] > p["x0"] > x[-1] - 0.01
    assert int(np.argmax(x)) == pytest.approx(np.searchsorted(t, p["t_rev"]), abs=5)


def test_the_equation_variant_takes_the_same_steady_motion():
    p = ENTRY.values(t_rev=1.0, x_s=5e-4)
    res = mt.simulate(ENTRY.build("equation", t_rev=1.0, x_s=5e-4), 0.3, rtol=1e-9,
                      atol=1e-10)
    ext = _steady(p, +1.0)
    assert res.final("v") == pytest.approx(ext["v"], rel=1e-7)
    assert res.final("p_A") == pytest.approx(ext["p_A"], rel=1e-7)

