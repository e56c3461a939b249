"""The dc_motor entry against the analytic solution of the linear second-order system."""

import numpy as np
import pytest
from scipy.linalg import expm

import mechatron as mt

ENTRY = mt.models.get("dc_motor")
V, R, L, K, J, B = 19.2, 7.1, 3.408e-4, 0.151, 4.8e-6, 1.236e-4
TIMES = [1e-4, 1e-3, 1e-2, 0.1, 0.5]


def analytic(t):
    """x = [i, w]; x' = A x + b V from rest, by the matrix exponential."""
    a = np.array([[-R / L, -K / L], [K / J, -B / J]])
    b = np.array([V / L, 0.0])
    x_inf = -np.linalg.solve(a, b)
    return np.array([x_inf - expm(a * tk) @ x_inf for tk in np.atleast_1d(t)])


@pytest.fixture(scope="module")
def acausal():
    return mt.simulate(ENTRY.build("acausal"), 0.5, rtol=1e-10, atol=1e-12,
                       t_out=np.array([0.0] + TIMES))


def test_acausal_matches_analytic_solution(acausal):
    out = ENTRY.output_paths("acausal")
    ref = analytic(TIMES)
    np.testing.assert_allclose(acausal[out["i"]][1:], ref[:, 0], rtol=1e-6)
    np.testing.assert_allclose(acausal[out["w"]][1:], ref[:, 1], rtol=1e-6)


def test_final_speed_is_k_V_over_RB_plus_k2(acausal):
    w_final = acausal.final(ENTRY.output_paths("acausal")["w"])
    assert w_final == pytest.approx(K * V / (R * B + K ** 2), rel=1e-6)
    assert w_final == pytest.approx(ENTRY.expected["w"], rel=1e-6)


def test_ode_variant_agrees_with_acausal_to_1e_8(acausal):
    ode = mt.simulate(ENTRY.build("ode"), 0.5, rtol=1e-12, atol=1e-14,
                      t_out=np.array([0.0] + TIMES))
    tight = mt.simulate(ENTRY.build("acausal"), 0.5, rtol=1e-12, atol=1e-14,
                        t_out=np.array([0.0] + TIMES))
    for label in ("w", "i"):
        a = tight[ENTRY.output_paths("acausal")[label]]
        b = ode[ENTRY.output_paths("ode")[label]]
        np.testing.assert_allclose(b, a, rtol=1e-8, atol=1e-12)


def test_blocks_variant_agrees_with_acausal_to_1e_8():
    """The Simulink-style diagram (two integrators, gains, sums) is the same system."""
    blk = mt.simulate(ENTRY.build("blocks"), 0.5, rtol=1e-12, atol=1e-14,
                      t_out=np.array([0.0] + TIMES))
    tight = mt.simulate(ENTRY.build("acausal"), 0.5, rtol=1e-12, atol=1e-14,
                        t_out=np.array([0.0] + TIMES))
    for label in ("w", "i"):
        a = tight[ENTRY.output_paths("acausal")[label]]
        b = blk[ENTRY.output_paths("blocks")[label]]
        np.testing.assert_allclose(b, a, rtol=1e-8, atol=1e-12)
    ref = analytic(TIMES)
    np.testing.assert_allclose(blk[ENTRY.output_paths("blocks")["w"]][1:], ref[:, 1],
                               rtol=1e-6)


def test_energy_balance_over_half_a_second():
    """Input energy = resistor and damper losses + magnetic and kinetic energy."""
    t = np.linspace(0, 0.5, 200001)
    res = mt.simulate(ENTRY.build("acausal"), 0.5, rtol=1e-11, atol=1e-13, t_out=t)
    from scipy.integrate import simpson
    e_in = simpson(res["source.v"] * res["source.i"] * -1, x=t)
    e_r = simpson(res["resistor.v"] * res["resistor.i"], x=t)
    e_d = simpson(res["damper.tau"] * res["damper.w"], x=t)
    e_l = 0.5 * L * res.final("inductor.i") ** 2
    e_j = 0.5 * J * res.final("inertia.w") ** 2
    assert e_in > 0
    assert (e_r + e_d + e_l + e_j) == pytest.approx(e_in, rel=1e-6)


def test_parameters_change_between_runs_without_recompiling():
    cm = mt.compile_model(ENTRY.build("acausal"))
    base = mt.simulate(cm, 0.5, rtol=1e-10, atol=1e-12)
    more_r = mt.simulate(cm, 0.5, rtol=1e-10, atol=1e-12, params={"resistor.R": "7.5 ohm"})
    assert base.final("inertia.w") == pytest.approx(K * V / (R * B + K ** 2), rel=1e-6)
    assert more_r.final("inertia.w") == pytest.approx(K * V / (7.5 * B + K ** 2), rel=1e-6)


def test_build_takes_quantities_with_units():
    res = mt.simulate(ENTRY.build("ode", L="340 uH", V="19.2 V"), 0.01, rtol=1e-8)
    assert res.final("w") > 0
    with pytest.raises(mt.errors.UnitError, match="dc_motor.L"):
        ENTRY.build("ode", L="3 kg")


def test_the_inputs_variant_is_driven_by_voltage_and_load_torque():
    """Voltage and load torque as external inputs: the final speed under a load step is
    (k V - R T) / (R B + k^2); with its defaults it is the database's step response."""
    import numpy as np

    import mechatron as mt
    entry = mt.models.get("dc_motor")
    cm = mt.compile_model(entry.build("inputs"))
    assert cm.input_names == ["V", "tau_load"]
    R, k, B = 7.1, 0.151, 1.236e-4
    t = np.array([0.0, 0.2, 0.2 + 1e-6, 1.0])
    res = mt.simulate(cm, 0.6, inputs={"V": 12.0, "tau_load": (t, [0.0, 0.0, 0.01, 0.01])},
                      rtol=1e-10, atol=1e-12)
    assert res.final("inertia.w") == pytest.approx((k * 12.0 - R * 0.01) / (R * B + k * k),
                                                   rel=1e-7)
    assert res.final("load.tau_in") == 0.01
