"""Cart-pole: for a small release angle the nonlinear closed loop follows the linear one
(matrix exponential of A - B K), and the LQR gain makes the linearisation stable."""

import numpy as np
import pytest
from scipy.linalg import expm

import mechatron as mt
from mechatron.models.cart_pendulum import linearization, lqr_gain

ENTRY = mt.models.get("cart_pendulum")


def test_lqr_closed_loop_is_stable():
    p = ENTRY.values()
    a, b = linearization(p["M"], p["m"], p["l"], p["b"])
    k = lqr_gain(p["M"], p["m"], p["l"], p["b"])
    assert np.max(np.linalg.eigvals(a).real) > 0                 # upright is unstable
    assert np.max(np.linalg.eigvals(a - b @ k).real) < -0.1


def _deviation_from_linear(theta0):
    """Largest |nonlinear - linear| of theta and x over 5 s, relative to theta0."""
    p = ENTRY.values(theta0=theta0, x_ref=0.0)
    a, b = linearization(p["M"], p["m"], p["l"], p["b"])
    acl = a - b @ lqr_gain(p["M"], p["m"], p["l"], p["b"])
    t = np.linspace(0, 5, 51)
    res = mt.simulate(ENTRY.build(theta0=theta0, x_ref=0.0), 5.0, rtol=1e-12, atol=1e-14,
                      t_out=t)
    lin = np.array([expm(acl * tk) @ [0, 0, theta0, 0] for tk in t])
    return np.array([np.max(np.abs(res["theta"] - lin[:, 2])),
                     np.max(np.abs(res["x"] - lin[:, 0]))]) / theta0


def test_small_angle_release_follows_the_linear_closed_loop():
    """The nonlinearity is O(theta^3), so the deviation relative to theta0 is O(theta0^2):
    100 times smaller for a 10 times smaller release angle."""
    small, larger = _deviation_from_linear(1e-3), _deviation_from_linear(1e-2)
    assert np.all(small < 1e-5)
    np.testing.assert_allclose(larger / small, 100.0, rtol=0.01)
