"""Variable-step simulation with SUNDIALS (CVODES for ODEs, IDAS for DAEs) through CasADi.

Relations are event modes: CasADi locates each zero crossing of ``s * d`` on the dense
output and calls the compiled transition function, which flips the mode, counts the event
and stores its time, all in native code. The integrator for a given output grid and
tolerances is built once and cached on the compiled model, so a second run with other
parameters costs only the integration. A large model's run goes over segments of the
output grid (see :data:`SEGMENT_VALUES`), so that CasADi does not keep an index per value
of the whole trajectory.
"""

from __future__ import annotations

import contextlib
import os
import sys

import casadi as ca
import numpy as np

from mechatron.compiler.compiled import CompiledModel
from mechatron.errors import SimulationError
from mechatron.solvers.fpenv import subnormals_flushed
from mechatron.solvers.hybrid import EVENT_TOL
from mechatron.solvers.inputs import driven_parameters
from mechatron.solvers.logging import evaluate_point

__all__ = ["integrate_variable", "consistent_algebraics", "held_states", "LINEAR_SOLVERS",
           "linear_solver_for", "auto_linear_solver", "linear_form", "LinearForm"]

#: Newton iterations that polish the algebraic unknowns at the output times
Z_ITERATIONS = 3


@contextlib.contextmanager
def _quiet_stderr():
    """Silence CasADi's C++ warning that event support is experimental (printed on the
    process's stderr when an integrator with events is created)."""
    try:
        fd = sys.stderr.fileno()
    except (AttributeError, ValueError, OSError):
        yield
        return
    sys.stderr.flush()
    saved = os.dup(fd)
    with open(os.devnull, "w") as null:
        os.dup2(null.fileno(), fd)
        try:
            yield
        finally:
            os.dup2(saved, fd)
            os.close(saved)

#: Linear solvers of the Newton iterations of CVODES and IDAS, by the name ``simulate``
#: takes, with the CasADi plug-in each uses. The Jacobian's sparsity comes from the
#: compiled model's expression graph (CasADi's automatic differentiation keeps it), and a
#: sparse solver factorizes only its nonzeros: on an RC ladder the iteration matrix is
#: tridiagonal, so a step costs O(N) rather than the O(N^3) of a dense factorization.
LINEAR_SOLVERS = {
    "auto": "qr",           # sparse QR (CasADi's own), for any size; see auto_linear_solver
    "sparse": "csparse",    # sparse LU with partial pivoting (CSparse)
    "dense": "lapacklu",    # dense LU (LAPACK): every entry, for comparison and tiny models
}

#: The plug-in ``linear_solver="auto"`` takes for a tridiagonal system it may solve
#: without pivoting (the Thomas algorithm, O(N) with no fill): see
#: :func:`auto_linear_solver`.
TRIDIAGONAL = "tridiag"

PLUGINS = {"cvodes": "cvodes", "bdf": "cvodes", "idas": "idas", "rosenbrock": "rosenbrock",
           "rk45": "erk"}


def choose_plugin(cm: CompiledModel, solver: str) -> str:
    """``auto``: CVODES (BDF) for ODEs, IDAS for DAEs. With events (CasADi's SUNDIALS
    interfaces check zero crossings only between output times): Dormand-Prince 5(4)
    (``erk``) for ODEs, which locates events correctly on any output grid, and the
    L-stable Rosenbrock method for DAEs (CasADi's Rosenbrock plug-in mislocates events
    that fall between the output times of a dense grid: a 10 kHz PWM on a 1001-point
    grid keeps its switch on for whole periods)."""
    if solver == "auto":
        return ("erk" if not cm.nz else "rosenbrock") if cm.nr else ("idas" if cm.nz else "cvodes")
    plugin = PLUGINS[solver]
    if cm.nz and plugin in ("cvodes", "erk"):
        return "idas" if plugin == "cvodes" else "rosenbrock"
    return plugin


