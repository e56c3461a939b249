"""The estimate, sensitivity and optimize commands on the example problem files."""

import json
import shutil
from pathlib import Path

import pytest

from mechatron.cli import main

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture()
def example(tmp_path):
    def copy(name):
        shutil.copy(EXAMPLES / name, tmp_path / name)
        shutil.copy(EXAMPLES / "rigs.py", tmp_path / "rigs.py")   # its [model] file
        return tmp_path / name
    return copy


def test_estimate_example_generates_its_data_and_writes_its_report(capsys, example,
                                                                  tmp_path):
    """The full acceptance case is in test_estimation_estimate.py; here a few iterations
    check the command: data generated when absent, JSON with parameters and ci95, files,
    progress on stderr, the human table."""
    cfg = example("dc_motor_estimate.toml")
    code, out, err = run(capsys, "estimate", str(cfg), "--json", "--max-iterations", "4",
                         "--out", str(tmp_path / "out"))
    assert code == 0, err
    doc = json.loads(out)
    assert (tmp_path / "dc_motor_data" / "multi_step.csv").exists()
    assert set(doc["ci95"]) == set(doc["parameters"]) >= {"R", "L", "k", "J", "B"}
    for lo, hi in doc["ci95"].values():
        assert lo < hi
    assert doc["cost"] < doc["cost_initial"]
    assert "estimate: 0" in err                      # progress lines on stderr
    assert (tmp_path / "out" / "estimate_fit.png").stat().st_size > 10000
    saved = json.loads((tmp_path / "out" / "estimate.json").read_text())
    assert saved["parameters"] == doc["parameters"]
    # the substeps per experiment and their error estimate (see test_estimation_substeps)
    assert set(doc["discretization"]) == {"locked_rotor", "multi_step"}
    assert all(d["substeps"] >= 1 and d["error"] is not None
               for d in doc["discretization"].values())
    code, out, err = run(capsys, "estimate", str(cfg), "--max-iterations", "1", "--quiet")
    assert code == 0 and "95% interval" in out and "NRMSE" in out and err == ""
    assert "discretization (Radau substeps per sample" in out


def test_sensitivity_example(capsys, example):
    cfg = example("dc_motor_sensitivity.toml")
    code, out, err = run(capsys, "sensitivity", str(cfg), "--samples", "8", "--workers",
                         "1", "--json", "--quiet")
    assert code == 0, err
    doc = json.loads(out)
    assert doc["evaluations"] == 8 * (8 + 2)
    assert doc["ranking"][0] == "k"
    assert len(doc["best"]) == 5


def test_optimize_example_meets_every_requirement(capsys, example):
    cfg = example("dc_motor_speed_pi_optimize.toml")
    code, out, err = run(capsys, "optimize", str(cfg), "--json", "--quiet")
    assert code == 0, err
    doc = json.loads(out)
    assert doc["all_met"]
    assert not all(r["start_met"] for r in doc["requirements"])


def test_bad_problem_files_are_one_line_errors(capsys, tmp_path):
    code, out, err = run(capsys, "estimate", str(tmp_path / "none.toml"))
    assert code == 2 and "none.toml: no such file" in err
    bad = tmp_path / "bad.toml"
    bad.write_text("[modle]\nname = 'x'\n")
    code, out, err = run(capsys, "estimate", str(bad))
    assert code == 2 and "unknown section(s) modle" in err
    bad.write_text("[model]\nname = 'dc_motor'\nvariant = 'ode'\n[parameters]\nQ = 1\n"
                   "[[experiments]]\nfile = 'x.csv'\n")
    code, out, err = run(capsys, "estimate", str(bad))
    assert code == 2 and "'Q' is not a parameter" in err


def test_empty_data_file_and_missing_dask_are_clear_errors(capsys, example, tmp_path,
                                                           monkeypatch):
    import sys
    cfg = example("dc_motor_estimate.toml")
    data = tmp_path / "dc_motor_data"
    data.mkdir()
    (data / "multi_step.csv").write_text("")
    (data / "locked_rotor.csv").write_text("")
    code, out, err = run(capsys, "estimate", str(cfg), "--quiet")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "multi_step.csv: the file is empty" in err
    # a machine without Dask (it is a dev extra): its modules made unimportable
    for name in [m for m in sys.modules if m == "dask" or m.startswith(("dask.",
                                                                        "distributed"))]:
        monkeypatch.delitem(sys.modules, name)
    for name in ("dask", "distributed", "dask.distributed"):
        monkeypatch.setitem(sys.modules, name, None)
    cfg = example("dc_motor_sensitivity.toml")
    code, out, err = run(capsys, "sensitivity", str(cfg), "--dask", "tcp://127.0.0.1:8786",
                         "--quiet")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert err.startswith("error: --dask: evaluating on a Dask cluster needs the packages "
                          "dask and distributed")


