"""MSL's IMC_DOL rebuilt: the end point is MSL's published nominal point (161.4 N*m at
1440.45 rpm, given to those digits), and early in the start the current is the
equivalent circuit's at the momentary slip (near standstill: the locked-rotor current)."""

import math

import numpy as np
import pytest

import mechatron as mt
from mechatron.models.induction_dol import ENTRY, steady_state


def test_end_point_is_msls_nominal_point():
    f = steady_state(**ENTRY.values())
    assert f["w"] * 60 / (2 * math.pi) == pytest.approx(1440.45, abs=0.01)
    assert f["T"] == pytest.approx(161.4, abs=0.01)


def test_start_draws_the_current_of_the_momentary_slip():
    p = ENTRY.values()
    t = np.linspace(0.0, 0.1, 2001)
    res = mt.simulate(ENTRY.build(), 0.1, t_out=t, rtol=1e-9, atol=1e-9)
    w_s = 2 * math.pi * p["f"]

    def current(slip):          # steady RMS stator current of the equivalent circuit
        z_r = p["R_r"] / slip + 1j * w_s * p["L_r_sigma"]
        z_m = 1j * w_s * p["L_m"]
        return abs(p["V"] / (p["R_s"] + 1j * w_s * p["L_s_sigma"] + z_m * z_r / (z_m + z_r)))
    # the 5th cycle: the switch-on's DC offset (stator time constant ~10 ms) has decayed,
    # the rotor has reached about a sixth of synchronous speed; quasi-steady within 5 %
    cycle = (t >= 0.08) & (t < 0.1)
    slip = 1 - np.mean(res["load.w"][cycle]) * p["p"] / w_s
    assert 0.7 < slip < 0.95
    rms = np.sqrt(np.mean(res["motor.a.i"][cycle] ** 2))
    assert rms == pytest.approx(current(slip), rel=0.05)
    assert rms > 4 * steady_state(**p)["I_rms"]     # vs the running current (100 A)