def linear_solver_for(cm: CompiledModel, choice: str) -> str:
    """The CasADi linear solver plug-in for ``simulate(linear_solver=choice)``."""
    plugin = LINEAR_SOLVERS.get(choice)
    if plugin is None:
        raise SimulationError(f"model '{cm.name}': unknown linear_solver {choice!r}. Choose "
                              f"one of {', '.join(map(repr, LINEAR_SOLVERS))}.",
                              path=cm.name)
    return plugin


def auto_linear_solver(cm: CompiledModel, plugin: str, p: np.ndarray,
                       drive: tuple = ()) -> str:
    """The plug-in of ``linear_solver="auto"``: the Thomas algorithm for a CVODES run of
    a linear, time-invariant ODE whose Jacobian ``J`` is tridiagonal (a chain: an RC
    ladder, a discretized rod or line) and, at the parameters ``p``, has
    ``J_ii <= 0`` and ``|J_ii| >= sum_j |J_ij|`` (j != i) in every row; sparse QR
    otherwise.

    CVODES solves ``(I - gamma J) d = r`` with ``gamma > 0``. Under those conditions
    that matrix is strictly diagonally dominant by rows for every ``gamma``, which is
    what the Thomas algorithm (elimination without pivoting) needs to be stable and
    never meet a zero pivot; a linear model's ``J`` does not change along the run, so
    checking it once at ``p`` covers every step. Anything else (a DAE, events,
    inputs given as tables, a Jacobian that depends on the states or on time, a band
    wider than one, a row that is not dominant) keeps the general sparse QR."""
    fallback = LINEAR_SOLVERS["auto"]
    if plugin != "cvodes" or cm.nz or cm.nr or drive or cm.nX < 3:
        return fallback
    form = _tridiagonal_form(cm)
    if form is None:
        return fallback
    key = np.asarray(p, dtype=float).tobytes()
    last = cm._cache.get("tridiagonal_p")
    if last is not None and last[0] == key:
        return last[1]
    values, rows, cols = form.nonzeros(p), form.rows, form.cols
    on_diag = rows == cols
    diag = np.zeros(cm.nX)
    diag[rows[on_diag]] = values[on_diag]
    off = np.bincount(rows[~on_diag], np.abs(values[~on_diag]), minlength=cm.nX)
    safe = np.all(np.isfinite(values)) and np.all(diag <= 0.0) and np.all(-diag >= off)
    cm._cache["tridiagonal_p"] = (key, TRIDIAGONAL if safe else fallback)
    return TRIDIAGONAL if safe else fallback


def _tridiagonal_form(cm: CompiledModel) -> LinearForm | None:
    """The model's `LinearForm` when its pattern with the diagonal added is the full
    tridiagonal band (what CasADi's ``tridiag`` plug-in indexes), else None; decided once
    per model."""
    cached = cm._cache.get("tridiagonal_form")
    if cached is None:
        form = linear_form(cm)
        # (the comparison forms two patterns of nX columns: about 0.1 ms at 1000 states,
        # once per model rather than on every run)
        cached = cm._cache["tridiagonal_form"] = form if form is not None and (
            form.sparsity + ca.Sparsity.diag(cm.nX) == ca.Sparsity.banded(cm.nX, 1)) \
            else False
    return cached or None


#: Fewest states for which a linear, time-invariant ODE runs in the linear form (see
#: :func:`linear_form`): below it the compiled Rodas4 of ``solver="auto"`` or the
#: expression graph's own evaluation cost less than a matrix-vector product's set-up.
LINEAR_FORM_STATES = 100


