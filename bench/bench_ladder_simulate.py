"""RC ladder simulation at scale: Mechatron's default run against hand-written SciPy.

The RC ladder of ``bench_scaling`` (1 V source, N sections of 1 Ohm and 1 mF) over 1 s,
rtol 1e-6, atol 1e-8, 1001 output points, for N = 1000 and 10000. Mechatron: the compiled
model loaded from a file in a fresh process, then ``mt.simulate`` (default solver and
logging: CVODES, sparse Jacobian, the states stored and every other variable computed on
demand): the time to load it, the first call (which deserializes the functions it reads:
a loaded model reads each when first used), the two together, and the median of the
following calls, the peak resident memory
of that process (``VmHWM``: loading the model and simulating; compiling is not part
of it; the memory goal is judged on it) and the part of it the runs add
(``simulate_increase_mb``: the peak less the resident set before the first run, the same
figure as for SciPy), and one variable that was not stored read back (``r{N/2}.i``; the peak after it,
``peak_after_reading_mb``, includes the output's expression graph that reading builds). SciPy, in its own
fresh process with its own peak memory: the same ODE written by hand
(``v' = A v + b``, A tridiagonal) with ``solve_ivp(method="LSODA")`` and the banded
Jacobian (``lband = uband = 1``), and with ``method="BDF"`` and the sparse Jacobian; and
LSODA again with subnormal numbers flushed to zero, as Mechatron's solvers run.
Final capacitor voltages are compared.

Run: ``python bench/bench_ladder_simulate.py [--quick]``; prints one JSON document.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

import _common  # noqa: F401  (import path)
from _common import log, main, ratio

import bench_scaling

import mechatron as mt

T_STOP, RTOL, ATOL, N_OUT = 1.0, 1e-6, 1e-8, 1001
GOAL_RATIO, GOAL_MB = 2.0, 300.0

_MECHATRON = r"""
import json, sys, time
import numpy as np
def status_mb(key):
    # VmHWM: this process's peak resident set (ru_maxrss would carry the parent's over
    # the fork); VmRSS: its resident set now
    for line in open("/proc/self/status"):
        if line.startswith(key + ":"):
            return int(line.split()[1]) / 1024
    return float("nan")
def peak_mb():
    return status_mb("VmHWM")
import mechatron as mt
path, n, repeats = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
t = time.perf_counter()
cm = mt.CompiledModel.load(path)
load = time.perf_counter() - t
grid = np.linspace(0.0, %(T)r, %(NOUT)d)
base = status_mb("VmRSS")     # the model loaded, nothing simulated yet
t = time.perf_counter()
res = mt.simulate(cm, %(T)r, rtol=%(RTOL)r, atol=%(ATOL)r, t_out=grid)
first = time.perf_counter() - t
times, cpu = [], []
for _ in range(repeats):
    res = None          # one run's log at a time, as a loop of studies holds it
    t, c = time.perf_counter(), time.process_time()
    res = mt.simulate(cm, %(T)r, rtol=%(RTOL)r, atol=%(ATOL)r, t_out=grid)
    times.append(time.perf_counter() - t)
    cpu.append(time.process_time() - c)