def test_bad_sample_and_worker_counts(capsys, example):
    cfg = example("dc_motor_sensitivity.toml")
    for argv, text in ((["--samples", "0"], "--samples: at least 2, got 0"),
                       (["--workers", "0"], "--workers: at least 1, got 0")):
        code, out, err = run(capsys, "sensitivity", str(cfg), *argv, "--quiet")
        assert code == 2 and err == f"error: {text}.\n"


def test_estimation_on_all_zero_data_is_refused_before_compiling(capsys, example,
                                                                  tmp_path):
    """All-zero measurements compiled a 1.5 MB C file for minutes before fitting
    nothing; now the problem is refused when it is built, naming the experiments."""
    cfg = example("dc_motor_estimate.toml")
    data = tmp_path / "dc_motor_data"
    data.mkdir()
    rows = "".join(f"{k * 1e-4:g},0,0,0,0\n" for k in range(200))
    for name in ("multi_step", "locked_rotor"):
        (data / f"{name}.csv").write_text("t [s],V [V],i [A],phi [rad],w [rad/s]\n" + rows)
    code, out, err = run(capsys, "estimate", str(cfg), "--quiet")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "every measured output of 'multi_step'" in err and "'locked_rotor'" in err
    assert "is zero" in err
    assert not list(tmp_path.rglob("*.c"))


def test_dask_without_a_scheduler_is_a_prompt_error(capsys, example):
    """With dask installed but no scheduler at the address, Dask waited 30 s and the
    message named no option; now the address is tried first (a refused port answers at
    once)."""
    import socket
    pytest.importorskip("distributed")
    with socket.socket() as s:                 # a free port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    cfg = example("dc_motor_sensitivity.toml")
    code, out, err = run(capsys, "sensitivity", str(cfg), "--dask",
                         f"tcp://127.0.0.1:{port}", "--quiet")
    assert code == 2 and out == "" and err.count("\n") == 1
    assert err.startswith(f"error: --dask tcp://127.0.0.1:{port}: no Dask scheduler "
                          "answers there")
    assert "--workers N" in err
    code, out, err = run(capsys, "sensitivity", str(cfg), "--dask", "tcp://nohost", "-q")
    assert code == 2 and "expected the scheduler's address as tcp://HOST:PORT" in err


def test_estimation_flags_unidentifiable_parameters(capsys, example, tmp_path):
    """From the locked-rotor run alone (w = 0 throughout) the current obeys
    L di/dt = V - R i: R and L are determined, the inertia J cannot be (the outputs do
    not depend on it). J is flagged as not identifiable, R and L are not."""
    cfg = example("dc_motor_estimate.toml")
    text = cfg.read_text()
    start = text.index("[[experiments]]")
    second = text.index("[[experiments]]", start + 1)
    text = text[:start] + text[second:]                   # drop the multi-step run
    text = text.replace('w = "rate(phi)"', "")
    params = text.index("[parameters]")
    fixed = text.index("[fixed]")
    text = (text[:params] + "[parameters]\nR = { initial = 10.0, min = 0 }\n"
            "L = { initial = 2e-4, min = 0 }\nJ = { initial = 1.6e-6, min = 0 }\n\n"
            + text[fixed:].replace("[fixed]", "[fixed]\nk = 0.151\nB = 1.2e-4\n"
                                   "T_C = 8.5e-3"))
    text = text.replace('offsets = ["i"]', "")
    cfg.write_text(text)
    code, out, err = run(capsys, "estimate", str(cfg), "--json", "--quiet",
                         "--max-iterations", "20")
    assert code == 0, err
    doc = json.loads(out)
    assert set(doc["flags"]) == {"J"}, doc["flags"]
    assert doc["flags"]["J"].startswith("is not identifiable")
    assert "warning: estimate: J is not identifiable" in err
    assert doc["parameters"]["R"] == pytest.approx(7.1, rel=0.05)   # table 6-1
