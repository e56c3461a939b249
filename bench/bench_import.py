"""``import mechatron``: seconds and modules, beside the import of CasADi alone (its floor:
the modeling language builds CasADi expressions) and an eager import of what
``import mechatron`` loaded before issue 17 (compiler, solvers, every library domain, the
model database, pint's registry).

Each figure is the best of several fresh interpreters (``--quick``: 3, else 9), timed in
turns, from the first import statement to its end (interpreter start-up excluded). The
number of modules is ``len(sys.modules)`` after the import minus that of an empty
interpreter. Goal (issue 17): ``import mechatron`` under 0.3 s.

Run: ``python bench/bench_import.py [--quick]``; prints one JSON document.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import _common  # noqa: F401  (import path)
from _common import ROOT, log, main

GOAL_S = 0.3
HEAVY = ("matplotlib", "pandas", "pyarrow", "scipy", "pint")

#: What is imported, per case.
CASES = {
    "mechatron": "import mechatron",
    "casadi": "import casadi",
    "mechatron_eager": ("import mechatron, mechatron.units\n"
                        "mechatron.units.ureg\n"
                        "import mechatron.compiler, mechatron.solvers, mechatron.library\n"
                        "for name in mechatron.library.__all__:\n"
                        "    getattr(mechatron.library, name)\n"
                        "import mechatron.models.dc_motor_control"),
}

_PROBE = """
import json, sys, time
before = len(sys.modules)
start = time.perf_counter()
exec(compile({code!r}, "<bench>", "exec"))
seconds = time.perf_counter() - start
print(json.dumps({{"seconds": seconds, "modules": len(sys.modules) - before,
                   "heavy": [m for m in {heavy!r} if m in sys.modules]}}))
"""


def measure(code: str) -> dict:
    """One fresh interpreter: seconds, modules added and heavy modules loaded by ``code``."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT / "src"),
                                                    env.get("PYTHONPATH")) if p)
    out = subprocess.run([sys.executable, "-c", _PROBE.format(code=code, heavy=HEAVY)],
                         capture_output=True, text=True, check=True, env=env, timeout=300)
    return json.loads(out.stdout.strip().splitlines()[-1])


def run(quick: bool = False, tiny: bool = False) -> dict:
    """Seconds and modules of ``import mechatron``, ``import casadi`` and an eager import."""
    repeats = 1 if tiny else 3 if quick else 9
    runs = {name: [] for name in CASES}
    for _ in range(repeats):
        for name, code in CASES.items():
            runs[name].append(measure(code))
    out = {}
    for name, rows in runs.items():
        best = min(rows, key=lambda r: r["seconds"])
        out[name] = {"best_s": best["seconds"], "all_s": [r["seconds"] for r in rows],
                     "modules": best["modules"], "heavy_loaded": best["heavy"]}
        log(f"import {name}: best {best['seconds']:.3f} s, {best['modules']} modules")
    mech = out["mechatron"]["best_s"]
    return {"cases": out, "import_mechatron_s": mech, "goal_s": GOAL_S,
            "goal_met": mech < GOAL_S,
            "ratio_mechatron_over_casadi": mech / out["casadi"]["best_s"],
            "ratio_eager_over_mechatron": out["mechatron_eager"]["best_s"] / mech,
            "repeats": repeats,
            "notes": ["best of fresh interpreters timed in turns; start-up excluded.",
                      "mechatron_eager: what `import mechatron` loaded before issue 17."]}


if __name__ == "__main__":
    main(run)
