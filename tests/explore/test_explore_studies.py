"""Estimation, sensitivity and optimization results opened in the explorer."""

from __future__ import annotations

import json

import pytest

from mechatron.errors import DataError
from mechatron.explore import Workspace
from mechatron.explore.studies import read_study

PNG = b"\x89PNG\r\n\x1a\n" + b"\0" * 16

ESTIMATE = {
    "parameters": {"R": 7.0, "L": 3.4e-4},
    "initial": {"R": 21.0, "L": 1.1e-4},
    "at_bound": {"L": {"side": "max", "bound": 3.4e-4}},
    "ci95": {"R": [6.9, 7.1], "L": [3.3e-4, 3.5e-4]},
    "std": {"R": 0.05, "L": 1.7e-6},
    "correlation": {"names": ["R", "L"], "matrix": [[1.0, -0.2], [-0.2, 1.0]]},
    "cost_initial": 100.0, "cost": 1.0,
    "nrmse": {"step": {"i": 0.09}}, "nrmse_initial": {"step": {"i": 1.03}},
    "iterations": 12, "evaluations": 13, "wall_time_s": 2.0, "success": True,
    "message": "converged", "trajectory": [],
}


def test_an_estimation_result_as_tables_and_plots(tmp_path):
    (tmp_path / "estimate.json").write_text(json.dumps(ESTIMATE))
    (tmp_path / "estimate_fit.png").write_bytes(PNG)
    (tmp_path / "other.png").write_bytes(PNG)                  # not this study's
    study = read_study(tmp_path / "estimate.json", "s1")
    assert study.kind == "estimate" and study.images == ["estimate_fit.png"]
    params = study.tables[0]
    rows = {r[0]: r for r in params["rows"]}
    assert params["headers"][:5] == ["parameter", "start", "estimate", "95 % low", "95 % high"]
    assert rows["R"][1:5] == ["21", "7", "6.9", "7.1"]
    assert rows["R"][5] == f"{100 * 0.05 / 7.0:.2f} %"          # relative standard deviation
    assert rows["L"][6] == "at upper bound"
    assert study.tables[1]["rows"] == [["step", "i", "1.03", "0.09"]]
    assert "cost 100 -> 1" in study.summary[0]


def test_sensitivity_and_optimization_results(tmp_path):
    sens = {"parameters": ["k", "J"], "requirements": ["sse"], "ranking": ["J", "k"],
            "method": "sobol", "samples": 64, "evaluations": 256, "failed": 0,
            "sobol_total": {"k": {"sse": 0.1}, "J": {"sse": 0.8}},
            "warnings": ["few samples"]}
    (tmp_path / "sensitivity.json").write_text(json.dumps(sens))
    study = read_study(tmp_path / "sensitivity.json", "s2")
    assert study.kind == "sensitivity" and study.warnings == ["few samples"]
    assert study.tables[0]["rows"] == [["J", "0.8"], ["k", "0.1"]]    # in ranking order
    opt = {"parameters": {"Kp": 2.0}, "initial": {"Kp": 1.0}, "objective": 0.5,
           "objective_initial": 3.0, "max_violation": 0.0, "iterations": 9}
    (tmp_path / "optimize.json").write_text(json.dumps(opt))
    study = read_study(tmp_path / "optimize.json", "s3")
    assert study.kind == "optimize" and study.tables[0]["rows"] == [["Kp", "1", "2"]]


def test_files_that_are_not_results(tmp_path):
    (tmp_path / "a.json").write_text('{"hello": 1}')
    with pytest.raises(DataError, match="not a result of `mechatron estimate`"):
        read_study(tmp_path / "a.json", "s1")
    (tmp_path / "b.json").write_text("{nope")
    with pytest.raises(DataError, match="not a JSON document"):
        read_study(tmp_path / "b.json", "s1")


def test_workspace_serves_only_the_studys_plots(tmp_path):
    (tmp_path / "estimate.json").write_text(json.dumps(ESTIMATE))
    (tmp_path / "estimate_fit.png").write_bytes(PNG)
    ws = Workspace()
    study = ws.load_study(tmp_path / "estimate.json")
    assert ws.study_image(study["id"], "estimate_fit.png") == PNG
    with pytest.raises(KeyError, match="no plot '../estimate.json'"):
        ws.study_image(study["id"], "../estimate.json")
    with pytest.raises(FileNotFoundError):
        ws.load_study(tmp_path / "missing.json")


def test_opened_through_the_api(tmp_path):
    import urllib.request

    from mechatron.explore import ExploreServer
    (tmp_path / "estimate.json").write_text(json.dumps(ESTIMATE))
    (tmp_path / "estimate_fit.png").write_bytes(PNG)
    srv = ExploreServer(Workspace(), port=0)
    srv.start()
    try:
        req = urllib.request.Request(srv.url + "api/open", headers={"Content-Type":
                                                                    "application/json"},
                                     data=json.dumps({"path": str(tmp_path / "estimate.json")})
                                     .encode())
        study = json.load(urllib.request.urlopen(req))["study"]
        with urllib.request.urlopen(f"{srv.url}api/studies/{study['id']}/image/"
                                    "estimate_fit.png") as r:
            assert r.headers["Content-Type"] == "image/png" and r.read() == PNG
        assert [s["id"] for s in json.load(urllib.request.urlopen(srv.url + "api/studies"))] \
            == [study["id"]]
    finally:
        srv.shutdown()
        srv.server_close()
