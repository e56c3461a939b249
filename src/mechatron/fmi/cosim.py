"""Co-simulation of a model with imported FMUs: the host integrated between communication
points, the FMUs stepped at them.

Why split the run rather than call the FMU from inside the solver (a CasADi ``Callback``):
the model's functions are SX, evaluated natively by CasADi's integrators, the fixed-step
loop (``mapaccum``) and the compiled Rodas4, none of which can call Python; and an FMU's
step is a communication-step operation, not a function of the state that a solver could
differentiate. Between communication points the host runs natively as any model does;
Python runs once per communication point.

One communication interval ``[t_k, t_k+1]`` (for the FMUs due at ``t_k``):

1. the tick at ``t_k`` has fired (the blocks' outputs took the values held for it, other
   sampled blocks read them in signal-flow order): read the FMU blocks' inputs ``u(t_k+)``;
2. each FMU takes them, steps over ``[t_k, t_k+1]`` and gives its outputs at ``t_k+1``,
   which go to the block's held parameters (read by its tick at ``t_k+1``);
3. the host integrates over ``[t_k, t_k+1]``; the tick at ``t_k+1`` fires inside the
   integration or, if the solver stopped just short of it, by the model's transition
   function called here (a no-op when it fired already).

Solvers: the fixed-step methods (``dt`` must divide every communication step), the
compiled ``rodas4`` (the default for ODE models: its library takes any time grid, so
intervals cost only the integration), and CasADi's variable-step plug-ins (an integrator is
built per interval and dropped after it).
"""

from __future__ import annotations

import time as _time

import numpy as np

from mechatron.errors import SimulationError

__all__ = ["cosimulate"]


def _interval_points(blocks, p, index, t0, t_stop, where):
    """The communication points of every block in ``[t0, t_stop]`` and the blocks due at
    each (rounded to 1e-9 of the step, as the model's clocks count ticks)."""
    due: dict[float, list[int]] = {}
    steps = []
    for b, blk in enumerate(blocks):
        Ts = float(p[index[blk["path"] + ".Ts"]])
        off = float(p[index[blk["path"] + ".offset"]])
        if not np.isfinite(Ts) or Ts <= 0:
            raise SimulationError(f"{blk['path']}: the communication step Ts must be > 0, "
                                  f"got {Ts!r}.", path=blk["path"])
        if off < t0 - 1e-9 * Ts:
            raise SimulationError(f"{blk['path']}: the first communication point (offset "
                                  f"{off:g} s) is before t0 = {t0:g} s. Set offset >= t0.",
                                  path=blk["path"])
        k = np.arange(0, int(np.floor((t_stop - off) / Ts + 1e-9)) + 1)
        if k.size > 10_000_000:
            raise SimulationError(f"{where}: {blk['path']} would take {k.size:,} "
                                  "communication steps. Choose a larger Ts.",
                                  path=blk["path"])
        for t in off + k * Ts:
            due.setdefault(float(t), []).append(b)
        steps.append(Ts)
    pts = sorted(set(due) | {float(t0), float(t_stop)})
    # merge points closer than 1e-9 of the smallest step (the same instant)
    merged: list[float] = []
    tol = 1e-9 * min(steps)
    dues: list[list[int]] = []
    for t in pts:
        if merged and t - merged[-1] <= tol:
            dues[-1] = dues[-1] + due.get(t, [])
            continue
        merged.append(t)
        dues.append(list(due.get(t, [])))
    return np.array(merged), dues, steps