peak_simulate = peak_mb()
t = time.perf_counter()
mid = res[f"r{n // 2}.i"]
read = time.perf_counter() - t
print(json.dumps({"load_s": load, "first_s": first, "load_and_first_s": load + first,
                  "median_s": float(np.median(times)),
                  "median_cpu_s": float(np.median(cpu)),
                  "min_s": float(min(times)), "repeats": repeats,
                  "solver": res.stats.solver, "steps": res.stats.steps,
                  "stored_variables": len(res.logged), "variables": len(res.names),
                  "read_one_variable_s": read, "mid_current_final": float(mid[-1]),
                  "peak_rss_mb": peak_simulate, "base_rss_mb": base,
                  "simulate_increase_mb": peak_simulate - base,
                  "peak_after_reading_mb": peak_mb(),
                  "final_v": [float(res[f"c{k}.v"][-1]) for k in (0, n // 2, n - 1)]}))
"""

_SCIPY = r"""
import json, sys, time
import numpy as np
def status_mb(key):
    # VmHWM: this process's peak resident set (ru_maxrss would carry the parent's over
    # the fork); VmRSS: its resident set now
    for line in open("/proc/self/status"):
        if line.startswith(key + ":"):
            return int(line.split()[1]) / 1024
    return float("nan")
def peak_mb():
    return status_mb("VmHWM")
import scipy.sparse as sp
from scipy.integrate import solve_ivp
method, n, repeats = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
flush = method.endswith("+flush")     # subnormals flushed as Mechatron's solvers do
method = method.removesuffix("+flush")
g = 1.0 / (%(R)r * %(C)r)
main = np.full(n, -2.0 * g); main[-1] = -g
off = np.full(n - 1, g)
b = np.zeros(n); b[0] = g * %(V)r
def rhs(t, v):
    d = np.empty_like(v)
    d[0] = -2.0 * g * v[0] + g * v[1] + b[0]
    d[1:-1] = g * (v[:-2] - 2.0 * v[1:-1] + v[2:])
    d[-1] = g * (v[-2] - v[-1])
    return d
if method == "LSODA":
    band = np.zeros((3, n)); band[0, 1:] = off; band[1] = main; band[2, :-1] = off
    opts = dict(method="LSODA", jac=lambda t, v: band, lband=1, uband=1)
else:
    opts = dict(method="BDF", jac=sp.diags([off, main, off], [-1, 0, 1], format="csc"))
grid = np.linspace(0.0, %(T)r, %(NOUT)d)
base = status_mb("VmRSS")     # SciPy imported, the ODE set up, nothing solved yet
times, cpu = [], []
if flush:       # each solve flushed, as Mechatron's solvers run (mechatron.solvers.fpenv)
    from mechatron.solvers.fpenv import subnormals_flushed
    solve_ivp = subnormals_flushed()(solve_ivp)
for _ in range(repeats):
    sol = None          # one run's solution at a time, as on the Mechatron side
    t, c = time.perf_counter(), time.process_time()
    sol = solve_ivp(rhs, (0.0, %(T)r), np.zeros(n), t_eval=grid, rtol=%(RTOL)r,
                    atol=%(ATOL)r, **opts)
    times.append(time.perf_counter() - t)
    cpu.append(time.process_time() - c)
print(json.dumps({"median_s": float(np.median(times)), "min_s": float(min(times)),
                  "median_cpu_s": float(np.median(cpu)),
                  "repeats": repeats, "success": bool(sol.success), "nfev": int(sol.nfev),
                  "peak_rss_mb": peak_mb(), "base_rss_mb": base,
                  "simulate_increase_mb": peak_mb() - base,
                  "final_v": [float(sol.y[k, -1]) for k in (0, n // 2, n - 1)]}))
"""


def _child(code: str, *args) -> dict:
    params = {"T": T_STOP, "NOUT": N_OUT, "RTOL": RTOL, "ATOL": ATOL,
              "R": bench_scaling.R_SERIES, "C": bench_scaling.C_SHUNT,
              "V": bench_scaling.V_SOURCE}
    proc = subprocess.run([sys.executable, "-c", code % params, *map(str, args)],
                          capture_output=True, text=True, timeout=1800)
    if proc.returncode != 0:
        return {"error": proc.stderr.strip().splitlines()[-1] if proc.stderr else "failed"}
    return json.loads(proc.stdout.strip().splitlines()[-1])


def run(quick: bool = False, tiny: bool = False) -> dict:
    """RC ladder N=1000/10000: default simulate against SciPy LSODA (banded) and BDF."""
    sizes = [10, 20] if tiny else [1000, 10000]
    repeats = 2 if tiny else 3 if quick else 7
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            cm = mt.compile_model(bench_scaling.rc_ladder(n))
            path = cm.save(Path(tmp) / f"ladder_{n}.pkl")
            del cm
            mech = _child(_MECHATRON, path, n, repeats)
            lsoda = _child(_SCIPY, "LSODA", n, repeats)
            bdf = _child(_SCIPY, "BDF", n, repeats)
            flushed = _child(_SCIPY, "LSODA+flush", n, repeats)
            row = {"N": n, "mechatron": mech, "scipy_LSODA_banded": lsoda,
                   "scipy_BDF_sparse": bdf, "scipy_LSODA_banded_flushed": flushed}
            if "error" not in mech and "error" not in lsoda:
                row["ratio_lsoda_over_mechatron"] = ratio(lsoda["median_s"], mech["median_s"])
                row["ratio_bdf_over_mechatron"] = ratio(bdf.get("median_s"), mech["median_s"])
                row["ratio_lsoda_flushed_over_mechatron"] = ratio(flushed.get("median_s"),
                                                                  mech["median_s"])
                # the same on processor time: steadier on a shared machine
                row["ratio_lsoda_over_mechatron_cpu"] = ratio(lsoda["median_cpu_s"],
                                                              mech["median_cpu_s"])
                row["max_abs_diff_final_v"] = max(abs(a - b) for a, b in
                                                  zip(mech["final_v"], lsoda["final_v"]))
                row["goal_ratio_met"] = (row["ratio_lsoda_over_mechatron"] or 0) >= GOAL_RATIO
                row["goal_memory_met"] = mech["peak_rss_mb"] < GOAL_MB
                log(f"rc_ladder N={n}: mechatron load {mech['load_s']:.3f} s, first "
                    f"{mech['first_s']:.3f} s, median "
                    f"{mech['median_s']:.4f} s, peak {mech['peak_rss_mb']:.0f} MB "
                    f"(simulating +{mech['simulate_increase_mb']:.0f} MB); LSODA banded "
                    f"{lsoda['median_s']:.4f} s, peak {lsoda['peak_rss_mb']:.0f} MB "
                    f"(solving +{lsoda['simulate_increase_mb']:.0f} MB); ratio "
                    f"{row['ratio_lsoda_over_mechatron']:.2f} (processor time "
                    f"{mech['median_cpu_s']:.4f} s against {lsoda['median_cpu_s']:.4f} s: "
                    f"{row['ratio_lsoda_over_mechatron_cpu']:.2f}); BDF sparse "
                    f"{bdf.get('median_s', float('nan')):.4f} s; LSODA with subnormals "
                    f"flushed {flushed.get('median_s', float('nan')):.4f} s")
            rows.append(row)
    return {"benchmark": "ladder_simulate",
            "settings": {"t_stop_s": T_STOP, "rtol": RTOL, "atol": ATOL,
                         "output_points": N_OUT, "sizes": sizes, "repeats": repeats},
            "goals": {"ratio_lsoda_over_mechatron": GOAL_RATIO, "peak_rss_mb_N10000": GOAL_MB},
            "rows": rows,
            "notes": ["Each side runs in a fresh process; peak_rss_mb is that process's "
                      "maximum resident set (VmHWM) (Python, NumPy/SciPy or CasADi included) "
                      "and is what the memory goal is judged on; simulate_increase_mb is "
                      "that peak less the resident set just before the first run "
                      "(base_rss_mb: Mechatron with the compiled model loaded, SciPy with "
                      "the ODE set up), the memory the runs themselves take, measured the "
                      "same way on both sides.",
                      "ratio = SciPy median / Mechatron median (first call excluded); "
                      "> 1 means Mechatron is faster. ratio_lsoda_over_mechatron_cpu: the "
                      "same on each process's processor time (time.process_time), which "
                      "other work on a shared machine disturbs less than wall time.",
                      "Mechatron's solvers flush subnormal numbers to zero while they run "
                      "(mechatron.solvers.fpenv): most of a long ladder's far voltages sit "
                      "below 1e-308, where many processors compute a hundred times slower. "
                      "The goal is judged against LSODA as written by hand (the processor's "
                      "default); scipy_LSODA_banded_flushed is the same run with the same "
                      "flush, for comparison (ratio_lsoda_flushed_over_mechatron)."]}


if __name__ == "__main__":
    main(run)
