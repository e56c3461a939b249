"""Multi-start estimation: the starting points, and a frequency fit with several local
minima that one start from a bad guess gets wrong and multi-start gets right.

The data are the analytic free response of a damped oscillator (written here, not
simulated), with seeded white noise of known level. The least-squares cost of the
natural frequency has a local minimum wherever an oscillation of another frequency
lines up with part of the three-period record (about 1.95, 2.86, 4.8 and 9.6 rad/s
besides the true 7 rad/s): a classic multi-minimum identification case."""

import inspect
import json

import numpy as np
import pytest

import mechatron as mt
from mechatron.cli import main
from mechatron.errors import ParameterError
from mechatron.estimation import EstimationProblem, Experiment, FreeParameter, estimate
from mechatron.estimation.multistart import LOG_SPAN, start_points

W_TRUE, ZETA_TRUE, SIGMA = 7.0, 0.05, 0.01


class Oscillator(mt.Component):
    """Free damped oscillator ``x'' + 2 zeta w x' + w^2 x = 0`` from ``x = 1``, at rest."""

    w = mt.Parameter("rad/s", default=1.0)
    zeta = mt.Parameter("1", default=0.1)
    x = mt.Variable("m", start=1.0)
    v = mt.Variable("m/s", start=0.0)

    def equations(self):
        return [mt.der(self.x) == self.v,
                mt.der(self.v) == -self.w ** 2 * self.x - 2 * self.zeta * self.w * self.v]


def free_response(t, w, zeta):
    """The analytic solution from x(0) = 1, x'(0) = 0 (under-damped)."""
    wd = w * np.sqrt(1 - zeta ** 2)
    return np.exp(-zeta * w * t) * (np.cos(wd * t) + zeta * w / wd * np.sin(wd * t))


def measured(seed: int = 1):
    t = np.linspace(0.0, 3.0, 301)
    y = free_response(t, W_TRUE, ZETA_TRUE)
    y = y + SIGMA * np.random.default_rng(seed).standard_normal(t.size)
    return Experiment("free", t=t, outputs={"x": y}, sigma={"x": SIGMA}, units={"x": "m"})


def oscillator_problem(w0=2.0):
    free = [FreeParameter("w", w0, 1.0, 12.0), FreeParameter("zeta", 0.05, 0.01, 0.1)]
    return EstimationProblem(Oscillator(), [measured()], free, outputs={"x": "x"},
                             jit=False)


@pytest.fixture(scope="module")
def problem():
    return oscillator_problem()


@pytest.fixture(scope="module")
def multi(problem):
    return estimate(problem, starts=8, seed=0, workers=1)


# ---------------------------------------------------------------------- starting points
def test_start_points_are_the_guess_then_a_latin_hypercube_inside_the_bounds(problem):
    X = start_points(problem, 9, seed=4)
    np.testing.assert_array_equal(X[0], problem.initial)
    lo, hi = problem.bounds
    for j in range(2):
        u = (X[1:, j] - lo[j]) / (hi[j] - lo[j])
        # one point in each of the 8 equal strata of every parameter's range
        assert sorted(np.floor(u * 8).astype(int)) == list(range(8))
    np.testing.assert_array_equal(X, start_points(problem, 9, seed=4))   # deterministic
    assert not np.array_equal(X[1:], start_points(problem, 9, seed=5)[1:])
    S = start_points(problem, 9, seed=4, sampling="sobol")
    assert np.all((S[1:] >= lo) & (S[1:] <= hi)) and len(np.unique(S[1:, 0])) == 8
    np.testing.assert_array_equal(start_points(problem, 1), problem.initial[None, :])


class Line(mt.Component):
    """x' = c."""

    c = mt.Parameter("1/s", default=1.0)
    x = mt.Variable("1", start=0.0)

    def equations(self):
        return [mt.der(self.x) == self.c]


def test_wide_positive_bounds_are_sampled_in_log_and_open_ones_kept():
    t = np.linspace(0, 1, 11)
    e = Experiment("line", t=t, outputs={"y": 0.5 + 2 * t})
    prob = EstimationProblem(Line(), [e], [FreeParameter("c", 1.0, 1e-3, 1e3)],
                             outputs={"y": "x"}, free_x0=["x"], offsets=["y"], jit=False)
    assert 1e3 / 1e-3 >= LOG_SPAN
    X = start_points(prob, 11, seed=0)
    u = np.log(X[1:, 0] / 1e-3) / np.log(1e6)               # uniform in the logarithm
    assert sorted(np.floor(u * 10).astype(int)) == list(range(10))
    # the offset and the initial state have no bounds: kept at their starting values
    np.testing.assert_array_equal(X[:, 1:], np.repeat(prob.initial[None, 1:], 11, axis=0))


