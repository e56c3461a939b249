"""Run every Mechatron benchmark and print one JSON document.

    python bench/run_all.py            # full run (N up to 10000; a few minutes)
    python bench/run_all.py --quick    # N up to 1000, fewer repeats (under a minute)
    python bench/run_all.py --only dc_motor --out bench/out/latest.json

Timings are printed, never asserted. Progress goes to stderr; stdout is the JSON document:
``environment`` (versions, machine, load), ``summary`` (the headline figures) and
``benchmarks`` (each benchmark's full output). See bench/README.md for how to read it.
"""

from __future__ import annotations

import argparse
import gc
import sys
import time
from pathlib import Path

import _common  # noqa: F401  (import path)
from _common import dumps, environment, log

import bench_codegen
import bench_dc_motor
import bench_dimensions
import bench_estimation
import bench_explore
import bench_multibody
import bench_pwm
import bench_realtime
import bench_scaling

BENCHMARKS = {"dc_motor": bench_dc_motor.run, "pwm": bench_pwm.run, "scaling": bench_scaling.run,
              "codegen": bench_codegen.run, "realtime": bench_realtime.run,
              "multibody": bench_multibody.run, "estimation": bench_estimation.run,
              "dimensions": bench_dimensions.run, "explore": bench_explore.run}


def _summary(results: dict) -> dict:
    """The headline figures of each benchmark, for a quick look."""
    out = {}
    dc = results.get("dc_motor")
    if dc and "error" not in dc:
        mech = dc["mechatron"]
        out["dc_motor"] = {
            "compile_acausal_s": dc["compile_acausal"]["time"]["median_s"],
            "mechatron_simulate_first_s": mech["first_call_s"],
            "mechatron_simulate_median_s": mech["simulate"]["median_s"],
            "mechatron_rel_err_w": mech["rel_err_w"],
            **{name: {"median_s": b["time"]["median_s"],
                      "ratio_scipy_over_mechatron": b["ratio_scipy_over_mechatron"],
                      "rel_err_w": b["rel_err_w"]}
               for name, b in dc["scipy"].items() if "time" in b},
        }
    sc = results.get("scaling")
    if sc and "error" not in sc:
        for kind, data in sc["models"].items():
            rows = []
            for r in data["rows"]:
                row = {"N": r["N"], "compile_s": r["compile_s"],
                       "equations_flat": (r["equations"] or {}).get("flat"),
                       "equations_after_alias": (r["equations"] or {}).get("after_alias"),
                       "states": r["n_states"],
                       "simulate_s": r.get("simulate_second_s", r["simulate_first_s"]),
                       "integrate_variable_s":
                           r["simulate_profile_s"]["integrate_variable_s"],
                       "solver_call_s": r["simulate_profile_s"]["solver_call_s"],
                       "logging_by_buffer_s": (r["logging_by_buffer"] or {}).get("seconds"),
                       "output_points": r["output_points"]}
                if "scipy_bdf_sparse" in r:
                    row["scipy_bdf_s"] = r["scipy_bdf_sparse"]["time"]["median_s"]
                    row["ratio_scipy_over_mechatron_simulate"] = (
                        r["scipy_bdf_sparse"]["ratio_scipy_over_mechatron_simulate"])
                rows.append(row)
            out[kind] = {"rows": rows,
                         "compile_growth_exponents": [e["exponent"] for e in
                                                      data["growth_exponents"]["compile"]],
                         "compile_goals": data["compile_goals"]}
    pw = results.get("pwm")
    if pw and "error" not in pw:
        solvers = ("auto", "rodas4")
        rows = {s: [r for r in pw["rows"] if (r["solver"] == "rodas4") == (s == "rodas4")]
                for s in solvers}
        out["pwm"] = {**{f"us_per_event_{s}": [r["us_per_event"] for r in rows[s]]
                         for s in solvers},
                      "events": [r["events"] for r in rows["auto"]],
                      **{f"us_per_event_growth_{s}": pw[f"us_per_event_growth_{s}"]
                         for s in solvers},
                      "ratio_auto_over_rodas4": pw["ratio_auto_over_rodas4"],
                      "rel_err_mean_current": max(r["rel_err_mean_current"]
                                                  for r in pw["rows"])}
    mb = results.get("multibody")
    if mb and "error" not in mb:
        out["multibody"] = {
            case: {"compile_s": mb[case]["compile"]["time"]["median_s"],
                   "simulate_s": mb[case]["mechatron"]["simulate"]["median_s"],
                   **{name: b["time"]["median_s"] for name, b in mb[case]["scipy"].items()}}
            for case in ("double_pendulum", "four_bar")}
    dm = results.get("dimensions")
    if dm and "error" not in dm:
        out["dimensions"] = {"share_of_compile": {r["n"]: r["share_of_compile"]["median"]
                                                  for r in dm["rows"]},
                             "goal_share": dm["goal_share"]}
    cg = results.get("codegen")
    if cg and "error" not in cg:
        out["codegen"] = {"dc_motor_rk4_ns": cg["dc_motor_rk4_ns"], "goal_ns": cg["goal_ns"],
                          "ns_per_step": {name: ([r["ns_per_step"] for r in rows]
                                                 if isinstance(rows, list) else None)
                                          for name, rows in cg["models"].items()}}
    ex = results.get("explore")
    if ex and "error" not in ex:
        out["explore"] = {name: {"change_median_s": ex[name]["change_s"]["median_s"],
                                 "first_s": ex[name]["first_s"]}
                          for name in ex if name.startswith(("dc_motor", "rc_ladder"))}
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="skip N = 10000 and use fewer repeats (under a minute)")
    parser.add_argument("--only", choices=sorted(BENCHMARKS), action="append",
                        help="run only this benchmark (repeatable)")
    parser.add_argument("--out", help="also write the JSON document to this file")
    args = parser.parse_args(argv)

    start = time.perf_counter()
    results = {}
    for name, run in BENCHMARKS.items():
        if args.only and name not in args.only:
            continue
        log(f"--- {name} ---")
        gc.collect()
        try:
            results[name] = run(quick=args.quick)
        except Exception as exc:   # one broken benchmark must not hide the others
            log(f"{name} failed: {type(exc).__name__}: {exc}")
            results[name] = {"error": f"{type(exc).__name__}: {exc}"}
    doc = {"environment": environment(), "quick": args.quick,
           "total_wall_s": time.perf_counter() - start,
           "summary": _summary(results), "benchmarks": results}
    text = dumps(doc)
    print(text)
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(text + "\n")
    return 1 if any("error" in r for r in results.values()) else 0


if __name__ == "__main__":
    sys.exit(main())
