"""The `codegen` command and the demo's code-generation step."""

import json
from types import SimpleNamespace

import pytest

import mechatron.codegen as codegen
from mechatron.cli import main


@pytest.fixture
def run(capsys):
    def _run(*args):
        code = main(list(args))
        out = capsys.readouterr()
        return SimpleNamespace(returncode=code, stdout=out.out, stderr=out.err)
    return _run


def test_codegen_command_writes_builds_and_checks(run, tmp_path):
    proc = run("codegen", "dc_motor", "--solver", "backward_euler", "--iterations", "2",
               "--dt", "1e-4", "--t-stop", "0.05", "--set", "V=12", "--out", str(tmp_path),
               "--check", "--json")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["max_rel_difference_to_desktop"] <= 1e-12
    assert doc["steps"] == 500 and doc["ns_per_step"] > 0
    for name in ("dc_motor.h", "dc_motor.c", "dc_motor_casadi.c", "dc_motor_main.c",
                 "Makefile"):
        assert (tmp_path / name).exists()
    # --set became the default of the generated code
    assert "12.0" in (tmp_path / "dc_motor.c").read_text()


def test_codegen_command_errors(run, tmp_path):
    proc = run("codegen", "dc_motor", "--out", str(tmp_path))
    assert proc.returncode == 2 and "--dt" in proc.stderr
    proc = run("codegen", "dc_motor", "--dt", "-1", "--out", str(tmp_path))
    assert proc.returncode == 2 and "step size" in proc.stderr
    proc = run("codegen", "dc_motor", "--solver", "rk5", "--dt", "1e-4", "--out",
               str(tmp_path))
    assert proc.returncode == 2


def test_demo_run_generates_compiles_and_runs_the_dc_motor(tmp_path):
    pytest.importorskip("fmpy")
    d = codegen.demo_run(tmp_path)
    assert d["max_rel_difference"] <= 1e-12
    assert d["final_w"] == pytest.approx(d["analytic_w"], rel=1e-6)
    assert d["ns_per_step"] > 0 and d["steps"] == 1000
    assert d["fmu_check"]["validation_problems"] == []
    assert d["fmu_check"]["max_rel_difference_to_desktop"] <= 1e-6


def test_codegen_arm_with_a_relative_out(run, tmp_path, monkeypatch):
    from mechatron.codegen.c.build import have_cross_compiler
    if not have_cross_compiler():
        pytest.skip("arm-none-eabi-gcc not installed")
    monkeypatch.chdir(tmp_path)
    proc = run("codegen", "dc_motor", "--dt", "1e-4", "--out", "gen/motor", "--arm",
               "--json")
    assert proc.returncode == 0, proc.stderr
    arm = json.loads(proc.stdout)["arm"]
    assert (tmp_path / "gen" / "motor" / "dc_motor_arm.elf").is_file()
    assert arm["flash_bytes"] == arm["text_bytes"] + arm["data_bytes"] > 0
    assert arm["ram_bytes"] == arm["data_bytes"] + arm["bss_bytes"]


def test_codegen_refuses_a_step_count_that_cannot_fit(run, tmp_path):
    proc = run("codegen", "dc_motor", "--dt", "1e-12", "--out", str(tmp_path / "c"))
    assert proc.returncode == 2 and "fixed steps" in proc.stderr
    assert not (tmp_path / "c").exists()


def test_c_harness_t_stop_inf_is_refused_not_undefined(run, tmp_path):
    """`--t-stop inf` made the harness convert an infinite step count to long (undefined
    behaviour); now it, a NaN and a run of more than 1e15 steps are usage errors (exit
    2), while a finite end time still runs: 0.01 s at dt 1e-4 is 100 steps + 1 row."""
    import subprocess
    import shutil
    if shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler")
    proc = run("codegen", "dc_motor", "--dt", "1e-4", "--t-stop", "0.05", "--out",
               str(tmp_path), "--check")
    assert proc.returncode == 0, proc.stderr
    exe = next(p for p in tmp_path.iterdir() if p.name.endswith("_run"))
    for value in ("inf", "-inf", "nan", "1e300", "infinity"):
        res = subprocess.run([str(exe), "--t-stop", value], capture_output=True, text=True,
                             timeout=30)
        assert res.returncode == 2 and "--t-stop" in res.stderr, (value, res.stderr)
        assert res.stdout == ""
    res = subprocess.run([str(exe), "--t-stop", "0.01"], capture_output=True, text=True,
                         timeout=30)
    assert res.returncode == 0 and len(res.stdout.splitlines()) == 1 + 101
