"""Batch runs on Dask: speed-up from one to two workers, and the cost of one task.

A parameter sweep of an RC ladder of 100 sections (``mechatron.batch.sweep``, 0.5 s per
run, CVODES at rtol 1e-8, the last capacitor's voltage kept) over a grid of the first
resistance, run on a
``dask.distributed.LocalCluster`` of one and then two worker processes (one thread
each), the compiled model scattered once per worker. The peer is the same sweep in this
process (``workers=1``), measured in the same run; results are checked to be identical.
Per-task overhead: ``mechatron.batch.map_blocks`` of a function that returns at once,
on the two-worker cluster, wall time per task.

Multi-start estimation (``estimate(problem, starts=K, client=...)``): the frequency and
damping of a damped oscillator fitted to three periods of its noisy free response (a
cost with several local minima, as in tests/estimation/test_estimation_multistart.py),
K Latin hypercube starts, on the same clusters of one and two workers; the peer is the
same multi-start run in this process (``workers=1``, its functions built beforehand),
checked to give identical starts. Each cluster run ships the problem to the workers,
which rebuild its CasADi functions: that cost is in the cluster figures.

Run: ``python bench/bench_dask.py [--quick]``; prints one JSON document.
"""

from __future__ import annotations

import time

import _common  # noqa: F401  (import path)
from _common import log, main, ratio

import numpy as np

import mechatron as mt
from mechatron import batch


N_LADDER = 100      # RC ladder sections: a run of some milliseconds, as a study's


def _nothing(shared, block):
    return block


class Oscillator(mt.Component):
    """Free damped oscillator ``x'' + 2 zeta w x' + w^2 x = 0`` from ``x = 1``."""

    w = mt.Parameter("rad/s", default=1.0)
    zeta = mt.Parameter("1", default=0.1)
    x = mt.Variable("m", start=1.0)
    v = mt.Variable("m/s", start=0.0)

    def equations(self):
        return [mt.der(self.x) == self.v,
                mt.der(self.v) == -self.w ** 2 * self.x - 2 * self.zeta * self.w * self.v]


def oscillator_problem():
    """Frequency 7 rad/s and damping 0.05 from 3 s of the analytic free response with 1%
    noise; the guess 2 rad/s lies in the valley of a wrong minimum."""
    from mechatron.estimation import EstimationProblem, Experiment, FreeParameter
    t = np.linspace(0.0, 3.0, 301)
    w, zeta = 7.0, 0.05
    wd = w * np.sqrt(1 - zeta ** 2)
    y = np.exp(-zeta * w * t) * (np.cos(wd * t) + zeta * w / wd * np.sin(wd * t))
    y = y + 0.01 * np.random.default_rng(1).standard_normal(t.size)
    e = Experiment("free", t=t, outputs={"x": y}, sigma={"x": 0.01})
    free = [FreeParameter("w", 2.0, 1.0, 12.0), FreeParameter("zeta", 0.05, 0.01, 0.1)]
    return EstimationProblem(Oscillator(), [e], free, outputs={"x": "x"}, jit=False)


def _starts(res) -> list:
    return [(r["cost"], r["parameters"]) for r in res.starts]


