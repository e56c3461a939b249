"""Shared helpers of the benchmarks: import path, clocks, environment, JSON output.

Benchmarks print timings; they never assert them. Progress goes to stderr so that stdout
holds one JSON document only.
"""

from __future__ import annotations

import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def ensure_importable() -> None:
    """Make ``import mechatron`` work from a checkout without installing it."""
    try:
        import mechatron  # noqa: F401
    except ImportError:
        sys.path.insert(0, str(ROOT / "src"))


ensure_importable()


def log(*parts) -> None:
    """Progress line on stderr."""
    print("[bench]", *parts, file=sys.stderr, flush=True)


def clock(fn, *args, **kwargs):
    """``(result, seconds)`` of one call, wall-clock (``time.perf_counter``)."""
    start = time.perf_counter()
    out = fn(*args, **kwargs)
    return out, time.perf_counter() - start


def repeat(fn, n: int):
    """Call ``fn()`` ``n`` times; return ``(last result, list of seconds)``."""
    times, out = [], None
    for _ in range(n):
        out, dt = clock(fn)
        times.append(dt)
    return out, times


def summary(times: list[float]) -> dict:
    """Median, minimum and maximum of repeated timings, in s."""
    return {"median_s": statistics.median(times), "min_s": min(times), "max_s": max(times),
            "repeats": len(times)}


def ratio(num: float | None, den: float | None) -> float | None:
    if not num or not den:
        return None
    return num / den


def peak_rss_mb() -> float:
    """This process's peak resident memory in MB: ``VmHWM`` where Linux gives it (a
    process started by a large one does not inherit its parent's peak, as
    ``ru_maxrss`` does across the fork), else ``ru_maxrss``."""
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    import resource
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / 1024 if sys.platform != "darwin" else peak / 2**20


def growth_exponent(n1: float, t1: float | None, n2: float, t2: float | None) -> float | None:
    """Exponent ``a`` of ``t ~ N**a`` fitted between two points."""
    if not t1 or not t2 or t1 <= 0 or t2 <= 0:
        return None
    return math.log(t2 / t1) / math.log(n2 / n1)


def profiled(fn):
    """Run ``fn()`` under cProfile; return ``(result, seconds, where)``.

    ``where`` names the few native calls that dominate ``mt.simulate`` (cumulative seconds,
    overlapping): the solver call with the conversion of its state trajectory
    (``integrate_variable``), the CasADi integrator call alone (``solver_call_s``: the
    ``casadi.Function.__call__`` made by ``integrate_variable``), the construction of the
    mapped output function (``casadi.Function.map``), every conversion of a ``casadi.DM`` to NumPy
    (``numpy.array`` on a DM goes through a Python list of floats), and the consistent
    initialization. Only a few hundred Python calls are profiled, so the overhead is
    negligible next to these.
    """
    import cProfile
    import pstats

    prof = cProfile.Profile()
    start = time.perf_counter()
    prof.enable()
    try:
        out = fn()
    finally:
        prof.disable()
    seconds = time.perf_counter() - start
    stats = pstats.Stats(prof).stats

    def cum(name: str, builtin: bool = False) -> float:
        total = 0.0
        for (file, _, func), (_, _, tt, ct, _) in stats.items():
            if builtin and file == "~" and func == f"<built-in method {name}>":
                total += ct
            elif not builtin and func == name and "mechatron" in file:
                total += ct
        return total

    def called_from(name: str, caller: str) -> float:
        """Cumulative seconds of the Python-level function ``name`` called by ``caller``."""
        total = 0.0
        for (_, _, func), (_, _, _, _, callers) in stats.items():
            if func != name:
                continue
            for (_, _, cfunc), (_, _, _, ct) in callers.items():
                if cfunc == caller:
                    total += ct
        return total

    where = {"integrate_variable_s": cum("integrate_variable"),
             "solver_call_s": called_from("__call__", "integrate_variable"),
             "initialize_s": cum("initialize"),
             "casadi_Function_map_s": cum("casadi._casadi.Function_map", builtin=True),
             "casadi_Function_call_s": cum("casadi._casadi.Function_call", builtin=True),
             "dm_to_numpy_s": cum("numpy.array", builtin=True)}
    return out, seconds, where