class LinearForm:
    """A linear, time-invariant ODE ``der(X) = A(p) X + c(t, p)``: ``jacobian`` gives
    ``A`` at the parameters (a sparse matrix of pattern ``sparsity``, nonzeros at
    ``rows, cols``), ``offset`` gives ``c``."""

    def __init__(self, jacobian: ca.Function, offset: ca.Function) -> None:
        self.jacobian, self.offset = jacobian, offset
        self.sparsity = jacobian.sparsity_out(0)
        self.rows, self.cols = (np.asarray(v, dtype=np.int64)
                                for v in self.sparsity.get_triplet())
        self._last: tuple | None = None     # the last parameters and their nonzeros

    def nonzeros(self, p: np.ndarray) -> np.ndarray:
        """The nonzeros of ``A(p)``, column by column (read-only). Those of the last
        parameters are kept: a run and the choice of its linear solver
        (`auto_linear_solver`) evaluate ``A`` once between them."""
        p = np.asarray(p, dtype=float)
        key = p.tobytes()
        last = self._last
        if last is None or last[0] != key:
            with np.errstate(all="ignore"):
                values = evaluate_point(self.jacobian, [p])
            values.flags.writeable = False
            last = self._last = (key, values)
        return last[1]


def linear_form(cm: CompiledModel) -> LinearForm | None:
    """The :class:`LinearForm` of an ODE model whose right-hand side is linear in the
    states with a Jacobian that depends on the parameters alone (an RC or RLC network, a
    thermal network, a chain of masses, springs and dampers), or None; decided once per
    model from the expression graph, never from values.

    A CVODES run of such a model (``integrate_variable``, without events, algebraic
    unknowns or input tables, and with at least :data:`LINEAR_FORM_STATES` states)
    evaluates its right-hand side as one sparse matrix-vector product ``A X`` with
    ``A``'s nonzeros computed once per run, plus ``c(t, p)``: CasADi's product kernel
    is about twice as fast as its expression-graph evaluation of the same sums on an
    RC ladder, and the Jacobian CVODES asks for is ``A`` itself. A model whose ``A``
    has more nonzeros than its right-hand side's graph has instructions keeps the
    graph."""
    cached = cm._cache.get("linear_form")
    if cached is None:
        cached = False
        if cm.nX and not cm.nz:
            t, X = ca.SX.sym("t"), ca.SX.sym("X", cm.nX)
            z, p = ca.SX.sym("z", 0), ca.SX.sym("p", cm.p0.size)
            ode = cm.f_ode(t, X, z, p)
            J = ca.jacobian(ode, X)
            # (the product costs about as much per nonzero as the graph per
            # instruction: a denser A than the graph's own work keeps the graph)
            if not ca.depends_on(J, ca.vertcat(t, X)) \
                    and J.nnz() <= cm.f_ode.n_instructions():
                offset = ca.substitute(ode, X, ca.DM.zeros(cm.nX))
                # the offset keeps its structural zeros (a ladder's is nonzero in its
                # first row only): the product's result takes it as a sparse sum
                cached = LinearForm(ca.Function("jac_ode", [p], [J]),
                                    ca.Function("ode_offset", [t, p], [ca.sparsify(offset)]))
        cm._cache["linear_form"] = cached
    return cached or None


def _uses_linear_form(cm: CompiledModel, plugin: str, drive: tuple) -> bool:
    return (plugin == "cvodes" and not cm.nr and not drive and cm.nX >= LINEAR_FORM_STATES
            and linear_form(cm) is not None)


def held_states(cm: CompiledModel) -> list[int]:
    """Entries of ``X`` held constant between events: discrete states (``der = 0``), the
    relations' modes, event counters and event times."""
    cached = cm._cache.get("held")
    if cached is None:
        t, X = ca.SX.sym("t"), ca.SX.sym("X", cm.nX)
        z, p = ca.SX.sym("z", cm.nz), ca.SX.sym("p", cm.p0.size)
        rhs = cm.f_ode(t, X, z, p)
        cached = cm._cache["held"] = [k for k in range(cm.nX) if rhs[k].is_zero()]
    return cached


