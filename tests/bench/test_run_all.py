"""`bench/run_all.py` reads the keys the benchmarks actually write (its summary of the PWM
benchmark once failed with a KeyError after a key of bench_pwm.py was renamed)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[2] / "bench"


@pytest.fixture(scope="module")
def bench_modules():
    sys.path.insert(0, str(BENCH))
    try:
        import bench_pwm
        import run_all
        yield bench_pwm, run_all
    finally:
        sys.path.remove(str(BENCH))


def test_summary_of_a_real_pwm_run(bench_modules):
    from mechatron.solvers.native import compiler
    if compiler() is None:
        pytest.skip("no C compiler for solver='rodas4'")
    bench_pwm, run_all = bench_modules
    # 2 and 4 ms of the 10 kHz PWM: 40 and 80 switching events, a few seconds in all
    out = bench_pwm.run(durations=(0.002, 0.004))
    summary = run_all._summary({"pwm": out})["pwm"]
    rows = {s: [r for r in out["rows"] if (r["solver"] == "rodas4") == (s == "rodas4")]
            for s in ("auto", "rodas4")}
    for s in ("auto", "rodas4"):
        assert summary[f"us_per_event_{s}"] == [r["us_per_event"] for r in rows[s]]
        first, last = summary[f"us_per_event_{s}"][0], summary[f"us_per_event_{s}"][-1]
        assert summary[f"us_per_event_growth_{s}"] == pytest.approx(last / first)
    # both solvers see the same switching events, and twice as many in twice the time
    assert summary["events"] == [r["events"] for r in rows["auto"]]
    assert summary["events"][1] == pytest.approx(2 * summary["events"][0], abs=2)
    assert summary["ratio_auto_over_rodas4"] == pytest.approx(
        [a["wall_s"] / b["wall_s"] for a, b in zip(rows["auto"], rows["rodas4"])])
    assert summary["rel_err_mean_current"] == max(r["rel_err_mean_current"]
                                                  for r in out["rows"])


def test_summary_skips_a_failed_benchmark(bench_modules):
    _, run_all = bench_modules
    assert run_all._summary({"pwm": {"error": "KeyError: 'x'"}}) == {}
