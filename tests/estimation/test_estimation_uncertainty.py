"""Honest uncertainty (`mechatron.estimation.uncertainty`): intervals that hold with
coloured noise, warnings for correlated residuals and poorly identified parameters, and
profile-likelihood intervals."""

import logging

import numpy as np
import pytest

import mechatron as mt
from mechatron.estimation import EstimationProblem, Experiment, FreeParameter, estimate
from mechatron.estimation.uncertainty import (acf, bartlett_critical, ccf,
                                              hac_covariance)


class FirstOrder(mt.Component):
    """tau y' = K u - y."""

    K = mt.Parameter("1", default=1.0)
    tau = mt.Parameter("s", default=1.0)
    u = mt.Parameter("1", default=0.0)
    y = mt.Variable("1", start=0.0)

    def equations(self):
        return [self.tau * mt.der(self.y) == self.K * self.u - self.y]


def _exact_zoh(K, tau, u, h):
    """The first-order lag driven by a held input, exactly on the sample grid (the
    analytic solution, not the estimator's Radau steps)."""
    a = np.exp(-h / tau)
    y = np.zeros(u.size)
    for k in range(u.size - 1):
        y[k + 1] = a * y[k] + (1 - a) * K * u[k]
    return y


def _ar1(rng, n, rho, std, reps):
    """``reps`` stationary AR(1) series of ``n`` samples (marginal std ``std``)."""
    w = rng.standard_normal((reps, n)) * std * np.sqrt(1 - rho ** 2)
    v = np.empty((reps, n))
    v[:, 0] = rng.standard_normal(reps) * std
    for k in range(1, n):
        v[:, k] = rho * v[:, k - 1] + w[:, k]
    return v


def _problem(y, u, h, jit=False, start=(1.5, 0.3)):
    t = np.arange(u.size) * h
    e = Experiment("prbs", t=t, inputs={"u": u}, outputs={"y": y})
    return EstimationProblem(FirstOrder(), [e], [FreeParameter("K", start[0], 0.1, 10),
                                                 FreeParameter("tau", start[1], 0.01, 5)],
                             inputs={"u": "u"}, outputs={"y": "y"}, jit=jit, substeps=4)


