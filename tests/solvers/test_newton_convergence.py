"""Every Newton solve says when it has not converged: fixed-step implicit methods raise
an error naming the time, the unknowns and what to try, or, as a real-time target that
keeps its fixed iteration count, count the steps (``newton="count"``)."""

import numpy as np
import pytest
from scipy.optimize import brentq

import mechatron as mt
from mechatron.errors import SimulationError

K = 1e4


class Cubic(mt.Component):
    """``dx/dt = -K x^3``: stiff and strongly nonlinear at x = 1 (``K x^2 = 1e4 1/s``)."""

    x = mt.Variable("1", start=1.0, doc="State")

    def equations(self):
        return [mt.der(self.x) == -K * self.x ** 3]


class Decay(mt.Component):
    """``dx/dt = -L x``, linear: Newton's first iteration is exact."""

    x = mt.Variable("1", start=1.0, doc="State")
    L = mt.Parameter("1/s", default=1e4, doc="Rate")

    def equations(self):
        return [mt.der(self.x) == -self.L * self.x]


@pytest.mark.parametrize("method", ["backward_euler", "trapezoidal", "ode14x"])
def test_a_step_too_large_for_one_iteration_is_an_error_naming_time_and_unknown(method):
    # h K x^2 = 500: the explicit predictor lands at x = -499, one Newton step cannot
    # bring it back to the root near 0.13
    with pytest.raises(SimulationError,
                       match=rf"{method}: Newton's iteration did not converge in 1 "
                             r"iteration\(s\) at t = 0\.05 s \(dt = 0\.05 s\); the next "
                             r"correction is largest for x \(.* x its tolerance\)\. Take "
                             r"a smaller step dt or more iterations") as info:
        mt.simulate(Cubic(), 0.5, solver=method, dt=0.05, iterations=1)
    assert info.value.variables == ["x"]
    assert info.value.path == "Cubic"


def test_a_real_time_run_keeps_its_iteration_count_and_counts_unconverged_steps():
    cm = mt.compile_model(Cubic())
    with pytest.raises(SimulationError, match="did not converge in 20 iteration"):
        mt.simulate(cm, 0.5, solver="backward_euler", dt=0.05, iterations=20)
    res = mt.simulate(cm, 0.5, solver="backward_euler", dt=0.05, iterations=20,
                      newton="count")
    assert 1 <= res.stats.unconverged_steps < 10
    assert res.stats["unconverged_steps"] == res.stats.unconverged_steps


def test_converged_backward_euler_is_the_exact_implicit_recursion():
    dt, n = 1e-4, 300
    res = mt.simulate(Cubic(), n * dt, solver="backward_euler", dt=dt, iterations=6)
    assert res.stats.unconverged_steps == 0
    # each step solves x1 + dt K x1^3 = x0 (monotone in x1: one root), here by bisection
    x = [1.0]
    for _ in range(n):
        x.append(brentq(lambda v, x0=x[-1]: v + dt * K * v ** 3 - x0, 0.0, x[-1],
                        xtol=1e-15, rtol=1e-15))
    np.testing.assert_allclose(res["x"], x, rtol=1e-9)


@pytest.mark.parametrize("method", ["backward_euler", "trapezoidal"])
def test_linear_stiff_models_converge_in_one_iteration(method):
    dt, lam = 1e-3, 1e4             # h lambda = 10
    res = mt.simulate(Decay(), 0.02, solver=method, dt=dt, iterations=1)
    theta = 1.0 if method == "backward_euler" else 0.5
    g = (1 - (1 - theta) * dt * lam) / (1 + theta * dt * lam)
    np.testing.assert_allclose(res["x"], g ** np.arange(len(res.t)), rtol=1e-12,
                               atol=1e-300)
    assert res.stats.unconverged_steps == 0


def test_newton_mode_is_checked():
    with pytest.raises(SimulationError, match="newton must be one of check, count"):
        mt.simulate(Decay(), 0.01, solver="backward_euler", dt=1e-3, newton="fixed")