def _hide(X: ca.MX, held: list[int]) -> ca.MX:
    """``X`` with its held entries cut from differentiation.

    A Rosenbrock step solves ``(I/(h gamma) - J) U = F + ...`` by a QR factorization; the
    columns of ``J`` for held states (a PWM's latched switch-off time, the relations'
    modes) mix the rounding of the other rows into their stage values, so a held state
    used to drift by a few ulps per step (a mode of 0.9999999999999994 then counted as an
    event by the transition, a counter above 0 taken for a recent event). Its stage
    values are zero exactly anyway (its row of ``F`` is zero and its row of ``J`` too), so
    dropping those columns leaves the step unchanged and makes ``U = 0`` exact."""
    n = X.numel()
    rows = [k for k in range(n) if k not in set(held)]
    keep = ca.DM(ca.Sparsity.triplet(n, 1, rows, [0] * len(rows)), 1.0)
    cut = ca.DM(ca.Sparsity.triplet(n, 1, list(held), [0] * len(held)), 1.0)
    return keep * X + ca.stop_diff(cut * X, 1)


def _model(cm: CompiledModel) -> ca.Function:
    """``(t, X, z, p) -> (ode, alg, zero)`` as one SX function (one call in an MX graph)."""
    fn = cm._cache.get("dae_sx")
    if fn is None:
        t, X = ca.SX.sym("t"), ca.SX.sym("X", cm.nX)
        z, p = ca.SX.sym("z", cm.nz), ca.SX.sym("p", cm.p0.size)
        outs = [cm.f_ode(t, X, z, p), cm.f_alg(t, X, z, p) if cm.nz else ca.SX(0, 1),
                cm.f_zero(t, X, z, p) if cm.nr else ca.SX(0, 1)]
        fn = cm._cache["dae_sx"] = ca.Function("model", [t, X, z, p],
                                               [ca.densify(o) for o in outs])
    return fn


