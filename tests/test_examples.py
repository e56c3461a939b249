"""Every script in examples/ runs, and the user-written motor matches the database's."""

import runpy
import subprocess
import sys
from pathlib import Path

import pytest

import mechatron as mt

EXAMPLES = sorted((Path(__file__).parents[1] / "examples").glob("*.py"))


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_example_runs(path):
    src = Path(__file__).parents[1] / "src"
    out = subprocess.run([sys.executable, str(path)], capture_output=True, text=True,
                         env={"PYTHONPATH": str(src), "PATH": "/usr/bin:/bin"}, timeout=120)
    assert out.returncode == 0, out.stderr


def test_user_written_motor_matches_the_dc_motor_entry():
    ns = runpy.run_path(str(Path(__file__).parents[1] / "examples" / "user_component.py"))
    res = mt.simulate(ns["build"](), 0.5, rtol=1e-10, atol=1e-12)
    ref = mt.simulate(mt.models.get("dc_motor").build("ode"), 0.5, rtol=1e-10, atol=1e-12)
    assert res.final("load.w") == pytest.approx(ref.final("w"), rel=1e-8)
    assert res.final("motor.i") == pytest.approx(ref.final("i"), rel=1e-8)
