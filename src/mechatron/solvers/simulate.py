"""``mt.simulate``: compile if needed, initialize, integrate, log every variable."""

from __future__ import annotations

import time as _time
from collections.abc import Mapping

import casadi as ca
import numpy as np

from mechatron.compiler.compiled import CompiledModel
from mechatron.core.component import Component
from mechatron.errors import RunTooLargeError, SimulationError
from mechatron.results import SimResult, SolverStats
from mechatron.solvers.diagnose import describe_nonfinite
from mechatron.solvers.fixed import METHODS, integrate_fixed
from mechatron.solvers.hybrid import events_on_outputs, terminal_event
from mechatron.solvers.initial import initialize
from mechatron.solvers.inputs import resolve_inputs
from mechatron.solvers.logging import OutputColumns, evaluate_outputs, evaluate_point
from mechatron.solvers.native import auto_library, integrate_native, native_library
from mechatron.solvers.stiffness import probe
from mechatron.solvers.variable import PLUGINS, consistent_algebraics, integrate_variable

__all__ = ["simulate", "SOLVERS"]

SOLVERS = ("auto",) + tuple(PLUGINS) + ("rodas4",) + tuple(METHODS)
DEFAULT_POINTS = 1001

#: Default limit on the estimated memory of a fixed-step run (bytes): every step is kept.
MAX_MEMORY = 2e9


def check_fixed_step_size(cm: CompiledModel, t0: float, t_stop: float, dt,
                          max_memory: float | None = MAX_MEMORY) -> float:
    """Estimated memory (bytes) of a fixed-step run from ``t0`` to ``t_stop`` with step
    ``dt``: every step keeps the states and every logged value as float64. A
    :class:`SimulationError` with the estimate when it exceeds ``max_memory`` (``None``:
    no limit), before any work is done."""
    if isinstance(dt, bool) or not isinstance(dt, (int, float, np.floating, np.integer)) \
            or not (np.isfinite(dt) and dt > 0):
        raise SimulationError(f"model '{cm.name}': dt must be a step size > 0 in s for a "
                              f"fixed-step solver, got {dt!r}.", path=cm.name)
    steps = (float(t_stop) - float(t0)) / float(dt)
    size = (steps + 1) * (len(cm.names) + cm.nx) * 8.0
    if max_memory is not None and size > max_memory:
        raise RunTooLargeError(
            f"model '{cm.name}': dt = {dt:g} s over {t_stop - t0:g} s is {steps:.3g} fixed "
            f"steps, which would keep about {_bytes(size)} in memory ({len(cm.names)} "
            f"logged values and {cm.nx} states per step; limit max_memory = "
            f"{_bytes(max_memory)}). Give a larger dt (at least "
            f"{dt * size / max_memory:.3g} s) or a shorter t_stop; or max_memory=None to "
            "go on anyway (command line: --force).", path=cm.name)
    return size


def _bytes(n: float) -> str:
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n:.0f} B"


