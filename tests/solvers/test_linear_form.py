"""The linear form of a linear, time-invariant ODE: ``der(X) = A(p) X + c(t, p)`` with
``A``'s nonzeros computed once per run (``mechatron.solvers.variable.linear_form``).

Checked against the matrix exponential and against the expression-graph right-hand side
of the same model (the general path), which the form must reproduce to the tolerances
of the run; a model that is not linear with constant coefficients keeps the general
path."""

from __future__ import annotations

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.library import translational as tr
from mechatron.solvers import variable
from tests.solvers.test_logging import C, R, V, exact_voltages, ladder, ladder_matrix
from tests.solvers.test_segments import ImplicitLoad, voltages

TIGHT = {"rtol": 1e-10, "atol": 1e-12}
N = 30


@pytest.fixture
def linear(monkeypatch):
    """Models of any size take the linear form."""
    monkeypatch.setattr(variable, "LINEAR_FORM_STATES", 1)


def general(cm, *args, **kwargs):
    """A run on the expression-graph right-hand side."""
    saved = variable.LINEAR_FORM_STATES
    variable.LINEAR_FORM_STATES = 10 ** 9
    try:
        return mt.simulate(cm, *args, **kwargs)
    finally:
        variable.LINEAR_FORM_STATES = saved


def test_the_ladder_in_linear_form_matches_the_matrix_exponential(linear):
    cm = mt.compile_model(ladder(N))
    form = variable.linear_form(cm)
    assert form is not None and variable._uses_linear_form(cm, "cvodes", ())
    A, b = ladder_matrix(N)
    # A(p) is the ladder's matrix, in the order of the states
    order = [cm.state_names.index(f"c{k}.v") for k in range(N)]
    dense = np.zeros((N, N))
    dense[form.rows, form.cols] = form.nonzeros(cm.parameter_vector(None))
    np.testing.assert_allclose(dense[np.ix_(order, order)], A, rtol=1e-14)
    res = mt.simulate(cm, 0.2, **TIGHT)
    assert res.stats.solver == "cvodes"
    assert np.max(np.abs(voltages(res, N) - exact_voltages(N, res.t))) < 1e-9
    ref = general(cm, 0.2, **TIGHT)
    np.testing.assert_allclose(voltages(res, N), voltages(ref, N), rtol=0, atol=1e-9)
    # a variable that is not stored, computed from the stored states
    np.testing.assert_allclose(res["r0.i"], (V - res["c0.v"]) / R, rtol=0, atol=1e-12)


def test_a_parameter_change_recomputes_the_matrix(linear):
    cm = mt.compile_model(ladder(N))
    mt.simulate(cm, 0.1)                      # the integrator is cached: A is data of a run
    res = mt.simulate(cm, 0.1, params={"r0.R": 3.0}, **TIGHT)
    ref = general(cm, 0.1, params={"r0.R": 3.0}, **TIGHT)
    np.testing.assert_allclose(voltages(res, N), voltages(ref, N), rtol=0, atol=1e-9)
    # by hand: only the first row's coupling to the source changes
    A, b = ladder_matrix(N)
    g0, g1 = 1.0 / (3.0 * C), 1.0 / (R * C)
    A[0, 0], b[0] = -(g0 + g1), g0 * V
    v_inf = np.linalg.solve(A, -b)
    from scipy.linalg import expm
    exact = np.array([v_inf - expm(A * t) @ v_inf for t in res.t]).T
    assert np.max(np.abs(voltages(res, N) - exact)) < 1e-9


def test_the_matrix_is_evaluated_once_per_parameters(linear, monkeypatch):
    """The choice of the linear solver and the run read the same nonzeros of ``A(p)``: one
    evaluation for each new set of parameters, and the kept values cannot be changed."""
    cm = mt.compile_model(ladder(N))
    form = variable.linear_form(cm)
    calls = []
    real = variable.evaluate_point
    monkeypatch.setattr(variable, "evaluate_point",
                        lambda f, args: calls.append(f) or real(f, args))
    res = mt.simulate(cm, 0.1, params={"r0.R": 2.0}, **TIGHT)
    assert res.stats.solver == "cvodes"
    assert variable.auto_linear_solver(cm, "cvodes", cm.parameter_vector(
        {"r0.R": 2.0})) == variable.TRIDIAGONAL
    assert calls.count(form.jacobian) == 1
    values = form.nonzeros(cm.parameter_vector({"r0.R": 2.0}))
    assert not values.flags.writeable
    changed = form.nonzeros(cm.parameter_vector({"r0.R": 4.0}))
    assert calls.count(form.jacobian) == 2
    assert not np.array_equal(changed, values)      # the source's row holds 1/R0


