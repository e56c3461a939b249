"""Every fixed-step method (the step functions that the C generator emits): order of
convergence against the exact solution of the linear DC motor, and stability on a stiff
motor (tiny inductance) where the explicit methods diverge."""

import numpy as np
import pytest
import scipy.linalg

import mechatron as mt
from mechatron.codegen import build, generate_c, run_harness
from mechatron.codegen.compare import max_relative_difference
from mechatron.solvers import METHODS

V, R, L, k, J, B = 19.2, 7.1, 3.408e-4, 0.151, 4.8e-6, 1.236e-4


def exact_motor(t, L=L):
    """[i, w](t) from rest under the voltage step: x' = A x + b, by the matrix exponential."""
    A = np.array([[-R / L, -k / L], [k / J, -B / J]])
    b = np.array([V / L, 0.0])
    return np.linalg.solve(A, (scipy.linalg.expm(A * t) - np.eye(2)) @ b)


@pytest.fixture(scope="module")
def motor():
    return mt.compile_model(mt.models.get("dc_motor").build())


def test_every_method_is_tested():
    assert set(METHODS) == {"euler", "heun", "rk4", "backward_euler", "trapezoidal",
                            "ode14x"}


@pytest.mark.parametrize("method", sorted(METHODS))
def test_order_of_convergence(motor, method):
    t_end = 2e-3
    exact = exact_motor(t_end)
    steps = [2e-5, 1e-5, 5e-6]
    errors = []
    for h in steps:
        res = mt.simulate(motor, t_end, solver=method, dt=h, iterations=3)
        got = np.array([res.final("inductor.i"), res.final("inertia.w")])
        errors.append(np.max(np.abs(got - exact) / np.abs(exact)))
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(rates - METHODS[method].order) < 0.2), (errors, rates)


def test_ode14x_generated_c_is_the_desktop_step(motor, tmp_path):
    code = generate_c(motor, tmp_path, solver="ode14x", dt=1e-4, iterations=1, t_stop=0.05)
    build(code)
    desk = mt.simulate(motor, 0.05, solver="ode14x", dt=1e-4, iterations=1)
    assert max_relative_difference(run_harness(code), desk) <= 1e-12


def test_implicit_methods_stay_stable_on_a_stiff_motor_where_explicit_ones_diverge(motor):
    stiff = {"inductor.L": 1e-8}          # L/R = 1.4 ns, step 100 us: h |lambda| ~ 7e4
    t_end, h = 0.05, 1e-4
    i_end, w_end = exact_motor(t_end, L=1e-8)
    for method in ("euler", "heun", "rk4"):
        with pytest.raises(mt.errors.SimulationError, match="not finite"):
            mt.simulate(motor, t_end, solver=method, dt=h, params=stiff)
    for method in ("backward_euler", "ode14x"):      # stiffly accurate: the fast mode dies
        res = mt.simulate(motor, t_end, solver=method, dt=h, iterations=2, params=stiff)
        assert res.final("inertia.w") == pytest.approx(w_end, rel=1e-3)
        assert res.final("inductor.i") == pytest.approx(i_end, rel=1e-2)
    # trapezoidal is A-stable but not L-stable: bounded, with the fast mode ringing
    res = mt.simulate(motor, t_end, solver="trapezoidal", dt=h, iterations=2, params=stiff)
    assert np.max(np.abs(res["inductor.i"])) < 2 * V / R
    assert res.final("inertia.w") == pytest.approx(w_end, rel=2e-2)