def simulate(model, t_stop: float, *, solver: str = "auto", dt: float | None = None,
             params: dict | None = None, inputs=None, rtol: float = 1e-6,
             atol: float = 1e-8, t_out=None, t0: float = 0.0, iterations: int = 3,
             max_step: float | None = None, newton: str = "check", log="states",
             linear_solver: str = "auto",
             max_memory: float | None = MAX_MEMORY) -> SimResult:
    """Simulate a model; its simlog has every variable.

    Parameters
    ----------
    model : Component or CompiledModel
        A model instance (compiled here) or a compiled model (reused, no recompilation).
    t_stop : float
        End time in s.
    solver : str
        ``"auto"`` (CVODES BDF for ODEs, IDAS for DAEs; for models with events
        Rosenbrock if the model is stiff at the start or a DAE, else rk45: see
        :func:`choose_auto`; ``stats.solver_reason`` says why), ``"cvodes"``, ``"idas"``, ``"rosenbrock"``, ``"rk45"``,
        ``"rodas4"`` (the model, a Rosenbrock integrator and its event handling compiled
        to one C library: the fastest for ODE models up to a few hundred states, see
        :mod:`mechatron.solvers.native`), or a fixed-step method: ``"euler"``,
        ``"heun"``, ``"rk4"``, ``"backward_euler"``, ``"trapezoidal"``, ``"ode14x"``.
    dt : float, optional
        Step size of a fixed-step solver (required for those).
    params : dict, optional
        Parameter values by instance path (numbers in SI or quantity strings).
    inputs : dict, optional
        Signals for the model's external inputs (signal inputs of its root component), by
        name: a constant, a ``(t, values)`` table (piecewise linear, held outside its
        range) or a function of time; see :mod:`mechatron.solvers.inputs`.
    rtol, atol : float
        Tolerances of the variable-step solvers.
    t_out : array_like, optional
        Output times of a variable-step run (default: 1001 points); fixed-step runs log
        every step.
    iterations : int
        Newton iterations per step of the implicit fixed-step methods (and of the
        algebraic unknowns of any fixed-step method).
    newton : {"check", "count"}
        What a fixed-step run does when ``iterations`` Newton iterations leave a step
        unconverged: ``"check"`` (default) raises a
        :class:`~mechatron.errors.SimulationError` naming the time and the unknowns;
        ``"count"`` keeps the fixed count, as a real-time target does, and reports the
        number of such steps in ``stats.unconverged_steps``.
    max_step : float, optional
        Largest step of the variable-step solvers (for models with events, by default a
        fiftieth of the simulated time, or half the shortest time scale a component
        declares).
    log : {"states", "all"} or list of str
        What a variable-step run stores: ``"states"`` (default) the trajectory (states,
        algebraic unknowns); a list of instance paths (variables, or components for every
        variable beneath them): those too; ``"all"``: every variable. Every variable of
        the simlog can be read in each case: one not stored is computed from the stored
        trajectory by the compiled output function when first read (the same values), so
        memory grows with states x time points. Fixed-step and ``"rodas4"`` runs store
        every variable.
    linear_solver : {"auto", "sparse", "dense"}
        Linear solver of the Newton iterations of CVODES and IDAS (see
        :data:`mechatron.solvers.variable.LINEAR_SOLVERS`): ``"auto"`` sparse QR, or
        for CVODES on a linear chain whose Jacobian is tridiagonal and diagonally
        dominant (an RC ladder) the Thomas algorithm (see
        :func:`mechatron.solvers.variable.auto_linear_solver`); ``"sparse"`` sparse LU,
        ``"dense"`` dense LU. The Jacobian's sparsity comes from the compiled model.
    max_memory : float or None
        Largest estimated memory (bytes) of a fixed-step run, which keeps every step: a
        run estimated above it is refused before it starts, with the estimate (default
        :data:`MAX_MEMORY`); ``None`` goes on anyway.
    """
    if solver not in SOLVERS:
        raise SimulationError(f"unknown solver '{solver}'. Choose one of "
                              f"{', '.join(SOLVERS)}.")
    if not (isinstance(log, str) and log in ("states", "all")) and (
            isinstance(log, str) or not all(isinstance(n, str) for n in log)):
        raise SimulationError(f"simulate: log must be 'states', 'all' or a list of "
                              f"instance paths, got {log!r}.")
    compile_time = None
    if isinstance(model, Component):
        from mechatron.compiler.pipeline import compile_model
        t_c = _time.perf_counter()
        cm = compile_model(model)
        compile_time = _time.perf_counter() - t_c
    elif isinstance(model, CompiledModel):
        cm = model
    else:
        raise TypeError(f"simulate: expected a Component or CompiledModel, got {model!r}.")
    if cm.report.get("external_blocks"):       # imported FMUs: a co-simulation
        from mechatron.fmi.cosim import cosimulate
        return cosimulate(cm, t_stop, solver=solver, dt=dt, params=params, inputs=inputs,
                          rtol=rtol, atol=atol, t_out=t_out, t0=t0, iterations=iterations,
                          max_step=max_step, newton=newton, compile_time=compile_time)
    if not np.isfinite(t_stop) or t_stop <= t0:
        raise SimulationError(f"model '{cm.name}': t_stop must be a number > t0 = {t0:g}, "
                              f"got {t_stop!r}.")
    asked = _asked_rows(cm, log)
    if solver in METHODS:
        check_fixed_step_size(cm, t0, t_stop, dt, max_memory)
    p = cm.parameter_vector(params)
    ext = resolve_inputs(cm, inputs, params, t0, t_stop)   # external inputs, or None
    if ext is not None:
        p = ext.apply(p)
    if solver == "rodas4" and ext is not None and ext.drive:
        raise SimulationError(f"model '{cm.name}': solver 'rodas4' takes constant "
                              "inputs only; for tables or functions of time use "
                              "solver='auto' (or 'cvodes', 'rk45').", path=cm.name)
    if solver == "rodas4" and "native_rodas4" not in cm._cache:
        # the model's C library is built (or loaded from the disk cache) once: that is
        # compilation, not simulation
        t_c = _time.perf_counter()
        native_library(cm)
        compile_time = (compile_time or 0.0) + (_time.perf_counter() - t_c)
    use_native = False
    if solver == "auto" and (ext is None or not ext.drive) and "native_auto" not in cm._cache:
        t_c = _time.perf_counter()
        if auto_library(cm) is not None:     # built now, or found in the disk cache
            compile_time = (compile_time or 0.0) + (_time.perf_counter() - t_c)
    if solver == "auto" and (ext is None or not ext.drive):
        use_native = auto_library(cm) is not None
    clock = _time.perf_counter()
    X0, z0, init_report = initialize(cm, p if ext is None else ext.columns(p, t0)[:, 0], t0)
    lazy = False
    native = None
    if solver == "rodas4" or use_native:
        try:
            native = _run_native(cm, t0, t_stop, t_out, X0, p, rtol, atol, max_step)
        except SimulationError:
            if not use_native:
                raise
            # auto: the compiled run failed (a value not finite, a step too small): the
            # variable-step path below diagnoses or integrates it
    if solver in METHODS:
        t, Y, Xf, unconverged = integrate_fixed(cm, t0, t_stop, dt, X0, z0, p,
                                                method=solver, iterations=iterations,
                                                inputs=ext, newton=newton)
        n = len(t) - 1
        if t_out is not None:
            t_req = np.asarray(t_out, dtype=float)
            Y = np.vstack([np.interp(t_req, t, row) for row in Y])
            t = t_req
        stats = SolverStats(solver=solver, steps=n, rejected_steps=0,
                            rhs_evals=n * _stages(solver), jac_evals=0,
                            solver_reason="asked for", unconverged_steps=unconverged)
    elif native is not None:
        t, Y, Xf, stats = native
        if use_native:
            stats.solver_reason = (f"no events, an ODE of {cm.nx} state(s): the model and "
                                   "a Rosenbrock method compiled to C (rodas4)")
    else:
        lazy = log != "all"
        if lazy:
            _state_rows(cm)    # probed once per model, before the integrator takes memory
        grid = _grid(cm, t0, t_stop, t_out)
        h_max = _max_step(cm, p, grid, max_step)
        plugin, reason = solver, "asked for"
        if solver == "auto":
            p_t0 = p if ext is None else ext.columns(p, t0)[:, 0]
            plugin, reason = choose_auto(cm, t0, t_stop, X0, z0, p_t0, h_max)
        X, Z, st, used = integrate_variable(cm, grid, X0, z0, p, solver=plugin, rtol=rtol,
                                            atol=atol, max_step=h_max, inputs=ext,
                                            linear_solver=linear_solver)
        p_log = p if ext is None else ext.logged_columns(p, grid)
        events_on_outputs(cm, grid, X, Z, p_log)
        if cm.nz and Z.size:
            Z = consistent_algebraics(cm, grid, X, Z, p_log, used)
        t, Xf = grid, X[:, -1]
        if t_out is not None and np.asarray(t_out, dtype=float)[0] != t0:
            t, X, Z = t[1:], X[:, 1:], Z[:, 1:]
            p_log = p_log[:, 1:] if np.ndim(p_log) == 2 else p_log
        if lazy:
            source = OutputColumns(cm.f_out, t, X, Z, p_log, cache=cm._cache)
        else:
            Y = evaluate_outputs(cm, t, X, Z, p_log)
        stats = SolverStats(solver=used,
                            steps=int(st.get("n_steps", st.get("nsteps", 0))),
                            rejected_steps=int(st.get("n_reject", st.get("netfails", 0))),
                            rhs_evals=int(st.get("n_rhs", st.get("nfevals", 0))),
                            jac_evals=int(st.get("n_jac", st.get("n_call_jacF", 0))),
                            solver_reason=reason)
    _check_chattering(cm, Xf, stats.solver)
    if cm.report.get("terminal_relations"):     # when(terminal()) acts at the last point
        if lazy:    # the outputs at the last point follow from the state after it
            Xf, _ = terminal_event(cm, float(t[-1]), Xf, z0, p)
            X[:, -1] = Xf
        else:
            Xf, Y[:, -1] = terminal_event(cm, float(t[-1]), Xf, z0, p)
        _check_chattering(cm, Xf, stats.solver)
    stats.events = _events(cm, Xf)
    if lazy and not (np.all(np.isfinite(X[:, -1])) and np.all(np.isfinite(source.last()))):
        lazy, Y = False, source(np.arange(len(cm.names)))
    stats.wall_time = _time.perf_counter() - clock
    stats.compile_time = compile_time
    names, units, index, descriptions = _log_names(cm)
    if lazy:
        rows, states, stored_at = _state_rows(cm)
        values = X[:cm.nx] if states == list(range(cm.nx)) else X[states]
        res = SimResult._of_model(t, values, names, units, index, descriptions,
                                  stats=stats, model_name=cm.name, stored=rows,
                                  source=source, stored_at=stored_at)
        res._keep(asked)
    else:
        if not np.all(np.isfinite(Y[:, -1])):
            _not_finite(cm, t, Y, Xf, p if ext is None else None)
        res = SimResult._of_model(t, Y, names, units, index, descriptions, stats=stats,
                                  model_name=cm.name)
    res.initialization = init_report
    res.event_times = _event_times(cm, Xf)
    return res


