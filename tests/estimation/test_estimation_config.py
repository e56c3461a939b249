"""Problem files, `mechatron.estimation.config`: every problem of a file is found at once
and named by file, table and key; the examples are sound."""

from __future__ import annotations

from pathlib import Path

import pytest

from mechatron.cli import main
from mechatron.errors import DataError, ParameterError
from mechatron.estimation.config import check_config, load_config

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

BAD = """
title = "everything wrong at once"
colour = "blue"

[model]
name = "dc_motor"

[[experiments]]
name = "step"
file = "step.csv"
outputs = ["i", "w"]
hold = "cubic"
sigma = { i = -1, w = 0 }

[parameters]
R = { initial = 7.1, min = 10, max = 5 }
L = { initial = "1 mH", min = "2 mH", max = "5 mH" }
k = { initial = 0.15, mni = 0 }

[options]
substeps = 0

[sensitivity]
samples = 0
method = "sobel"
[sensitivity.distributions]
R = { kind = "uniform", low = 9, high = 5 }
J = { kind = "normal", mean = 1e-5, std = 0 }
B = { kind = "loguniform", low = 0, high = 1 }

[[requirements]]
type = "bound"
signal = "i"
lower = 3
upper = -3
"""


def test_every_problem_is_collected_and_named(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(BAD)
    with pytest.raises(DataError) as info:
        load_config(path)
    problems = info.value.problems
    assert all(p.startswith(f"{path}: ") for p in problems)
    expected = [
        "top level: unknown section(s) colour",
        "[[experiments]] 1 (step) hold: must be one of zoh, linear, got 'cubic'",
        "[[experiments]] 1 (step) sigma.i: must be > 0, got -1",
        "[[experiments]] 1 (step) sigma.w: must be > 0, got 0",
        "[parameters] R: the lower bound min = 10 is not below the upper bound max = 5",
        "[parameters] L: initial = '1 mH' is outside ['2 mH', '5 mH']",
        "[parameters] k: unknown key(s) mni",
        "[options] substeps: must be at least 1, got 0",
        "[sensitivity] samples: must be at least 2, got 0",
        "[sensitivity] method: must be one of random, lhs, sobol, got 'sobel'",
        "[sensitivity.distributions] R: low = 9 is not below high = 5",
        "[sensitivity.distributions] J.std: must be > 0, got 0",
        "[sensitivity.distributions] B.low: a loguniform distribution needs low > 0",
        "[[requirements]] 1 (bound): lower = 3 is not below upper = -3",
    ]
    for text in expected:
        assert any(text in p for p in problems), (text, problems)
    assert len(problems) == len(expected)
    assert str(info.value).startswith(f"{path}: {len(expected)} problem(s): ")


def test_the_example_files_are_sound():
    for path in sorted(EXAMPLES.glob("*.toml")):
        cfg = load_config(path)
        assert check_config(cfg, str(path)) == [], path


def test_units_are_compared_in_si_and_a_decimal_comma_is_reported():
    cfg = {"model": {"name": "dc_motor"},
           "parameters": {"L": {"initial": "300 uH", "min": "0.1 mH", "max": "1 mH"},
                          "R": {"initial": "7,1 ohm"}},
           "design": {"Kp": {"initial": 0.5, "min": 1, "max": 1}}}
    problems = check_config(cfg, "f.toml")
    assert len(problems) == 2, problems
    assert problems[0].startswith("f.toml: [parameters] R.initial: '7,1 ohm' has a comma")
    assert problems[1] == ("f.toml: [design] Kp: the lower bound min = 1 is not below the "
                           "upper bound max = 1")


def test_a_bad_file_is_one_line_and_exit_2(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text(BAD)
    for command in ("estimate", "sensitivity", "optimize"):
        code = main([command, str(path)])
        out, err = capsys.readouterr()
        assert code == 2 and out == "", command
        assert err.startswith(f"error: {path}: 14 problem(s): ")
        assert len(err.strip().splitlines()) == 1


def test_the_library_checks_sigma_substeps_and_samples_too():
    import numpy as np
    from mechatron.estimation import EstimationProblem
    from mechatron.estimation.data import Experiment
    from mechatron.estimation.sensitivity import Distribution, run_sensitivity
    t = np.linspace(0, 1, 5)
    with pytest.raises(DataError, match="sigma of 'y' is a noise level and must be > 0, "
                                        "got -1"):
        Experiment("run", t, outputs={"y": t}, sigma={"y": -1})
    with pytest.raises(ParameterError, match="substeps must be a whole number >= 1"):
        EstimationProblem(None, [], [], substeps=0)
    dists = {n: Distribution("uniform", 0, 1) for n in "abc"}
    with pytest.raises(ParameterError, match="give at least 5"):
        run_sensitivity(None, dists, n=0, method="lhs")
    with pytest.raises(ParameterError, match="give at least 3"):
        run_sensitivity(None, dists, n=2, method="sobol")


def test_unknown_toml_keys_name_the_nearest_valid_one():
    cfg = {"modle": {"name": "dc_motor"},
           "parameters": {"R": {"initial": 7.1, "mni": 0, "maxx": 9}},
           "options": {"substep": 4}}
    problems = check_config(cfg, "f.toml")
    text = "\n".join(problems)
    assert "unknown section(s) modle (did you mean model?)" in text
    assert "[parameters] R: unknown key(s) maxx (did you mean max?), mni (did you mean " \
           "min?)" in text
    assert "[options]: unknown key(s) substep (did you mean substeps?)" in text


def test_substeps_1e5_is_limited():
    """substeps = 1e5 wrote 80 MB of C; the file check and the library refuse more than
    MAX_SUBSTEPS."""
    from mechatron.estimation import EstimationProblem
    from mechatron.estimation.problem import MAX_SUBSTEPS
    cfg = {"model": {"name": "dc_motor"}, "options": {"substeps": 100000}}
    assert any(f"[options] substeps: must be at most {MAX_SUBSTEPS}, got 100000" in p
               for p in check_config(cfg, "f.toml"))
    with pytest.raises(ParameterError, match="substeps = 100000 per sample is more than"):
        EstimationProblem(None, [], [], substeps=100000)
