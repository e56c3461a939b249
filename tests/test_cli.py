"""Tests of the ``mechatron`` command, `mechatron.cli`: each command's output and files,
checked against the physics of the DC motor, and every user error as one line, exit 2."""

from __future__ import annotations

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mechatron as mt
from mechatron.cli import DEMO_STEPS, main

SRC = Path(__file__).resolve().parents[1] / "src"

ENTRY = mt.models.get("dc_motor")
P = ENTRY.values()
W_FINAL = P["k"] * P["V"] / (P["R"] * P["B"] + P["k"] ** 2)   # analytic final speed


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def run_json(capsys, *argv: str) -> dict:
    code, out, err = run(capsys, *argv, "--json")
    assert code == 0, err
    return json.loads(out)


# ---------------------------------------------------------------------------- models, show
def test_models_json_lists_dc_motor(capsys):
    data = run_json(capsys, "models")
    names = [m["name"] for m in data["models"]]
    assert "dc_motor" in names
    motor = data["models"][names.index("dc_motor")]
    assert motor["variants"] == ["acausal", "ode", "blocks", "inputs"]
    assert motor["description"]


def test_models_human_and_tag_filter(capsys):
    code, out, _ = run(capsys, "models", "--tag", "motor")
    assert code == 0
    assert "dc_motor" in out and "acausal, ode" in out


def test_models_unknown_tag_is_an_error(capsys):
    code, out, err = run(capsys, "models", "--tag", "no-such-tag")
    assert code == 2 and out == ""
    assert err.startswith("error: --tag no-such-tag") and "motor" in err


def test_show_lists_parameters_variants_outputs(capsys):
    code, out, _ = run(capsys, "show", "dc_motor")
    assert code == 0
    for text in ("Armature inductance", "0.0003408", "seed table 6-1", "acausal (default)",
                 "inertia.w", "inductor.i", "t_stop 0.5 s", "rtol 1e-08", "122.4398781"):
        assert text in out


def test_show_json(capsys):
    data = run_json(capsys, "show", "dc_motor")
    assert data["parameters"]["L"] == {"default": 3.408e-4, "unit": "H",
                                       "description": "Armature inductance",
                                       "source": "seed table 6-1, calculated"}
    assert data["outputs"]["w"] == {"unit": "rad/s",
                                    "paths": {"acausal": "inertia.w", "ode": "w",
                                              "blocks": "speed.y",
                                              "inputs": "inertia.w"}}
    assert data["experiment"]["t_stop"] == 0.5
    assert data["expected"]["w"] == pytest.approx(W_FINAL, rel=1e-12)


# ------------------------------------------------------------------------------- simulate
@pytest.mark.parametrize("variant", ["acausal", "ode"])
def test_simulate_json_final_speed_is_analytic(capsys, variant):
    data = run_json(capsys, "simulate", "dc_motor", "--variant", variant)
    assert data["model"] == "dc_motor" and data["variant"] == variant
    assert data["t_stop"] == 0.5 and data["solver"] == ENTRY.experiment.solver
    assert data["outputs"] == ENTRY.outputs[variant]
    assert data["final"]["w"] == pytest.approx(W_FINAL, rel=1e-5)
    stats = data["stats"]
    assert stats["steps"] > 0 and stats["rhs_evals"] >= stats["steps"]
    assert stats["compile_time"] > 0
    assert data["files"] == {}


def test_simulate_human_summary(capsys):
    code, out, err = run(capsys, "simulate", "dc_motor")
    assert code == 0, err
    assert "122.4398781" in out and "rad/s" in out
    for word in ("steps", "rejected", "rhs evals", "jac evals", "events", "wall time",
                 "compile time"):
        assert word in out


def test_set_with_unit_changes_the_parameter(capsys):
    # L only shapes the transient: with a shorter horizon w(t) depends on it. R changes
    # the steady state: w_final = k V / (R B + k^2).
    base = run_json(capsys, "simulate", "dc_motor", "--t-stop", "2e-4")
    big_l = run_json(capsys, "simulate", "dc_motor", "--t-stop", "2e-4",
                     "--set", "L=3408 uH")
    assert big_l["parameters"]["L"] == pytest.approx(3.408e-3, rel=1e-12)
    assert big_l["set"] == {"L": "3408 uH"}
    assert big_l["final"]["i"] < 0.5 * base["final"]["i"]   # 10x L: current rises slower

    data = run_json(capsys, "simulate", "dc_motor", "--set", "L=340 uH", "--set", "R=7.5")
    assert data["parameters"]["L"] == pytest.approx(3.4e-4, rel=1e-12)
    assert data["parameters"]["R"] == 7.5
    w_final = P["k"] * P["V"] / (7.5 * P["B"] + P["k"] ** 2)
    assert data["final"]["w"] == pytest.approx(w_final, rel=1e-5)
    assert data["expected"] == {}   # reference values hold for the default run only