def cosimulate(cm, t_stop: float, *, solver: str = "auto", dt: float | None = None,
               params: dict | None = None, inputs=None, rtol: float = 1e-6,
               atol: float = 1e-8, t_out=None, t0: float = 0.0, iterations: int = 3,
               max_step: float | None = None, newton: str = "check",
               compile_time: float | None = None):
    """Simulate the compiled model ``cm`` whose ``report["external_blocks"]`` lists FMU
    blocks (called by :func:`mechatron.simulate`; the arguments are its own).

    ``solver="auto"``: ``rodas4`` for an ODE model with constant external inputs, else
    the variable-step choice of :func:`mechatron.solvers.simulate.choose_auto`, made once
    at the start. The result logs every variable at ``t_out`` (default: 1001 points and
    every communication point); ``stats`` sums the intervals' solver counts and adds
    ``communication_steps``.
    """
    from mechatron.fmi.slaves import open_slave
    from mechatron.results import SimResult, SolverStats
    from mechatron.solvers.fixed import METHODS
    from mechatron.solvers.initial import initialize
    from mechatron.solvers.inputs import resolve_inputs
    from mechatron.solvers.native import MAX_STATES
    from mechatron.solvers.simulate import (_check_chattering, _event_times, _events,
                                            _max_step, choose_auto)

    where = f"model '{cm.name}'"
    blocks = [b for b in cm.report.get("external_blocks", []) if b.get("type") == "fmu"]
    if not np.isfinite(t_stop) or t_stop <= t0:
        raise SimulationError(f"{where}: t_stop must be a number > t0 = {t0:g}, got "
                              f"{t_stop!r}.", path=cm.name)
    index = {n: i for i, n in enumerate(cm.param_names)}
    names = {n: i for i, n in enumerate(cm.names)}
    p = cm.parameter_vector(params)
    ext = resolve_inputs(cm, inputs, params, t0, t_stop)
    if ext is not None:
        p = ext.apply(p)
    for blk in blocks:
        for port, _, _ in blk["parameters"] + blk["outputs"]:
            if blk["path"] + "." + port not in index and \
                    blk["path"] + ".next_" + port not in index:
                raise SimulationError(f"{blk['path']}: the parameter '{port}' is bound to "
                                      "an expression of another parameter; give the FMU "
                                      "block numbers.", path=blk["path"])
    pts, dues, steps = _interval_points(blocks, p, index, t0, t_stop, where)

    # the solver of the intervals
    fixed = solver in METHODS
    if fixed:
        if dt is None:
            raise SimulationError(f"{where}: solver '{solver}' needs a step dt.",
                                  path=cm.name)
        gaps = np.diff(pts)
        n = np.round(gaps / dt)
        if np.any(n < 1) or np.any(np.abs(n * dt - gaps) > 1e-9 * np.maximum(gaps, dt)):
            shown = ", ".join(f"{s:g}" for s in steps)
            raise SimulationError(f"{where}: the fixed step dt = {dt:g} s must divide "
                                  f"every communication interval (steps {shown} s, and "
                                  "t_stop). Choose dt = Ts / n.", path=cm.name)
    drive = ext is not None and ext.drive
    if solver == "auto":
        solver = "rodas4" if (cm.nz == 0 and 0 < cm.nx <= MAX_STATES and not drive) \
            else "auto"
    if solver == "rodas4" and drive:
        raise SimulationError(f"{where}: solver 'rodas4' takes constant inputs only; use "
                              "solver='rk45' or 'rosenbrock' for tables.", path=cm.name)

    # output grid: t_out, else 1001 points and every communication point
    if t_out is None:
        grid = np.union1d(np.linspace(t0, t_stop, 1001), pts)
    else:
        grid = np.asarray(t_out, dtype=float).ravel()
        if grid.size == 0 or np.any(np.diff(grid) <= 0) or grid[0] < t0 \
                or grid[-1] > t_stop * (1 + 1e-12):
            raise SimulationError(f"{where}: t_out must be strictly increasing times in "
                                  f"[t0, t_stop].", path=cm.name)

    def p_at(t):
        return p if ext is None else ext.columns(p, np.array([t]))[:, 0]

    clock = _time.perf_counter()
    slaves = []
    try:
        # FMUs: parameters from p, inputs at their start values, initialized at t0
        for blk in blocks:
            pars = {vr: p[index[blk["path"] + "." + port]] for port, _, vr in
                    blk["parameters"]}
            # the inputs keep the FMU's start values until the first step
            slaves.append(open_slave(blk, t0, pars, None, rtol=rtol, max_step=max_step))
        hold = [[index[blk["path"] + ".next_" + port] for port, _, _ in blk["outputs"]]
                for blk in blocks]
        reads = []
        for blk in blocks:
            ids = []
            for port, _, _ in blk["inputs"]:
                name = blk["path"] + "." + port
                if name not in names:
                    raise SimulationError(f"{blk['path']}: input '{port}' is not logged.",
                                          path=blk["path"])
                ids.append(names[name])
            reads.append(ids)
        for b, s in enumerate(slaves):
            p[hold[b]] = s.outputs()
        X, z, init_report = initialize(cm, p_at(t0), t0)
        plugin, reason = solver, "asked for"
        if solver == "auto":
            plugin, reason = choose_auto(cm, t0, t_stop, X, z, p_at(t0),
                                         _max_step(cm, p, grid, max_step))
            if plugin != "rodas4" and cm.nr == 0:
                plugin = "idas" if cm.nz else "cvodes"
        h_max = _max_step(cm, p, np.array([t0, t_stop]), max_step)
        counts = dict(steps=0, rejected=0, rhs=0, jac=0, unconverged=0)
        T, Ys = [], []
        y_now = np.array(cm.f_out(t0, X, z, p_at(t0)), dtype=float).ravel()
        if grid[0] == t0:
            T.append(t0)
            Ys.append(y_now)
        cache_keys = set(cm._cache)
        for j in range(len(pts) - 1):
            a, b = float(pts[j]), float(pts[j + 1])
            for k in dues[j]:                   # FMUs due at a: inputs after its tick
                s = slaves[k]
                s.set_inputs(y_now[reads[k]])
                due_next = [jj for jj in range(j + 1, len(pts)) if k in dues[jj]]
                h = (float(pts[due_next[0]]) if due_next else b) - a
                s.step(h)
                p[hold[k]] = s.outputs()
            inner = grid[(grid > a) & (grid < b)]
            if fixed and t_out is None:        # a fixed-step run logs every step
                inner = a + dt * np.arange(1, int(round((b - a) / dt)))
            seg = np.concatenate([[a], inner, [b]])
            X, z, Y = _segment(cm, plugin, fixed, seg, X, z, p, ext, dt=dt, rtol=rtol,
                               atol=atol, max_step=h_max, iterations=iterations,
                               newton=newton, counts=counts)
            # the ticks at b (if the solver stopped short of them) and the values after
            pb = p_at(b)
            X = np.array(cm.f_transition(-1, b, X, z, pb)[0], dtype=float).ravel()
            y_now = np.array(cm.f_out(b, X, z, pb), dtype=float).ravel()
            for i in range(1, len(seg) - 1):
                T.append(float(seg[i]))
                Ys.append(Y[:, i])
            if (fixed and t_out is None) or \
                    np.any(np.abs(grid - b) <= 1e-12 * max(1.0, abs(b))):
                T.append(b)
                Ys.append(y_now)
            for key in set(cm._cache) - cache_keys:     # per-interval integrators
                if isinstance(key, tuple) and key and key[0] == "var":
                    del cm._cache[key]
    finally:
        for s in slaves:
            s.close()
    _check_chattering(cm, X, plugin)
    stats = SolverStats(solver=plugin, steps=counts["steps"],
                        rejected_steps=counts["rejected"], rhs_evals=counts["rhs"],
                        jac_evals=counts["jac"],
                        solver_reason=f"{reason}; co-simulation of {len(blocks)} FMU(s)",
                        unconverged_steps=counts["unconverged"])
    stats.events = _events(cm, X)
    stats.wall_time = _time.perf_counter() - clock
    stats.compile_time = compile_time
    stats.communication_steps = len(pts) - 1
    Y = np.column_stack(Ys) if Ys else np.zeros((len(cm.names), 0))
    res = SimResult(np.array(T), Y, cm.names, cm.units, stats=stats, model_name=cm.name,
                    descriptions={n: d for n, d in zip(cm.names, cm.docs) if d})
    res.initialization = init_report
    res.event_times = _event_times(cm, X)
    return res