def test_stated_95_percent_intervals_cover_the_truth_with_coloured_noise(caplog):
    """200 records of a first-order lag with AR(1) noise (rho = 0.8): the HAC intervals
    cover the true K and tau in 90-98% of them; the white-noise intervals, which assume
    independent errors, in far fewer (about half)."""
    caplog.set_level(logging.ERROR)
    rng = np.random.default_rng(7)
    n, h, K, tau, rho = 400, 0.05, 2.0, 0.4, 0.8
    u = np.repeat(rng.choice([-1.0, 1.0], n // 20 + 1), 20)[:n]
    y = _exact_zoh(K, tau, u, h)
    noise = _ar1(rng, n, rho, 0.15, 200)
    prob = _problem(y, u, h, start=(1.8, 0.36))     # a start near the truth: fewer steps
    hits = np.zeros(2)
    hits_white = np.zeros(2)
    for v in noise:
        prob.bound[0]["Ym"] = (y + v)[None, :]      # same problem, new measurement
        res = estimate(prob, refine=False)
        for j, (name, truth) in enumerate((("K", K), ("tau", tau))):
            lo, hi = res.ci95[name]
            hits[j] += lo <= truth <= hi
            lo, hi = res.ci95_white[name]
            hits_white[j] += lo <= truth <= hi
    coverage = hits / len(noise)
    assert np.all((coverage >= 0.90) & (coverage <= 0.98)), coverage
    assert np.all(hits_white / len(noise) < 0.75)
    assert res.covariance == "hac"
    assert res.residual_rho1["prbs/y"] > 0.5


def test_hac_equals_white_covariance_for_white_residuals_with_a_zero_bandwidth():
    """Bandwidth 1 (no lags): the sandwich of ordinary least squares with homoskedastic
    residuals, n/(n-q) (X'X)^-1 X' diag(r^2) X (X'X)^-1 (White's estimator, by hand)."""
    rng = np.random.default_rng(0)
    X = rng.standard_normal((50, 2))
    r = rng.standard_normal(50)
    cov, b = hac_covariance(X, r, [[(slice(0, 50), np.arange(50))]], bandwidth=1.0)
    Ai = np.linalg.inv(X.T @ X)
    ref = 50 / 48 * Ai @ (X.T * r ** 2) @ X @ Ai
    assert cov == pytest.approx(ref, rel=1e-12)
    assert b == pytest.approx(1 / 50)
    assert bartlett_critical(0.0) == pytest.approx(1.959964)


def test_hac_covariance_of_a_mean_matches_the_bartlett_long_run_variance():
    """For the mean of a series (J = ones), C = n/(n-1) sum_|j|<S (1-|j|/S) gamma_j / n^2
    with gamma_j the sample autocovariance sums (written out here with a loop)."""
    rng = np.random.default_rng(1)
    x = _ar1(rng, 200, 0.6, 1.0, 1)[0]
    r = x - x.mean()
    S = 7.0
    cov, _ = hac_covariance(np.ones((200, 1)), r, [[(slice(0, 200), np.arange(200))]],
                            bandwidth=S)
    lrv = sum((1 - abs(j) / S) * sum(r[k] * r[k - abs(j)] for k in range(abs(j), 200))
              for j in range(-6, 7))
    assert cov[0, 0] == pytest.approx(200 / 199 * lrv / 200 ** 2, rel=1e-12)


def test_acf_and_ccf_of_known_series():
    x = np.sin(np.arange(400) * 0.3)
    assert acf(x, 3)[0] == 1.0
    assert acf(x, 3)[1] == pytest.approx(np.cos(0.3), abs=0.01)
    u = np.random.default_rng(2).standard_normal(300)
    c = ccf(np.r_[0.0, 0.0, u[:-2]], u, 4)            # x_k = u_(k-2)
    assert np.argmax(c) == 4 + 2 and c[6] == pytest.approx(1.0, abs=0.02)


def test_warnings_name_correlated_residuals_and_correlation_partners(caplog):
    """y = (a + b) u cannot separate a and b: each is named with the other as its partner;
    the residuals, coloured, are warned about."""

    class Sum(mt.Component):
        a = mt.Parameter("1", default=1.0)
        b = mt.Parameter("1", default=1.0)
        u = mt.Parameter("1", default=0.0)
        y = mt.Variable("1", start=0.0)

        def equations(self):
            return [0.1 * mt.der(self.y) == (self.a + self.b) * self.u - self.y]

    rng = np.random.default_rng(3)
    t = np.arange(300) * 0.02
    u = np.repeat(rng.choice([-1.0, 1.0], 16), 20)[:300]
    y = _exact_zoh(3.0, 0.1, u, 0.02) + _ar1(rng, 300, 0.9, 0.1, 1)[0]
    e = Experiment("run", t=t, inputs={"u": u}, outputs={"y": y})
    prob = EstimationProblem(Sum(), [e], [FreeParameter("a", 1.0, 0.0, 10),
                                          FreeParameter("b", 1.5, 0.0, 10)],
                             inputs={"u": "u"}, outputs={"y": "y"}, jit=False)
    with caplog.at_level(logging.WARNING):
        res = estimate(prob)
    text = " ".join(res.warnings)
    assert "residuals are correlated" in text and "run/y" in text
    assert "'a' is poorly identified" in text and "'b'" in text
    assert any("poorly identified" in r.getMessage() for r in caplog.records)


def test_profile_interval_of_a_linear_model_equals_the_wald_interval(caplog):
    """For a model linear in its parameters the cost is quadratic: the profile-likelihood
    interval equals the sandwich interval (to the root-finding tolerance)."""
    caplog.set_level(logging.ERROR)
    rng = np.random.default_rng(4)
    n, h = 300, 0.05
    u = np.repeat(rng.choice([-1.0, 1.0], 16), 20)[:n]
    y = _exact_zoh(2.0, 0.4, u, h) + _ar1(rng, n, 0.5, 0.1, 1)[0]
    t = np.arange(n) * h
    e = Experiment("prbs", t=t, inputs={"u": u}, outputs={"y": y})
    prob = EstimationProblem(FirstOrder(tau=0.4), [e], [FreeParameter("K", 1.0, 0.1, 10)],
                             inputs={"u": "u"}, outputs={"y": "y"}, jit=False, substeps=4)
    res = estimate(prob, profile=["K"])
    lo, hi = res.profile_ci95["K"]
    assert lo == pytest.approx(res.ci95["K"][0], rel=1e-3)
    assert hi == pytest.approx(res.ci95["K"][1], rel=1e-3)


def test_profile_interval_of_a_time_constant_is_asymmetric(caplog):
    """tau enters nonlinearly: the profile interval is not symmetric about the estimate,
    and contains it."""
    caplog.set_level(logging.ERROR)
    rng = np.random.default_rng(5)
    n, h = 200, 0.05
    u = np.repeat(rng.choice([-1.0, 1.0], 11), 20)[:n]
    y = _exact_zoh(2.0, 0.4, u, h) + 0.2 * rng.standard_normal(n)
    prob = _problem(y, u, h)
    res = estimate(prob, profile=True)
    v = res.parameters["tau"]
    lo, hi = res.profile_ci95["tau"]
    assert lo < v < hi
    assert abs((hi - v) - (v - lo)) > 1e-3 * (hi - lo)
    assert set(res.profile_ci95) == {"K", "tau"}