def test_out_csv_has_t_then_paths(capsys, tmp_path):
    path = tmp_path / "log.csv"
    data = run_json(capsys, "simulate", "dc_motor", "--variant", "ode", "--out", str(path))
    assert data["files"] == {"out": str(path)}
    with open(path, newline="") as fh:
        header = next(csv.reader(fh))
    assert header[0] == "t" and set(header[1:]) == {"i", "w"}
    table = np.loadtxt(path, delimiter=",", skiprows=1)
    assert table[0, 0] == 0.0 and table[-1, 0] == pytest.approx(0.5)
    assert table[-1, header.index("w")] == pytest.approx(W_FINAL, rel=1e-5)


def test_out_parquet_round_trips(capsys, tmp_path):
    path = tmp_path / "log.parquet"
    data = run_json(capsys, "simulate", "dc_motor", "--out", str(path))
    res = mt.SimResult.load(path)
    assert res.final("inertia.w") == data["final"]["w"]
    assert res.units["inertia.w"] == "rad/s"


def test_plot_writes_png(capsys, tmp_path):
    path = tmp_path / "motor.png"
    code, out, err = run(capsys, "simulate", "dc_motor", "--plot", str(path))
    assert code == 0, err
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert str(path) in out


def test_fixed_step_solver(capsys):
    data = run_json(capsys, "simulate", "dc_motor", "--variant", "ode", "--solver", "rk4",
                    "--dt", "1e-5", "--t-stop", "0.05")
    assert data["dt"] == 1e-5 and data["stats"]["solver"] == "rk4"
    assert data["stats"]["steps"] == 5000
    assert data["final"]["w"] == pytest.approx(W_FINAL, rel=1e-4)


# -------------------------------------------------------------------------- user errors
@pytest.mark.parametrize("argv, names", [
    (["simulate", "no_such_model"], ["no_such_model"]),
    (["show", "dc_moter"], ["dc_moter", "dc_motor"]),
    (["simulate", "dc_motor", "--set", "R=3 kg"], ["R", "3 kg"]),
    (["simulate", "dc_motor", "--set", "Q=3"], ["Q"]),
    (["simulate", "dc_motor", "--set", "r=3"], ["r", "Did you mean R?"]),
    (["simulate", "dc_motor", "--set", "R=-5"], ["R", "-5"]),
    (["simulate", "dc_motor", "--variant", "ode", "--set", "R=-5"], ["R", "-5"]),
    (["simulate", "dc_motor", "--set", "R"], ["R", "NAME=VALUE"]),
    (["simulate", "dc_motor", "--set", "R=nan"], ["R", "nan"]),
    (["simulate", "dc_motor", "--variant", "bond_graph"], ["bond_graph", "acausal"]),
    (["simulate", "dc_motor", "--solver", "rk4"], ["rk4", "--dt"]),
    (["simulate", "dc_motor", "--dt", "1e-3"], ["--dt"]),
    (["simulate", "dc_motor", "--solver", "magic"], ["magic"]),
    (["simulate", "dc_motor", "--t-stop", "-1"], ["t_stop"]),
    (["simulate", "dc_motor", "--out", "log.txt"], ["--out", ".txt"]),
    (["simulate", "dc_motor", "--out", "no/such/dir/log.csv"], ["--out", "no/such/dir"]),
])
def test_user_error_is_one_line_exit_2(capsys, argv, names):
    code, out, err = run(capsys, *argv)
    assert code == 2
    assert out == ""
    assert err.startswith("error: ") and err.count("\n") == 1
    assert "Traceback" not in err
    for name in names:
        assert name in err


def test_argparse_errors_exit_2(capsys):
    assert run(capsys, "no-such-command")[0] == 2
    assert run(capsys, "simulate", "dc_motor", "--t-stop", "soon")[0] == 2
    assert run(capsys)[0] == 2