CHUNK = 64   # output points per mapped evaluation in logging_by_buffer


def logging_by_buffer(cm, grid, X, Z, p, chunk: int = CHUNK):
    """Seconds to evaluate every logged variable at every output point with the core's
    chunked buffer evaluation (``mechatron.solvers.logging``, what ``mt.simulate`` uses).
    Returns ``(Y, seconds)``, ``Y`` of shape (number of logged variables, points)."""
    import numpy as np

    from mechatron.solvers.logging import evaluate_outputs

    start = time.perf_counter()
    Y = evaluate_outputs(cm, np.asarray(grid, dtype=float), np.asarray(X, dtype=float),
                         np.asarray(Z, dtype=float), np.asarray(p, dtype=float))
    return Y, time.perf_counter() - start


def logging_alternative(cm, res, grid) -> dict | None:
    """Evaluate every logged variable with CasADi's buffer interface instead (see
    ``logging_by_buffer``) and check that it gives the same numbers."""
    import numpy as np

    logged = set(res.names)
    if cm.nX != cm.nx or not logged.issuperset(cm.state_names + cm.alg_names):
        return None   # modes of relations, or states not logged under their names
    X = np.array([res[n] for n in cm.state_names]).reshape(cm.nx, grid.size)
    Z = np.array([res[n] for n in cm.alg_names]).reshape(cm.nz, grid.size)
    Y, seconds = logging_by_buffer(cm, grid, X, Z, cm.p0)
    sample = range(0, len(cm.names), max(1, len(cm.names) // 200))
    diff = max(float(np.max(np.abs(Y[i] - res[cm.names[i]]))) for i in sample)
    return {"seconds": seconds, "max_abs_diff_vs_simulate": diff}


def environment() -> dict:
    """Versions, machine and load: timings mean little without them."""
    import casadi
    import numpy
    import scipy

    import mechatron

    try:
        commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                                capture_output=True, text=True, timeout=10).stdout.strip()
        dirty = bool(subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain",
                                     "src"], capture_output=True, text=True,
                                    timeout=10).stdout.strip())
    except (OSError, subprocess.SubprocessError):
        commit, dirty = "", None
    try:
        load = os.getloadavg()
    except OSError:
        load = None
    return {"mechatron": mechatron.__version__, "commit": commit, "src_modified": dirty,
            "python": platform.python_version(), "casadi": casadi.__version__,
            "numpy": numpy.__version__, "scipy": scipy.__version__,
            "machine": platform.machine(), "system": platform.system(),
            "cpus": os.cpu_count(), "load_average_1_5_15min": load,
            "date": time.strftime("%Y-%m-%dT%H:%M:%S%z")}


def _plain(obj):
    """numpy scalars and arrays -> JSON types; round floats to 6 significant digits."""
    import numpy as np

    if isinstance(obj, dict):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_plain(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _plain(obj.tolist())
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        x = float(obj)
        if not math.isfinite(x):
            return None
        return float(f"{x:.6g}")
    return obj


def dumps(result: dict) -> str:
    return json.dumps(_plain(result), indent=2)


def main(run, argv=None) -> None:
    """Command line of a single benchmark module: ``--quick``, ``--out FILE``."""
    import argparse

    parser = argparse.ArgumentParser(description=(run.__doc__ or "").splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="fewer repeats and sizes (under a minute)")
    parser.add_argument("--out", help="also write the JSON document to this file")
    args = parser.parse_args(argv)
    doc = {"environment": environment(), "quick": args.quick, **run(quick=args.quick)}
    text = dumps(doc)
    print(text)
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(text + "\n")