def test_multistart_needs_a_bounded_variable_and_a_known_sampling():
    e = Experiment("line", t=np.linspace(0, 1, 11), outputs={"y": np.linspace(0, 2, 11)})
    prob = EstimationProblem(Line(), [e], [FreeParameter("c", 1.0, min=0.0)],
                             outputs={"y": "x"}, jit=False)
    with pytest.raises(ParameterError, match="none of c has both a finite min and max"):
        estimate(prob, starts=4)
    with pytest.raises(ParameterError, match="sampling 'grid': use lhs or sobol"):
        start_points(prob, 4, sampling="grid")
    with pytest.raises(ParameterError, match="starts must be a whole number >= 1, got 0"):
        estimate(prob, starts=0)


# ------------------------------------------------------------------ the multi-minimum fit
def test_one_start_from_a_bad_guess_ends_in_a_wrong_minimum(problem):
    one = estimate(problem)
    assert abs(one.parameters["w"] - W_TRUE) > 1.0
    # far above the noise level: n residuals of unit variance cost about n
    assert one.cost > 1000 * problem.n_residuals
    assert not one.starts and one.best_start == 0


def test_multistart_finds_the_true_frequency_and_damping(problem, multi):
    n, q = problem.n_residuals, 2
    assert multi.best_start != 0
    # the global minimum: residuals at the noise level (chi-square with n - q degrees of
    # freedom: mean n - q, std sqrt(2 (n - q)), here 24)
    assert abs(multi.cost - (n - q)) < 4 * np.sqrt(2 * (n - q))
    for name, truth in (("w", W_TRUE), ("zeta", ZETA_TRUE)):
        j = multi.names.index(name)
        assert abs(multi.values[j] - truth) < 3 * multi.std[j], name
        lo, hi = multi.ci95[name]
        assert lo < truth < hi
    assert multi.success and multi.problem is problem


def test_every_start_is_reported_and_the_best_is_the_cheapest(problem, multi):
    rows = multi.starts
    assert [r["start"] for r in rows] == list(range(8))
    X = start_points(problem, 8, seed=0)
    for r, x in zip(rows, X):
        assert [r["initial"][n] for n in problem.names] == list(x)
        assert r["error"] is None and set(r["parameters"]) == {"w", "zeta"}
    costs = [r["cost"] for r in rows]
    assert multi.best_start == min(range(8), key=lambda k: (costs[k], k))
    assert multi.cost == costs[multi.best_start]
    assert multi.parameters == rows[multi.best_start]["parameters"]
    # start 0 is the single fit from the guess, in the wrong minimum
    one = estimate(problem)
    assert rows[0]["cost"] == one.cost and rows[0]["parameters"] == one.parameters
    assert sum(c < 2 * problem.n_residuals for c in costs) >= 2   # several found it
    doc = multi.to_dict()
    assert doc["best_start"] == multi.best_start and len(doc["starts"]) == 8
    json.dumps(doc["starts"])


def test_local_processes_give_the_serial_results(problem, multi):
    par = estimate(problem, starts=8, seed=0, workers=2)
    assert [(r["cost"], r["parameters"], r["converged"]) for r in par.starts] == \
        [(r["cost"], r["parameters"], r["converged"]) for r in multi.starts]
    np.testing.assert_array_equal(par.values, multi.values)
    np.testing.assert_array_equal(par.std, multi.std)


def test_a_local_cluster_of_two_workers_gives_the_serial_results(problem, multi):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None, silence_logs=40) as cluster, \
            distributed.Client(cluster) as client:
        remote = estimate(problem, starts=8, seed=0, client=client)
    assert [(r["cost"], r["parameters"], r["converged"]) for r in remote.starts] == \
        [(r["cost"], r["parameters"], r["converged"]) for r in multi.starts]
    assert remote.best_start == multi.best_start
    np.testing.assert_array_equal(remote.values, multi.values)
    np.testing.assert_array_equal(remote.std, multi.std)


