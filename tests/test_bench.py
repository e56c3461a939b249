"""The benchmarks run and their summary and table code reads what they produce (issue 17,
part 7): every ``bench/*.py`` imports, every benchmark of ``run_all`` runs at its tiny size
(seconds, not minutes: the figures mean nothing, the keys do), and ``run_all``'s summary
and table are built from those outputs, so a key renamed in a benchmark fails here rather
than at the end of a long benchmark run. Speed itself is never asserted."""

import importlib
import inspect
import itertools
import json
import math
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

BENCH = Path(__file__).resolve().parents[1] / "bench"


def _bench_module(name: str):
    """Import ``bench/<name>.py`` with bench/ on the path for the fixture's lifetime."""
    sys.path.insert(0, str(BENCH))
    try:
        yield importlib.import_module(name)
    finally:
        sys.path.remove(str(BENCH))


@pytest.fixture(scope="module")
def run_all():
    yield from _bench_module("run_all")


@pytest.fixture(scope="module")
def tiny_results(run_all):
    results, seconds = {}, {}
    for name, run in run_all.BENCHMARKS.items():
        if name in ("codegen", "realtime") and shutil.which("cc") is None:
            continue
        start = time.perf_counter()
        results[name] = run(quick=True, tiny=True)
        seconds[name] = time.perf_counter() - start
    return results, seconds


def test_every_bench_script_imports_and_is_in_run_all(run_all):
    scripts = sorted(p.stem for p in BENCH.glob("*.py"))
    for name in scripts:
        importlib.import_module(name)
    benchmarks = {f"bench_{name}" for name in run_all.BENCHMARKS}
    assert benchmarks == {s for s in scripts if s.startswith("bench_")}
    for name, run in run_all.BENCHMARKS.items():
        assert "tiny" in inspect.signature(run).parameters, name
        assert name in run_all.TABLE_ROWS, name


def test_summary_and_table_read_every_benchmark(run_all, tiny_results):
    results, _ = tiny_results
    for name, out in results.items():
        assert "error" not in out, (name, out.get("error"))
    summary = run_all._summary(results)         # raises KeyError on a renamed key
    assert {"dc_motor", "pwm", "rc_ladder", "codegen"} <= set(summary)
    rows = run_all.table(results)
    assert {r["benchmark"] for r in rows} == set(results) - (
        {"realtime"} if "skipped" in results.get("realtime", {}) else set())
    for row in rows:
        assert isinstance(row["figure"], str) and row["figure"]
        value = row["mechatron"]
        assert isinstance(value, (int, float)) and math.isfinite(value), row
        if row["peer"] is not None:
            ratio = row["ratio_peer_over_mechatron"]
            assert ratio is None or (math.isfinite(ratio) and ratio > 0), row
        if row["goal"] is not None and row["goal_met"] is not None:
            assert isinstance(row["goal_met"], bool), row
    text = run_all.format_table(rows)
    assert len(text.splitlines()) == len(rows) + 2
    json.loads(run_all.dumps({"table": rows, "summary": summary}))


def test_a_missing_key_is_reported_not_fatal(run_all, tiny_results):
    results, _ = tiny_results
    broken = dict(results, pwm={k: v for k, v in results["pwm"].items()
                                if k != "us_per_event_growth_auto"})
    out = run_all._guarded(run_all.table, broken, "table")
    assert out == {"error": "KeyError: 'us_per_event_growth_auto'"}


@pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler")
def test_hand_written_c_peer_is_the_dc_motor_rk4_step(tmp_path):
    """The peer of the generated C computes the same thing: its states after 2000 steps
    agree with an RK4 written here in NumPy, and with the desktop fixed-step run, to
    rounding."""
    import subprocess

    import mechatron as mt
    from mechatron.codegen.c.build import C_FLAGS

    exe = tmp_path / "hand"
    subprocess.run(["cc", *C_FLAGS.split(), "-o", str(exe), str(BENCH / "c" / "dc_motor_rk4.c"),
                    "-lm"], check=True, capture_output=True)
    cm = mt.compile_model(mt.models.get("dc_motor").build())
    V, R, L, k, J, D = (float(v) for v in cm.p0)
    out = subprocess.run([str(exe), *map(repr, (V, R, L, k, J, D)), "2000"], check=True,
                         capture_output=True, text=True).stdout
    x_c = np.array(json.loads(out)["x"])

    def f(x):
        return np.array([(V - R * x[0] - k * x[1]) / L, (k * x[0] - D * x[1]) / J])

    h, x = 1e-4, np.zeros(2)
    for _ in range(2000):
        k1 = f(x)
        k2 = f(x + h / 2 * k1)
        k3 = f(x + h / 2 * k2)
        k4 = f(x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    np.testing.assert_allclose(x_c, x, rtol=1e-12)
    desk = mt.simulate(cm, 0.2, solver="rk4", dt=h)
    np.testing.assert_allclose(x_c, [desk.final("inductor.i"), desk.final("inertia.w")],
                               rtol=1e-12)


@pytest.fixture(scope="module")
def bench_scaling():
    yield from _bench_module("bench_scaling")


def test_compile_growth_reads_what_its_fresh_processes_write(bench_scaling, monkeypatch):
    """``bench_scaling.py --growth`` at a tiny size: one round of a ladder of 10 and two
    of 5, each compiled in a fresh process; its growth figures are the ratios of the
    sizes' means, medians and minima (what is printed is computed from what ran)."""
    monkeypatch.setattr(bench_scaling, "machine_spells",
                        lambda seconds=10.0: {"slow_share": 0.0})
    monkeypatch.setattr(bench_scaling, "fresh_page_cost",
                        lambda mb=256: {"us_per_page": 1.0})
    out = bench_scaling.compile_growth(rounds=1, small=5, large=10, per_round=2)
    small, large = out["sizes"]["5"], out["sizes"]["10"]
    assert len(small["us_per_equation"]) == 2 and len(large["us_per_equation"]) == 1
    for stat in ("mean", "median", "min"):
        assert out["growth"][stat] == pytest.approx(large[stat] / small[stat])
    # the minima over equally many runs: the one large run against the mean of the
    # small ones (the expected minimum of one draw)
    assert out["growth"]["min_equal_draws"] == pytest.approx(
        large["min"] / statistics.mean(small["us_per_equation"]))
    assert out["met"] == (out["growth"]["min_equal_draws"] < out["goal"])
    assert set(large["passes_us_per_equation"][0]) >= {"flatten", "structure", "total"}
    # each pass's median per equation at both sizes (where the growth is)
    per_pass = out["passes_median_us_per_equation"]
    assert set(per_pass) == set(large["passes_us_per_equation"][0])
    for key, both in per_pass.items():
        for n, size in (("5", small), ("10", large)):
            assert both[n] == pytest.approx(statistics.median(
                p[key] for p in size["passes_us_per_equation"]))
    # user and kernel time apart: user alone grows as the ratio of the user times
    for stat, f in (("min", min), ("median", statistics.median)):
        assert out["growth_user"][stat] == pytest.approx(
            f(large["user_us_per_equation"]) / f(small["user_us_per_equation"]))
    assert out["growth_user"]["min_equal_draws"] == pytest.approx(
        min(large["user_us_per_equation"]) / statistics.mean(small["user_us_per_equation"]))
    for size in (small, large):
        assert len(size["system_us_per_equation"]) == len(size["us_per_equation"])
        assert all(f > 0 for f in size["page_faults_per_equation"])
    # its peer ran beside each compile, in a fresh process of its own
    peer = out["peer_structure_on_arrays"]
    assert [len(peer["sizes"][k]["us_per_equation"]) for k in ("5", "10")] == [2, 1]
    for stat in ("min", "median"):
        assert peer["growth"][stat] == pytest.approx(
            peer["sizes"]["10"][stat] / peer["sizes"]["5"][stat])
    assert peer["compile_over_peer_min"]["10"] == pytest.approx(
        large["min"] / peer["sizes"]["10"]["min"])


def test_expected_min_is_the_mean_minimum_over_every_choice(bench_scaling):
    """`expected_min(values, k)`, the fastest of k runs expected from a larger sample
    (what `--growth` compares with the fastest of k large runs), equals the mean of the
    minima over every choice of k of the values, ties and any order included."""
    values = [3.0, 1.5, 2.0, 2.0, 7.25, 0.5, 4.0]
    for k in range(1, len(values) + 1):
        choices = list(itertools.combinations(values, k))
        assert bench_scaling.expected_min(values, k) == pytest.approx(
            sum(map(min, choices)) / len(choices))
    assert bench_scaling.expected_min(values, 1) == pytest.approx(statistics.mean(values))
    assert bench_scaling.expected_min(values, len(values)) == min(values)
    with pytest.raises(ValueError, match="3 draws from 2 values"):
        bench_scaling.expected_min([1.0, 2.0], 3)


@pytest.mark.parametrize("n", [1, 2, 5, 12])
def test_structure_on_arrays_counts_what_the_compiler_counts(bench_scaling, n):
    """The array peer of ``--growth`` does the compiler's structural work on the same RC
    ladder, written independently: its counts of flat equations and variables, of the
    equations left after alias elimination, of the unknowns matched and of the BLT
    blocks equal the compiler's report."""
    import mechatron as mt

    got = bench_scaling.structure_on_arrays(n)
    report = mt.compile_model(bench_scaling.rc_ladder(n)).report
    assert got["equations_flat"] == report["equations"]["flat"]
    assert got["variables_flat"] == report["variables"]["flat"]
    assert got["after_alias"] == report["equations"]["after_alias"]
    assert got["unknowns"] == report["variables"]["after_alias"]
    assert got["blocks"] == report["blocks"]


def test_fresh_page_cost_touches_every_page(bench_scaling):
    got = bench_scaling.fresh_page_cost(mb=8)
    # one fault per 4 KiB page of a fresh mapping (fewer only with huge pages, which
    # the kernel gives an anonymous mapping only on request)
    assert got["page_faults"] >= 0.9 * 8 * 256
    assert got["us_per_page"] > 0 and got["system_us_per_page"] >= 0


def test_machine_spells_counts_its_loops(bench_scaling):
    got = bench_scaling.machine_spells(seconds=0.2)
    assert got["loops"] > 0 and got["fastest_ms"] > 0
    assert 0.0 <= got["slow_share"] <= 1.0 and got["slowest_over_fastest"] >= 1.0


def test_cachegrind_totals_reads_events_and_summary(bench_scaling, tmp_path):
    out = tmp_path / "cachegrind.out"
    out.write_text("desc: LL cache: 33554432 B, 64 B, 16-way associative\n"
                   "cmd: python x.py\nevents: Ir D1mr DLmr DLmw\nfl=x.c\nfn=f\n1 5 1 0 0\n"
                   "summary: 700 30 4 2\n")
    assert bench_scaling.cachegrind_totals(out) == {"Ir": 700, "D1mr": 30, "DLmr": 4,
                                                    "DLmw": 2}
    out.write_text("events: Ir D1mr\n")
    with pytest.raises(ValueError, match="not a complete cachegrind output"):
        bench_scaling.cachegrind_totals(out)


def test_counted_processes_run_alike(bench_scaling, monkeypatch, tmp_path):
    """Each ``--counted`` process under cachegrind is seeded alike and runs one BLAS
    thread (idle OpenBLAS threads spin a varying count of instructions), the caller's
    other settings, such as ``OPENBLAS_CORETYPE``, left as they are."""
    seen = {}

    def run(cmd, env, **kwargs):
        seen.update(cmd=cmd, env=env)
        out = next(a.split("=", 1)[1] for a in cmd if a.startswith("--cachegrind-out-file="))
        with open(out, "w") as f:
            f.write("events: Ir D1mr DLmr DLmw\nsummary: 1 2 3 4\n")
        return subprocess.CompletedProcess(cmd, 0, '{"N": 10, "stop": "build"}\n', "")

    monkeypatch.setenv("OPENBLAS_CORETYPE", "Haswell")
    monkeypatch.setattr(bench_scaling.subprocess, "run", run)
    line, totals = bench_scaling._cachegrind(10, "build", str(tmp_path))
    assert line["stop"] == "build" and totals["Ir"] == 1
    env = seen["env"]
    assert env["PYTHONHASHSEED"] == "0" and env["OPENBLAS_NUM_THREADS"] == "1"
    assert env["OPENBLAS_CORETYPE"] == "Haswell"


def test_compile_counted_subtracts_the_build_and_divides_by_equations(bench_scaling):
    """``bench_scaling.py --counted [--passes]``: each size's compile process less its
    build-only process, per flat equation, each pass as the process stopped after it
    less the one stopped before, and the growth from the first size (a runner standing
    in for cachegrind, whose runs take minutes)."""
    stops = ["build", *bench_scaling.COUNTED_STOPS, "compile"]

    def runner(n, stop, folder):
        # each pass does k * n^2 instructions, 1 + k last-level misses per n^2 / 10
        k = stops.index(stop)
        totals = {"Ir": 1000 * n + 10 * k * (k + 1) // 2 * n ** 2, "D1mr": 10 * n,
                  "DLmr": n + k * n ** 2 // 10, "DLmw": n * min(k, 1)}
        return {"N": n, "stop": stop, "equations_flat": 12 * n if stop == "compile"
                else 0}, totals

    out = bench_scaling.compile_counted((10, 100), passes=True, runner=runner)
    small, large = out["rows"]
    whole = 10 * 15 * 10 ** 2       # the five passes of 10 k n^2, k = 1..5
    assert small["instructions_per_equation"] == pytest.approx(whole / 120)
    assert large["last_level_read_misses_per_equation"] == pytest.approx(5 * 1000 / 1200)
    assert large["instructions_growth"] == pytest.approx(10.0)
    assert large["last_level_write_misses_growth"] == pytest.approx(1.0)
    assert list(small["passes"]) == [*bench_scaling.COUNTED_STOPS, "rest"]
    assert [p["instructions_per_equation"] for p in small["passes"].values()] == \
        pytest.approx([10 * k * 100 / 120 for k in range(1, 6)])
    assert sum(p["instructions_per_equation"] for p in large["passes"].values()) == \
        pytest.approx(large["instructions_per_equation"])
    only_whole = bench_scaling.compile_counted((10,), runner=runner)["rows"][0]
    assert "passes" not in only_whole and \
        only_whole["instructions_per_equation"] == small["instructions_per_equation"]
