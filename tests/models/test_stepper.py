"""Hybrid stepper in wave drive: after n steps the rotor rests at n * 1.8 degrees, a
single step rings at the frequency of the linearised motor, which is sqrt(N K I / J)
when the drive holds the current stiffly, and the converted power balances."""

import math

import numpy as np
import pytest
from scipy.integrate import trapezoid

import mechatron as mt
from mechatron.models.stepper import linearization, step_angle

ENTRY = mt.models.get("stepper_motor")


@pytest.mark.parametrize("variant", ["acausal", "equation"])
@pytest.mark.parametrize("n", [1, 3, 5])
def test_rotor_rests_at_n_full_steps(n, variant):
    p = ENTRY.values(n_steps=n)
    t_stop = p["t_start"] + (n - 1) / p["f_step"] + 0.12
    res = mt.simulate(ENTRY.build(variant, n_steps=n), t_stop, rtol=1e-9, atol=1e-11)
    out = ENTRY.output_paths(variant)
    theta = res.final(out["theta"])
    assert math.degrees(step_angle(p["N"])) == pytest.approx(1.8, rel=1e-12)
    assert math.degrees(theta) == pytest.approx(n * 1.8, rel=1e-7)
    # the energised phase of step n carries the full current, the other none
    i_a, i_b = res.final(out["i_a"]), res.final(out["i_b"])
    I = p["V"] / p["R"]
    assert (i_a, i_b) == pytest.approx({0: (I, 0), 1: (0, I), 2: (-I, 0),
                                        3: (0, -I)}[n % 4], abs=1e-6)


def _ringing(params, t_stop=0.08, first=3, count=7):
    """Damped frequency and decay rate of the rotor's ringing after a single step, from
    its zero crossings and the ratio of successive extrema (linear regime: skipping the
    ``first`` large swings, where the sin(N theta) torque is not yet linear)."""
    t = np.linspace(0.0, t_stop, int(t_stop / 2e-6) + 1)
    res = mt.simulate(ENTRY.build("acausal", n_steps=1, **params), t_stop, rtol=1e-10,
                      atol=1e-12, t_out=t)
    p = ENTRY.values(n_steps=1, **params)
    e = res["motor.theta"] - step_angle(p["N"])
    k0 = int(np.searchsorted(t, p["t_start"]))
    t, e = t[k0:], e[k0:]
    idx = np.nonzero(np.sign(e[:-1]) != np.sign(e[1:]))[0]
    crossings = t[idx] - e[idx] * (t[idx + 1] - t[idx]) / (e[idx + 1] - e[idx])
    crossings = crossings[first:first + count]
    half = np.diff(crossings)
    peaks = np.array([np.abs(e[(t > a) & (t < b)]).max()
                      for a, b in zip(crossings[:-1], crossings[1:])])
    omega_d = math.pi / half.mean()
    sigma = np.mean(np.log(peaks[1:] / peaks[:-1]) / half[1:])
    return omega_d, sigma, half


def test_single_step_rings_at_the_linearised_frequency():
    p = ENTRY.values()
    omega_d, sigma, half = _ringing({})
    lam = np.linalg.eigvals(linearization(p["V"], p["R"], p["L"], p["K"], p["N"],
                                          p["T_d"], p["J"], p["B"]))
    pair = lam[np.argmax(np.abs(lam.imag))]
    assert np.ptp(half) < 1e-3 * half.mean()          # a linear oscillation by now
    assert omega_d == pytest.approx(abs(pair.imag), rel=1e-3)
    assert sigma == pytest.approx(pair.real, rel=2e-2)
    # the back-EMF current of the idle phase damps (and stiffens) the ringing: the
    # undamped sqrt(N K I / J) is only an estimate here
    assert omega_d == pytest.approx(math.sqrt(p["N"] * p["K"] * p["V"] / p["R"]
                                              / p["J"]), rel=0.2)


def test_with_a_stiff_current_the_natural_frequency_is_sqrt_NKI_over_J():
    # the same current I = V / R from a 100x higher voltage and resistance (same L/R):
    # the back-EMF barely changes the current; no detent torque; a friction B that
    # damps the swings (zeta ~ 0.18) into the linear range within a few periods
    params = {"V": 300.0, "R": 200.0, "L": 0.1, "T_d": 0.0, "B": 0.01}
    p = ENTRY.values(**params)
    omega_d, sigma, half = _ringing(params, t_stop=0.1, first=6, count=7)
    omega_n = math.sqrt(p["N"] * p["K"] * (p["V"] / p["R"]) / p["J"])
    # a damped oscillator's natural frequency is |lambda| = sqrt(omega_d^2 + sigma^2)
    assert math.hypot(omega_d, sigma) == pytest.approx(omega_n, rel=2e-3)
    assert -sigma == pytest.approx((p["B"] + p["K"] ** 2 / p["R"]) / (2 * p["J"]),
                                   rel=2e-2)


def test_power_balance_of_the_motor():
    # the supply steps at each commutation: the trapezoid rule across a step is off by
    # about h |jump| / 2 (8e-5 of the energy on 25001 points, 6e-6 on 250001), so the
    # grid is fine enough for the balance's 1e-4
    p = ENTRY.values()
    t = np.linspace(0.0, ENTRY.experiment.t_stop, 250001)
    res = mt.simulate(ENTRY.build("acausal"), t[-1], rtol=1e-10, atol=1e-12, t_out=t)
    ia, ib, w = res["motor.i_a"], res["motor.i_b"], res["rotor.w"]
    va, vb = res["supply_a.v"], res["supply_b.v"]
    supplied = trapezoid(va * ia + vb * ib, t)
    copper = trapezoid(p["R"] * (ia ** 2 + ib ** 2), t)
    friction = trapezoid(p["B"] * w ** 2, t)
    magnetic = 0.5 * p["L"] * ((ia[-1] ** 2 + ib[-1] ** 2) - (ia[0] ** 2 + ib[0] ** 2))
    theta_end = res.final("motor.theta")
    # the detent torque is conservative: potential T_d (1 - cos(4 N theta)) / (4 N)
    detent = p["T_d"] * (1 - math.cos(4 * p["N"] * theta_end)) / (4 * p["N"])
    kinetic = 0.5 * p["J"] * w[-1] ** 2
    assert supplied == pytest.approx(copper + friction + magnetic + detent + kinetic,
                                     rel=1e-4)