def test_a_tie_goes_to_the_lower_start(monkeypatch, problem):
    from mechatron.estimation import multistart
    real = multistart._fit_start

    def same_cost(prob, job):
        out = real(prob, job)
        out["row"]["cost"] = 1.0
        out["result"].cost = 1.0
        return out
    monkeypatch.setattr(multistart, "_fit_start", same_cost)
    res = estimate(problem, starts=3, seed=0, workers=1, max_iterations=2)
    assert res.best_start == 0


def test_a_failed_start_is_reported_and_not_chosen(monkeypatch, problem):
    from mechatron.errors import MechatronError, SimulationError
    from mechatron.estimation import problem as module
    real = module.estimate
    X = start_points(problem, 4, seed=0)

    def failing(prob, *, initial=None, **kw):
        if initial is not None and (initial[0] == X[2][0] or kw.get("max_iterations") == 3):
            raise SimulationError("Radau step did not converge (stand-in)")
        return real(prob, initial=initial, **kw)
    monkeypatch.setattr(module, "estimate", failing)
    res = real(problem, starts=4, seed=0, workers=1, max_iterations=20)
    row = res.starts[2]
    assert row["error"] == "SimulationError: Radau step did not converge (stand-in)"
    assert row["parameters"] is None and not row["converged"] and row["cost"] == np.inf
    assert res.best_start != 2 and all(r["error"] is None for k, r in
                                       enumerate(res.starts) if k != 2)
    with pytest.raises(MechatronError, match="all 4 starts failed; the first: "
                                             "SimulationError"):
        real(problem, starts=4, seed=0, workers=1, max_iterations=3)


def test_an_error_inside_casadi_fails_its_start_only(monkeypatch, problem):
    """CasADi reports a failure inside its own code (an integrator, a Function call) as
    a RuntimeError: that start is failed and reported, the others go on."""
    from mechatron.estimation import problem as module
    real = module.estimate
    X = start_points(problem, 3, seed=0)

    def failing(prob, *, initial=None, **kw):
        if initial is not None and initial[0] == X[1][0]:
            raise RuntimeError("Error in Function::call for 'F' [CvodesInterface]: "
                               "CV_CONV_FAILURE (stand-in)")
        return real(prob, initial=initial, **kw)
    monkeypatch.setattr(module, "estimate", failing)
    res = real(problem, starts=3, seed=0, workers=1, max_iterations=20)
    assert res.starts[1]["error"].startswith("RuntimeError: Error in Function::call")
    assert res.best_start != 1 and res.starts[0]["error"] is None \
        and res.starts[2]["error"] is None


# --------------------------------------------------------------------------------- CLI
#: the model file the command reads: the oscillator above, as its source
MODEL_FILE = "import mechatron as mt\n\n\n" + inspect.getsource(Oscillator)


def test_estimate_command_runs_the_starts_of_its_file(tmp_path, capsys):
    e = measured()
    (tmp_path / "osc.py").write_text(MODEL_FILE)
    np.savetxt(tmp_path / "free.csv", np.column_stack([e.t, e.outputs["x"]]),
               delimiter=",", header="t,x", comments="")
    cfg = tmp_path / "osc.toml"
    cfg.write_text('[model]\nfile = "osc.py"\n\n[[experiments]]\nname = "free"\n'
                   'file = "free.csv"\noutputs = ["x"]\nsigma = { x = 0.01 }\n\n'
                   '[outputs]\nx = "x"\n\n[parameters]\n'
                   'w = { initial = 2.0, min = 1.0, max = 12.0 }\n'
                   'zeta = { initial = 0.05, min = 0.01, max = 0.1 }\n\n'
                   '[options]\njit = false\n\n[estimation]\nstarts = 8\nseed = 0\n')
    assert main(["estimate", str(cfg), "--json", "--workers", "1", "--quiet"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert len(doc["starts"]) == 8 and doc["best_start"] != 0
    assert doc["parameters"]["w"] == pytest.approx(W_TRUE, abs=0.01)
    assert main(["estimate", str(cfg), "--starts", "3", "--seed", "2", "--workers", "1",
                 "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "3 starts on local processes" in out and "converged" in out
    assert main(["estimate", str(cfg), "--starts", "1", "--dask", "tcp://127.0.0.1:1"]) == 2
    assert "give --starts K (K > 1)" in capsys.readouterr().err
    assert main(["estimate", str(cfg), "--dask", "tcp://127.0.0.1:1"]) == 2
    assert "no Dask scheduler answers there" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text(cfg.read_text().replace("starts = 8", "starts = 0"))
    assert main(["estimate", str(bad)]) == 2
    assert "[estimation] starts" in capsys.readouterr().err
