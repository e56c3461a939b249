"""The mass-spring-damper cases against a hand-written SciPy integration of Newton's law
(written here independently of the models' equations) and against physics."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechatron as mt

G, V_C = 9.81, 0.01
CASES = {"msd_horizontal": 0.0, "msd_incline": math.radians(60), "msd_vertical": math.pi / 2}


def newton(alpha, m, k_s, b, mu=0.0, F=0.0):
    def rhs(t, s):
        y, v = s
        forces = (F - k_s * y - b * v + m * G * math.sin(alpha)
                  - mu * m * G * math.cos(alpha) * math.tanh(v / V_C))
        return [v, forces / m]
    return rhs


@pytest.mark.parametrize("name", CASES)
@pytest.mark.parametrize("variant", ["acausal", "equation", "multibody"])
def test_trajectory_matches_scipy(name, variant):
    entry = mt.models.get(name)
    t = np.linspace(0, 5, 201)
    res = mt.simulate(entry.build(variant), 5.0, rtol=1e-10, atol=1e-12, t_out=t)
    ref = solve_ivp(newton(CASES[name], **entry.values()), (0, 5), [0.0, 0.0],
                    method="DOP853", rtol=1e-12, atol=1e-14, t_eval=t)
    paths = entry.output_paths(variant)
    np.testing.assert_allclose(res[paths["y"]], ref.y[0], atol=1e-8)
    np.testing.assert_allclose(res[paths["v"]], ref.y[1], atol=1e-7)


def test_vertical_case_oscillates_at_the_damped_natural_frequency():
    entry = mt.models.get("msd_vertical")
    p = entry.values()
    t = np.linspace(0, 3, 30001)
    res = mt.simulate(entry.build("acausal"), 3.0, rtol=1e-10, atol=1e-12, t_out=t)
    y = res[entry.output_paths("acausal")["y"]] - p["m"] * G / p["k_s"]
    wn = math.sqrt(p["k_s"] / p["m"])
    zeta = p["b"] / (2 * math.sqrt(p["k_s"] * p["m"]))
    wd = wn * math.sqrt(1 - zeta ** 2)
    # upward zero crossings of the deviation from the equilibrium are one period apart
    k = np.nonzero((y[:-1] < 0) & (y[1:] >= 0))[0]
    up = t[k] - y[k] * (t[k + 1] - t[k]) / (y[k + 1] - y[k])   # linear interpolation
    assert np.diff(up) == pytest.approx(2 * math.pi / wd, rel=1e-6)
