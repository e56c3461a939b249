"""``import mechatron`` loads the modeling language only (issue 17, part 5): the heavy
dependencies and the applications are imported when first used, and every public name
still resolves. The timing itself is in ``bench/bench_import.py``."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

SRC = str(Path(__file__).resolve().parents[1] / "src")

HEAVY = ["matplotlib", "pandas", "pyarrow", "scipy", "pint",
         "mechatron.compiler", "mechatron.solvers", "mechatron.library.electrical",
         "mechatron.models.dc_motor", "mechatron.codegen", "mechatron.estimation",
         "mechatron.realtime", "mechatron.report", "mechatron.viz"]


def _run(code: str) -> dict:
    env = dict(os.environ, PYTHONPATH=SRC + os.pathsep + os.environ.get("PYTHONPATH", ""))
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_import_mechatron_does_not_load_heavy_modules():
    loaded = _run("import json, sys, mechatron\n"
                  f"print(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))")
    assert loaded == []


def test_public_names_resolve_on_first_use():
    code = """
import json, sys
import mechatron as mt
from mechatron import compile_model, simulate, library, models
out = {
    "resistor": mt.library.electrical.Resistor.__name__,
    "inertia": mt.library.rotational.Inertia.__name__,
    "entry": mt.models.get("dc_motor").name,
    "listed": "dc_motor_speed_pi" in [e.name for e in mt.models.list()],
    "simulate": mt.simulate is simulate and simulate.__module__,
    "compiled": mt.CompiledModel.__name__,
    "compile": compile_model is mt.compile_model,
    "submodules": [type(getattr(mt, n)).__name__ for n in ("codegen", "units", "results")],
    "all": sorted(n for n in mt.__all__ if not hasattr(mt, n)),
    "dir": {"simulate", "library", "compile_model"} <= set(dir(mt)),
    "lib_dir": {"electrical", "multibody"} <= set(dir(mt.library)),
}
print(json.dumps(out))
"""
    out = _run(code)
    assert out == {"resistor": "Resistor", "inertia": "Inertia", "entry": "dc_motor",
                   "listed": True, "simulate": "mechatron.solvers.simulate",
                   "compiled": "CompiledModel", "compile": True,
                   "submodules": ["module", "module", "module"], "all": [],
                   "dir": True, "lib_dir": True}


def test_unknown_attribute_is_an_attribute_error():
    out = _run("import json, mechatron as mt\n"
               "try:\n    mt.no_such_name\nexcept AttributeError as e:\n"
               "    print(json.dumps(str(e)))")
    assert "no_such_name" in out


def test_a_saved_model_loads_and_runs_without_the_compiler_or_pint(tmp_path):
    """Loading a compiled model and simulating it need neither the compiler's passes nor
    the unit registry (pint); the compiler is imported by compiling."""
    path = tmp_path / "rc.mtm"
    _run(f"""
import json
import mechatron as mt
from mechatron.library import electrical as el
m = mt.System("rc")
src, r = m.add("src", el.DCVoltageSource(V=1.0)), m.add("r", el.Resistor(R=1e3))
c, g = m.add("c", el.Capacitor(C=1e-6)), m.add("g", el.ElectricalReference())
m.connect(src.p, r.p); m.connect(r.n, c.p); m.connect(src.n, c.n, g.port)
mt.compile_model(m).save({str(path)!r})
print(json.dumps(0))
""")
    out = _run(f"""
import json, sys
import mechatron as mt
cm = mt.CompiledModel.load({str(path)!r})
res = mt.simulate(cm, 5e-3)
print(json.dumps({{"v": float(res["c.v"][-1]), "i": float(res["r.i"][-1]),
                  "loaded": [m for m in ("pint", "mechatron.compiler.flatten",
                                         "mechatron.compiler.pipeline") if m in sys.modules]}}))
""")
    tau = 1e3 * 1e-6
    assert abs(out["v"] - (1 - np.exp(-5e-3 / tau))) < 1e-5
    assert abs(out["i"] - np.exp(-5e-3 / tau) / 1e3) < 1e-8
    assert out["loaded"] == []


def test_the_command_line_parser_imports_no_compiler_pass():
    """Every command's parser is built on each call of ``mechatron``: building it must
    import neither the compiler's passes nor the library and its unit registry (a few
    tenths of a second each, before any work)."""
    loaded = _run("import json, sys\n"
                  "from mechatron.cli import build_parser\n"
                  "build_parser()\n"
                  "print(json.dumps([m for m in ('mechatron.compiler.flatten', "
                  "'mechatron.compiler.pipeline', 'mechatron.report.diagram', "
                  "'mechatron.library.blocks', 'pint') if m in sys.modules]))")
    assert loaded == []
