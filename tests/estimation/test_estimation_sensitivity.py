"""Sensitivity analysis: sampling, Sobol indices against an analytic case, and the DC
motor ranking against a finite-difference local sensitivity."""

import numpy as np
import pytest

from mechatron.errors import ParameterError
from mechatron.estimation import EstimationProblem, FreeParameter
from mechatron.estimation.bench import TABLE_6_1, VirtualBench
from mechatron.estimation.sensitivity import (Distribution, local_sensitivity,
                                              regression_intervals, run_sensitivity,
                                              sample, sobol_indices,
                                              sobol_intervals, sobol_warnings,
                                              standardized_regression)


def test_distributions_map_the_unit_interval():
    u = np.array([0.1, 0.5, 0.9])
    np.testing.assert_allclose(Distribution("uniform", 2, 4).ppf(u), [2.2, 3, 3.8])
    np.testing.assert_allclose(Distribution("loguniform", 1, 100).ppf(u),
                               [10 ** 0.2, 10, 10 ** 1.8])
    from scipy.stats import norm
    np.testing.assert_allclose(Distribution("normal", 1, 2).ppf(u), norm.ppf(u, 1, 2))
    with pytest.raises(ParameterError, match="low must be > 0"):
        Distribution("loguniform", 0, 1)


def test_latin_hypercube_puts_one_sample_in_each_stratum():
    X = sample({"a": Distribution("uniform", 0, 1), "b": Distribution("uniform", 0, 1)},
               50, "lhs", seed=2)
    for j in range(2):
        assert sorted(np.floor(X[:, j] * 50).astype(int)) == list(range(50))


def test_sobol_indices_of_an_additive_model_are_analytic():
    """y = 4 a + 2 b + 0 c with independent U(0,1): S_a = 16/20, S_b = 4/20, S_c = 0."""
    d = {n: Distribution("uniform", 0, 1) for n in "abc"}
    A, B, AB = sample(d, 4096, "sobol", seed=1)

    def f(X):
        return 4 * X[..., 0] + 2 * X[..., 1]
    S1, ST = sobol_indices(f(A), f(B), f(AB))
    np.testing.assert_allclose(S1, [0.8, 0.2, 0.0], atol=0.02)
    np.testing.assert_allclose(ST, [0.8, 0.2, 0.0], atol=0.02)


def _additive(X):
    return 4 * X[..., 0] + 2 * X[..., 1]


def test_sobol_intervals_hold_the_analytic_indices_and_shrink_with_samples():
    """Bootstrap 95% intervals of y = 4 a + 2 b + 0 c: they contain S = (0.8, 0.2, 0),
    and four times the samples halve them (the estimator's error goes as 1/sqrt(n))."""
    d = {n: Distribution("uniform", 0, 1) for n in "abc"}
    exact = np.array([0.8, 0.2, 0.0])
    widths = []
    for n in (256, 1024):
        A, B, AB = sample(d, n, "sobol", seed=4)
        S1, ST = sobol_indices(_additive(A), _additive(B), _additive(AB))
        s1_lo, s1_hi, st_lo, st_hi = sobol_intervals(_additive(A), _additive(B),
                                                     _additive(AB), seed=0)
        assert np.all(s1_lo - 1e-12 <= exact) and np.all(exact <= s1_hi + 1e-12)
        assert np.all(st_lo - 1e-12 <= exact) and np.all(exact <= st_hi + 1e-12)
        widths.append((s1_hi - s1_lo)[:2])
    ratio = widths[1] / widths[0]
    assert np.all((0.3 < ratio) & (ratio < 0.75)), ratio


