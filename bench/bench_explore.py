"""The explorer's responsiveness: time from a parameter change to new plot data.

What the page does when a parameter is edited, over HTTP to a server on 127.0.0.1 (in
this process, in a thread): ``POST /api/simulate`` with the changed parameter and the run
to replace (the compiled model is kept: no recompilation), then one
``GET /api/runs/ID/signal`` per plotted signal at the plot's pixel width (1200). Measured
for:

* ``dc_motor`` (the seed's motor, 2 states; plotted: speed and current), changing the
  supply voltage;
* the RC ladder of ``bench_scaling.py`` with N = 1000 sections (1000 states; plotted: the
  first and the last capacitor voltage), changing the source voltage.

Also, for a large log: a synthetic simlog of 10,000 variables x 2,001 points loaded from
Parquet, the time to list its variables (names and units, no values, what the page's tree
needs) and to fetch one signal decimated to 1200 pixels, and one zoomed to a tenth.

``first_s`` is the first request (which compiles the model); ``change_s`` the median over
the repeated changes, split into ``simulate_s`` and ``fetch_s``. The browser's drawing is
not included (a few ms for two 1200-pixel polylines). Run:
``python bench/bench_explore.py [--quick]``.
"""

from __future__ import annotations

import json
import tempfile
import time
import urllib.request
from pathlib import Path

import _common  # noqa: F401  (import path)
from _common import log, main, summary

import numpy as np

from bench_scaling import rc_ladder
from mechatron.explore import ExploreServer, Workspace
from mechatron.models.entry import Experiment, ModelEntry
from mechatron.results import SimResult

WIDTH = 1200


def _request(url: str, body: dict | None = None) -> dict:
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(url, data=data, headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(req, timeout=600) as r:
        return json.loads(r.read())


def _changes(server, model: str, param: str, values: list[float], signals: list[str]) -> dict:
    base = server.url + "api/"
    start = time.perf_counter()
    run = _request(base + "simulate", {"model": model})
    first = time.perf_counter() - start
    sims, fetches, totals = [], [], []
    for value in values:
        t0 = time.perf_counter()
        run = _request(base + "simulate", {"model": model, "params": {param: value},
                                           "replace": run["id"]})
        t1 = time.perf_counter()
        for name in signals:
            _request(base + f"runs/{run['id']}/signal?name={name}&width={WIDTH}")
        t2 = time.perf_counter()
        sims.append(t1 - t0)
        fetches.append(t2 - t1)
        totals.append(t2 - t0)
    return {"first_s": first, "change_s": summary(totals), "simulate_s": summary(sims),
            "fetch_s": summary(fetches), "solver_wall_s": run["seconds"],
            "n_t": run["n_t"], "n_vars": run["n_vars"], "signals": signals,
            "changes": len(values)}


def _large_log(server, n_vars: int, n_t: int) -> dict:
    t = np.linspace(0.0, 1.0, n_t)
    rng = np.random.default_rng(0)
    values = np.sin(np.outer(rng.uniform(1, 50, n_vars), t)) + rng.normal(0, 0.01, (n_vars, n_t))
    names = [f"part{k // 10}.sub{k % 10}.x" for k in range(n_vars)]
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "large.parquet"
        SimResult(t, values, names, ["m"] * n_vars).save(path)
        start = time.perf_counter()
        run = server.workspace.load(path)
        load = time.perf_counter() - start
    base = server.url + f"api/runs/{run.id}/"
    start = time.perf_counter()
    with urllib.request.urlopen(base + "variables") as r:
        listing = r.read()
    variables = time.perf_counter() - start
    fetch, zoom = [], []
    for k in range(5):
        start = time.perf_counter()
        _request(base + f"signal?name={names[k * (n_vars // 5)]}&width={WIDTH}")
        fetch.append(time.perf_counter() - start)
        start = time.perf_counter()
        _request(base + f"signal?name={names[k * (n_vars // 5)]}&width={WIDTH}&t0=0.45&t1=0.55")
        zoom.append(time.perf_counter() - start)
    return {"n_vars": n_vars, "n_t": n_t, "load_parquet_s": load, "variables_s": variables,
            "variables_bytes": len(listing), "signal_s": summary(fetch),
            "zoomed_signal_s": summary(zoom)}


def run(quick: bool = False, tiny: bool = False) -> dict:
    """Time from a parameter change to new plot data in the explorer."""
    ws = Workspace()
    n = 20 if tiny else 1000
    ws.add_entry(ModelEntry(name=f"rc_ladder_{n}", description="RC ladder of bench_scaling",
                            parameters={}, variants={"acausal": lambda: rc_ladder(n)},
                            outputs={"acausal": {"last": f"c{n - 1}.v"}},
                            output_units={"last": "V"},
                            experiment=Experiment(t_stop=1.0, solver="cvodes")))
    server = ExploreServer(ws, port=0)
    server.start()
    repeats = 2 if tiny else 5 if quick else 15
    try:
        log("dc_motor")
        motor = _changes(server, "dc_motor", "source.V",
                         [19.2 * (1 + 0.01 * k) for k in range(1, repeats + 1)],
                         ["inertia.w", "inductor.i"])
        log(f"rc_ladder_{n} (compiles first)")
        ladder = _changes(server, f"rc_ladder_{n}", "src.V",
                          [1.0 + 0.1 * k for k in range(1, max(3, repeats // 3) + 1)],
                          ["c0.v", f"c{n - 1}.v"])
        log("large log")
        large = _large_log(server, 200 if tiny else 2_000 if quick else 10_000,
                           201 if tiny else 2001)
    finally:
        server.shutdown()
        server.server_close()
    return {"dc_motor": motor, f"rc_ladder_{n}": ladder, "large_log": large,
            "notes": ["change_s: POST /api/simulate (replace the run, no recompilation) then "
                      "GET /api/runs/ID/signal for each plotted signal at 1200 px; "
                      "median, min, max over the changes.",
                      "first_s: the first simulate request, which compiles the model.",
                      "large_log: a synthetic Parquet simlog; variables_s lists names and "
                      "units only (the page's tree), signal_s fetches one variable "
                      "decimated to 1200 px (min/max per pixel column)."]}


if __name__ == "__main__":
    main(run)
