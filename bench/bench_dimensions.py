"""Cost of the dimension check (compiler/dimensions.py) within compile time.

The RC ladder of ``bench_scaling.py`` (N = 1000 and 10000 sections; ``--quick``: 100 and
1000) is compiled with ``mt.compile_model``; the report's pass timings give the time of
the ``dimensions`` pass and its share of the total compile time. The pass is also timed
on its own, on the flat model, split into its parts: collecting the symbols and their
dimensions, building the CasADi function over all residuals, and reading its instruction
list. Every figure is the median of ``repeats`` runs (1 for the largest size).

Run: ``python bench/bench_dimensions.py [--quick]``; prints one JSON document.
"""

from __future__ import annotations

import gc
import statistics
import time

import _common  # noqa: F401  (import path)
from _common import log, main, summary

import casadi as ca

import mechatron as mt
from bench_scaling import rc_ladder
from mechatron.compiler import dimensions as dim
from mechatron.compiler.flatten import flatten


def _parts(flat) -> dict:
    """The pass on ``flat`` in its three parts (seconds each)."""
    t0 = time.perf_counter()
    symbols = dim._Symbols(flat)
    rows = [eq.residual for eq in flat.equations]
    t1 = time.perf_counter()
    f = dim._function(rows, symbols.vector)
    t2 = time.perf_counter()
    out = dim.infer(f, symbols.dims)
    t3 = time.perf_counter()
    assert not any(type(d) is tuple for d in out)
    return {"symbols_s": t1 - t0, "function_s": t2 - t1, "walk_s": t3 - t2,
            "instructions": f.n_instructions(), "equations": len(rows)}


def _one(n: int, repeats: int) -> dict:
    shares, passes, totals, parts = [], [], [], []
    for _ in range(repeats):
        cm = mt.compile_model(rc_ladder(n))
        t = cm.report["timings"]
        passes.append(t["dimensions"])
        totals.append(t["total"])
        shares.append(t["dimensions"] / t["total"])
        del cm
        enabled = gc.isenabled()
        gc.disable()             # as compile_model runs its passes
        try:
            parts.append(_parts(flatten(rc_ladder(n))))
        finally:
            if enabled:
                gc.enable()
    best = min(range(repeats), key=lambda k: passes[k])
    row = {"n": n, "dimensions_s": summary(passes), "compile_total_s": summary(totals),
           "share_of_compile": {"median": statistics.median(shares), "min": min(shares),
                                "max": max(shares)},
           "parts_of_one_run": parts[best]}
    log(f"rc_ladder {n}: dimensions {row['dimensions_s']['median_s']:.3f} s of "
        f"{row['compile_total_s']['median_s']:.2f} s "
        f"({100 * row['share_of_compile']['median']:.1f} %)")
    return row


def run(quick: bool = False, tiny: bool = False) -> dict:
    """Time of the dimension pass and its share of compile time on the RC ladder."""
    sizes = (10,) if tiny else (100, 1000) if quick else (1000, 10000)
    rows = [_one(n, 1 if n >= 10000 or tiny else 3) for n in sizes]
    return {"casadi": ca.__version__, "goal_share": 0.10, "rows": rows}


if __name__ == "__main__":
    main(run)
