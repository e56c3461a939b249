"""Real-time runner and HIL bridge: step time (median, worst), wake-up jitter, overruns.

    python bench/bench_realtime.py [--quick]

Three runs of the generated plant at 10 kHz: open loop (the runner alone), SIL speed
control over UDP, and SIL over a pseudo-terminal at 2 kHz. ``--quick`` runs 0.5 s each
instead of 2 s. Prints one JSON document (timings printed, never asserted).
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import _common  # noqa: F401  (import path)
from _common import dumps, log

import numpy as np


def _figures(summary: dict) -> dict:
    keys = ("steps", "overruns", "missed_steps", "lost_packets", "late_packets",
            "median_step_time_s", "max_step_time_s", "rms_diff_percent",
            "realtime_scheduling", "realtime_factor")
    out = {k: summary.get(k) for k in keys}
    t = summary.get("timing", {})
    out.update({k: t.get(k) for k in ("step_time_p99_s", "jitter_median_s",
                                      "jitter_p99_s", "jitter_max_s",
                                      "round_trip_median_s", "round_trip_max_s")})
    return out


def _open_loop(duration: float, rate: float) -> dict:
    from mechatron.realtime.cgen import build_host
    from mechatron.realtime.hil import _read_log
    from mechatron.realtime.loop import build_loop
    with tempfile.TemporaryDirectory(prefix="mechatron-bench-rt-") as d:
        d = Path(d)
        exes = build_host(build_loop("speed", rate=rate), d)
        steps = int(duration * rate)
        subprocess.run([str(exes["plant"]), "--rate", str(rate), "--steps", str(steps),
                        "--transport", "none", "--duty", "0.75", "--rt",
                        "--log", str(d / "log.bin"), "--stats", str(d / "stats.json")],
                       check=True, capture_output=True)
        stats = json.loads((d / "stats.json").read_text())
        log_ = _read_log(d / "log.bin")
    late = log_["wake_late_s"]
    return {"steps": stats["steps"], "overruns": stats["overruns"],
            "median_step_time_s": stats["median_step_time_s"],
            "max_step_time_s": stats["max_step_time_s"],
            "step_time_p99_s": float(np.percentile(log_["exec_s"], 99)),
            "jitter_median_s": float(np.median(late)),
            "jitter_p99_s": float(np.percentile(late, 99)),
            "jitter_max_s": float(late.max()),
            "realtime_scheduling": stats["realtime"]}


def run(quick: bool = False, tiny: bool = False) -> dict:
    """The runner's timing figures (see the module docstring)."""
    if shutil.which("cc") is None:
        return {"skipped": "no C compiler (cc)"}
    from mechatron.realtime.hil import run_hil
    duration = 0.02 if tiny else 0.5 if quick else 2.0
    out = {"duration_s": duration, "rate_hz": 10_000.0}
    log("realtime: open-loop runner at 10 kHz")
    out["open_loop_10khz"] = _open_loop(duration, 10_000.0)
    log("realtime: SIL speed control over UDP at 10 kHz")
    out["sil_udp_10khz"] = _figures(run_hil("speed", duration=duration).summary())
    if not tiny:        # the tests' tiny run stops after the first two runs
        log("realtime: SIL position control over a pty at 2 kHz")
        out["sil_pty_2khz"] = _figures(run_hil("position", duration=duration, rate=2_000.0,
                                               transport="pty").summary())
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="0.5 s runs instead of 2 s")
    args = p.parse_args(argv)
    print(dumps(run(quick=args.quick)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
