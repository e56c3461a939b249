"""Large variable-step runs integrated over segments of the output grid, and the
tridiagonal linear solver ``linear_solver="auto"`` picks for chains.

A segmented run restarts the solver at each segment's start from the state the previous
segment ended with (BDF restarts at order 1), so its step sequence differs from the one
pass and the two agree to the solver's accuracy, not to the last bit. Here both are
checked at tight tolerances against solutions computed independently in this file (the
matrix exponential of the ladder, the closed-form response of an RC to a sine, SciPy's
``solve_ivp`` for a table input and for a DAE), and against each other.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.solvers import variable

from tests.solvers.test_logging import C, R, V, exact_voltages, ladder  # noqa: F401

TIGHT = {"rtol": 1e-10, "atol": 1e-12}


def voltages(res, n: int) -> np.ndarray:
    return np.array([res[f"c{k}.v"] for k in range(n)])


@pytest.fixture(scope="module")
def cm():
    return mt.compile_model(ladder(30))


def segmented(monkeypatch, values: int):
    """Make runs of more than ``values`` trajectory values run in segments."""
    monkeypatch.setattr(variable, "SEGMENT_VALUES", values)


def test_segments_cover_the_grid_with_equal_lengths_and_a_shorter_last():
    grid = np.linspace(0.0, 0.2, 212)                    # 211 intervals
    assert variable._segments(grid, 30) is None          # small: one pass
    variable_values = 30 * 60
    segments = _with(variable_values, grid, 30)
    bounds = [(a, b) for a, b, _ in segments]
    assert bounds[0][0] == 0 and bounds[-1][1] == 211
    assert all(a2 == b1 for (_, b1), (a2, _) in zip(bounds, bounds[1:]))
    lengths = [b - a for a, b in bounds]
    assert len(set(lengths[:-1])) == 1 and 0 < lengths[-1] <= lengths[0]
    assert max(lengths) + 1 <= variable_values // 30     # each within the budget
    # two integrators: one for the equal segments, one for the shorter last
    assert len({id(tau) for _, _, tau in segments}) == 2
    for a, b, tau in segments:
        np.testing.assert_allclose(grid[a] + tau, grid[a + 1:b + 1], rtol=0, atol=1e-16)
    # a first output time after t0 (a first segment of its own) still segments
    late = np.concatenate([[0.0], np.linspace(0.05, 0.25, 211)])
    assert len({id(tau) for _, _, tau in _with(variable_values, late, 30)}) == 3
    # a grid whose spacing keeps changing runs in one pass (each segment would need an
    # integrator of its own)
    assert _with(variable_values, grid ** 1.5, 30) is None


def _with(values, grid, width):
    saved = variable.SEGMENT_VALUES
    variable.SEGMENT_VALUES = values
    try:
        return variable._segments(grid, width)
    finally:
        variable.SEGMENT_VALUES = saved


@pytest.mark.parametrize("points", [201, 212])
def test_a_segmented_ladder_run_matches_the_one_pass_and_the_matrix_exponential(
        cm, monkeypatch, points):
    t_out = np.linspace(0.0, 0.2, points)
    one = mt.simulate(cm, 0.2, t_out=t_out, **TIGHT)
    segmented(monkeypatch, 30 * 40)                      # 5 or 6 segments
    seg = mt.simulate(cm, 0.2, t_out=t_out, **TIGHT)
    assert seg.stats.solver == one.stats.solver == "cvodes"
    assert seg.stats.steps > one.stats.steps             # the restarts
    exact = exact_voltages(30, t_out)
    assert np.max(np.abs(voltages(one, 30) - exact)) < 1e-8
    assert np.max(np.abs(voltages(seg, 30) - exact)) < 1e-8
    np.testing.assert_allclose(voltages(seg, 30), voltages(one, 30), rtol=0, atol=2e-8)
    # the start of each segment is the end of the previous one: the currents, computed
    # on demand from the stored trajectory, are continuous and right there too
    i0 = (V - exact[0]) / R
    np.testing.assert_allclose(seg["r0.i"], i0, rtol=0, atol=1e-8)
    np.testing.assert_array_equal(seg.t, t_out)


def test_a_segmented_run_at_default_tolerances_stays_within_the_one_pass_error(
        cm, monkeypatch):
    t_out = np.linspace(0.0, 0.2, 201)
    exact = exact_voltages(30, t_out)
    one = mt.simulate(cm, 0.2, t_out=t_out)
    err_one = np.max(np.abs(voltages(one, 30) - exact))
    segmented(monkeypatch, 30 * 40)
    seg = mt.simulate(cm, 0.2, t_out=t_out)
    err_seg = np.max(np.abs(voltages(seg, 30) - exact))
    assert err_one < 1e-5 and err_seg < 1e-5


class SineRC(mt.Component):
    """RC low-pass driven by a sine: the model depends on time explicitly."""

    src = el.ACVoltageSource(V_amp=2.0, f=50.0)
    r = el.Resistor(R=100.0)
    c = el.Capacitor(C=1e-4)
    g = el.ElectricalReference()

    def equations(self):
        return [mt.connect(self.src.p, self.r.p), mt.connect(self.r.n, self.c.p),
                mt.connect(self.src.n, self.c.n, self.g.port)]


def test_a_segmented_run_keeps_the_time_of_each_segment(monkeypatch):
    """Each segment's integrator runs from 0 and takes its start time as a parameter:
    a time-dependent source must see the absolute time."""
    t_out = np.linspace(0.0, 0.1, 401)
    segmented(monkeypatch, 25)                           # 24 points per segment
    assert len(variable._segments(t_out, 1)) == 17
    res = mt.simulate(SineRC(), 0.1, t_out=t_out, **TIGHT)
    tau, w, a = 100.0 * 1e-4, 2 * np.pi * 50.0, 2.0
    wt = w * tau
    exact = a / (1 + wt ** 2) * (np.sin(w * t_out) - wt * np.cos(w * t_out)
                                 + wt * np.exp(-t_out / tau))
    np.testing.assert_allclose(res["c.v"], exact, rtol=0, atol=1e-8)


class DrivenRC(mt.Component):
    """RC low-pass whose source voltage is the external input ``u``."""

    u = mt.Input("V", doc="Source voltage")
    src = el.ControlledVoltageSource()
    r = el.Resistor(R=1e3)
    c = el.Capacitor(C=1e-6)
    g = el.ElectricalReference()

    def equations(self):
        return [mt.connect(self.u, self.src.u), mt.connect(self.src.p, self.r.p),
                mt.connect(self.r.n, self.c.p),
                mt.connect(self.src.n, self.c.n, self.g.port)]


def test_a_segmented_run_reads_input_tables_at_the_absolute_time(monkeypatch):
    t_tab = np.linspace(0.0, 5e-3, 11)
    v_tab = np.cos(t_tab * 1e3)
    t_out = np.linspace(0.0, 5e-3, 301)
    segmented(monkeypatch, 40)
    assert len(variable._segments(t_out, 1)) == 8
    res = mt.simulate(DrivenRC(), 5e-3, t_out=t_out, inputs={"u": (t_tab, v_tab)}, **TIGHT)
    ref = solve_ivp(lambda t, x: (np.interp(t, t_tab, v_tab) - x) / 1e-3, (0.0, 5e-3),
                    [0.0], t_eval=t_out, rtol=1e-12, atol=1e-14, method="DOP853",
                    max_step=1e-5)
    np.testing.assert_allclose(res["c.v"], ref.y[0], rtol=0, atol=1e-8)


class ImplicitLoad(mt.Component):
    """``x' = y - x`` with ``y`` the root of ``y^3 + y = 2 - x``: an algebraic unknown
    that stays in the DAE (IDAS)."""

    x = mt.Variable("1", start=0.0, doc="State")
    y = mt.Variable("1", start=1.0, doc="Algebraic unknown")

    def equations(self):
        return [mt.der(self.x) == self.y - self.x, self.y ** 3 + self.y == 2.0 - self.x]


def test_a_segmented_dae_run_restarts_with_consistent_algebraics(monkeypatch):
    cm = mt.compile_model(ImplicitLoad())
    if not cm.nz:
        pytest.skip("the compiler solved the loop explicitly: no DAE to segment")
    t_out = np.linspace(0.0, 2.0, 201)
    segmented(monkeypatch, 30)
    assert len(variable._segments(t_out, cm.nX + cm.nz)) > 5
    res = mt.simulate(cm, 2.0, t_out=t_out, **TIGHT)
    assert res.stats.solver == "idas"

    def y_of(x):
        return brentq(lambda y: y ** 3 + y - (2.0 - x), -10.0, 10.0, xtol=1e-15)

    ref = solve_ivp(lambda t, x: [y_of(x[0]) - x[0]], (0.0, 2.0), [0.0], t_eval=t_out,
                    rtol=1e-12, atol=1e-14, method="DOP853")
    np.testing.assert_allclose(res["x"], ref.y[0], rtol=0, atol=1e-8)
    np.testing.assert_allclose(res["y"], [y_of(x) for x in ref.y[0]], rtol=0, atol=1e-8)


# -------------------------------------------------------------- tridiagonal solver
def test_auto_takes_the_tridiagonal_solver_for_a_dissipative_chain(cm):
    p = cm.parameter_vector(None)
    assert variable.auto_linear_solver(cm, "cvodes", p) == variable.TRIDIAGONAL
    # IDAS, or a row that is not dominant (a negative resistance): sparse QR
    assert variable.auto_linear_solver(cm, "idas", p) == variable.LINEAR_SOLVERS["auto"]
    bad = p.copy()
    bad[cm.param_names.index("r7.R")] = -1.0    # (bounds checked by simulate, not here)
    assert variable.auto_linear_solver(cm, "cvodes", bad) == variable.LINEAR_SOLVERS["auto"]


def test_auto_keeps_sparse_qr_for_a_nonlinear_or_wider_jacobian():
    assert variable.auto_linear_solver(mt.compile_model(ImplicitLoad()), "cvodes",
                                       np.zeros(0)) == variable.LINEAR_SOLVERS["auto"]
    rc = mt.compile_model(SineRC())     # one state: too small to bother
    assert variable.auto_linear_solver(rc, "cvodes", rc.parameter_vector(None)) \
        == variable.LINEAR_SOLVERS["auto"]


def test_the_tridiagonal_solver_gives_the_sparse_solvers_solution(cm):
    ref = mt.simulate(cm, 0.2, linear_solver="sparse", **TIGHT)
    res = mt.simulate(cm, 0.2, **TIGHT)                   # auto: tridiagonal
    np.testing.assert_allclose(voltages(res, 30), voltages(ref, 30), rtol=0, atol=1e-9)
    assert np.max(np.abs(voltages(res, 30) - exact_voltages(30, res.t))) < 1e-9


def test_each_run_reports_its_own_work(cm, monkeypatch):
    """CasADi counts the Jacobian evaluations over the integrator's lifetime; a run
    reports its own, and a segmented run the sum over its segments."""
    first = mt.simulate(cm, 0.1)
    again = mt.simulate(cm, 0.1)
    assert again.stats.jac_evals == first.stats.jac_evals > 0
    assert again.stats.steps == first.stats.steps
    segmented(monkeypatch, 30 * 200)                     # 1001 points: 6 segments
    parts = mt.simulate(cm, 0.1)
    assert parts.stats.jac_evals >= 6 and parts.stats.steps > first.stats.steps
