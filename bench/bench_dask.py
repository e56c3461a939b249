"""Batch runs on Dask: speed-up from one to two workers, and the cost of one task.

A parameter sweep of an RC ladder of 100 sections (``mechatron.batch.sweep``, 0.5 s per
run, CVODES at rtol 1e-8, the last capacitor's voltage kept) over a grid of the first
resistance, run on a
``dask.distributed.LocalCluster`` of one and then two worker processes (one thread
each), the compiled model scattered once per worker. The peer is the same sweep in this
process (``workers=1``), measured in the same run; results are checked to be identical.
Per-task overhead: ``mechatron.batch.map_blocks`` of a function that returns at once,
on the two-worker cluster, wall time per task.

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


def run(quick: bool = False, tiny: bool = False) -> dict:
    """RC ladder sweep on a LocalCluster of 1 and 2 workers, and per-task overhead."""
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError as exc:
        return {"benchmark": "dask", "error": f"dask.distributed not installed ({exc})"}
    n_runs = 8 if tiny else 200 if quick else 600
    n_tasks = 20 if tiny else 200 if quick else 1000
    import bench_scaling
    cm = mt.compile_model(bench_scaling.rc_ladder(N_LADDER))
    path = f"c{N_LADDER - 1}.v"
    params = [{"r0.R": R} for R in np.linspace(0.5, 2.0, n_runs)]
    opts = dict(outputs=[path], t_out=np.linspace(0.0, 0.5, 101), rtol=1e-8, atol=1e-10)
    t = time.perf_counter()
    local = batch.sweep(cm, params, 0.5, workers=1, **opts)
    t_local = time.perf_counter() - t
    out = {"benchmark": "dask", "settings": {"runs": n_runs, "tasks_overhead": n_tasks,
                                             "model": f"rc_ladder_{N_LADDER}", "t_stop_s": 0.5},
           "local_s": t_local}
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
            if workers == 2:
                t = time.perf_counter()
                batch.map_blocks(_nothing, None, list(range(n_tasks)), client=client)
                out["per_task_overhead_s"] = (time.perf_counter() - t) / n_tasks
                out["shipped_per_worker"] = client.run(batch.received)
    out["speedup_1_to_2_workers"] = ratio(out["workers_1_s"], out["workers_2_s"])
    out["ratio_local_over_2_workers"] = ratio(t_local, out["workers_2_s"])
    log(f"dask: {n_runs} ladder runs local {t_local:.2f} s, 1 worker "
        f"{out['workers_1_s']:.2f} s, 2 workers {out['workers_2_s']:.2f} s (speed-up "
        f"{out['speedup_1_to_2_workers']:.2f}); per task {out['per_task_overhead_s'] * 1e3:.2f} ms")
    out["notes"] = ["The machine has 2 cores shared with other work: the speed-up is "
                    "bounded by 2 and by the load (see environment.load_average).",
                    "per_task_overhead_s: wall time per task of map_blocks on the "
                    "two-worker cluster for a function that returns at once (scheduling, "
                    "serialization, the round trip)."]
    return out


if __name__ == "__main__":
    main(run)