def test_sobol_warnings_for_indices_outside_zero_one():
    names, reqs = ["a", "b", "c"], ["sse_i"]
    S1 = np.array([[0.5], [-0.004], [-0.2]])
    ST = np.array([[1.08], [0.01], [0.02]])
    iv = {"S1_low": np.array([[0.3], [-0.02], [-0.3]]),
          "S1_high": np.array([[0.7], [0.01], [-0.1]]),
          "ST_low": np.array([[0.9], [0.0], [0.0]]),
          "ST_high": np.array([[1.3], [0.03], [0.05]])}
    warnings = sobol_warnings(names, reqs, S1, ST, iv, 16)
    # c's first-order index is below 0 beyond its interval; b's is noise inside it;
    # a's total index exceeds 1
    assert len(warnings) == 2, warnings
    assert warnings[0].startswith("c: first-order Sobol index for sse_i is -0.200 (95% "
                                  "interval [-0.300, -0.100]), which is negative beyond")
    assert warnings[1].startswith("a: total Sobol index for sse_i is +1.080 (95% interval "
                                  "[+0.900, +1.300]), which exceeds 1")
    assert all("more samples (e.g. 64" in w for w in warnings)
    assert sobol_warnings(names, reqs, None, None, {}, 16) == []


def test_standardized_regression_coefficients_of_a_linear_model():
    rng = np.random.default_rng(0)
    X = rng.random((2000, 2))
    y = 3 * X[:, 0] - X[:, 1]
    src, r2 = standardized_regression(X, y)
    # exact for a linear model: b_j std(x_j) / std(y)
    expected = np.array([3, -1]) * X.std(0) / y.std()
    np.testing.assert_allclose(src, expected, rtol=1e-10)
    assert r2 == pytest.approx(1.0)


def test_monte_carlo_bootstrap_intervals_hold_the_analytic_coefficients():
    """Monte Carlo (LHS) runs got no intervals (issue 20). For y = 3 a - b + noise with
    a, b ~ U(0, 1) the standardized coefficients are exactly b_j std(x_j) / std(y) with
    std(y)^2 = (9 + 1)/12 + s^2: the bootstrap 95% intervals contain them, and 16 times
    the samples shrink them about fourfold (1/sqrt(n))."""
    noise = 0.3
    exact = np.array([3, -1]) / np.sqrt(12) / np.sqrt(10 / 12 + noise ** 2)
    d = {n: Distribution("uniform", 0, 1) for n in "ab"}
    widths = []
    for n in (200, 3200):
        X = sample(d, n, "lhs", seed=3)
        y = 3 * X[:, 0] - X[:, 1] + noise * np.random.default_rng(5).standard_normal(n)
        lo, hi = regression_intervals(X, y[:, None], seed=0)
        assert np.all(lo[:, 0] <= exact) and np.all(exact <= hi[:, 0]), (lo, hi, exact)
        widths.append(hi[:, 0] - lo[:, 0])
    ratio = widths[1] / widths[0]
    assert np.all((0.15 < ratio) & (ratio < 0.4)), ratio