def test_unexpected_error_exit_1_without_traceback(capsys, monkeypatch):
    def broken(name):
        raise RuntimeError("disk on fire")

    monkeypatch.setattr(mt.models, "get", broken)
    monkeypatch.delenv("MECHATRON_DEBUG", raising=False)
    code, _, err = run(capsys, "show", "dc_motor")
    assert code == 1
    assert err.startswith("error: unexpected RuntimeError: disk on fire")
    assert "Traceback" not in err

    monkeypatch.setenv("MECHATRON_DEBUG", "1")
    code, _, err = run(capsys, "show", "dc_motor")
    assert code == 1 and "Traceback" in err


def test_help_of_every_command(capsys):
    for argv in ([], ["models"], ["show"], ["simulate"], ["compare"], ["demo"]):
        code, out, _ = run(capsys, *argv, "--help")
        assert code == 0 and out.startswith("usage: mechatron")


def test_module_help_in_subprocess():
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(SRC), *filter(None, [os.environ.get("PYTHONPATH")])]))
    proc = subprocess.run([sys.executable, "-m", "mechatron.cli", "--help"], env=env,
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    for command in ("models", "show", "simulate", "compare", "demo"):
        assert command in proc.stdout


# -------------------------------------------------------------------------------- compare
def test_compare_variants_agree(capsys, tmp_path):
    path = tmp_path / "compare.png"
    code, out, err = run(capsys, "compare", "dc_motor", "--out", str(path))
    assert code == 0, err
    assert "ode" in out and "acausal" in out
    section = out.split("largest deviation")[1].split("\n\n")[0]
    rows = [line.split() for line in section.splitlines() if line.split()[:1] == ["ode"]]
    assert {r[1] for r in rows} == {"w", "i"}
    assert all(float(r[-1]) < 1e-6 for r in rows)            # max relative deviation
    assert path.read_bytes()[:4] == b"\x89PNG"


def test_compare_json(capsys):
    data = run_json(capsys, "compare", "dc_motor")
    assert data["reference"] == "acausal"
    assert data["variants"] == ["acausal", "ode", "blocks", "inputs"]
    assert data["points"] == 1001
    for variant in ("ode", "blocks"):
        for label in ("w", "i"):
            assert data["deviations"][variant][label]["max_rel"] < 1e-6
        assert data["final"][variant]["w"] == pytest.approx(W_FINAL, rel=1e-5)


# ----------------------------------------------------------------------------------- demo
def test_demo_writes_plots_and_logs(capsys, tmp_path):
    out_dir = tmp_path / "demo"
    code, out, err = run(capsys, "demo", "--out", str(out_dir))
    assert code == 0, out + err
    assert f"{len(DEMO_STEPS)}/{len(DEMO_STEPS)}" in out
    assert "checks passed" in out and "FAILED" not in out
    pngs = sorted(out_dir.glob("*.png"))
    csvs = sorted(out_dir.glob("*.csv"))
    assert pngs and csvs
    assert all(p.read_bytes()[:4] == b"\x89PNG" for p in pngs)
    log = mt.SimResult.load(out_dir / "dc_motor_acausal.csv")
    assert log.final("inertia.w") == pytest.approx(W_FINAL, rel=1e-8)


# ------------------------------------------------------------------ silently wrong values
@pytest.mark.parametrize("value", ["R=7,1 ohm", "R=7,1"])
def test_set_with_a_decimal_comma_is_an_error_not_71_ohm(capsys, value):
    code, out, err = run(capsys, "simulate", "dc_motor", "--set", value)
    assert code == 2 and out == ""
    assert err.startswith("error: --set R: ") and "comma" in err and "'7.1" in err
    assert len(err.strip().splitlines()) == 1


def test_input_with_a_decimal_comma_is_an_error(capsys):
    code, out, err = run(capsys, "simulate", "dc_motor", "--input", "u=3,5 V")
    assert code == 2 and err.startswith("error: --input u: ") and "comma" in err


# ---------------------------------------------------------------- crashes made clear errors
def _one_line_exit_2(code, out, err):
    assert code == 2 and out == ""
    assert err.startswith("error: ") and err.count("\n") == 1 and "unexpected" not in err


@pytest.mark.parametrize("text, what", [("", "an empty file"),
                                        ("t,u\n", "a header and no rows")])
def test_empty_input_csv_is_a_clear_error(capsys, tmp_path, text, what):
    path = tmp_path / "u.csv"
    path.write_text(text)
    code, out, err = run(capsys, "simulate", "dc_motor", "--input", f"u={path}")
    _one_line_exit_2(code, out, err)
    assert f"--input u={path}: {what}" in err


def test_a_tiny_fixed_step_is_refused_before_memory_runs_out(capsys):
    code, out, err = run(capsys, "simulate", "dc_motor", "--solver", "rk4", "--dt", "1e-12")
    _one_line_exit_2(code, out, err)
    # 0.5 s (the experiment) / 1e-12 s = 5e11 steps
    assert "--dt 1e-12 s with t_stop 0.5 s: 5e+11 fixed steps" in err
    assert "at least 5e-08 s" in err
    code, out, err = run(capsys, "simulate", "dc_motor", "--solver", "rk4", "--dt", "1e-7",
                         "--t-stop", "2")
    _one_line_exit_2(code, out, err)
    assert "2e+07 fixed steps" in err


def test_simulate_out_interrupted_keeps_the_previous_log(capsys, tmp_path, monkeypatch):
    path = tmp_path / "run.csv"
    code, _, err = run(capsys, "simulate", "dc_motor", "--out", str(path))
    assert code == 0, err
    before = path.read_bytes()

    def interrupted(fh, *args, **kwargs):
        fh.write("0,1,2\n")                     # half a table, then Ctrl-C
        raise KeyboardInterrupt
    monkeypatch.setattr(np, "savetxt", interrupted)
    code, _, err = run(capsys, "simulate", "dc_motor", "--set", "V=12", "--out", str(path))
    assert code == 130 and err == "error: interrupted.\n"
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.csv"]


# ---------------------------------------------------------------------------------- logging
def test_verbose_shows_what_is_written_and_warnings_show_without_it(capsys, tmp_path,
                                                                     monkeypatch):
    import logging
    from mechatron import cli
    path = tmp_path / "run.csv"
    for argv in (["-v", "simulate", "dc_motor", "--out", str(path)],
                 ["simulate", "dc_motor", "--out", str(path), "--verbose"]):
        code, out, err = run(capsys, *argv)
        assert code == 0 and f"wrote {path}" in err.splitlines()
    code, out, err = run(capsys, "simulate", "dc_motor", "--out", str(path))
    assert code == 0 and err == ""          # quiet by default

    def models(args):                       # a command whose library code logs
        logger = logging.getLogger("mechatron.somewhere")
        logger.warning("something to know")
        logger.info("what it does")
        logger.debug("details")
        return 0
    monkeypatch.setattr(cli, "cmd_models", models)
    assert run(capsys, "models")[2] == "warning: something to know\n"
    assert run(capsys, "-v", "models")[2] == "warning: something to know\nwhat it does\n"
    assert run(capsys, "models", "-vv")[2] == ("warning: something to know\nwhat it does\n"
                                               "debug: details\n")
    # the handler is removed after each command
    assert not any(type(h).__name__ == "_StderrHandler"
                   for h in logging.getLogger("mechatron").handlers)


def test_a_full_disk_is_a_one_line_error_naming_the_file(capsys, tmp_path, monkeypatch):
    import errno
    path = tmp_path / "run.csv"

    def full(fh, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr(np, "savetxt", full)
    code, out, err = run(capsys, "simulate", "dc_motor", "--out", str(path))
    assert code == 2 and out == ""
    assert err == f"error: [Errno 28] No space left on device: '{path}'\n"
    assert list(tmp_path.iterdir()) == []


def test_a_fixed_step_run_over_the_memory_limit_needs_force(capsys, monkeypatch):
    from mechatron import cli
    monkeypatch.setattr(cli, "MAX_MEMORY", 1e4)            # 10 kB: 0.01 s at 1e-5 s is more
    code, out, err = run(capsys, "simulate", "dc_motor", "--solver", "rk4", "--dt", "1e-5",
                         "--t-stop", "0.01")
    _one_line_exit_2(code, out, err)
    assert "1e+03 fixed steps" in err and "--force" in err
    data = run_json(capsys, "simulate", "dc_motor", "--solver", "rk4", "--dt", "1e-5",
                    "--t-stop", "0.01", "--force")
    assert data["stats"]["steps"] == 1000


def test_usage_errors_are_one_line_too(capsys):
    code, out, err = run(capsys, "simulate", "--t-stop", "soon")
    assert code == 2 and out == ""
    assert err == ("error: mechatron simulate: the following arguments are required: NAME; "
                   "see `mechatron simulate --help`.\n") or (
        err.startswith("error: mechatron simulate: argument --t-stop: invalid float value")
        and err.count("\n") == 1)


# ---------------------------------------------------------------------------- interruption
def _mechatron_leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if "mechatron" in p.name.lower())


@pytest.mark.skipif(not hasattr(os, "killpg") or __import__("shutil").which("cc") is None,
                    reason="POSIX signals and a C compiler (cc) needed")
@pytest.mark.parametrize("phase", ["build", "run"])
def test_temporary_build_folders_are_left_behind_after_interrupted_runs(tmp_path, phase):
    """SIGTERM (what `timeout` sends) during `mechatron hil`'s C build or its run: the
    command unwinds like Ctrl-C (child processes stopped, no traceback, exit 143) and
    leaves no mechatron folder in TMPDIR."""
    import signal
    import time
    tmpdir = tmp_path / "tmp"
    tmpdir.mkdir()
    env = dict(os.environ, PYTHONPATH=str(SRC), TMPDIR=str(tmpdir))
    env.pop("MECHATRON_DEBUG", None)
    # a long lockstep run over UDP: a temporary build folder, two child processes
    proc = subprocess.Popen([sys.executable, "-m", "mechatron", "hil", "speed",
                             "--mode", "sil", "--transport", "udp", "--lockstep",
                             "--duration", "100", "--rate", "1000"],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    try:
        # wait (polling, no timing asserted) for the phase to interrupt
        want = "mt_plant" if phase == "run" else None
        for _ in range(1200):
            folders = [p for p in tmpdir.glob("mechatron-hil-*") if p.is_dir()]
            if folders and (want is None or (folders[0] / want).exists()):
                break
            assert proc.poll() is None, proc.stderr.read()
            time.sleep(0.05)
        else:
            pytest.fail("the hil build folder never appeared")
        if phase == "run":
            time.sleep(1.0)               # let the plant and the controller start
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 143, err
    assert "Traceback" not in err
    assert err.strip().splitlines()[-1].startswith("error: terminated")
    assert _mechatron_leftovers(tmpdir) == []


def test_sigterm_handler_is_restored_after_the_command(capsys):
    import signal
    before = signal.getsignal(signal.SIGTERM)
    assert main(["models"]) == 0
    assert signal.getsignal(signal.SIGTERM) == before


# ------------------------------------------------------------------------ plot labelling
@pytest.mark.parametrize("argv", [
    ["simulate", "dc_motor", "--plot", "{d}/sim.png"],
    ["compare", "dc_motor", "--out", "{d}/compare.png"],
    ["demo", "--out", "{d}/demo"],
    ["report", "dc_motor", "--out", "{d}/report.html"],
    ["linearize", "dc_motor", "--input", "source.V", "--output", "inertia.w", "--trim",
     "inertia.w=100", "--free", "source.V", "--bode", "{d}/bode.png"],
], ids=["simulate", "compare", "demo", "report", "bode"])
def test_some_plots_lack_quantity_names_and_units(capsys, tmp_path, saved_figures, argv):
    """Every figure a command writes labels each axis with a quantity and its unit, and
    names each labelled curve in a legend (checked on the Figure as it is saved)."""
    code, out, err = run(capsys, *[a.format(d=tmp_path) for a in argv])
    assert code == 0, out + err
    assert saved_figures, "the command saved no figure"
    assert saved_figures.problems() == []


def test_an_interrupt_inside_a_c_extension_still_exits_as_interrupted(monkeypatch, capsys):
    """SIGTERM arriving while CasADi converts a matrix surfaces as a SystemError whose
    context is the interrupt: the command still exits 143 (130 for Ctrl-C), not as a bug."""
    from mechatron import cli

    def command(kind):
        def run(args):
            try:
                raise kind()
            except kind as stop:
                raise SystemError("<function DM.__array__> returned a result with an "
                                  "exception set") from stop
        return run

    for kind, code, said in ((cli.Terminated, 143, "terminated"),
                             (KeyboardInterrupt, 130, "interrupted")):
        args = type("Args", (), {"func": staticmethod(command(kind)), "verbose": 0,
                                 "verbose_command": 0})()
        monkeypatch.setattr(cli, "build_parser", lambda: type(
            "Parser", (), {"parse_args": lambda self, argv: args})())
        assert cli.main([]) == code
        err = capsys.readouterr().err
        assert said in err and "bug" not in err