def _run_native(cm: CompiledModel, t0: float, t_stop: float, t_out, X0: np.ndarray,
                p: np.ndarray, rtol: float, atol: float, max_step: float | None):
    """The compiled Rodas4 run: ``(t, Y, Xf, stats)``."""
    grid = _grid(cm, t0, t_stop, t_out)
    Y, Xf, st = integrate_native(cm, grid, X0, p, rtol=rtol, atol=atol,
                                 max_step=_max_step(cm, p, grid, max_step))
    t = grid
    if t_out is not None and np.asarray(t_out, dtype=float)[0] != t0:
        t, Y = t[1:], Y[:, 1:]
    stats = SolverStats(solver="rodas4", steps=st["n_steps"], rejected_steps=st["n_reject"],
                        rhs_evals=st["n_rhs"], jac_evals=st["n_jac"],
                        solver_reason="asked for")
    return t, Y, Xf, stats


def _asked_rows(cm: CompiledModel, log) -> list[int]:
    """Rows of ``cm.names`` that ``log`` (a list of paths or component prefixes) asks for."""
    if isinstance(log, str):
        return []
    index = cm._cache.get("name_index")
    if index is None:
        index = cm._cache["name_index"] = {n: i for i, n in enumerate(cm.names)}
    rows: list[int] = []
    for path in log:
        row = index.get(path)
        if row is not None:
            rows.append(row)
            continue
        start = path.rstrip(".") + "."
        beneath = [i for i, n in enumerate(cm.names) if n.startswith(start)]
        if not beneath:
            import difflib
            close = difflib.get_close_matches(path, cm.names, 3)
            raise SimulationError(
                f"model '{cm.name}': log: '{path}' is neither a variable nor a component "
                "with variables." + (f" Did you mean {', '.join(close)}?" if close else
                                     " CompiledModel.names lists them all."),
                path=path, variables=close)
        rows += beneath
    return rows