def test_monte_carlo_with_too_few_samples_warns(capsys, tmp_path):
    """20 LHS samples for the 8 parameters of the example: fewer than 10 per parameter,
    so the command prints the regression table with a warning instead of as if sound."""
    import shutil
    from pathlib import Path
    from mechatron.cli import main
    examples = Path(__file__).resolve().parents[2] / "examples"
    cfg = tmp_path / "s.toml"
    shutil.copy(examples / "dc_motor_sensitivity.toml", cfg)
    shutil.copy(examples / "rigs.py", tmp_path / "rigs.py")     # the file's own model
    code = main(["sensitivity", str(cfg), "--method", "lhs", "--samples", "20",
                 "--workers", "1", "--quiet"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "warning: sensitivity: 20 Monte Carlo samples for 8 parameter(s) are too few" \
        in err and "use at least 90" in err
    assert "! 20 samples are too few for the regression coefficients" in out


@pytest.fixture(scope="module")
def motor_problem():
    bench = VirtualBench(seed=5)
    step = bench.voltage_step(t_stop=0.02)
    names = ["R", "L", "k", "J", "B", "T_C", "T_brk", "w_brk"]
    free = [FreeParameter(n, TABLE_6_1[n], 0.0) for n in names]
    return names, EstimationProblem(bench.model(), [step], free, inputs={"V": "V"},
                                    outputs={"i": "i", "w": "rate(phi)"}, offsets=["i"])


def test_ranking_agrees_with_local_finite_differences(motor_problem):
    names, prob = motor_problem
    dists = {n: Distribution("uniform", 0.7 * TABLE_6_1[n], 1.3 * TABLE_6_1[n])
             for n in names}
    res = run_sensitivity(prob, dists, n=64, method="sobol", workers=2, seed=3)
    assert res.evaluations == 64 * (len(names) + 2) and res.failed == 0
    # an interval per index, and every index outside [0, 1] that the rule flags is
    # reported as a warning
    for est, lo, hi in ((res.S1, "S1_low", "S1_high"), (res.ST, "ST_low", "ST_high")):
        assert res.intervals[lo].shape == est.shape
        assert np.all(res.intervals[lo] <= res.intervals[hi])
    assert res.warnings == sobol_warnings(names, res.requirements, res.S1, res.ST,
                                          res.intervals, 64)
    assert res.to_dict()["warnings"] == res.warnings
    local = local_sensitivity(prob, names)
    score = {n: max(v.values()) for n, v in local.items()}
    by_local = sorted(names, key=lambda n: -score[n])
    # the three that matter most for current and speed come first in both
    assert set(res.ranking[:3]) == set(by_local[:3])
    # the breakaway parameters hardly matter in a run far from standstill: last in both
    assert set(res.ranking[-2:]) == {"T_brk", "w_brk"} == set(by_local[-2:])
    # best samples are sorted by cost and come from the samples
    costs = [b["cost"] for b in res.best]
    assert costs == sorted(costs)
    assert res.throughput > 0


def test_parallel_and_serial_evaluation_agree(motor_problem):
    names, prob = motor_problem
    dists = {n: Distribution("uniform", 0.9 * TABLE_6_1[n], 1.1 * TABLE_6_1[n])
             for n in ("R", "k")}
    a = run_sensitivity(prob, dists, n=16, method="lhs", workers=1)
    b = run_sensitivity(prob, dists, n=16, method="lhs", workers=2)
    np.testing.assert_allclose(a.Y, b.Y, rtol=1e-12)


def test_a_problem_pickles_for_worker_processes(motor_problem):
    """Process pools (spawn) and Dask ship the problem pickled: rebuilt with the same
    substeps, it gives the same residuals."""
    import pickle
    _, prob = motor_problem
    again = pickle.loads(pickle.dumps(prob))
    assert [b["substeps"] for b in again.bound] == [b["substeps"] for b in prob.bound]
    np.testing.assert_array_equal(again.residuals(prob.initial), prob.residuals(prob.initial))


@pytest.mark.parametrize("command,example,extra", [
    ("sensitivity", "dc_motor_sensitivity.toml",
     ["--method", "lhs", "--samples", "20", "--workers", "1"]),
    ("optimize", "dc_motor_speed_pi_optimize.toml", ["--max-iterations", "3"]),
], ids=["sensitivity", "optimize"])
def test_some_plots_lack_quantity_names_and_units(capsys, tmp_path, saved_figures, command,
                                                  example, extra):
    """The scatter matrix and tornado of `sensitivity`, the response plot of `optimize`:
    every axis a quantity with its unit (parameters and requirements in theirs), every
    labelled curve in a legend."""
    import shutil
    from pathlib import Path
    from mechatron.cli import main
    examples = Path(__file__).resolve().parents[2] / "examples"
    cfg = tmp_path / example
    shutil.copy(examples / example, cfg)
    shutil.copy(examples / "rigs.py", tmp_path / "rigs.py")
    code = main([command, str(cfg), *extra, "--out", str(tmp_path / "out"), "--quiet"])
    assert code in (0, 1), capsys.readouterr().err      # 1: requirements not all met
    capsys.readouterr()
    assert saved_figures
    assert saved_figures.problems() == []