def _segment(cm, plugin, fixed, seg, X, z, p, ext, *, dt, rtol, atol, max_step,
             iterations, newton, counts):
    """Integrate the host over one communication interval on the points ``seg``; return
    the state and algebraic values at its end and the logged variables at ``seg``."""
    from mechatron.solvers.fixed import integrate_fixed
    from mechatron.solvers.logging import evaluate_outputs
    from mechatron.solvers.native import integrate_native
    from mechatron.solvers.variable import consistent_algebraics, integrate_variable
    a, b = float(seg[0]), float(seg[-1])
    if fixed:
        t, Y, Xf, unconv = integrate_fixed(cm, a, b, dt, X, z, p, method=plugin,
                                           iterations=iterations, inputs=ext, newton=newton)
        n = len(t) - 1
        counts["steps"] += n
        counts["unconverged"] += unconv
        row = {nm: i for i, nm in enumerate(cm.names)}
        zf = np.array([Y[row[nm], -1] for nm in cm.alg_names]) if cm.nz else z
        Yseg = np.vstack([np.interp(seg, t, r) for r in Y])
        Yseg[:, -1] = Y[:, -1]
        return Xf, zf, Yseg
    if plugin == "rodas4":
        Y, Xf, st = integrate_native(cm, seg, X, p, rtol=rtol, atol=atol, max_step=max_step)
        counts["steps"] += st["n_steps"]
        counts["rejected"] += st["n_reject"]
        counts["rhs"] += st["n_rhs"]
        counts["jac"] += st["n_jac"]
        return Xf, z, Y
    Xs, Z, st, used = integrate_variable(cm, seg, X, z, p, solver=plugin, rtol=rtol,
                                         atol=atol, max_step=max_step, inputs=ext)
    p_log = p if ext is None else ext.logged_columns(p, seg)
    if cm.nz and Z.size:
        Z = consistent_algebraics(cm, seg, Xs, Z, p_log, used)
    Y = evaluate_outputs(cm, seg, Xs, Z, p_log)
    counts["steps"] += int(st.get("n_steps", st.get("nsteps", 0)))
    counts["rejected"] += int(st.get("n_reject", st.get("netfails", 0)))
    counts["rhs"] += int(st.get("n_rhs", st.get("nfevals", 0)))
    counts["jac"] += int(st.get("n_jac", st.get("n_call_jacF", 0)))
    return Xs[:, -1], (Z[:, -1] if cm.nz else z), Y