def _integrator(cm: CompiledModel, plugin: str, grid: np.ndarray, rtol: float,
                atol: float, max_step: float | None, drive: tuple = (),
                linear_solver: str = "qr", shifted: bool = False) -> ca.Function:
    # drive: (p slot, table length) of each external input given as a table; the tables
    # are data of the integrator's parameter vector (see mechatron.solvers.inputs);
    # linear_solver: the CasADi plug-in (not the name simulate takes); shifted: the
    # integrator runs from 0 over ``grid`` (times after the start of a segment) and
    # takes the segment's start time as one more parameter, so that one integrator
    # serves every segment of a chunked run (see integrate_variable)
    key = ("var", plugin, grid.size, float(grid[0]), float(grid[-1]), hash(grid.tobytes()),
           rtol, atol, max_step, drive, linear_solver, shifted,
           _uses_linear_form(cm, plugin, drive))
    cached = cm._cache.get(key)
    if cached is not None:
        return cached
    held = held_states(cm) if plugin == "rosenbrock" else []
    # the linear form: A's nonzeros follow the parameters (see integrate_variable)
    form = linear_form(cm) if key[-1] else None
    # MX passes input tables as blocks, not elements, can hide held states from AD and
    # multiplies a sparse matrix in one kernel
    S = ca.MX if drive or held or form is not None else ca.SX
    tau = S.sym("t")
    # SUNDIALS needs at least one state: a model of algebraic equations only gets a
    # constant dummy state (dropped again by integrate_variable)
    pad = 1 if cm.nX == 0 else 0
    Xi = S.sym("X", cm.nX + pad)
    X = Xi[:cm.nX]
    Xd = _hide(X, held) if held else X     # X as the step's Jacobian sees it
    z = S.sym("z", cm.nz)
    n_p = cm.p0.size + 2 * sum(n for _, n in drive)
    n_a = form.sparsity.nnz() if form is not None else 0
    p = S.sym("p", n_p + n_a + (1 if shifted else 0))
    t = tau + p[n_p + n_a] if shifted else tau      # the model's time
    pm = p[:n_p] if shifted or n_a else p
    pe = driven_parameters(cm.p0.size, t, pm, drive) if drive else pm
    u = S.sym("u", 0)
    empty = S(0, 1)
    if form is not None:
        # c(t, p) as one SX function of the whole parameter vector: no copy of its
        # model part per evaluation
        ts, ps = ca.SX.sym("t"), ca.SX.sym("p", p.numel())
        offset = ca.Function("offset", [ts, ps], [form.offset(
            ts + ps[n_p + n_a] if shifted else ts, ps[:n_p])])
        ode = ca.densify(ca.mtimes(S(form.sparsity, p[n_p:n_p + n_a]), X) + offset(tau, p))
        alg = zero = empty
    elif S is ca.MX:
        ode, alg, zero = _model(cm)(t, Xd, z, pe)
    else:
        ode = cm.f_ode(t, X, z, pe)
        alg = cm.f_alg(t, X, z, pe) if cm.nz else empty
        zero = cm.f_zero(t, X, z, pe) if cm.nr else empty
    outs = [ca.vertcat(ode, S.zeros(pad)), alg if cm.nz else empty, empty,
            zero if cm.nr else empty]
    outs = [ca.densify(o) for o in outs]
    dae = ca.Function("dae", [tau, Xi, z, p, u], outs, ca.dyn_in(), ca.dyn_out())
    opts = {"abstol": atol, "reltol": rtol, "max_num_steps": 10_000_000}
    if plugin in ("cvodes", "idas"):
        opts["print_stats"] = False
        opts["linear_solver"] = linear_solver
    if max_step:
        opts["max_step_size"] = max_step
    if cm.nr:
        idx = S.sym("index")
        post_x, post_z = cm.f_transition(idx, t, X, z, pe)
        opts["transition"] = ca.Function("transition", [idx, tau, X, z, p, u],
                                         [post_x, post_z], ca.event_in(), ca.event_out())
        opts["event_tol"] = EVENT_TOL
        opts["max_events"] = 100_000_000
        opts["max_event_iter"] = 100
    if plugin == "idas":
        opts["calc_ic"] = True
    with _quiet_stderr():
        integ = ca.integrator(f"sim_{cm.name}", plugin, dae,
                              0.0 if shifted else float(grid[0]), grid, opts)
    if linear_solver == TRIDIAGONAL and not (
            integ.has_function("jacF") and integ.get_function("jacF").sparsity_out(0)
            + ca.Sparsity.diag(cm.nX) == ca.Sparsity.banded(cm.nX, 1)):
        # the plug-in reads three entries per column: only the full band will do
        return _integrator(cm, plugin, grid, rtol, atol, max_step, drive,
                           LINEAR_SOLVERS["auto"], shifted)
    cm._cache[key] = integ
    return integ


