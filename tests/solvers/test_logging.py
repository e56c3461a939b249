"""Selective logging and the linear solvers of CVODES/IDAS: the same simlog either way.

The RC ladder is a tridiagonal linear ODE, so its solution is also checked against the
matrix exponential computed here; the selectively logged run must equal the fully logged
one to 1e-12 (they evaluate the same output function on the same trajectory), and the
sparse and dense linear solvers must agree to 1e-9 at tight tolerances.
"""

import pickle

import numpy as np
import pytest
from scipy.linalg import expm

import mechatron as mt
from mechatron.errors import SimulationError
from mechatron.library import electrical as el
from mechatron.solvers import logging as simlog

R, C, V = 1.0, 1e-3, 1.0


def ladder(n: int, c: float = C) -> mt.System:
    """``n`` sections of ``R`` in series and ``c`` to ground after a source of ``V``: a
    step at the source travels about one section in ``R c``."""
    m = mt.System(f"ladder_{n}")
    src = m.add("src", el.DCVoltageSource(V=V))
    gnd = m.add("gnd", el.ElectricalReference())
    m.connect(src.n, gnd.port)
    node = src.p
    for k in range(n):
        r = m.add(f"r{k}", el.Resistor(R=R))
        cap = m.add(f"c{k}", el.Capacitor(C=c))
        m.connect(node, r.p)
        m.connect(r.n, cap.p)
        m.connect(cap.n, gnd.port)
        node = r.n
    return m


def ladder_matrix(n: int, r: float = R) -> tuple[np.ndarray, np.ndarray]:
    """``v' = A v + b`` of the ladder with every resistor ``r``."""
    g = 1.0 / (r * C)
    A = np.diag(np.full(n, -2.0 * g)) + np.diag(np.full(n - 1, g), 1) \
        + np.diag(np.full(n - 1, g), -1)
    A[-1, -1] = -g
    b = np.zeros(n)
    b[0] = g * V
    return A, b


def exact_voltages(n: int, t: np.ndarray) -> np.ndarray:
    """Capacitor voltages of the ladder from rest: ``v' = A v + b``, by expm."""
    A, b = ladder_matrix(n)
    v_inf = np.linalg.solve(A, -b)
    return np.array([v_inf - expm(A * tk) @ v_inf for tk in t]).T


@pytest.fixture(scope="module")
def cm():
    return mt.compile_model(ladder(40))


def test_selective_log_equals_the_full_log(cm):
    t_out = np.linspace(0.0, 0.2, 201)
    full = mt.simulate(cm, 0.2, solver="cvodes", t_out=t_out, log="all")
    lazy = mt.simulate(cm, 0.2, solver="cvodes", t_out=t_out)
    assert lazy.names == full.names
    assert set(lazy.logged) == {f"c{k}.v" for k in range(40)}
    for name in ("r17.i", "c39.i", "r0.p.v", "c3.v", "src.i"):
        np.testing.assert_allclose(lazy[name], full[name], rtol=0, atol=1e-12)
    np.testing.assert_allclose(lazy.values, full.values, rtol=0, atol=1e-12)
    # the physics: capacitor voltages against the matrix exponential
    v = np.array([lazy[f"c{k}.v"] for k in range(40)])
    assert np.max(np.abs(v - exact_voltages(40, t_out))) < 1e-5
    # exports hold every variable
    df = lazy.to_pandas()
    assert list(df.columns) == full.names
    np.testing.assert_allclose(df.to_numpy().T, full.values, rtol=0, atol=1e-12)
    part = lazy.select("r5", "c5.v")
    np.testing.assert_allclose(part.values, full.select("r5", "c5.v").values,
                               rtol=0, atol=1e-12)


def test_a_large_log_computes_only_what_is_read(cm, monkeypatch):
    monkeypatch.setattr(mt.results, "_SMALL_LOG", 10)
    full = mt.simulate(cm, 0.1, solver="cvodes", log="all")
    lazy = mt.simulate(cm, 0.1, solver="cvodes")
    np.testing.assert_allclose(lazy["r20.i"], full["r20.i"], rtol=0, atol=1e-12)
    assert len(lazy._computed) == 1         # one variable computed, and kept
    assert lazy["r20.i"] is lazy["r20.i"]
    with pytest.raises(ValueError):
        lazy["r20.i"][0] = 1.0              # read-only, as a stored row


def test_log_a_list_of_paths(cm):
    full = mt.simulate(cm, 0.1, solver="cvodes", log="all")
    res = mt.simulate(cm, 0.1, solver="cvodes", log=["r3.i", "c7"])
    kept = {res.names[r] for r in res._computed}
    assert "r3.i" in kept and {"c7.i", "c7.p.v"} <= kept
    for name in ("r3.i", "c7.i", "r30.v"):
        np.testing.assert_allclose(res[name], full[name], rtol=0, atol=1e-12)
    with pytest.raises(SimulationError, match="log: 'r3.x' is neither a variable"):
        mt.simulate(cm, 0.1, log=["r3.x"])
    with pytest.raises(SimulationError, match="log must be 'states', 'all' or a list"):
        mt.simulate(cm, 0.1, log="everything")


def test_a_selective_log_pickles_and_saves(cm, tmp_path):
    res = mt.simulate(cm, 0.05, solver="cvodes", t_out=np.linspace(0.01, 0.05, 5))
    back = pickle.loads(pickle.dumps(res))
    np.testing.assert_allclose(back["r9.i"], res["r9.i"], rtol=0, atol=0)
    path = res.save(tmp_path / "ladder.csv")
    loaded = mt.SimResult.load(path)
    np.testing.assert_allclose(loaded["r9.i"], res["r9.i"], rtol=0, atol=0)
    assert loaded.names == res.names


def test_output_columns_of_a_subset_equal_the_whole_output(cm):
    res = mt.simulate(cm, 0.05, solver="cvodes", log="all")
    X = np.array([res[n] for n in cm.state_names])
    cols = simlog.OutputColumns(cm.f_out, res.t, X, np.zeros((0, res.t.size)), cm.p0)
    rows = [3, 50, 401]
    np.testing.assert_array_equal(cols(rows), res.values[rows])       # one function each
    many = list(range(0, len(cm.names), 2))
    np.testing.assert_array_equal(cols(many), res.values[many])       # the whole output


@pytest.mark.parametrize("linear_solver", ["sparse", "dense"])
def test_sparse_and_dense_linear_solvers_agree(cm, linear_solver):
    ref = mt.simulate(cm, 0.2, solver="cvodes", rtol=1e-12, atol=1e-14)
    res = mt.simulate(cm, 0.2, solver="cvodes", rtol=1e-12, atol=1e-14,
                      linear_solver=linear_solver)
    assert np.max(np.abs(res.values - ref.values)) < 1e-9
    v = np.array([res[f"c{k}.v"] for k in range(40)])
    assert np.max(np.abs(v - exact_voltages(40, res.t))) < 1e-9


def test_an_unknown_linear_solver_is_named(cm):
    with pytest.raises(SimulationError, match="unknown linear_solver 'klu'"):
        mt.simulate(cm, 0.1, solver="cvodes", linear_solver="klu")
