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


def test_the_inputs_variant_driven_by_the_ramp_is_the_hoist():
    """The voltage input given the ramp as a table, (0, 0) to (t_ramp, V), held: the
    ``acausal`` hoist to 1e-9 (the ramp's kink is an event there and a table corner here,
    which the integrator meets within its tolerance, 1e-12)."""
    from mechatron.models.planetary_hoist import ramp_input
    t = np.linspace(0, 1.0, 201)
    ref = mt.simulate(ENTRY.build("acausal"), 1.0, t_out=t, rtol=1e-12, atol=1e-14)
    cm = mt.compile_model(ENTRY.build("inputs"))
    assert cm.input_names == ["V", "F_load"]
    res = mt.simulate(cm, 1.0, t_out=t, rtol=1e-12, atol=1e-14,
                      inputs=ramp_input(ENTRY.values(), 1.0))
    for path in ENTRY.output_paths("inputs").values():
        np.testing.assert_allclose(res[path], ref[path], rtol=0,
                                   atol=1e-9 * np.abs(ref[path]).max())


def test_a_load_force_input_is_a_heavier_load():
    """A load force F pulling down: the steady state of a mass m + F / g."""
    values = ENTRY.values()
    F = 5.0
    res = mt.simulate(ENTRY.build("inputs"), 2.0, rtol=1e-9, atol=1e-11,
                      inputs={"V": 24.0, "F_load": F})
    expect = steady_state(**dict(values, m=values["m"] + F / values["g"]))
    assert res.final("motor.inertia.w") == pytest.approx(expect["w"], rel=1e-6)
    assert res.final("motor.inductor.i") == pytest.approx(expect["i"], rel=1e-6)
    assert res.final("rope.s_rel") == pytest.approx(expect["L_r"], rel=1e-6)