def test_a_segmented_run_in_linear_form_keeps_its_time(linear, monkeypatch):
    """The offset ``c(t, p)`` of a sine-driven ladder reads the absolute time in every
    segment."""
    m = mt.System("sine_ladder")
    src = m.add("src", el.ACVoltageSource(V_amp=1.0, f=20.0))
    gnd = m.add("gnd", el.ElectricalReference())
    m.connect(src.n, gnd.port)
    node = src.p
    for k in range(N):
        r, c = m.add(f"r{k}", el.Resistor(R=R)), m.add(f"c{k}", el.Capacitor(C=C))
        m.connect(node, r.p)
        m.connect(r.n, c.p)
        m.connect(c.n, gnd.port)
        node = r.n
    cm = mt.compile_model(m)
    assert variable.linear_form(cm) is not None       # time enters c only
    t_out = np.linspace(0.0, 0.2, 201)
    ref = general(cm, 0.2, t_out=t_out, **TIGHT)
    monkeypatch.setattr(variable, "SEGMENT_VALUES", N * 40)
    res = mt.simulate(cm, 0.2, t_out=t_out, **TIGHT)
    assert res.stats.steps > ref.stats.steps          # the restarts of the segments
    np.testing.assert_allclose(voltages(res, N), voltages(ref, N), rtol=0, atol=2e-8)
    assert np.max(np.abs(voltages(ref, N))) > 0.1     # the source did drive the ladder


def test_a_mass_spring_damper_chain_in_linear_form(linear):
    """Second-order states (positions and velocities), a Jacobian that is not
    tridiagonal: the form applies and agrees with the general path."""
    m = mt.System("chain")
    ref = m.add("ref", tr.TranslationalReference())
    prev = ref.port
    for k in range(8):
        mass = m.add(f"m{k}", tr.Mass(m=1.0 + 0.1 * k))
        start = {"x": 0.01} if k == 7 else {}
        spring = m.add(f"k{k}", tr.TranslationalSpring(k=1e3, **start))
        damper = m.add(f"b{k}", tr.TranslationalDamper(b=2.0))
        m.connect(mass.port, spring.A, damper.A)
        m.connect(spring.B, damper.B, prev)
        prev = mass.port
    cm = mt.compile_model(m)
    assert variable.linear_form(cm) is not None
    res = mt.simulate(cm, 0.5, **TIGHT)
    ref_run = general(cm, 0.5, **TIGHT)
    for k in range(8):
        np.testing.assert_allclose(res[f"k{k}.x"], ref_run[f"k{k}.x"], rtol=0, atol=1e-10)
    # the chain is passive: its energy never grows
    energy = sum(0.5 * (1.0 + 0.1 * k) * res[f"m{k}.v"] ** 2 + 0.5 * 1e3 * res[f"k{k}.x"] ** 2
                 for k in range(8))
    assert np.all(np.diff(energy) <= 1e-9 * energy[0])
    assert energy[-1] < 0.9 * energy[0]


class Cubic(mt.Component):
    """``x' = -x^3``: nonlinear in the state."""

    x = mt.Variable("1", start=1.0, doc="State")

    def equations(self):
        return [mt.der(self.x) == -self.x ** 3]


class Fading(mt.Component):
    """``x' = -x / (1 + t)``: linear, but its coefficient changes with time."""

    x = mt.Variable("1", start=1.0, doc="State")

    def equations(self):
        return [mt.der(self.x) == -self.x / (1.0 + self.time)]


@pytest.mark.parametrize("model", [Cubic, Fading])
def test_a_nonlinear_or_time_varying_model_keeps_the_general_path(linear, model):
    cm = mt.compile_model(model())
    assert variable.linear_form(cm) is None
    assert not variable._uses_linear_form(cm, "cvodes", ())
    res = mt.simulate(cm, 1.0, **TIGHT)
    exact = (1.0 / np.sqrt(1.0 + 2.0 * res.t)) if model is Cubic else 1.0 / (1.0 + res.t)
    np.testing.assert_allclose(res["x"], exact, rtol=1e-8)


def test_a_dae_keeps_the_general_path(linear):
    cm = mt.compile_model(ImplicitLoad())
    if not cm.nz:
        pytest.skip("the compiler solved the loop explicitly: no DAE")
    assert variable.linear_form(cm) is None


def _mean_field(n: int):
    """``x_i' = -(x_1 + ... + x_n)``: linear and constant, but every entry of ``A`` is
    nonzero while the graph computes the sum once."""
    attrs = {f"x{k}": mt.Variable("1", start=float(k + 1), doc="State") for k in range(n)}

    def equations(self):
        total = sum(getattr(self, f"x{k}") for k in range(n))
        return [mt.der(getattr(self, f"x{k}")) == -total for k in range(n)]
    attrs["equations"] = equations
    return type("MeanField", (mt.Component,), attrs)()


def test_a_denser_matrix_than_the_graph_keeps_the_graph(linear):
    n = 12
    cm = mt.compile_model(_mean_field(n))
    assert cm.f_ode.n_instructions() < n * n
    assert variable.linear_form(cm) is None
    res = mt.simulate(cm, 0.5, **TIGHT)
    # the sum s obeys s' = -n s; each x_k = x_k(0) + (s(t) - s(0)) / n
    s0 = n * (n + 1) / 2
    s = s0 * np.exp(-n * res.t)
    np.testing.assert_allclose(res["x3"], 4.0 + (s - s0) / n, rtol=0, atol=1e-8)
