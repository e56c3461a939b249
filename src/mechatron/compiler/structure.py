"""Passes 4 to 6 and lowering: structural analysis, index reduction, BLT with tearing,
and the symbolic solution of every block into a semi-explicit DAE

    x' = f(t, x, z, p, m),   0 = g(t, x, z, p, m)

where ``x`` are the states chosen by dummy-derivative selection, ``z`` the tearing
variables of the nonlinear algebraic loops that remain, ``p`` the parameters and ``m`` the
relation placeholders (modes). The graph algorithms come from :mod:`mechatron.compiler.graph`
and see only integer incidence; this module owns the symbols.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import chain

import casadi as ca
import numpy as np

from mechatron.compiler.flatten import ColumnRows, Origins, stack_columns
from mechatron.compiler.graph import (block_order, dummy_derivatives, maximum_matching,
                                      pantelides, tear)
from mechatron.compiler.linear import (DENSE_ROW, Combined, jacobian_apart, owner_of,
                                       reveal, sparse_jacobian)
from mechatron.compiler.pivoting import largest, pivot_columns
from mechatron.errors import StructuralError

__all__ = ["Lowered", "lower"]

_MAX_SYMBOLIC_SOLVE = 12   # linear torn blocks up to this size are solved symbolically


@dataclass
class Lowered:
    states: list[str]
    state_syms: list[ca.SX] | ColumnRows
    alg: list[str]
    alg_syms: list[ca.SX]
    ode: list[ca.SX] | ColumnRows
    residuals: list[ca.SX]
    assigned: ca.SX                  # symbols of explicitly solved unknowns, in order
    assigned_expr: ca.SX             # their expressions (earlier ones may appear)
    #: the number of each of ``assigned`` among the variables of the structural problem
    #: (the unknowns as given, then the derivatives)
    assigned_rows: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.intp))
    differentiated: list[str] = field(default_factory=list)
    n_blocks: int = 0
    largest_block: int = 0
    n_torn: int = 0
    n_equations: int = 0
    n_unknowns: int = 0
    state_col: ca.SX | None = None   # state_syms and ode stacked (taken from the stacked
    ode_col: ca.SX | None = None     # unknowns when they are there: no vertcat of scalars)


_SAMPLED_PATTERN_ROWS = 250_000   # from this many equations on, see _pattern
_PROBE_COLUMNS = 1024             # columns sampled to find the dense rows (_pattern)


def _pattern(expr: ca.SX, syms: ca.SX, narrow: np.ndarray | None = None
             ) -> tuple[ca.Sparsity, ca.SX | None]:
    """``jacobian_sparsity(expr, syms)``, with the rows that hold many variables
    found first and swept apart from the others when there are many rows; and the
    Jacobian itself when it was formed on the way (else None).

    CasADi's sweep over a few hundred thousand rows slows down several-fold when one
    row (the flow balance of a reference node that every branch of a ladder meets)
    holds most columns. Such rows are found on a sample of the columns: one in 64, at
    most `_PROBE_COLUMNS` (a few sweeps at any size), picked at random with a fixed
    seed, not evenly spaced: a model's columns repeat with the period of its
    components, which a stride can miss entirely. A row with 8 of them there holds
    hundreds of variables of a small model, thousands of a large one (rows of a few
    thousand cost little). Rows known to hold few variables (``narrow``, a mask: see
    `_narrow_rows`) are left out of the sample's sweep. The pattern is the same either
    way. Each part is then differentiated at once, and the pattern read off its
    Jacobian: ``casadi.jacobian`` forms the same pattern inside, and on such a graph
    every sweep costs (`mechatron.compiler.linear.reveal` takes the Jacobian)."""
    if expr.numel() < _SAMPLED_PATTERN_ROWS:
        return ca.jacobian_sparsity(expr, syms), None
    rows = None if narrow is None else np.flatnonzero(~narrow)   # the rows to probe
    dense = np.zeros(0, dtype=np.int64)
    if rows is None or rows.size:
        n_col = syms.numel()
        picked = np.sort(np.random.default_rng(0).choice(
            n_col, min(_PROBE_COLUMNS, max(n_col // 64, 1)), replace=False)).tolist()
        probe = ca.jacobian_sparsity(expr if rows is None else expr[rows.tolist()],
                                     syms[picked])
        count = np.diff(np.asarray(probe.get_crs()[0], dtype=np.int64))
        dense = np.flatnonzero(count >= 8)
        if rows is not None:
            dense = rows[dense]
    if dense.size == 0:
        return ca.jacobian_sparsity(expr, syms), None
    jac = jacobian_apart(expr, syms, dense)
    return jac.sparsity(), jac


def _narrow_rows(origins, n_rows: int) -> np.ndarray | None:
    """Which of ``n_rows`` residuals hold fewer than `DENSE_ROW` variables for certain,
    read off their origins (`Origins`) without a sweep: a row of a class template's
    equation holds at most as many variables as the template has symbols (its
    instance's variables, their derivatives, parameters and time; aliases replaced by
    one variable or a number each), unless the row was replaced since (its origin then
    held as given); a flow sum's row at most its terms (`Origins.terms`). None when
    ``origins`` are no such record of these rows."""
    if not isinstance(origins, Origins) or origins.formed is not None \
            or len(origins) != n_rows or len(origins.which) != n_rows:
        return None
    narrow = np.zeros(n_rows, dtype=bool)
    if origins.templates:
        small = np.array([t.svec.numel() < DENSE_ROW for t in origins.templates])
        at = np.flatnonzero(origins.which >= 0)
        narrow[at] = small[origins.which[at]]
        if origins.given:
            narrow[list(origins.given)] = False
    terms = origins.terms
    narrow[(terms >= 0) & (terms < DENSE_ROW)] = True
    return narrow


def _csr(expr: ca.SX, syms: ca.SX, narrow: np.ndarray | None = None
         ) -> tuple[list[list[int]], ca.Sparsity, ca.SX | None]:
    """The incidence of ``expr`` in ``syms`` as rows of column indices, the sparsity of
    the Jacobian it comes from, and that Jacobian if it was formed (see `_pattern`)."""
    sp, jac = _pattern(expr, syms, narrow)
    ptr, col = sp.get_crs()
    # one integer object per column, held by every row that holds the column, instead
    # of one per entry as read (the rows live through the structural analysis: a
    # million rows of four entries hold 128 MB of integers, the shared ones 38 MB)
    col = list(map(list(range(sp.size2())).__getitem__, col))
    return [col[a:b] for a, b in zip(ptr, ptr[1:])], sp, jac


class _Singular(StructuralError):
    """A loop of equations found numerically singular: it may be a cut set or loop
    closed through a parameter coefficient, which the exact elimination with symbolic
    coefficients reduces (see `lower`)."""


def lower(name: str, residuals: list[ca.SX], origins: list[str], unknowns: list[str],
          syms: dict[str, ca.SX] | list[ca.SX] | ColumnRows,
          derivative: dict[str, ca.SX] | list[ca.SX | None], time: ca.SX,
          start_guess, hints: dict[str, str],
          preference: dict[str, float] | None = None,
          declared: dict[str, int] | None = None,
          roles: dict[str, tuple[str, str, str, bool]] | None = None,
          classes: dict[str, str] | None = None,
          physical: set[str] | None = None,
          parameters: list[ca.SX] | None = None,
          stacked: tuple[ca.SX, ca.SX] | None = None,
          others: ca.SX | None = None) -> Lowered:
    """Index-reduce, sort, tear and solve the equations for the unknowns.

    Parameters
    ----------
    residuals, origins
        Equations (after alias elimination) and where each came from.
    unknowns
        Names of the unknowns (alias representatives); ``syms`` maps names to symbols
        (or lists them in the order of ``unknowns``) and ``derivative`` names to
        derivative symbols (or lists each unknown's, None where it has none).
    start_guess : callable
        ``start_guess(list_of_syms) -> ndarray``, numeric point for Jacobian-based choices.
    hints
        A hint per variable name for messages about unmatched variables.
    preference : dict, optional
        State preference per unknown name (0 default, > 0 rather a state, < 0 rather a
        dummy derivative); the derivatives of a variable inherit its preference. Columns
        of the state-selection Jacobian are scaled by ``10**(-3*preference)`` before the
        pivoted QR, so a preferred variable is made dummy only when no other choice is
        nonsingular.
    declared : dict, optional
        Declaration order of each unknown (its place in the flat model); an exact tie in
        state selection keeps the unknown declared first as a state. Default: the order
        of `unknowns`.

    roles, classes
        For messages about dependent network equations (see
        `mechatron.compiler.linear.reveal`): the port role and quantity of each unknown,
        the class name of each component.
    physical : set of str, optional
        Components with physical (conserving) ports: a singular algebraic loop through
        them is reported as a network problem, not as a loop of signal blocks.
    parameters : list of SX, optional
        Parameter symbols: linear coefficients that depend on them alone (a transformer
        ratio) take part in the exact elimination of `mechatron.compiler.linear.reveal`.
    stacked : (SX, SX), optional
        ``vertcat(*residuals)`` and the unknowns' symbols followed by the derivative
        symbols (in the order of ``unknowns``), stacked, if the caller has them already.
    others : SX, optional
        With ``stacked``: a column of the other symbols the residuals may hold (the
        parameters, time), so that the numbers among the Jacobian's entries are read by
        one function of the symbols (see `mechatron.compiler.linear.reveal`).

    Notes
    -----
    State selection depends on the numbers only where they differ: the pivoted QR
    (`mechatron.compiler.pivoting.pivot_columns`) treats residual column norms within
    a relative `TIE_RTOL` as equal and gives the tie to the candidate that
    `dummy_derivatives` ranks first (preference, then derivatives created by index
    reduction, then derivative order, then later declaration, see `declared`). The
    states, equations and generated code are then the same whatever
    BLAS kernel evaluates the Jacobian.

    The exact elimination of `mechatron.compiler.linear.reveal` first works with the
    numeric coefficients alone (network laws of ±1: cheap, and enough for nearly every
    model). If an algebraic loop or the state selection then turns out singular, and
    `parameters` are given, the equations are lowered again with coefficients that are
    expressions of the parameters taken exactly (a cut set closed through a
    transformer's or gear's ratio); only if that fails too is the model refused.
    """
    args = (name, residuals, origins, unknowns, syms, derivative, time, start_guess,
            hints, preference, declared, roles, classes, physical)
    try:
        return _lower(*args, None, stacked, others)
    except _Singular:
        if not parameters:
            raise
    try:
        return _lower(*args, parameters, stacked, others)
    except _Singular as exc:
        raise StructuralError(str(exc), equations=exc.equations, variables=exc.variables,
                              path=exc.path) from None


def _own(items) -> list | ColumnRows | Origins:
    """A copy of ``items`` that `_lower` may change: a `ColumnRows` or `Origins` stays
    one (its items not formed), anything else becomes a list."""
    return items.copy() if isinstance(items, (ColumnRows, Origins)) else list(items)


def _lower(name, residuals, origins, unknowns, syms, derivative, time, start_guess, hints,
           preference, declared, roles, classes, physical, parameters,
           stacked=None, others=None) -> Lowered:
    # -- variables of the structural problem: unknowns and their derivatives -------------
    var_syms: list[ca.SX] = _own(syms) if isinstance(syms, (list, ColumnRows)) else \
        [syms[n] for n in unknowns]
    var_names: list[str] = list(unknowns)
    var_to_diff = [-1] * len(var_syms)
    ders = derivative if isinstance(derivative, list) else \
        [derivative.get(n) for n in unknowns]
    for i, (n, d) in enumerate(zip(unknowns, ders)):
        if d is not None:
            var_to_diff[i] = len(var_syms)
            var_syms.append(d)
            var_names.append(f"der({n})")
            var_to_diff.append(-1)
    res = _own(residuals)
    orig = _own(origins)
    # the residuals and variables stacked once (a vertcat converts each scalar from
    # Python); the caller may pass them already stacked
    if res:
        res_vec, var_vec = stacked if stacked is not None else (ca.vertcat(*res),
                                                                ca.vertcat(*var_syms))
    # which rows the sampled search for dense rows may skip: read only where it runs
    narrow = _narrow_rows(origins, len(res)) if len(res) >= _SAMPLED_PATTERN_ROWS else None
    adj, pattern, jac = _csr(res_vec, var_vec, narrow) if res else ([], None, None)
    # derivative symbols that appear nowhere do not make their variable a state
    used = set(chain.from_iterable(adj))
    for i, d in enumerate(var_to_diff):
        if d != -1 and d not in used:
            var_to_diff[i] = -1
    _check_counts(name, res, orig, var_names, var_to_diff, adj, hints)

    # -- index reduction ------------------------------------------------------------------
    # constraints hidden in the linear network equations (a cut set of current sources
    # and inductors, a loop of voltage sources and capacitors) are exposed first
    reduction = reveal(name, res, orig, var_syms, var_names, var_to_diff, adj, roles,
                       classes, parameters, stacked=(res_vec, var_vec) if res else None,
                       sparsity=pattern, jacobian=jac,
                       symbols=stack_columns(var_vec, others)
                       if res and others is not None and stacked is not None else None)
    try:
        ir = pantelides(len(var_syms), reduction.adj, var_to_diff)
    except StructuralError as exc:
        _raise_singular(name, orig, var_names, exc, hints)
    # an equation that is differentiated takes its reduced form; the others stay as
    # written (equivalent: the reduced forms add equations that stay)
    reduced = {e: reduction.residual(e, res, var_syms) for e in reduction.changed
               if ir.eq_to_diff[e] != -1}
    restored = False
    for e in reduction.changed:
        if e in reduced:
            res[e] = reduced[e]
            orig[e] = Combined([orig[k] for k in sorted(reduction.reduced[e][1])])
        else:
            ir.adj[e] = list(dict.fromkeys(adj[e]))
            restored = True
    differentiated = []
    while len(var_syms) < ir.n_var:
        v = len(var_syms)
        base = ir.var_to_diff.index(v)
        var_syms.append(ca.SX.sym(f"der({var_names[base]})"))
        var_names.append(f"der({var_names[base]})")
    sym_index = ({s.name(): i for i, s in enumerate(var_syms)}
                 if len(ir.adj) > len(res) else {})
    for e in range(len(res), len(ir.adj)):
        src = ir.eq_to_diff.index(e)
        res.append(_time_derivative(res[src], var_syms, sym_index, ir.var_to_diff, time))
        orig.append(f"d/dt[{orig[src]}]")
        differentiated.append(str(orig[src]))
    adj = ir.adj
    var_to_diff = ir.var_to_diff

    pref = preference or {}
    n_orig = len(residuals)
    point: dict[str, float] = {}
    assembled: list[bool] = []

    def guess(free):
        """Start values, corrected to satisfy the position-level constraints (done once,
        on the first call): the Jacobians that choose the states are then evaluated at
        an assembled configuration, not at zeros that may put every link on one line."""
        if pref and not assembled:
            is_derivative = set(d for d in ir.var_to_diff if d != -1)
            point.update(_assembled(res[:n_orig], adj[:n_orig], var_syms, is_derivative,
                                    start_guess, set(pref)))
            assembled.append(True)
        base = start_guess(free)
        return [point.get(s.name(), b) for s, b in zip(free, base)]

    def weight(v: int) -> float:
        name = var_names[v]
        while name.startswith("der(") and name.endswith(")"):
            name = name[4:-1]
        return float(pref.get(name, 0.0))

    def select(eqs, candidates, k):
        jac = ca.jacobian(ca.vertcat(*[res[e] for e in eqs]),
                          ca.vertcat(*[var_syms[c] for c in candidates]))
        free = ca.symvar(jac)
        fun = ca.Function("jac_select", free, [jac])
        value = np.array(fun.call(guess(free))[0], dtype=float)
        value = np.atleast_2d(value).reshape(len(eqs), len(candidates))
        scale = np.array([10.0 ** (-3.0 * weight(c)) for c in candidates])
        chosen = pivot_columns(value * scale, k)
        if pref and k and _singular(value[:, chosen]):
            _raise_singular_selection(name, [orig[e] for e in eqs],
                                      [var_names[c] for c in candidates])
        return [candidates[j] for j in chosen]

    dummies: set[int] = set()
    if differentiated:
        priority = [-weight(v) for v in range(len(var_syms))] if pref else None
        n_unknown = len(unknowns)
        rank = ([declared.get(n, len(declared) + i) for i, n in enumerate(unknowns)]
                if declared is not None else list(range(n_unknown)))
        rank += range(n_unknown, ir.n_var_original)   # derivatives: their root's rank
        dummies = set(dummy_derivatives(ir, select=select, priority=priority, rank=rank))
    states = [v for v, d in enumerate(var_to_diff) if d != -1 and d not in dummies]
    allowed = [True] * len(var_syms)
    for v in states:
        allowed[v] = False

    # -- matching of the non-states, BLT, tearing -----------------------------------------
    if differentiated or restored:
        m = maximum_matching(len(var_syms), adj, allowed=allowed)
    else:
        # nothing differentiated: the states are the variables with a derivative, the
        # incidence is the one index reduction matched, and its matching is this one
        m = ir.matching
    if -1 in m.eq_to_var or any(e == -1 and ok for e, ok in zip(m.var_to_eq, allowed)):
        _raise_structural(name, res, orig, var_names, m, allowed, hints)
    # the blocks as arrays: most are one equation, and a model of 10^5 components has
    # as many (see `BlockOrder`)
    blocks = block_order(len(var_syms), adj, m)
    sizes = blocks.sizes()
    if pref and differentiated:
        for k in np.flatnonzero(sizes > 1).tolist():
            _check_selection(name, res, orig, var_syms, var_names, blocks.block(k), guess)
    else:
        for k in np.flatnonzero((sizes > 1) & (sizes <= _LOOP_CHECK_MAX)).tolist():
            _check_loop(name, res, orig, var_syms, var_names, blocks.block(k), guess,
                        time, physical or set())
    # the states' symbols and derivatives are read off their columns at the end: read
    # one by one here, they would form every unknown's symbol (see ColumnRows)
    out = Lowered(states=[var_names[v] for v in states], state_syms=[],
                  alg=[], alg_syms=[], ode=[], residuals=[], assigned=ca.SX(0, 1),
                  assigned_expr=ca.SX(0, 1),
                  differentiated=differentiated, n_blocks=len(blocks),
                  n_equations=len(res), n_unknowns=sum(allowed))
    coef_cache: dict[tuple[int, int], ca.SX | None] = {}
    unknown_names = _OnFirstUse(lambda: {x.name() for x in var_syms})   # loops only

    def coefficient(e: int, v: int):
        """d res[e] / d v when res[e] is linear in v with a nonzero coefficient, else None."""
        key = (e, v)
        if key not in coef_cache:
            r, x = res[e], var_syms[v]
            coef = ca.jacobian(r, x)
            ok = not coef.is_zero() and not ca.depends_on(coef, x)
            coef_cache[key] = coef if ok else None
        return coef_cache[key]

    def solvable(e: int, v: int) -> bool:
        return coefficient(e, v) is not None

    # the given equations and their Jacobian (from `reveal`) serve the one-equation
    # blocks, unless index reduction replaced or added equations among them
    ones = np.flatnonzero(sizes == 1)
    firsts = blocks.ptr[ones]
    es, single_vs = blocks.equations[firsts].tolist(), blocks.variables[firsts].tolist()
    given = None
    if res and reduction.jacobian is not None and (not es or (
            max(es) < n_orig and max(single_vs) < var_vec.numel()
            and not (reduced and any(e in reduced for e in es)))):
        given = (res_vec, var_vec, reduction.jacobian, pattern, reduction.entries)
    bulk_x, bulk_solved, bulk_sols = _solve_singles(res, var_syms, es, single_vs, given)
    del es, single_vs
    out.largest_block = int(sizes.max()) if sizes.size else 0
    # each block's place among the bulk solutions (-1 for a block solved on its own)
    bulk = np.full(len(blocks), -1, dtype=np.intp)
    bulk[ones[bulk_solved]] = np.arange(len(bulk_solved))
    # the blocks solved on their own, in block order: their assignments are scalars
    syms: list[ca.SX] = []
    exprs: list[ca.SX] = []
    assigned_vars: list[int] = []   # the variable of each of them
    marks: list[int] = []           # how many there were before each block

    def assign(v: int, expr: ca.SX) -> None:
        syms.append(var_syms[v])
        assigned_vars.append(v)
        exprs.append(expr)

    rest = np.flatnonzero(bulk < 0)
    at = blocks.ptr[rest]
    for k, size, e, v in zip(rest.tolist(), sizes[rest].tolist(),
                             blocks.equations[at].tolist(), blocks.variables[at].tolist()):
        marks.append(len(syms))
        if size > 1:
            block = blocks.block(k)
            _solve_block(out, assign, block.equations, block.variables, adj, res,
                         var_syms, var_names, coefficient, unknown_names)
            continue
        quick = _explicit(res[e], var_syms[v])
        if quick is not None:
            assign(v, quick)
            continue
        coef = coefficient(e, v)
        if coef is not None:
            assign(v, _solve_linear(res[e], var_syms[v], coef))
        else:
            out.alg.append(var_names[v])
            out.alg_syms.append(var_syms[v])
            out.residuals.append(res[e])
    if bulk_solved or syms:
        # the assignments in block order: one from each block solved in bulk (its row
        # among the stacked bulk solutions), those of the others after them (their
        # scalars stacked after the bulk's); one gather of each stacked vector orders
        # them
        count = (bulk >= 0).astype(np.intp)
        count[rest] = np.diff(np.append(marks, len(syms)))
        start = np.cumsum(count) - count
        n_x, n_bulk = bulk_x.numel(), len(bulk_solved)
        x_rows = np.empty(count.sum(), dtype=np.intp)
        e_rows = np.empty_like(x_rows)
        out.assigned_rows = np.empty_like(x_rows)
        done = np.flatnonzero(bulk >= 0)
        x_rows[start[done]] = np.asarray(bulk_solved, dtype=np.intp)[bulk[done]]
        e_rows[start[done]] = bulk[done]
        out.assigned_rows[start[done]] = blocks.variables[blocks.ptr[done]]
        if syms:
            c = count[rest]
            places = np.repeat(start[rest] - (np.cumsum(c) - c), c) + np.arange(len(syms))
            x_rows[places] = n_x + np.arange(len(syms))
            e_rows[places] = n_bulk + np.arange(len(syms))
            out.assigned_rows[places] = assigned_vars
        out.assigned = (stack_columns(bulk_x, ca.vertcat(*syms)) if syms else bulk_x)[
            x_rows.tolist()]
        out.assigned_expr = stack_columns(*bulk_sols, *([ca.vertcat(*exprs)] if exprs
                                                         else []))[e_rows.tolist()]
    ders = [var_to_diff[v] for v in states]
    out.state_col, out.ode_col = (
        var_vec[rows] if res and (not rows or max(rows) < var_vec.numel())
        else (ca.vertcat(*[var_syms[v] for v in rows]) if rows else ca.SX(0, 1))
        for rows in (states, ders))
    # as lists whose scalars are formed when read
    out.state_syms, out.ode = ColumnRows(out.state_col), ColumnRows(out.ode_col)
    return out


_ASSEMBLY_MAX = 3000   # largest position-level system assembled at compile time


def _assembled(res, adj, var_syms, is_derivative, start_guess, keep) -> dict[str, float]:
    """A point near the start values that satisfies the equations free of derivatives
    (kinematic constraints, algebraic relations), by Gauss-Newton with minimum-norm steps.

    First the variables with a nonzero start value or a state preference (``keep``)
    are held and only the others move (positions of frames that follow from the joint
    coordinates); if that cannot satisfy the equations (inconsistent start values),
    every variable moves, the held ones 1000 times less. Returns ``{name: value}`` of the
    variables moved; empty when the system is too large or the iteration fails."""
    rows = [e for e in range(len(res)) if not any(v in is_derivative for v in adj[e])]
    cols = sorted({v for e in rows for v in adj[e]})
    if not rows or not cols or len(cols) > _ASSEMBLY_MAX:
        return {}
    xs = [var_syms[v] for v in cols]
    r = ca.vertcat(*[res[e] for e in rows])
    x = ca.vertcat(*xs)
    params = [s for s in ca.symvar(r) if not ca.depends_on(s, x)]
    fun = ca.Function("assemble", [x] + params, [r, ca.jacobian(r, x)])
    x0 = np.array(start_guess(xs), dtype=float)
    pv = [float(v) for v in start_guess(params)]
    held = (x0 != 0.0) | np.array([s.name() in keep for s in xs])
    for scale in (np.where(held, 0.0, 1.0), np.where(held, 1e-3, 1.0)):
        xk = _gauss_newton(fun, x0.copy(), pv, scale)
        if xk is not None:
            return {s.name(): float(v) for s, v, v0 in zip(xs, xk, x0) if v != v0}
    return {}


def _gauss_newton(fun, xk, pv, scale, iterations: int = 30):
    """Minimum-norm Gauss-Newton on ``fun(x) = 0`` in the scaled variables; ``None`` if
    it does not converge."""
    for _ in range(iterations):
        rv, jv = fun(xk, *pv)
        rv = np.array(rv, dtype=float).ravel()
        ok = np.isfinite(rv)
        if np.all(ok) and np.max(np.abs(rv), initial=0.0) < 1e-12:
            return xk
        # a residual or derivative that is not finite (0/0 or sqrt at 0: coincident
        # points at the zero guess) carries no direction this iteration; the rows that
        # do move the iterate away from it
        jd = np.nan_to_num(np.array(jv, dtype=float), nan=0.0, posinf=0.0,
                           neginf=0.0) * scale
        jd[~ok] = 0.0
        rv = np.where(ok, rv, 0.0)
        try:
            step = np.linalg.lstsq(jd, -rv, rcond=None)[0]
        except np.linalg.LinAlgError:
            return None
        xk = xk + scale * step
    return None


def _check_selection(name, res, orig, var_syms, var_names, block, guess) -> None:
    """With the states chosen, every algebraic loop must be solvable for its unknowns:
    the loop's Jacobian at the (assembled) start point must be nonsingular. A singular
    one names the equations and variables of its null space."""
    eqs, cols = list(block.equations), list(block.variables)
    if len(eqs) > _ASSEMBLY_MAX:
        return
    jac = ca.jacobian(ca.vertcat(*[res[e] for e in eqs]),
                      ca.vertcat(*[var_syms[v] for v in cols]))
    free = ca.symvar(jac)
    value = np.array(ca.Function("jac_check", free, [jac]).call(guess(free))[0],
                     dtype=float).reshape(len(eqs), len(cols))
    if not _singular(value):
        return
    # each equation's and variable's share of the (numerical) null space: the diagonal of
    # its projector, which does not depend on the basis LAPACK returns for it
    u, s, vt = np.linalg.svd(value)
    rank = min(int(np.sum(s > 1e-10 * max(1.0, s[0]))), len(s) - 1)
    left = np.sqrt(np.sum(u[:, rank:] ** 2, axis=1))
    right = np.sqrt(np.sum(vt[rank:] ** 2, axis=0))
    suspects = [str(orig[eqs[i]]) for i in largest(left, 6, floor=1e-3)]
    vs = [var_names[cols[j]] for j in largest(right, 8, floor=1e-3)]
    _raise_singular_selection(name, suspects, vs)


_LOOP_CHECK_MAX = 200   # largest algebraic loop checked for singularity at compile time


def _check_loop(name, res, orig, var_syms, var_names, block, guess, time,
                physical: set[str]) -> None:
    """An algebraic loop (a strongly connected block of equations) must have a unique
    solution: its Jacobian at the start values must be nonsingular. A singular loop (e.g.
    a sum whose output feeds back through a gain of exactly 1) is reported with the
    components of the equations in it."""
    eqs, cols = list(block.equations), list(block.variables)
    jac = ca.jacobian(ca.vertcat(*[res[e] for e in eqs]),
                      ca.vertcat(*[var_syms[v] for v in cols]))
    free = ca.symvar(jac)
    # only a loop whose Jacobian is fixed by the parameters is singular for good; one that
    # depends on unknowns, time or modes may be singular at the start guess only
    unknown = {s.name() for s in var_syms} | {time.name()}
    if any(s.name() in unknown or "[" in s.name() for s in free):
        return
    try:
        value = np.array(ca.Function("loop_check", free, [jac]).call(guess(free))[0],
                         dtype=float).reshape(len(eqs), len(cols))
    except Exception:   # noqa: BLE001 - a loop that cannot be evaluated is left to the solver
        return
    if not np.all(np.isfinite(value)):
        return
    # equilibrate rows and columns (physical units spread entries over many decades: a
    # pipe of 1e10 Pa s/m^3 beside a pump of 2e-6 m^3/rad), then ask for an exact-zero
    # singular value: only a loop singular for any scaling is reported
    for axis in (1, 0):
        peak = np.max(np.abs(value), axis=axis, keepdims=True)
        value = value / np.where(peak > 0, peak, 1.0)
    sv = np.linalg.svd(value, compute_uv=False)
    if sv.size and sv[-1] > 1e-13 * max(sv[0], 1.0):
        return
    owners = []
    for e in eqs:
        where = owner_of(orig[e])
        if where not in owners:
            owners.append(where)
    if any(w.startswith("connect(") or w in physical for w in owners):
        parts = [w for w in owners if not w.startswith("connect(")] or owners
        raise _Singular(
            f"model '{name}': the network equations of {', '.join(parts)} are singular "
            f"for {', '.join(var_names[v] for v in cols[:8])} with the parameter values "
            "given: a parameter of 0, or parameters whose values make a loop or cut "
            "set of ideal elements close (e.g. transformer ratios whose product is "
            "exactly 1 around a loop). Check these parameters, or add a resistance (a "
            "damper or spring in mechanics) to that loop or cut set.",
            equations=[str(orig[e]) for e in eqs], variables=owners, path=name)
    raise _Singular(
        f"model '{name}': the algebraic loop through {', '.join(owners)} has no unique "
        f"solution (its {len(eqs)} equations are singular for "
        f"{', '.join(var_names[v] for v in cols[:8])} at the start values: a loop gain of "
        "exactly 1?). Change a gain, or break the loop with a delay or a state (e.g. "
        "blocks.FirstOrder, blocks.UnitDelay).",
        equations=[str(orig[e]) for e in eqs], variables=owners, path=name)


def _singular(a: np.ndarray) -> bool:
    """Whether the square matrix ``a`` is numerically singular (False when it holds
    entries that are not finite: then nothing can be told)."""
    if not np.all(np.isfinite(a)):
        return False
    s = np.linalg.svd(a, compute_uv=False)
    return s.size == 0 or s[-1] <= 1e-10 * max(1.0, s[0])


def _raise_singular_selection(name, eqs, candidates) -> None:
    raise _Singular(
        f"model '{name}': state selection is singular at the start values: the "
        f"constraints {'; '.join(str(e) for e in eqs[:6])} cannot be solved for "
        f"{', '.join(candidates[:8])} with the states chosen. The mechanism "
        "may start in a singular configuration (links aligned, a dead point); change the "
        "initial position, or remove a redundant constraint.",
        equations=[str(e) for e in eqs], variables=list(candidates), path=name)


def _is_symbol(expr: ca.SX, name: str) -> bool:
    return expr.is_symbolic() and expr.name() == name


def _solve_singles(res: list[ca.SX], var_syms: list[ca.SX], es: list[int], vs: list[int],
                   given: tuple | None = None) -> tuple[ca.SX, list[int], list[ca.SX]]:
    """Solve the one-equation blocks (equation ``es[i]`` for variable ``vs[i]``)
    together, in a few calls over all of them, with the same result as `_solve_linear`
    one by one: ``x = -e(x = 0) / J``, where ``J = de/dx`` is free of ``x`` and not 0.

    Every ``J`` comes from one Jacobian. ``e(x = 0)`` must zero the block's own variable
    only, not the variables of other blocks that appear in ``e``: the blocks are
    coloured so that no equation holds the variable of another block of its colour
    (greedy, on the integer incidence; a BLT chain needs a few colours), and each colour
    takes one substitution (in pieces on a long colour, `_zeroed`). Returns ``(X,
    solved, exprs)``: the variables of all the blocks stacked, the rows of X solved
    (colour by colour; row ``i`` is block ``i``'s), and the expressions of those rows in
    pieces (one per colour, to be stacked once by the caller); the others (not linear
    in their variable) are left to the equation-by-equation path.

    ``given = (R, V, J, S, entries)``: the residuals and variables stacked, the
    Jacobian of R in V, its sparsity and the rows and columns of its entries (column by
    column, `mechatron.compiler.linear.Reduction.entries`); each block's equation is
    then a row of R, its variable a row of V, and all of these are read instead of
    computed again."""
    n = len(es)
    if n < 2:
        return ca.SX(0, 1), [], []
    if given is not None:
        R, V, J, S, entries = given
        E, X = R[es], V[vs]
        # J's nonzeros in column-major order: their keys col * rows + row are sorted
        r_nz, c_nz = entries
        keys = c_nz * J.size1() + r_nz
        want = np.asarray(vs, dtype=np.int64) * J.size1() + np.asarray(es, dtype=np.int64)
        at = np.minimum(np.searchsorted(keys, want), max(keys.size - 1, 0))
        hit = np.flatnonzero(keys[at] == want) if keys.size else np.zeros(0, np.int64)
        d = ca.SX.zeros(n)
        if hit.size:
            d[hit.tolist()] = J.nz[at[hit].tolist()]
        if S == J.sparsity():
            r, c = _sub_entries(r_nz, c_nz, J.shape, es, vs)
        else:
            r, c = (np.asarray(a, dtype=np.int64)
                    for a in S.sub(es, vs, False)[0].get_triplet())
    else:
        E = ca.vertcat(*[res[e] for e in es])
        X = ca.vertcat(*[var_syms[v] for v in vs])
        d = ca.diag(sparse_jacobian(E, X))
        r, c = (np.asarray(a, dtype=np.int64)
                for a in ca.jacobian_sparsity(E, X).get_triplet())
    # blocks i and j clash when the equation of one holds the variable of the other; in
    # the greedy colouring (in block order) only the earlier of the two looks at it
    a, b = np.concatenate([r, c]), np.concatenate([c, r])
    keep = b < a
    a, b = a[keep], b[keep]
    order = np.argsort(a, kind="stable")
    ptr = np.searchsorted(a[order], np.arange(n + 1)).tolist()
    earlier = b[order].tolist()
    # a block is left out when its coefficient J is 0 or depends on a variable
    usable = np.zeros(n, dtype=bool)
    usable[ca.sparsify(d).sparsity().get_triplet()[0]] = True
    usable[ca.jacobian_sparsity(d, X).get_triplet()[0]] = False
    colour = [-1] * n
    classes: list[list[int]] = []
    for i in np.flatnonzero(usable).tolist():
        lo, hi = ptr[i], ptr[i + 1]
        if lo == hi:
            k = 0
        elif hi - lo == 1:
            k = 1 if colour[earlier[lo]] == 0 else 0
        else:
            taken = {colour[j] for j in earlier[lo:hi]}
            k = 0
            while k in taken:
                k += 1
        colour[i] = k
        if k == len(classes):
            classes.append([])
        classes[k].append(i)
    sols = []
    for idx in classes:
        # slices of the stacked vectors (indexing by a list of ints stays in C++; a
        # vertcat of the scalars converts each one from Python)
        ex, xs, ds = E[idx], X[idx], d[idx]
        sols.append(-_zeroed(ex, xs) / ds)
    return X, [i for idx in classes for i in idx], sols


def _zeroed(ex: ca.SX, xs: ca.SX) -> ca.SX:
    """``substitute(ex, xs, 0)`` where row ``i`` of ``ex`` holds no element of ``xs`` but
    its own ``xs[i]`` (one colour of `_solve_singles`): on long columns piece by piece
    (`_ZEROED_PIECE` rows), each piece's graph walked while it is in the cache, where
    one walk over a million rows meets each node cold (15-25 % less time at 2-3 * 10^5
    rows). Each row is the same expression either way; a subexpression shared by rows of
    two pieces is formed once in each."""
    n = ex.numel()
    if n <= 2 * _ZEROED_PIECE:
        return ca.substitute(ex, xs, ca.DM.zeros(n))
    ends = [(k, min(k + _ZEROED_PIECE, n)) for k in range(0, n, _ZEROED_PIECE)]
    return stack_columns(*[ca.substitute(ex[a:b], xs[a:b], ca.DM.zeros(b - a))
                           for a, b in ends])


#: rows of a colour zeroed at once (`_zeroed`)
_ZEROED_PIECE = 16384


def _sub_entries(rows: np.ndarray, cols: np.ndarray, shape: tuple[int, int],
                 es: list[int], vs: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """The entries ``(rows, cols)`` of a matrix of ``shape`` that lie in rows ``es`` and
    columns ``vs``, numbered by their place there: ``Sparsity.sub(es, vs)``'s entries
    (in the given order, not CasADi's), by array lookups."""
    place_e = np.full(shape[0], -1, dtype=np.int64)
    place_e[es] = np.arange(len(es))
    place_v = np.full(shape[1], -1, dtype=np.int64)
    place_v[vs] = np.arange(len(vs))
    r, c = place_e[rows], place_v[cols]
    inside = (r >= 0) & (c >= 0)
    return r[inside], c[inside]


def _explicit(r: ca.SX, x: ca.SX):
    """x from the common forms ``x - b``, ``b - x``, ``c*x - b`` with b, c free of x, read
    off the expression tree (cheaper than a Jacobian and a substitution); else None."""
    if not r.is_op(ca.OP_SUB):
        return None
    name = x.name()
    a, b = r.dep(0), r.dep(1)
    if _is_symbol(a, name):
        return None if ca.depends_on(b, x) else b
    if _is_symbol(b, name):
        return None if ca.depends_on(a, x) else a
    if a.is_op(ca.OP_MUL):
        c0, c1 = a.dep(0), a.dep(1)
        for factor, other in ((c1, c0), (c0, c1)):
            if _is_symbol(factor, name) and not ca.depends_on(other, x) \
                    and not ca.depends_on(b, x):
                return b / other
    return None


def _solve_linear(r: ca.SX, x: ca.SX, coef: ca.SX) -> ca.SX:
    """x from r(x) = coef*x + rest = 0."""
    rest = ca.substitute(r, x, ca.SX(0))
    return -rest / coef


class _OnFirstUse:
    """A set built on its first membership test."""

    def __init__(self, build):
        self._build, self._set = build, None

    def __contains__(self, item) -> bool:
        if self._set is None:
            self._set = self._build()
        return item in self._set


def _solve_block(out: Lowered, assign, eqs, vs, adj, res, var_syms, var_names,
                 coefficient, unknown_names) -> None:
    # the sequence divides by its coefficients: only those free of unknowns are safe (a
    # coefficient such as sin(q) of a rigid link vanishes in some configurations and
    # would turn a nonsingular loop into 0/0); the loop's linear part is then solved by
    # QR on the tearing variables
    def safe(e: int, v: int) -> bool:
        coef = coefficient(e, v)
        return coef is not None and (coef.is_constant() or not any(
            x.name() in unknown_names for x in ca.symvar(coef)))

    t = tear(eqs, vs, adj, safe)
    out.n_torn += len(t.tearing_vars)
    seq_syms = [var_syms[v] for _, v in t.sequence]
    seq_expr = [_solve_linear(res[e], var_syms[v], coefficient(e, v)) for e, v in t.sequence]
    resid = [res[e] for e in t.residuals]
    tv = [var_syms[v] for v in t.tearing_vars]
    if seq_syms:
        seq_expr, resid = ca.substitute_inplace(seq_syms, seq_expr, resid, False)
    rvec, zvec = ca.vertcat(*resid), ca.vertcat(*tv)
    if tv and len(tv) <= _MAX_SYMBOLIC_SOLVE and ca.is_linear(rvec, zvec):
        a = ca.jacobian(rvec, zvec)
        b = ca.substitute(rvec, zvec, ca.DM.zeros(zvec.shape))
        sol = -ca.solve(a, b) if len(tv) > 1 else -b / a
        for i, v in enumerate(t.tearing_vars):
            assign(v, sol[i])
    else:
        for v in t.tearing_vars:
            out.alg.append(var_names[v])
            out.alg_syms.append(var_syms[v])
        out.residuals.extend(resid)
    for (_, v), expr in zip(t.sequence, seq_expr):
        assign(v, expr)


def _time_derivative(r: ca.SX, var_syms, sym_index, var_to_diff, time) -> ca.SX:
    vs, dvs = [], []
    for s in ca.symvar(r):
        i = sym_index.get(s.name())
        if i is not None:
            vs.append(s)
            dvs.append(var_syms[var_to_diff[i]])
    out = ca.jacobian(r, time) if ca.depends_on(r, time) else ca.SX(0)
    if vs:
        out = out + ca.jtimes(r, ca.vertcat(*vs), ca.vertcat(*dvs))
    return out


def _check_counts(name, res, orig, var_names, var_to_diff, adj, hints) -> None:
    """Over- and under-determined systems, with the suspects named."""
    highest = [d == -1 for d in var_to_diff]
    n_unknown = sum(highest)
    if len(res) == n_unknown:
        return
    m = maximum_matching(len(var_names), adj, allowed=highest)
    _raise_structural(name, res, orig, var_names, m, highest, hints)


def _raise_singular(name, orig, var_names, exc, hints) -> None:
    eqs = [str(orig[e]) for e in exc.equations if isinstance(e, int) and e < len(orig)]
    vs = [var_names[v] for v in exc.variables if isinstance(v, int) and v < len(var_names)]
    raise StructuralError(
        f"model '{name}': {len(eqs)} equations for {len(vs)} unknowns in a subsystem "
        f"({', '.join(vs[:8])}). Potential extra equation(s): {'; '.join(eqs[:8])}. "
        "Two components may fix the same quantity (e.g. two ideal voltage sources in "
        "parallel); remove one or put a resistance between them.",
        equations=eqs, variables=vs, path=name) from None


def _raise_structural(name, res, orig, var_names, m, allowed, hints) -> None:
    n_unknown = sum(allowed)
    extra_eq = [str(orig[e]) for e in m.unmatched_equations]
    free_var = [var_names[v] for v in range(len(var_names))
                if allowed[v] and m.var_to_eq[v] == -1]
    parts = [f"model '{name}': {len(res)} equations for {n_unknown} unknowns."]
    if extra_eq:
        parts.append("Potential extra equation(s): " + "; ".join(extra_eq[:8]) +
                     (" ..." if len(extra_eq) > 8 else "") + ".")
    if free_var:
        parts.append("Unmatched variable(s): " + ", ".join(free_var[:8]) +
                     (" ..." if len(free_var) > 8 else "") + ".")
    hint = next((hints.get(v.removeprefix("der(").removesuffix(")"))
                 for v in free_var if hints.get(v.removeprefix("der(").removesuffix(")"))),
                "")
    if extra_eq and not free_var:
        hint = hint or ("Two components may fix the same quantity (e.g. two ideal sources "
                        "in parallel); remove one or put a resistance between them.")
    elif not hint:
        hint = "Check for unconnected parts or a missing reference."
    parts.append(hint)
    raise StructuralError(" ".join(parts), equations=extra_eq, variables=free_var,
                          path=name)