@subnormals_flushed()
def integrate_variable(cm: CompiledModel, grid: np.ndarray, X0: np.ndarray, z0: np.ndarray,
                       p: np.ndarray, *, solver: str, rtol: float, atol: float,
                       max_step: float | None = None, inputs=None,
                       linear_solver: str = "auto"):
    """Integrate on ``grid``; return ``(X, Z, stats)`` with one column per grid point.

    ``inputs`` (:class:`mechatron.solvers.inputs.Inputs`, optional) drives the model's
    external inputs; ``linear_solver`` is one of :data:`LINEAR_SOLVERS` (see
    :func:`linear_solver_for`)."""
    plugin = choose_plugin(cm, solver)
    if cm.nr and plugin in ("cvodes", "idas"):
        owners = sorted({owner or cm.name for owner, _ in cm.relations})
        raise SimulationError(
            f"model '{cm.name}': solver '{solver}' cannot locate the events of "
            f"{', '.join(owners[:6])}{' ...' if len(owners) > 6 else ''}: CasADi's SUNDIALS "
            "interface checks zero crossings only at output times. Use solver='auto' or "
            "'rosenbrock' (stiff) or 'rk45'.", path=cm.name)
    if cm.nX == 0 and cm.nz == 0:   # outputs are functions of time alone
        return np.zeros((0, grid.size)), np.zeros((0, grid.size)), {}, "none"
    drive = inputs.drive if inputs is not None else ()
    if drive:
        p = inputs.integrator_parameters(p)
    linsol = linear_solver_for(cm, linear_solver)
    if linear_solver == "auto":
        linsol = auto_linear_solver(cm, plugin, p, drive)
    pad = 1 if cm.nX == 0 else 0
    # CasADi's buffer interface: the integrator reads and writes NumPy memory directly
    # (a casadi.DM of the trajectory costs more to convert than the integration itself
    # on large models); the trajectory is column-major, one column per grid point
    x0 = np.ascontiguousarray(np.concatenate([X0, np.zeros(pad)]), dtype=float)
    zz0 = np.ascontiguousarray(z0, dtype=float)
    pp = np.ascontiguousarray(p, dtype=float)
    if _uses_linear_form(cm, plugin, drive):
        pp = np.concatenate([pp, linear_form(cm).nonzeros(pp)])
    xs = np.empty((grid.size, cm.nX + pad))
    zs = np.empty((grid.size, cm.nz))
    segments = _segments(grid, cm.nX + pad + cm.nz) if plugin in ("cvodes", "idas") else None
    try:
        if segments is None:
            integ = _integrator(cm, plugin, grid, rtol, atol, max_step, drive, linsol)
            stats = _run(integ, x0, zz0, pp, xs, zs)
        else:
            stats = _run_segments(cm, plugin, grid, segments, rtol, atol, max_step, drive,
                                  linsol, x0, zz0, pp, xs, zs)
    except RuntimeError as exc:
        cause = _nonfinite_cause(cm, float(grid[0]), X0, z0, p, drive)
        raise SimulationError(_explain(cm, str(exc)) + (f" At the start: {cause}." if cause
                                                        else ""), path=cm.name) from None
    X = xs.T[:cm.nX]      # (nX, n) views, no copies
    Z = zs.T
    return X, Z, stats, plugin


#: A variable-step run whose trajectory has more values than this (64 MB) is integrated
#: over segments of the output grid: a CasADi integrator keeps the sparsity pattern of
#: its output (one index per value, as many bytes as the trajectory itself, built twice
#: over while the integrator is made), so one integrator over the whole grid of a large
#: model would hold a second copy of the trajectory's size for as long as it is cached.
#: Each segment restarts the solver from the state the previous one ended with (a BDF
#: restart: order 1 and a fresh initial step), so the results differ from one pass
#: within the tolerances, and the steps grow by a few per segment.
SEGMENT_VALUES = 1 << 23


#: Most integrators (distinct times after a segment's start) a chunked run may build:
#: a grid whose segments need more runs in one pass.
SEGMENT_KINDS = 3