def _log_names(cm: CompiledModel):
    """Names, units, name index and descriptions of the simlog, built once per model and
    shared by its results (a result never changes them)."""
    cached = cm._cache.get("log_names")
    if cached is None:
        names = list(map(str, cm.names))
        index = dict(zip(names, range(len(names))))
        if len(index) != len(names):    # a compiled model's names are unique
            raise SimulationError(f"model '{cm.name}': repeated logged variable names.")
        cached = cm._cache["log_names"] = (names, list(map(str, cm.units)), index,
                                           _Descriptions(names, cm.docs))
    return cached


class _Descriptions(Mapping):
    """The descriptions of a compiled model's logged variables by name (those it has),
    formed when first read: most runs never read one, and a model of 10^5 variables
    takes tens of milliseconds to form them."""

    __slots__ = ("_names", "_docs", "_map")

    def __init__(self, names: list[str], docs: list):
        self._names, self._docs, self._map = names, docs, None

    def _formed(self) -> dict[str, str]:
        if self._map is None:
            self._map = {n: str(d) for n, d in zip(self._names, self._docs) if d}
        return self._map

    def __getitem__(self, name: str) -> str:
        return self._formed()[name]

    def __iter__(self):
        return iter(self._formed())

    def __len__(self) -> int:
        return len(self._formed())


