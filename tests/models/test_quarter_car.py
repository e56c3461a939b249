"""Quarter car: the body's steady motion is the road sine times H(j w)."""

import math

import numpy as np
import pytest

import mechatron as mt
from mechatron.models.quarter_car import body_response

ENTRY = mt.models.get("quarter_car")


@pytest.mark.parametrize("f", [1.0, 10.0])
def test_steady_amplitude_and_phase_follow_the_transfer_function(f):
    p = ENTRY.values(f=f)
    t = np.linspace(18.0, 20.0, 4001)
    res = mt.simulate(ENTRY.build("acausal", f=f), 20.0, rtol=1e-10, atol=1e-12, t_out=t)
    z = res[ENTRY.output_paths("acausal")["z_s"]]
    # least-squares fit of a sin + b cos over whole periods
    w = 2 * math.pi * f
    basis = np.column_stack([np.sin(w * t), np.cos(w * t)])
    (a, b), *_ = np.linalg.lstsq(basis, z, rcond=None)
    h = body_response(p["m_s"], p["m_u"], p["k_s"], p["b_s"], p["k_t"], w)
    assert math.hypot(a, b) == pytest.approx(abs(h) * p["A"], rel=1e-6)
    assert math.atan2(b, a) == pytest.approx(np.angle(h), abs=1e-6)


def test_wheel_hop_resonance_is_above_the_body_resonance():
    p = ENTRY.values()
    args = (p["m_s"], p["m_u"], p["k_s"], p["b_s"], p["k_t"])
    body = math.sqrt(p["k_s"] / p["m_s"])            # about 8 rad/s
    # the body moves more than the road near its resonance and far less above it
    assert abs(body_response(*args, body)) > 1.5
    assert abs(body_response(*args, 10 * body)) < 0.1