def run(quick: bool = False, tiny: bool = False) -> dict:
    """RC ladder sweep on a LocalCluster of 1 and 2 workers, and per-task overhead."""
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError as exc:
        return {"benchmark": "dask", "error": f"dask.distributed not installed ({exc})"}
    n_runs = 8 if tiny else 200 if quick else 600
    n_tasks = 20 if tiny else 200 if quick else 1000
    n_starts = 3 if tiny else 8 if quick else 16
    from mechatron.estimation import estimate
    prob = oscillator_problem()
    estimate(prob, max_iterations=1)          # build the sensitivity functions once
    t = time.perf_counter()
    ms_local = estimate(prob, starts=n_starts, workers=1)
    t_ms_local = time.perf_counter() - t
    import bench_scaling
    cm = mt.compile_model(bench_scaling.rc_ladder(N_LADDER))
    path = f"c{N_LADDER - 1}.v"
    params = [{"r0.R": R} for R in np.linspace(0.5, 2.0, n_runs)]
    opts = dict(outputs=[path], t_out=np.linspace(0.0, 0.5, 101), rtol=1e-8, atol=1e-10)
    t = time.perf_counter()
    local = batch.sweep(cm, params, 0.5, workers=1, **opts)
    t_local = time.perf_counter() - t
    out = {"benchmark": "dask", "settings": {"runs": n_runs, "tasks_overhead": n_tasks,
                                             "model": f"rc_ladder_{N_LADDER}", "t_stop_s": 0.5,
                                             "multistart_starts": n_starts,
                                             "multistart_problem": "oscillator w, zeta"},
           "local_s": t_local, "multistart_local_s": t_ms_local,
           "multistart_best": ms_local.parameters}
    for workers in (1, 2):
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                          dashboard_address=None, silence_logs=40) as cluster, \
                Client(cluster) as client:
            batch.sweep(cm, params[:4], 0.5, client=client, **opts)   # warm the workers
            t = time.perf_counter()
            remote = batch.sweep(cm, params, 0.5, client=client, **opts)
            out[f"workers_{workers}_s"] = time.perf_counter() - t
            out[f"workers_{workers}_identical"] = all(
                np.array_equal(a.values, b.values) for a, b in zip(local, remote))
            # warm the workers' imports; each run ships the problem anew (the workers
            # rebuild its functions: part of the measured time)
            estimate(prob, starts=2 * workers, client=client, max_iterations=1)
            t = time.perf_counter()
            ms = estimate(prob, starts=n_starts, client=client)
            out[f"multistart_workers_{workers}_s"] = time.perf_counter() - t
            out[f"multistart_workers_{workers}_identical"] = _starts(ms) == _starts(ms_local)
            if workers == 2:
                t = time.perf_counter()
                batch.map_blocks(_nothing, None, list(range(n_tasks)), client=client)
                out["per_task_overhead_s"] = (time.perf_counter() - t) / n_tasks
                out["shipped_per_worker"] = client.run(batch.received)
    out["speedup_1_to_2_workers"] = ratio(out["workers_1_s"], out["workers_2_s"])
    out["ratio_local_over_2_workers"] = ratio(t_local, out["workers_2_s"])
    out["multistart_speedup_1_to_2_workers"] = ratio(out["multistart_workers_1_s"],
                                                     out["multistart_workers_2_s"])
    out["multistart_ratio_local_over_2_workers"] = ratio(t_ms_local,
                                                         out["multistart_workers_2_s"])
    log(f"dask: {n_runs} ladder runs local {t_local:.2f} s, 1 worker "
        f"{out['workers_1_s']:.2f} s, 2 workers {out['workers_2_s']:.2f} s (speed-up "
        f"{out['speedup_1_to_2_workers']:.2f}); per task {out['per_task_overhead_s'] * 1e3:.2f} ms")
    log(f"dask: {n_starts}-start estimation local {t_ms_local:.2f} s, 1 worker "
        f"{out['multistart_workers_1_s']:.2f} s, 2 workers "
        f"{out['multistart_workers_2_s']:.2f} s (speed-up "
        f"{out['multistart_speedup_1_to_2_workers']:.2f})")
    out["notes"] = ["The machine has 2 cores shared with other work: the speed-up is "
                    "bounded by 2 and by the load (see environment.load_average).",
                    "per_task_overhead_s: wall time per task of map_blocks on the "
                    "two-worker cluster for a function that returns at once (scheduling, "
                    "serialization, the round trip).",
                    "multistart_*: one task per start; the starts differ in length (a start "
                    "in a wrong valley iterates longer), so two workers balance them only "
                    "as well as the longest start allows."]
    return out


if __name__ == "__main__":
    main(run)