def _state_rows(cm: CompiledModel) -> tuple[list[int], list[int], dict[int, int]]:
    """The logged variables that are states: their rows in ``cm.names``, their indices
    in ``X``, and each row's place among them (``{row: k}``, shared read-only by every
    log of the model), for each state the output function returns unchanged, so a
    selective log stores the trajectory's rows as they are (no copy) and they equal what
    a full log holds bit for bit.

    Found by probing rather than by building the output's expression graph (which costs
    memory on large models): at three points where every input (time, states, algebraic
    unknowns, parameters) is drawn at random, of both signs, a row that returns the
    state's value bit for bit each time is the state itself (a row that depended on any
    other input, or transformed it, would match by coincidence only)."""
    cached = cm._cache.get("state_rows")
    if cached is None:
        index = _log_names(cm)[2]
        pairs = [(index[n], i) for i, n in enumerate(cm.state_names) if n in index]
        keep = np.ones(len(pairs), dtype=bool)
        if pairs:
            r = np.array([a for a, _ in pairs])
            i = np.array([b for _, b in pairs])
            rng = np.random.default_rng(20260517)
            for _ in range(3):
                X = rng.uniform(-2.0, 2.0, cm.nX)
                z = rng.uniform(-2.0, 2.0, cm.nz)
                p = cm.p0 * rng.uniform(0.5, 1.5, cm.p0.size) + rng.uniform(-1, 1,
                                                                         cm.p0.size)
                with np.errstate(all="ignore"):
                    y = evaluate_point(cm.f_out, [rng.uniform(0.1, 2.0), X, z, p])
                keep &= y[r] == X[i]
        rows = [a for k, (a, _) in enumerate(pairs) if keep[k]]
        states = [b for k, (_, b) in enumerate(pairs) if keep[k]]
        cached = cm._cache["state_rows"] = (rows, states,
                                            {r: k for k, r in enumerate(rows)})
    return cached


def choose_auto(cm: CompiledModel, t0: float, t_stop: float, X0: np.ndarray,
                z0: np.ndarray, p: np.ndarray, max_step: float | None) -> tuple[str, str]:
    """The variable-step solver of ``solver="auto"`` and why.

    Without events, BDF (CVODES; IDAS for a DAE), whose variable order and step suit
    stiff and non-stiff models alike. With events (located inside the integrator, which
    CasADi's SUNDIALS interfaces do only at output times): for a DAE the Rosenbrock
    method; for an ODE the stiffness probe of :mod:`mechatron.solvers.stiffness` decides
    between the L-stable Rosenbrock method (stiff) and Dormand-Prince (``rk45``)."""
    if not cm.nr:
        return ("idas" if cm.nz else "cvodes"), "no events: BDF suits stiff and non-stiff"
    if cm.nz:
        return "rosenbrock", (f"events and {cm.nz} algebraic unknown(s): the Rosenbrock "
                              "method integrates the DAE and locates the events")
    verdict = probe(cm, t0, X0, z0, p, t_stop - t0, max_step)
    return ("rosenbrock" if verdict.stiff else "rk45"), "events, " + verdict.reason()


def _max_step(cm: CompiledModel, p: np.ndarray, grid: np.ndarray,
              max_step: float | None) -> float | None:
    """The largest step of a variable-step run: the user's, else half the shortest time
    scale a component declares, else (for models with events) a fiftieth of the run."""
    if max_step is None and cm.f_scales is not None and cm.f_scales.size1_out(0):
        scales = np.array(cm.f_scales(p), dtype=float).ravel()
        scales = scales[np.isfinite(scales) & (scales > 0)]
        if scales.size:
            max_step = 0.5 * float(scales.min())
    if max_step is None and cm.nr:
        # an event indicator that depends on time directly (a sine through a
        # quantizer) can cross and cross back within one long step of a model whose
        # states barely move; Simulink's default bounds the step the same way
        max_step = (float(grid[-1]) - float(grid[0])) / 50
    return max_step


def _grid(cm: CompiledModel, t0: float, t_stop: float, t_out) -> np.ndarray:
    """The output grid of a variable-step run: ``t_out`` (checked) or 1001 points, always
    starting at ``t0``."""
    if t_out is None:
        return np.linspace(t0, t_stop, DEFAULT_POINTS)
    grid = np.asarray(t_out, dtype=float).ravel()
    if grid.size == 0 or not np.all(np.isfinite(grid)) or np.any(np.diff(grid) <= 0) \
            or grid[0] < t0:
        shown = ", ".join(f"{v:g}" for v in grid[:4]) + (" ..." if grid.size > 4 else "")
        raise SimulationError(f"model '{cm.name}': t_out must be finite, strictly "
                              f"increasing times from t0 = {t0:g} s on; got [{shown}].",
                              path=cm.name)
    return grid if grid[0] == t0 else np.concatenate([[t0], grid])


