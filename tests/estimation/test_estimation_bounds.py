"""Results on a bound, `mechatron.estimation.bounds`: flagged, not reported as an
interior optimum."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mechatron.estimation.bounds import at_bounds, describe_at_bounds


def test_values_on_a_finite_bound_are_found():
    hits = at_bounds(["Kp", "Ki", "Kd", "T"], [1.0, 0.0, 0.5, 3.0],
                     [1e-4, 0.0, 0.0, -math.inf], [1.0, 200.0, 1.0, math.inf],
                     scales=[None, 5.0, None, None])
    assert hits == {"Kp": {"side": "max", "bound": 1.0}, "Ki": {"side": "min", "bound": 0.0}}
    # a value a little inside is not on the bound
    assert at_bounds(["Kp"], [1.0 - 1e-4], [0.0], [1.0]) == {}
    text = describe_at_bounds(hits, "gain")
    assert text.startswith("Kp at its upper bound 1; Ki at its lower bound 0: the bound "
                           "decided the gain")
    assert describe_at_bounds({}) == ""


def test_a_gain_limited_by_its_bound_is_flagged_in_result_and_report(tmp_path, capsys):
    """The speed PI of the examples with Kp capped at 0.01: the optimum (Kp about 0.1,
    see test_estimation_optimize) lies beyond the cap, so SLSQP stops on it."""
    from mechatron.cli import main
    from mechatron.estimation.optimize import (DesignVariable, ResponseProblem,
                                               StepResponse, optimize_response)
    from mechatron.models.dc_motor_control import DCMotorSpeedPIVoltage
    design = [DesignVariable("Kp", 0.005, 1e-4, 0.01), DesignVariable("Ki", 5.0, 0.0, 200.0)]
    reqs = [StepResponse("w", 100.0, rise_time=0.01, overshoot_pct=5, settling_time=0.025)]
    prob = ResponseProblem(DCMotorSpeedPIVoltage(), design, reqs, t_stop=0.05,
                           n_points=501)
    res = optimize_response(prob, max_iterations=30)
    assert res.values[0] == pytest.approx(0.01, rel=1e-9)
    assert res.at_bound["Kp"] == {"side": "max", "bound": 0.01}
    assert "Ki" not in res.at_bound
    assert res.to_dict()["at_bound"] == res.at_bound

    cfg = tmp_path / "capped.toml"
    # [model] name takes database names only; the class comes in through a model file
    (tmp_path / "rig.py").write_text(
        "from mechatron.models.dc_motor_control import DCMotorSpeedPIVoltage\n")
    cfg.write_text("""
[model]
file = "rig.py"
class = "DCMotorSpeedPIVoltage"
[simulation]
t_stop = 0.05
points = 501
[design]
Kp = { initial = 0.005, min = 1e-4, max = 0.01 }
Ki = { initial = 5.0, min = 0.0, max = 200.0 }
[[requirements]]
type = "step"
signal = "w"
final = 100.0
rise_time = 0.01
overshoot = 5.0
settling_time = 0.025
""")
    code = main(["optimize", str(cfg), "--quiet", "--max-iterations", "30"])
    out, err = capsys.readouterr()
    row = next(line for line in out.splitlines() if line.strip().startswith("Kp"))
    assert "AT UPPER BOUND 0.01" in row
    assert "Kp at its upper bound 0.01" in err           # the logged warning
    assert code in (0, 1)


def test_free_parameters_and_design_variables_check_their_bounds():
    from mechatron.errors import ParameterError
    from mechatron.estimation import FreeParameter
    from mechatron.estimation.optimize import DesignVariable
    for cls, kind in ((FreeParameter, "free parameter"), (DesignVariable, "design variable")):
        with pytest.raises(ParameterError, match=rf"{kind} 'R': the lower bound min = 10 is "
                                                 r"not below the upper bound max = 5\."):
            cls("R", 7.0, 10.0, 5.0)
        with pytest.raises(ParameterError, match=rf"{kind} 'R': starting value 20 is outside "
                                                 r"\[0, 10\]"):
            cls("R", 20.0, 0.0, 10.0)
        with pytest.raises(ParameterError, match="'R': scale must be > 0, got 0"):
            cls("R", 1.0, scale=0.0)
        with pytest.raises(ParameterError, match="'R': min must be a number, got nan"):
            cls("R", 1.0, math.nan)
        assert cls("R", 7.0, 0.0).max == math.inf


def test_optimizer_flags_the_active_constraint(tmp_path, capsys):
    """The speed PI of the example is limited by the armature current: the fastest step
    the +-3 A bound allows. The result names that bound as active (the optimum sits on
    it), and an independent simulation of the optimized gains peaks at 3 A; the step
    envelope keeps slack and is not named."""
    import json
    import shutil
    from pathlib import Path
    from mechatron.cli import main
    examples = Path(__file__).resolve().parents[2] / "examples"
    cfg = tmp_path / "pi.toml"
    shutil.copy(examples / "dc_motor_speed_pi_optimize.toml", cfg)
    shutil.copy(examples / "rigs.py", tmp_path / "rigs.py")     # the file's own model
    code = main(["optimize", str(cfg), "--json", "--quiet"])
    out, err = capsys.readouterr()
    assert code == 0, err
    doc = json.loads(out)
    assert doc["active"] == ["i bound"]
    peak = next(r for r in doc["requirements"] if r["requirement"] == "max i")
    assert peak["value"] == pytest.approx(3.0, rel=5e-3)
    code = main(["optimize", str(cfg), "--quiet"])
    out, _ = capsys.readouterr()
    assert "active constraints (they decide the optimum): i bound" in out


def test_identifiability_flags_by_rule():
    """The three rules of estimation.problem.identifiability on a made-up Jacobian:
    a zero column (the outputs do not depend on c), an estimate of exactly 0 (d; not
    when it sits on its bound, reported there), a std above the estimate (b; only
    for a converged fit)."""
    from mechatron.estimation.problem import identifiability
    J = np.array([[1.0, 0.5, 0.0, 2.0], [0.0, 1.0, 0.0, 1.0]])
    theta = np.array([1.0, 0.1, 3.0, 0.0])
    std = np.array([0.1, 0.2, np.inf, 0.01])
    flags = identifiability(list("abcd"), theta, J, std)
    assert set(flags) == {"b", "c", "d"}
    assert flags["c"].startswith("is not identifiable")
    assert flags["d"].startswith("is estimated as exactly 0")
    assert flags["b"].startswith("is poorly identifiable: standard deviation 0.2 is more "
                                 "than 100% of the estimate 0.1")
    assert set(identifiability(list("abcd"), theta, J, std, converged=False,
                               on_bound={"d": {}})) == {"c"}
