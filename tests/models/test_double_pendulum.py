"""The double pendulum's equation variant against an independent SciPy integration of
the explicit (mass-matrix-inverted) Lagrange equations, and its energy conservation."""

import math

import numpy as np
from scipy.integrate import solve_ivp

import mechatron as mt

G = 9.81


def explicit_rhs(m1, m2, l1, l2):
    def rhs(t, s):
        a1, a2, w1, w2 = s
        d = a1 - a2
        mass = np.array([[(m1 + m2) * l1, m2 * l2 * math.cos(d)],
                         [l1 * math.cos(d), l2]])
        rest = np.array([-m2 * l2 * w2 ** 2 * math.sin(d) - (m1 + m2) * G * math.sin(a1),
                         l1 * w1 ** 2 * math.sin(d) - G * math.sin(a2)])
        acc = np.linalg.solve(mass, rest)
        return [w1, w2, acc[0], acc[1]]
    return rhs


def test_equation_variant_matches_scipy_and_conserves_energy():
    entry = mt.models.get("double_pendulum")
    p = entry.values()
    t = np.linspace(0, 5, 501)
    res = mt.simulate(entry.build("equation"), 5.0, rtol=1e-12, atol=1e-12, t_out=t)
    ref = solve_ivp(explicit_rhs(p["m1"], p["m2"], p["l1"], p["l2"]), (0, 5),
                    [p["alpha1_0"], p["alpha2_0"], 0.0, 0.0], method="DOP853",
                    rtol=1e-13, atol=1e-13, t_eval=t)
    np.testing.assert_allclose(res["alpha1"], ref.y[0], atol=1e-6)
    np.testing.assert_allclose(res["alpha2"], ref.y[1], atol=1e-6)
    e0 = -p["m2"] * G * p["l2"]          # released from rest, rod 1 horizontal
    assert np.max(np.abs(res["E"] - e0)) / abs(e0) < 1e-8
