"""Regression runs of the database as batch tasks: the same rows in this process, on
local processes and on a Dask LocalCluster of two workers; a wrong expected value
fails its row and the command."""

import dataclasses
import json

import pytest

import mechatron as mt
from mechatron.cli import main
from mechatron.models import registry
from mechatron.models.regression import check_model, run_regression

#: A few fast models, of several variants each.
NAMES = ["msd_vertical", "dc_motor", "motor_heating", "induction_dol"]
G = 9.81          # the database's gravity (mechatron.models.msd.G)


def _numbers(rows):
    """The rows without their wall times (which differ from run to run)."""
    return [{k: v for k, v in r.items() if "wall_time" not in k} for r in rows]


@pytest.fixture(scope="module")
def serial():
    return run_regression(NAMES, workers=1)


def test_rows_check_expected_values_and_variants(serial):
    assert [r["model"] for r in serial] == NAMES
    for r in serial:
        entry = mt.models.get(r["model"])
        assert r["error"] is None and r["passed"], r
        assert r["variants"][0] == r["reference"] and len(r["variants"]) >= 2
        assert set(r["expected"]) == set(entry.expected)
        assert r["expected_worst"] == max(e["rel_error"] for e in r["expected"].values())
        assert r["expected_worst"] <= entry.expected_tolerance
        assert 0 <= r["variants_worst"] <= entry.variant_tolerance
    # the hanging mass settles at its static deflection m g / k
    par = mt.models.get("msd_vertical").parameters
    y = serial[0]["expected"]["y"]["value"]
    assert y == pytest.approx(par["m"].default * G / par["k_s"].default, rel=1e-6)


def test_local_processes_give_the_serial_rows(serial):
    assert _numbers(run_regression(NAMES, workers=2)) == _numbers(serial)


def test_a_local_cluster_of_two_workers_gives_the_serial_rows(serial, monkeypatch):
    """Also for an entry registered here at run time, which the workers' own database
    lacks: it travels with the tasks."""
    distributed = pytest.importorskip("distributed")
    mine = dataclasses.replace(mt.models.get("msd_vertical"), name="msd_registered_here",
                               variants={k: (lambda f: lambda **kw: f(**kw))(f) for k, f
                                         in mt.models.get("msd_vertical").variants.items()})
    monkeypatch.setitem(registry._REGISTRY, mine.name, mine)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None, silence_logs=40) as cluster, \
            distributed.Client(cluster) as client:
        remote = run_regression(NAMES + [mine.name], client=client)
    assert _numbers(remote[:-1]) == _numbers(serial)
    here = check_model(mine)
    assert remote[-1]["model"] == mine.name and here["passed"]
    assert _numbers(remote[-1:]) == _numbers([here])


def test_a_wrong_expected_value_fails_its_row_and_the_command(monkeypatch, capsys):
    good = mt.models.get("msd_vertical")
    wrong = dataclasses.replace(good, name="msd_wrong", expected={"y": 2 * G / 100.0})
    monkeypatch.setitem(registry._REGISTRY, "msd_wrong", wrong)
    row = check_model("msd_wrong")
    assert not row["passed"] and row["error"] is None
    assert row["expected"]["y"]["rel_error"] == pytest.approx(0.5, rel=1e-5)
    assert main(["regression", "msd_vertical", "msd_wrong", "--workers", "1"]) == 1
    out = capsys.readouterr().out
    assert "1 of 2 passed; failed: msd_wrong." in out and "FAILED" in out
    assert main(["regression", "msd_vertical", "--workers", "1", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["passed"] and doc["models"][0]["model"] == "msd_vertical"
    assert main(["regression", "msd_vertical", "--dask", "tcp://127.0.0.1:1"]) == 2
    assert "no Dask scheduler answers there" in capsys.readouterr().err
    assert main(["regression", "no_such_model"]) == 2
    assert "no model 'no_such_model'" in capsys.readouterr().err
