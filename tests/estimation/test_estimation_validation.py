"""Validation (`mechatron.estimation.validation`): the figures against values computed
here from the known truth, and the `validate` command."""

from __future__ import annotations

import json
import logging

import numpy as np
import pytest

from mechatron.cli import main
from mechatron.estimation import EstimationProblem, Experiment, estimate, validate

from tests.estimation.test_estimation_rigs import (PROBLEM, RIG, TRUTH, _lag,
                                                   _write_run)
from tests.estimation.test_estimation_uncertainty import FirstOrder


def test_figures_of_the_true_model_are_those_of_the_noise(caplog):
    """Simulated with the true parameters, the error is the added noise (up to the
    discretization error, 1e-6 here): RMSE, fit % and the autocorrelation of the noise,
    computed here with numpy, and the cross-correlation with an independent input is
    inside the white-noise band at most lags."""
    caplog.set_level(logging.ERROR)
    rng = np.random.default_rng(11)
    n, h = 500, 0.02
    u = np.repeat(rng.choice([-1.0, 1.0], n // 25 + 1), 25)[:n]
    y = _lag(u, h, 2.0, 0.3)
    v = np.zeros(n)
    w = 0.05 * rng.standard_normal(n)
    for k in range(1, n):
        v[k] = 0.5 * v[k - 1] + w[k]
    e = Experiment("run", t=np.arange(n) * h, inputs={"u": u}, outputs={"y": y + v})
    prob = EstimationProblem(FirstOrder(), [e], ["K", "tau"], inputs={"u": "u"},
                             outputs={"y": "y"}, jit=False, substeps=8)
    rep = validate({"K": 2.0, "tau": 0.3}, problem=prob, lags=10)
    (row,) = rep.rows
    assert row["rmse"] == pytest.approx(np.sqrt(np.mean(v ** 2)), rel=1e-3)
    nrmse = np.linalg.norm(v) / np.linalg.norm(y + v - np.mean(y + v))
    assert row["fit_percent"] == pytest.approx(100 * (1 - nrmse), abs=1e-3)
    vc = v - v.mean()
    ref = [vc[j:] @ vc[:n - j] / (vc @ vc) for j in range(11)]
    assert rep.series[0]["acf"] == pytest.approx(ref, abs=1e-3)
    assert row["rho1"] == pytest.approx(0.5, abs=0.1)          # the AR(1) coefficient
    assert row["ccf_outside"] <= 0.2
    # a fit on these data: the report of the estimation set equals validate(result)
    res = estimate(prob)
    assert validate(res).rows[0]["rmse"] <= row["rmse"]


def test_missed_input_dynamics_show_in_the_cross_correlation(caplog):
    """A model with the wrong time constant leaves an error correlated with the input
    at positive lags (the input leads): the largest cross-correlation is far outside the
    band."""
    caplog.set_level(logging.ERROR)
    rng = np.random.default_rng(12)
    n, h = 500, 0.02
    u = rng.choice([-1.0, 1.0], n)
    y = _lag(u, h, 2.0, 0.3) + 0.01 * rng.standard_normal(n)
    e = Experiment("run", t=np.arange(n) * h, inputs={"u": u}, outputs={"y": y})
    prob = EstimationProblem(FirstOrder(), [e], ["K", "tau"], inputs={"u": "u"},
                             outputs={"y": "y"}, jit=False, substeps=8)
    rep = validate({"K": 2.0, "tau": 0.1}, problem=prob, lags=10)
    c = rep.series[0]["ccf"]["u"]
    assert np.argmax(np.abs(c)) > 10                           # positive lag
    assert rep.rows[0]["max_ccf"] > 5 * 1.96 / np.sqrt(n)


@pytest.fixture
def rig(tmp_path):
    (tmp_path / "models").mkdir()
    (tmp_path / "models" / "rig.py").write_text(RIG)
    _write_run(tmp_path / "a.csv", 600, 0.3, 1)
    _write_run(tmp_path / "b.csv", 300, -0.2, 2)
    _write_run(tmp_path / "other.csv", 400, 0.1, 3)
    cfg = tmp_path / "p.toml"
    cfg.write_text(PROBLEM)
    return cfg


def test_validate_command_on_another_file_and_from_a_saved_fit(rig, capsys):
    """`mechatron validate CONFIG --data other.csv`: fit, then the other run (its own
    offset 0.1 fitted again); with --fit the parameters of an earlier `estimate --out`
    are used without fitting, and give the same figures."""
    out = rig.parent / "v"
    assert main(["validate", str(rig), "--data", str(rig.parent / "other.csv"),
                 "--out", str(out), "--json", "--quiet"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["parameters"]["K"] == pytest.approx(TRUTH["K"], rel=1e-3)
    (row,) = doc["validation"]["validation"]["rows"]
    assert row["experiment"] == "other" and row["n"] == 400 and row["fit_percent"] > 99
    assert doc["validation"]["validation"]["parameters"]["other:off"] == \
        pytest.approx(0.1, abs=5e-3)
    page = (out / "validate_report.html").read_text()
    assert "Estimation data" in page and "Validation data" in page
    assert {p.name for p in out.iterdir()} == {
        "validate.json", "estimation_residuals.png", "validation_residuals.png",
        "validate_report.html"}
    est = rig.parent / "e"
    assert main(["estimate", str(rig), "--out", str(est), "--quiet", "--json"]) == 0
    capsys.readouterr()
    assert main(["validate", str(rig), "--data", str(rig.parent / "other.csv"), "--fit",
                 str(est / "estimate.json"), "--json"]) == 0
    again = json.loads(capsys.readouterr().out)
    (row2,) = again["validation"]["validation"]["rows"]
    assert row2["rmse"] == pytest.approx(row["rmse"], rel=1e-6)
    code = main(["validate", str(rig), "--fit", str(rig.parent / "a.csv")])
    assert code == 2 and "not the estimate.json" in capsys.readouterr().err


def test_some_plots_lack_quantity_names_and_units(rig, capsys, saved_figures):
    """The fit, trajectory and residual plots of `estimate` and `validate` label every
    axis with a quantity and its unit and name their curves in legends."""
    assert main(["estimate", str(rig), "--out", str(rig.parent / "e"), "--quiet",
                 "--json"]) == 0
    assert main(["validate", str(rig), "--data", str(rig.parent / "other.csv"),
                 "--out", str(rig.parent / "v"), "--json", "--quiet"]) == 0
    capsys.readouterr()
    assert len(saved_figures) >= 4
    assert saved_figures.problems() == []