def _segments(grid: np.ndarray, width: int) -> list[tuple[int, int, np.ndarray]] | None:
    """``[(a, b, tau), ...]``: the output points ``grid[a..b]`` of each segment of a
    chunked run (consecutive segments share their end point) and their times after the
    segment's start, ``tau``; or None for one pass. Segments are equal in length but
    the last; segments whose times after their start agree to the rounding of the
    grid's times share one ``tau`` (one integrator), as on a uniform grid (with, say, a
    different first or shorter last segment); a grid that would need more than
    :data:`SEGMENT_KINDS` integrators runs in one pass."""
    n = grid.size
    if width * n <= SEGMENT_VALUES or n < 3:
        return None
    per = max(1, SEGMENT_VALUES // width - 1)        # intervals per segment
    count = -(-(n - 1) // per)
    per = -(-(n - 1) // count)                       # balanced
    tol = 8 * np.finfo(float).eps * float(np.max(np.abs(grid)))
    kinds: list[np.ndarray] = []
    out = []
    for a in range(0, n - 1, per):
        b = min(a + per, n - 1)
        rel = grid[a + 1:b + 1] - grid[a]
        tau = next((k for k in kinds if k.size == rel.size
                    and np.max(np.abs(k - rel)) <= tol), None)
        if tau is None:
            if len(kinds) == SEGMENT_KINDS:
                return None
            tau = rel
            kinds.append(tau)
        out.append((a, b, tau))
    return out


def _run(integ: ca.Function, x0, z0, p, xs: np.ndarray, zs: np.ndarray) -> dict:
    """One integrator call through the buffer interface: ``x0, z0, p`` in, the
    trajectory written into ``xs, zs`` (one row per output time); its statistics."""
    buf, evaluate = integ.buffer()
    buf.set_arg(0, memoryview(x0))
    buf.set_arg(1, memoryview(z0))
    buf.set_arg(2, memoryview(p))
    buf.set_res(0, memoryview(xs.reshape(-1)))
    buf.set_res(1, memoryview(zs.reshape(-1)))
    try:
        before = buf.stats()    # the calls and times of earlier runs (on this memory)
    except RuntimeError:        # none yet
        before = {}
    evaluate()
    stats = buf.stats()
    for k, v in before.items():
        if k.startswith(_LIFETIME) and isinstance(v, (int, float)):
            stats[k] = stats[k] - v
    return stats


#: CasADi's counts and times of the calls of the model's functions (``n_call_jacF``:
#: Jacobians) add up over the integrator's lifetime: :func:`_run` subtracts what earlier
#: runs left, so that a run reports its own.
_LIFETIME = ("n_call_", "t_proc_", "t_wall_")
#: Statistics that count one call's work, added over the segments of a chunked run (the
#: others, such as the last step size, are the last segment's).
_PER_CALL = ("nsteps", "nfevals", "nlinsetups", "netfails", "nniters", "nncfails",
             "n_steps", "n_reject", "n_rhs", "n_jac")


def _run_segments(cm: CompiledModel, plugin: str, grid: np.ndarray, segments, rtol: float,
                  atol: float, max_step, drive, linsol: str, x0, z0, p,
                  xs: np.ndarray, zs: np.ndarray) -> dict:
    """Integrate segment by segment into ``xs, zs`` (one integrator per kind of segment,
    with the segment's start time as a parameter); each starts from where the previous
    one ended."""
    xs[0], zs[0] = x0, z0
    pt = np.concatenate([p, [0.0]])
    stats: dict = {}
    for a, b, tau in segments:
        integ = _integrator(cm, plugin, tau, rtol, atol, max_step, drive, linsol,
                            shifted=True)
        pt[-1] = grid[a]
        st = _run(integ, np.ascontiguousarray(xs[a]), np.ascontiguousarray(zs[a]), pt,
                  xs[a + 1:b + 1], zs[a + 1:b + 1])
        for k, v in st.items():
            per_call = k in _PER_CALL or k.startswith(_LIFETIME)
            stats[k] = stats.get(k, 0) + v if per_call else v
    return stats


def _nonfinite_cause(cm: CompiledModel, t0: float, X0, z0, p, drive) -> str:
    """Which equation gives a value that is not finite at the start point, if one does
    (replayed from the compiled functions; "" when none does or inputs drive ``p``)."""
    if drive:
        return ""
    from mechatron.solvers.diagnose import describe_nonfinite
    args = [t0, np.asarray(X0, dtype=float), np.asarray(z0, dtype=float),
            np.asarray(p, dtype=float)]
    for f, names in ((cm.f_ode, [f"der({n})" for n in cm.state_names]),
                     (cm.f_alg, [f"the algebraic equation solved for {n}"
                                 for n in cm.alg_names]),
                     (cm.f_out, cm.names)):
        if f is None or f.n_out() == 0 or f.nnz_out(0) == 0:
            continue
        cause = describe_nonfinite(f, args, names, t0)
        if cause:
            return cause
    return ""


def consistent_algebraics(cm: CompiledModel, grid: np.ndarray, X: np.ndarray,
                          Z: np.ndarray, p: np.ndarray, solver: str) -> np.ndarray:
    """The algebraic unknowns at the output times, solved to convergence.

    A one-step integrator interpolates ``z`` to an output time and corrects it by a
    single Newton step (CasADi's Rosenbrock plug-in), IDAS interpolates; neither checks
    that ``alg(t, x, z) = 0`` holds there. :data:`Z_ITERATIONS` Newton iterations from
    those values (one mapped CasADi call, no Python per point) settle them, and the
    correction one more iteration would make is checked against ``1e-10 + 1e-6 |z|``
    (:data:`mechatron.solvers.fixed.NEWTON_ATOL`): a point where it is not met raises a
    :class:`SimulationError` naming the time and the unknowns. ``p`` is one parameter
    vector or one column per point."""
    from mechatron.solvers.fixed import NEWTON_ATOL, NEWTON_RTOL
    n = grid.size
    key = ("z_polish", n)
    fn = cm._cache.get(key)
    if fn is None:
        t, X_, z0 = ca.SX.sym("t"), ca.SX.sym("X", cm.nX), ca.SX.sym("z", cm.nz)
        p_ = ca.SX.sym("p", cm.p0.size)
        zs = ca.SX.sym("zs", cm.nz)
        g = cm.f_alg(t, X_, zs, p_)
        step = ca.Function("newton_z", [zs, t, X_, p_], [ca.solve(ca.jacobian(g, zs), g)])
        z = z0
        for _ in range(Z_ITERATIONS):
            z = z - step(z, t, X_, p_)
        err = ca.fabs(step(z, t, X_, p_)) / (NEWTON_ATOL + NEWTON_RTOL * ca.fabs(z))
        fn = cm._cache[key] = ca.Function("polish_z", [t, X_, z0, p_],
                                          [z, err]).map(n, "serial")
    P = p if np.ndim(p) == 2 else np.repeat(np.asarray(p).reshape(-1, 1), n, axis=1)
    zp, err = (np.array(v, dtype=float) for v in fn(grid.reshape(1, -1), X, Z, P))
    bad = ~np.all(err <= 1.0, axis=0)
    if bad.any():
        k = int(np.argmax(bad))
        score = np.where(np.isfinite(err[:, k]), err[:, k], np.inf)
        worst = [i for i in np.argsort(-score, kind="stable")[:3] if not score[i] <= 1.0]
        names = [cm.alg_names[i] for i in worst]
        raise SimulationError(
            f"model '{cm.name}': {solver}: the algebraic unknowns did not converge at "
            f"t = {grid[k]:.9g} s ({', '.join(names)}; {int(bad.sum())} output time(s) "
            f"in all) after {Z_ITERATIONS} Newton iterations from the integrator's values. "
            "The algebraic loop may have lost its solution (a singular Jacobian, a root "
            "that vanished): check the parameters, or try a tighter tolerance.",
            path=cm.name, variables=names)
    return zp.reshape(cm.nz, n)


def _explain(cm: CompiledModel, text: str) -> str:
    last = text.strip().splitlines()[-1] if text.strip() else text
    hint = "Try a tighter tolerance, a smaller max step, or check the model's parameters."
    if "too much work" in text.lower() or "mxstep" in text.lower():
        hint = "The solver took too many steps: the model may be stiff or chattering."
    if "convergence" in text.lower() or "err test" in text.lower():
        hint = ("The solver failed to converge: look for a discontinuity without an event "
                "or an algebraic loop without a solution.")
    return f"model '{cm.name}': the variable-step solver failed ({last}). {hint}"
