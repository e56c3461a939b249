"""The ball-screw axis's ``inputs`` variant: voltage and load force from outside."""

import math

import numpy as np
import pytest

import mechatron as mt

ENTRY = mt.models.get("ball_screw_axis")


def test_the_inputs_variant_driven_by_the_step_is_the_axis():
    """The voltage input at the step's value and no load force: the ``acausal`` axis to
    1e-9."""
    t = np.linspace(0, 0.1, 51)
    ref = mt.simulate(ENTRY.build("acausal"), 0.1, t_out=t, rtol=1e-11, atol=1e-13)
    cm = mt.compile_model(ENTRY.build("inputs"))
    assert cm.input_names == ["V", "F_load"]
    res = mt.simulate(cm, 0.1, t_out=t, rtol=1e-11, atol=1e-13,
                      inputs={"V": 19.2, "F_load": 0.0})
    for path in ENTRY.output_paths("inputs").values():
        np.testing.assert_allclose(res[path], ref[path], rtol=0,
                                   atol=1e-9 * np.abs(ref[path]).max())


def test_a_load_force_input_slows_the_axis_to_the_analytic_speed():
    """With the motor driving, the screw needs m F / eta of torque for a force F:
    w = (k V - R m F / eta) / (R (B + b m^2 / eta) + k^2), v = m w."""
    p = ENTRY.values()
    F, V = 100.0, 19.2
    m = p["lead"] / (2 * math.pi)
    w = (p["k"] * V - p["R"] * m * F / p["eta"]) / (
        p["R"] * (p["B"] + p["b"] * m ** 2 / p["eta"]) + p["k"] ** 2)
    res = mt.simulate(ENTRY.build("inputs"), 0.5, rtol=1e-10, atol=1e-12,
                      inputs={"V": V, "F_load": F})
    assert 0 < w < 0.9 * (p["k"] * V / (p["R"] * (p["B"] + p["b"] * m ** 2 / p["eta"])
                                        + p["k"] ** 2))     # the load slows it
    assert res.final("rotor.w") == pytest.approx(w, rel=1e-7)
    assert res.final("carriage.v") == pytest.approx(m * w, rel=1e-7)
