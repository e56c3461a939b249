"""Fixed-step methods: order of convergence, stiff stability, the step function."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.solvers import METHODS, make_step


def rc(R=1.0, C=1.0):
    m = mt.System("rc")
    src = m.add("src", el.DCVoltageSource(V=1.0))
    r = m.add("r", el.Resistor(R=R))
    c = m.add("c", el.Capacitor(C=C))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, r.p)
    m.connect(r.n, c.p)
    m.connect(src.n, c.n, g.port)
    return mt.compile_model(m)


@pytest.mark.parametrize("method, order", [("euler", 1), ("heun", 2), ("rk4", 4),
                                           ("backward_euler", 1), ("trapezoidal", 2)])
def test_order_of_convergence(method, order):
    cm = rc()
    errors = []
    steps = [0.1, 0.05, 0.025]
    for h in steps:
        res = mt.simulate(cm, 1.0, solver=method, dt=h)
        errors.append(abs(res.final("c.v") - (1 - np.exp(-1.0))))
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(rates - order) < 0.15), rates
    assert METHODS[method].order == order


def test_implicit_methods_stay_stable_where_explicit_ones_diverge():
    cm = rc(R=1.0, C=1e-4)          # time constant 0.1 ms, step 1 ms: h/tau = 10
    for method in ("backward_euler", "trapezoidal"):
        res = mt.simulate(cm, 0.05, solver=method, dt=1e-3)
        assert abs(res.final("c.v") - 1.0) < 1e-6
    with pytest.raises(mt.errors.SimulationError, match="not finite"):
        mt.simulate(cm, 0.5, solver="rk4", dt=1e-3)


def test_step_function_is_one_casadi_function_with_the_documented_signature():
    cm = rc()
    step = make_step(cm, "rk4", 1e-3)
    assert step.name_in() == ["x", "u", "p", "t"]
    assert step.name_out() == ["x_next", "y"]
    x1, y1 = step(np.concatenate([[0.0]]), np.zeros(0), cm.p0, 0.0)
    assert float(x1[0]) == pytest.approx(1 - np.exp(-1e-3), rel=1e-12)


def test_fixed_step_agrees_with_variable_step():
    cm = rc()
    ref = mt.simulate(cm, 1.0, rtol=1e-12, atol=1e-14, t_out=np.linspace(0, 1, 101))
    fix = mt.simulate(cm, 1.0, solver="rk4", dt=1e-3, t_out=np.linspace(0, 1, 101))
    np.testing.assert_allclose(fix["c.v"], ref["c.v"], atol=1e-12)


def test_long_runs_cross_chunk_boundaries_exactly():
    from mechatron.solvers import fixed
    cm = rc()
    n = fixed.CHUNK * 2 + 7
    res = mt.simulate(cm, n * 1e-4, solver="rk4", dt=1e-4)
    assert res.stats.steps == n and len(res.t) == n + 1
    np.testing.assert_allclose(res["c.v"], 1 - np.exp(-res.t), atol=1e-12)


def test_parameters_set_by_path_are_range_checked():
    cm = rc()
    with pytest.raises(mt.errors.ParameterError, match=r"r.R must be >= 0, got -5"):
        mt.simulate(cm, 1.0, params={"r.R": -5})


def test_simulate_dt_1e_12_is_refused_with_a_size_estimate():
    """simulate(dt=1e-12) from Python tried to allocate 5e11 steps. It is refused before
    any work with the estimate: (steps + 1) x (logged values + states) x 8 bytes, and
    max_memory=None goes on (checked on a run small enough to finish)."""
    import mechatron as mt
    from mechatron.errors import SimulationError
    from mechatron.solvers.simulate import check_fixed_step_size
    cm = mt.compile_model(mt.models.get("dc_motor").build("ode"))
    size = (0.5 / 1e-12 + 1) * (len(cm.names) + cm.nx) * 8
    with pytest.raises(SimulationError, match=r"5e\+11 fixed steps, which would keep "
                                              rf"about {size / 1e12:.3g} TB in memory") as e:
        mt.simulate(cm, 0.5, solver="rk4", dt=1e-12)
    assert "max_memory=None" in str(e.value) and "--force" in str(e.value)
    assert check_fixed_step_size(cm, 0.0, 0.01, 1e-5, None) == pytest.approx(
        1001 * (len(cm.names) + cm.nx) * 8)
    with pytest.raises(SimulationError, match="limit max_memory = 1 kB"):
        mt.simulate(cm, 0.01, solver="rk4", dt=1e-5, max_memory=1e3)
    res = mt.simulate(cm, 0.01, solver="rk4", dt=1e-5, max_memory=None)
    assert res.stats.steps == 1000
    with pytest.raises(SimulationError, match="dt must be a step size > 0"):
        mt.simulate(cm, 0.01, solver="rk4", dt=float("nan"))