def _stages(method: str) -> int:
    m = METHODS[method]
    return len(m.c) if hasattr(m, "c") else 2


def _check_chattering(cm: CompiledModel, Xf: np.ndarray, solver: str) -> None:
    """Raise if the transition marked a relation as chattering (see
    :mod:`mechatron.compiler.events`): after its event it was driven straight back onto
    its switching surface, so it would switch again at once, endlessly."""
    from mechatron.compiler.compiled import CHATTER_FLAG, LOOP_FLAG
    nx, nr = cm.nx, cm.nr
    looping = [k for k in range(nr) if Xf[nx + nr + k] >= 0.75 * LOOP_FLAG]
    if looping:
        t_ev = float(Xf[nx + 2 * nr + looping[0]])
        from mechatron.solvers.hybrid import loop_message
        raise SimulationError(loop_message(cm, looping, f"at t = {t_ev:.9g} s ({solver})"),
                              path=cm.name, variables=[cm.relations[k][0] for k in looping])
    bad = [k for k in range(nr) if Xf[nx + nr + k] >= 0.5 * CHATTER_FLAG]
    if not bad:
        return
    owners = []
    for k in bad:
        if cm.relations[k][0] not in owners:
            owners.append(cm.relations[k][0])
    k = bad[0]
    t_ev = float(Xf[nx + 2 * nr + k])
    count = int(round(Xf[nx + nr + k] % CHATTER_FLAG))
    raise SimulationError(
        f"model '{cm.name}': {solver}: chattering at t = {t_ev:.9g} s: events at "
        f"'{', '.join(o or cm.name for o in owners)}' would repeat without end (after "
        f"event {count} the switched dynamics drive the relation straight back across its "
        "switching surface, a sliding mode). Add hysteresis (blocks.Relay), a dead zone, "
        "or smooth the switching law.", path=owners[0] or cm.name, variables=owners)


def _events(cm: CompiledModel, Xf: np.ndarray) -> dict[str, int]:
    counts: dict[str, int] = {}
    nx, nr = cm.nx, cm.nr
    for k, (owner, _) in enumerate(cm.relations):
        n = int(round(Xf[nx + nr + k]))
        if n:
            counts[owner] = counts.get(owner, 0) + n
    return counts


def _event_times(cm: CompiledModel, Xf: np.ndarray) -> dict[str, float]:
    """Time of the last event of each component that had one."""
    out: dict[str, float] = {}
    nx, nr = cm.nx, cm.nr
    for k, (owner, _) in enumerate(cm.relations):
        if Xf[nx + nr + k] > 0:
            out[owner] = max(out.get(owner, -np.inf), float(Xf[nx + 2 * nr + k]))
    return out


def _not_finite(cm: CompiledModel, t, Y, Xf, p) -> None:
    """Raise the error for a run whose logged values stop being finite: from when, which
    variables, and (replaying the model's functions at that point) which operation on
    which values broke first."""
    cols = np.nonzero(~np.all(np.isfinite(Y), axis=0))[0]
    k = int(cols[0]) if cols.size else Y.shape[1] - 1
    bad = [cm.names[i] for i in np.nonzero(~np.isfinite(Y[:, k]))[0][:5]]
    cause = ""
    if p is not None:
        row = {n: i for i, n in enumerate(cm.names)}
        xi = [row.get(n) for n in cm.state_names]
        zi = [row.get(n) for n in cm.alg_names]
        # the replay needs the event modes at that point: known for a model without
        # relations, or at the last point (the final modes)
        if None not in xi and None not in zi and (not cm.nr or k == Y.shape[1] - 1):
            def point(j):
                X = np.concatenate([Y[xi, j], np.asarray(Xf, dtype=float)[cm.nx:]])
                return [t[j], X, Y[zi, j], p]
            if np.all(np.isfinite(Y[xi, k])):     # states fine: an output broke
                cause = describe_nonfinite(cm.f_out, point(k), cm.names, t[k])
            elif k > 0:                           # states broke: their derivatives
                cause = describe_nonfinite(cm.f_ode, point(k - 1),
                                           [f"der({n})" for n in cm.state_names], t[k - 1])
    hint = ("Check the parameters and the equation named." if cause else
            "The step may be too large for a fixed-step solver, or the model unstable.")
    raise SimulationError(f"model '{cm.name}': the solution is not finite from t = "
                          f"{t[k]:g} s on ({', '.join(bad)})"
                          + (f": {cause}" if cause else "") + f". {hint}",
                          path=cm.name, variables=bad)

