"""``compile_model``: the passes of docs/compiler.md in order, timed and counted."""

from __future__ import annotations

import gc
import time as _time
from collections.abc import Mapping

import casadi as ca
import numpy as np

from mechatron.compiler.alias import eliminate_aliases
from mechatron.compiler.compiled import CompiledModel
from mechatron.compiler.dimensions import check_dimensions as _check_dimensions
from mechatron.compiler.events import Lowering as EventLowering
from mechatron.compiler.events import (bind_pre, clock_distances, direct_relations,
                                        prepare_events, replace_pre)
from mechatron.compiler.flatten import ColumnRows, column_of, flatten, stack_columns
from mechatron.compiler.heap import ARENAS_FROM, kept_heap
from mechatron.compiler.relations import extract_relations
from mechatron.compiler.structure import lower
from mechatron.core.component import Component

__all__ = ["compile_model"]


def compile_model(model: Component, *, name: str | None = None,
                  check_dimensions: bool = True) -> CompiledModel:
    """Compile a model into a :class:`CompiledModel` (see :func:`_compile`).

    ``check_dimensions=False`` skips the dimension check of the equations
    (:mod:`mechatron.compiler.dimensions`); a component class can opt out on its own with
    the class attribute ``check_dimensions = False``.

    The cyclic garbage collector is paused while compiling: the passes allocate hundreds of
    thousands of short-lived wrappers and no cycles, and full collections over a growing
    heap would make compile time grow faster than the model. No cycles is a rule the
    passes keep (tests/compiler/test_pipeline.py): what a compile drops is freed by
    reference counts as it goes, while a cycle would hold its memory to the end and
    leave the collector's first pass after the compile to visit all of it.

    glibc keeps the memory the compile frees for the compile's own later use, and hands
    it back when the compile is done; so does Python for its arenas when the model has
    `ARENAS_FROM` elements or more (:mod:`mechatron.compiler.heap`).
    """
    enabled = gc.isenabled()
    gc.disable()
    try:
        with kept_heap(arenas=_at_least(model, ARENAS_FROM)):
            return _compile(model, name, check_dimensions)
    finally:
        if enabled:
            gc.enable()


def _at_least(model: Component, count: int) -> bool:
    """Whether the tree of ``model`` holds ``count`` elements or more (its components and
    ports), walked only until it does."""
    seen, stack = 0, [model]
    while stack:
        children = stack.pop()._children
        seen += len(children)
        if seen >= count:
            return True
        stack.extend([c for c in children.values() if isinstance(c, Component)])
    return False


def _external_blocks(model: Component, classes: frozenset) -> list[dict]:
    """What each part stepped outside the model's functions needs (an imported FMU, see
    :mod:`mechatron.fmi`): the ``external_block()`` of every such part, in tree order.
    No walk over the tree when no class among ``classes`` (the classes of its elements,
    `FlatModel.classes`) has that method."""
    if not any(hasattr(cls, "external_block") for cls in classes):
        return []
    out, stack = [], [model]
    while stack:
        el = stack.pop()
        describe = getattr(el, "external_block", None)
        if describe is not None:
            out.append(describe())
        stack.extend(reversed([c for c in el._children.values()
                               if isinstance(c, Component)]))
    return out


def _read_through(column: ca.SX, rep: np.ndarray, scale: np.ndarray,
                  kept: np.ndarray, out: ca.SX | None = None,
                  place: np.ndarray | None = None) -> ca.SX:
    """Each variable read through alias elimination, ``scale * column[rep]`` where
    ``kept``, else the constant ``scale``: rows of ``column`` gathered and put in place by
    slices of a column of zeros (a sign where one is -1, a product where the factor is
    another number), not a sparse product and its densification (a sixth of the cost).
    Written into rows ``place`` of ``out`` when given (else a new column of them alone)."""
    if out is None:
        out, place = ca.SX.zeros(len(rep)), np.arange(len(rep))
    unit = kept & (scale == 1.0)
    for at, sign in ((np.flatnonzero(unit), 1.0),
                     (np.flatnonzero(kept & (scale == -1.0)), -1.0),
                     (np.flatnonzero(kept & ~unit & (scale != -1.0)), None)):
        if at.size:
            part = column[rep[at].tolist()]
            out.nz[place[at].tolist()] = part if sign == 1.0 else -part if sign == -1.0 \
                else part * ca.DM(scale[at].tolist())
    fixed = np.flatnonzero(~kept)
    if fixed.size:
        out.nz[place[fixed].tolist()] = ca.DM(scale[fixed].tolist())
    return out


def _logged(flat, alias, values: ca.SX) -> tuple[list, list, list, ca.SX]:
    """Every logged variable: names, units, docs, and the column of their expressions in
    the unknowns, formed in bulk (no CasADi call per variable): the model's variables by
    `_read_through`, the variables of folded ports put in place between them: those of
    one term by `_read_through` too, the longer sums as one sparse matrix times the
    model's stacked variable symbols plus constants. Each is
    a sum of model variables read through alias elimination (a variable removed by it is
    a scaled representative or a constant): a model variable the sum of itself, a
    variable of a folded subsystem port (:mod:`mechatron.compiler.folding`) that of its
    terms, logged where its port is declared.

    The rows of the model's variables come from alias elimination's arrays for all of
    them at once (`AliasResult.representative`, `AliasResult.scale`); only the folded
    variables, placed between them, are read term by term.

    ``values``: what each unknown (`AliasResult.unknowns`, in order) stands for, its
    symbol or the expression the lowering solved it by; the representatives are read
    from it, so that the column needs no substitution of the solved unknowns (a walk
    over every logged variable)."""
    variables = flat.variables
    n = len(variables)
    names = list(variables)
    units = column_of(variables, "unit")
    docs = column_of(variables, "doc")
    if alias.representative is not None:
        rep, scale = alias.representative, alias.scale
    else:
        rep, scale = np.arange(n), np.ones(n)
    f_names, f_units, f_docs, position, f_terms = flat.folded_columns()
    n_f = len(f_names)
    if not names and not n_f:
        return names, units, docs, ca.SX(0, 1)
    # row of each model variable: after the folded variables placed before it
    var_row = np.arange(n) + np.searchsorted(position, np.arange(n), side="right")
    kept = rep >= 0
    # each representative read by its place among the unknowns
    unknown = alias.unknown_index if alias.unknown_index is not None else \
        np.zeros(0, dtype=np.intp)
    place = np.full(n, -1, dtype=np.intp)
    place[unknown] = np.arange(len(unknown))
    rep, x, n_x = np.where(kept, place[rep], -1), values, values.numel()
    if not n_f:
        return names, units, docs, _read_through(x, rep, scale, kept)
    # the folded variables' rows among the model's, the model's variables put in place
    # around them, then the folded ones' terms in bulk
    at = np.minimum(position, n) + np.arange(n_f)
    is_folded = np.zeros(n + n_f, dtype=bool)
    is_folded[at] = True
    merged = []
    for mine, extra in ((names, f_names), (units, f_units), (docs, f_docs)):
        out = np.empty(n + n_f, dtype=object)
        out[at] = extra
        out[~is_folded] = mine
        merged.append(out.tolist())
    column = ca.SX.zeros(n + n_f)
    _read_through(x, rep, scale, kept, column, var_row)
    t_ptr, t_var = f_terms
    count = np.diff(t_ptr)
    # a sum of one term (an across variable, a port with one member inside) is that
    # model variable read through as the model's are; only the longer sums need the
    # sparse product (the rows with no term stay 0)
    single = np.flatnonzero(count == 1)
    if single.size:
        v = t_var[t_ptr[single]]
        _read_through(x, rep[v], scale[v], kept[v], column, at[single])
    many = np.flatnonzero(count > 1)
    if many.size:
        t_row = np.repeat(np.arange(many.size), count[many])
        t_var = t_var[np.repeat(count > 1, count)]     # their terms, row after row
        t_coef = scale[t_var]
        t_rep = rep[t_var]
        gone = t_rep < 0
        constant = np.zeros(many.size)
        np.add.at(constant, t_row[gone], t_coef[gone])
        # the terms of one representative add up (a triplet keeps one entry per place)
        key = t_row[~gone].astype(np.int64) * max(n_x, 1) + t_rep[~gone]
        uniq, inverse = np.unique(key, return_inverse=True)
        sums = np.bincount(inverse, weights=t_coef[~gone], minlength=uniq.size)
        M = ca.DM.triplet((uniq // max(n_x, 1)).tolist(), (uniq % max(n_x, 1)).tolist(),
                          ca.DM(sums.tolist()), many.size, n_x)
        terms = ca.mtimes(M, x)
        nonzero = np.flatnonzero(constant)
        if len(nonzero):         # the constants where there are any (a sparse column)
            terms = terms + ca.DM.triplet(nonzero.tolist(), [0] * len(nonzero),
                                          ca.DM(constant[nonzero].tolist()), many.size, 1)
        column.nz[at[many].tolist()] = ca.densify(terms)
    return (*merged, column)


def _compile(model: Component, name: str | None, dimensions: bool = True) -> CompiledModel:
    """Compile a model into a :class:`CompiledModel`.

    Passes: flatten and connect; the dimension check of every equation (unless
    ``dimensions`` is false); alias elimination; structural analysis with index reduction
    (Pantelides, dummy derivatives); block-lower-triangular sorting with tearing and
    symbolic solution; relations to event modes; lowering to CasADi functions.
    ``CompiledModel.report`` holds counts and timings of each pass.
    """
    timings: dict[str, float] = {}
    cpu_timings: dict[str, float] = {}    # process CPU time: steadier on a shared machine
    clock, cpu_clock = _time.perf_counter(), _time.process_time()

    def lap(key: str) -> None:
        nonlocal clock, cpu_clock
        now, cpu_now = _time.perf_counter(), _time.process_time()
        timings[key], cpu_timings[key] = now - clock, cpu_now - cpu_clock
        clock, cpu_clock = now, cpu_now

    flat = flatten(model, name)
    replace_pre(flat)
    # a folded port variable counts as an unknown and the equation that gives it
    n_folded = flat.n_folded
    n_vars_flat = len(flat.variables) + n_folded
    n_eqs_flat = len(flat.equations) + len(flat.aliases) + n_folded
    lap("flatten")

    if dimensions:
        _check_dimensions(flat, model)
        lap("dimensions")

    alias = eliminate_aliases(flat)
    # no pass after this one reads the flat equations and aliases (the residuals,
    # origins and owners kept live on in `alias`): let them go now, so that the
    # structural analysis reuses their memory instead of touching fresh pages
    flat.equations = flat.aliases = None
    for template in getattr(alias.origins, "templates", ()):
        template.release()      # kept for the origins of messages: not its residuals
    lap("alias")

    ctx = flat.context
    params = list(flat.parameters.values())
    p = flat.parameter_column()     # the symbols formed alone only where read alone
    residuals, origins, owners = alias.residuals, alias.origins, alias.owners
    # stacked once (by alias elimination) for the relation scan and the structural
    # analysis (a vertcat converts each scalar from Python: about 1 us each)
    res_vec = alias.stacked
    scanned, relations = extract_relations(residuals, owners, stacked=res_vec,
                                           origins=origins)
    # the residuals unchanged (no relation in them): their stack serves the lowering; the
    # lowering's variables are the unknowns, then their derivatives
    # (the scalars stacked apart: CasADi's vertcat of a column and 10^5 scalars costs
    # half as much again as the two steps)
    # each unknown's row among the model's variables (none without variables)
    unknown_rows = alias.unknown_index if alias.unknown_index is not None else \
        np.zeros(0, dtype=np.intp)
    unknown_col = flat.stack_rows(unknown_rows.tolist())
    # each unknown's derivative symbol (None if it has none) and theirs stacked: by row
    # when the class templates made them, else by name (a vertcat of scalars)
    def by_name() -> list:
        return [ctx.derivative.get(n) for n in alias.unknowns]

    by_row = flat.derivatives_by_row(unknown_rows.tolist())
    if by_row is None:
        der_of = by_name()
        der_syms = [d for d in der_of if d is not None]
        der_col = ca.vertcat(*der_syms) if der_syms else ca.SX(0, 1)
    else:
        der_of, der_col = by_row
    stacked = (res_vec, stack_columns(unknown_col, der_col)) \
        if residuals and not relations else None
    residuals = scanned
    n_der = len(ctx.derivative)
    plan = prepare_events(flat, alias, relations)
    if len(ctx.derivative) != n_der:      # an event made a derivative: read them again
        der_of = by_name()
        stacked = None
    lap("relations")

    variables = flat.variables
    # in the order of the unknowns, split off their column (a variable's symbol is
    # formed as a Python object only when read: see flatten._ColumnVariable)
    syms = ColumnRows(unknown_col) if alias.unknowns else []
    p_value = _OnDemand(lambda: {q.name: q.value for q in params})   # named by path

    def start_guess(free):
        """Start values of symbols named by path: an unknown's (see `_guess`), a
        parameter's value, else 0."""
        out = []
        for s in free:
            name = s.name()
            if name in variables and name not in alias.eliminated:
                out.append(_guess(flat, alias, name))
            else:
                out.append(p_value.get(name, 0.0))
        return out

    # the hints are read only by messages; the declaration order of the unknowns only
    # by state selection, when index reduction differentiated something
    hints = _OnDemand(lambda: {n: v.hint for n, v in variables.items() if v.hint})
    low = lower(flat.name, residuals, origins, alias.unknowns, syms, der_of,
                ctx.time, start_guess, hints, preference=_state_preference(flat, alias),
                declared=_OnDemand(lambda: dict(zip(alias.unknowns,
                                                    unknown_rows.tolist()))),
                roles=_OnDemand(lambda: _port_roles(flat, alias)),
                classes=flat.components, physical=flat.physical_owners,
                parameters=ColumnRows(p) if params else [], stacked=stacked,
                others=stack_columns(p, ctx.time))
    lap("structure")

    dists = [r.d for r in relations]
    n_ode, n_res = len(low.ode), len(low.residuals)
    shadow = ca.SX.sym("pre_x", len(low.states))
    bind_pre(plan, flat, alias, list(low.states), shadow)
    ini = _initial_residuals(flat, alias)
    n_ini = len(ini)
    # the derivatives and the residuals ride along as one column each (converted from
    # Python once), the logged variables as one column, last
    ode_col = low.ode_col if n_ode else ca.SX(0, 1)
    res_col = ca.vertcat(*low.residuals) if n_res else ca.SX(0, 1)
    n_dist = 2
    pile = [ode_col, res_col] + dists + ini + plan.exprs
    # what each unknown stands for: its symbol, or the expression of the states,
    # algebraic unknowns, parameters and time that it was solved by
    values = unknown_col
    if low.assigned.numel():
        solved, pile = ca.substitute_inplace([low.assigned], [low.assigned_expr], pile,
                                             False)
        rows = low.assigned_rows
        mine = np.flatnonzero(rows < unknown_col.numel())   # not a derivative's
        if mine.size:
            values = ca.SX(unknown_col)
            values.nz[rows[mine].tolist()] = solved[0][mine.tolist()]
    # every logged variable as an expression of those: gathered, not substituted
    names, units, docs, out_col = _logged(flat, alias, values)
    pile.append(out_col)
    if plan:   # action right-hand sides: relations read directly, not through modes
        n_act = len(plan.exprs)
        plan.exprs = direct_relations(pile[len(pile) - 1 - n_act:-1], relations,
                                      pile[n_dist:n_dist + len(dists)])
        pile = pile[:len(pile) - 1 - n_act] + pile[-1:]
    # bind relation placeholders to modes
    modes = ca.SX.sym("mode", len(relations))
    counters = ca.SX.sym("events", len(relations))
    tlast = ca.SX.sym("t_event", len(relations))
    if relations:
        values = [modes[k] if r.op == "sign" else (1 - modes[k]) / 2 if r.op == "initial"
                  else (modes[k] + 1) / 2 for k, r in enumerate(relations)]
        pile = ca.substitute(pile, [r.placeholder for r in relations], values)
    ode_col, res_col = pile[0], pile[1]
    dist = pile[n_dist:n_dist + len(dists)]
    ini = pile[n_dist + len(dists):-1]
    out_col = pile[-1]
    for k, d_clock in clock_distances(plan, relations, ctx.time, counters).items():
        dist[k] = d_clock

    t = ctx.time
    x = low.state_col if low.state_syms else ca.SX(0, 1)
    X = stack_columns(x, modes, counters, tlast)
    z = ca.vertcat(*low.alg_syms) if low.alg_syms else ca.SX(0, 1)
    nr = len(relations)
    xdot = stack_columns(ode_col, ca.SX.zeros(3 * nr)) if (n_ode or nr) else ca.SX(0, 1)
    args, argn = [t, X, z, p], ["t", "x", "z", "p"]
    f_ode = ca.Function("ode", args, [xdot], argn, ["ode"])
    f_alg = ca.Function("alg", args, [res_col], argn,
                        ["alg"])
    f_out = ca.Function("out", args, [out_col], argn,
                        ["y"])
    dvec = ca.vertcat(*dist) if dist else ca.SX(0, 1)
    # time derivative of the distances along the trajectory: decides a mode whose distance
    # is exactly zero (a pulse starting at t = 0 rises; it is not "off")
    ddot = ca.jacobian(dvec, t) + ca.jtimes(dvec, X, xdot) if nr else ca.SX(0, 1)
    f_dist = ca.Function("dist", args, [dvec, ddot], argn, ["d", "d_dot"])
    # and the second derivative, for a relation at rest on its surface to first order (a
    # clutch at the instant its torque reaches break-away: it slides off at once)
    d2dot = ca.jacobian(ddot, t) + ca.jtimes(ddot, X, xdot) if nr else ca.SX(0, 1)
    f_dist2 = ca.Function("dist2", args, [dvec, ddot, d2dot], argn, ["d", "d_dot", "d_ddot"])
    # + 1e-300: an indicator exactly 0 at the end of a step (an edge falling on an output
    # time) would be followed by a negative value without a sign change the solver sees
    f_zero = ca.Function("zero", args, [modes * dvec + 1e-300 if nr else ca.SX(0, 1)],
                         argn, ["zero"])
    index = ca.SX.sym("index")
    events = EventLowering(plan, relations, flat, alias, list(low.states),
                           low.state_syms, flat.name, p=p, shadow=shadow, t=t, z=z)
    post = events.transition(f_dist2, index, t, x, modes, counters, tlast, z, p) if nr \
        else X
    f_transition = ca.Function("transition", [index, t, X, z, p], [post, z],
                               ca.event_in()[:5], ["post_x", "post_z"])
    f_events = ca.Function("events", args, [events.step_events(
        f_dist2, t, x, modes, counters, tlast, z, p) if nr else X], argn, ["post_x"])
    f_init = _initial_function(flat, ini, args, argn, ca.vertcat(x, z, p, t)
                               if n_ini else None)
    scales = ca.vertcat(*flat.time_scales) if flat.time_scales else ca.SX(0, 1)
    f_scales = ca.Function("scales", [p], [scales], ["p"], ["scales"])
    lap("lowering")

    state_starts = []
    state_prior = []
    for n in low.states:
        base = n
        val, prio = 0.0, "none"
        if base in alias.starts:
            val, prio, _ = alias.starts[base]
        state_starts.append(val)
        state_prior.append(prio)
    state_set = set(low.states)
    wanted = [(rep, val, prio, given) for rep, (val, prio, given) in alias.starts.items()
              if rep not in state_set and prio in ("high", "low")]
    name_index = {n: i for i, n in enumerate(names)} if wanted else {}
    targets = [(given, name_index[rep], val, prio) for rep, val, prio, given in wanted]
    z_start = np.array([_guess(flat, alias, n) if n in flat.variables else 0.0
                        for n in low.alg], dtype=float)
    report = {
        "variables": {"flat": n_vars_flat, "after_alias": len(alias.unknowns),
                      "states": len(low.states), "algebraic": len(low.alg)},
        "equations": {"flat": n_eqs_flat, "after_alias": len(alias.residuals),
                      "after_index_reduction": low.n_equations,
                      "residual": len(low.residuals)},
        "aliases_eliminated": len(alias.eliminated),
        "states": list(low.states),
        "differentiated_equations": list(low.differentiated),
        "blocks": low.n_blocks, "largest_block": low.largest_block,
        "tearing_variables": low.n_torn,
        "relations": len(relations),
        "event_actions": len(plan.groups),
        "when_relations": [k for k, w in enumerate(events.is_when) if w],
        "terminal_relations": [k for k, r in enumerate(relations) if r.op == "terminal"],
        "relation_labels": list(events.labels),
        "discrete": dict(flat.discrete),
        "initial_equations": [str(eq.origin) for eq in flat.initial_equations],
        # the parameters of parts bound to their parents', for messages (CompiledModel.
        # parameter_vector: setting one names the parameter to set instead)
        "bindings": flat.binding_sources(),
        "external_blocks": _external_blocks(model, flat.classes),
        "timings": timings,
        "cpu_timings": cpu_timings,
    }
    cm = CompiledModel(
        name=flat.name, state_names=list(low.states), alg_names=list(low.alg),
        param_names=[q.name for q in params], param_units=[q.unit for q in params],
        p0=np.array([q.value for q in params], dtype=float),
        names=names, units=units, docs=docs,
        relations=[(r.owner, r.op) for r in relations],
        x_start=np.array(state_starts, dtype=float), x_priority=state_prior,
        z_start=z_start, targets=targets, f_ode=f_ode, f_alg=f_alg, f_out=f_out,
        f_zero=f_zero, f_dist=f_dist, f_dist2=f_dist2, f_transition=f_transition, f_scales=f_scales,
        f_events=f_events, f_init=f_init,
        param_bounds=[q.bounds for q in params], report=report,
        input_names=[q.name for q in params if q.is_input],
        input_index=[i for i, q in enumerate(params) if q.is_input],
        input_units=[q.unit for q in params if q.is_input],
        input_docs=[q.doc for q in params if q.is_input],
        input_defaults=[_input_default(flat, q.name) for q in params if q.is_input])
    timings["total"] = sum(timings.values())
    cpu_timings["total"] = sum(cpu_timings.values())
    return cm


def _initial_residuals(flat, alias) -> list:
    """Residuals of the initial equations with aliases replaced by representatives."""
    res = [eq.residual for eq in flat.initial_equations]
    if not res:
        return []
    old, new = [], []
    for name, (rep, k) in alias.eliminated.items():
        old.append(flat.variables[name].sym)
        new.append(ca.SX(k) if rep is None else k * flat.variables[rep].sym)
    return ca.substitute(res, old, new) if old else res


def _initial_function(flat, ini, args, argn, known):
    """``init(t, X, z, p)``: the residuals of the initial equations; None without any.
    A symbol left in them (a derivative that is not a state's, an unknown eliminated by
    index reduction) is an error naming the equation."""
    if known is None:
        return None
    from mechatron.errors import StructuralError
    names = {s.name() for s in ca.symvar(ca.vertcat(known, args[1]))}
    for eq, r in zip(flat.initial_equations, ini):
        free = [s.name() for s in ca.symvar(r) if s.name() not in names
                and not s.name().startswith(("mode_", "events_", "t_event_"))]
        if free:
            raise StructuralError(
                f"model '{flat.name}': initial equation '{eq.origin}' uses "
                f"{', '.join(free[:4])}, which the compiled model does not compute (a "
                "derivative of a variable that is not a state?). Write it in terms of the "
                "states and their derivatives.", variables=free, path=flat.name)
    return ca.Function("init", args, [ca.vertcat(*ini)], argn, ["residual"])


_STATE_SELECT = {"avoid": -1.0, "default": 0.0, "prefer": 1.0}


def _state_preference(flat, alias) -> dict[str, float]:
    """State preference of each alias representative: the highest ``state_select`` of
    its alias class, plus one half for a high-priority start value (the coordinates a
    user fixes initially are the ones to integrate). Only nonzero entries."""
    pref: dict[str, float] = {}
    selects = column_of(flat.variables, "state_select")
    if any(_STATE_SELECT.get(s, 0.0) for s in set(selects)):   # else nothing to read
        for n, select in zip(flat.variables, selects):
            level = _STATE_SELECT.get(select, 0.0)
            if level:
                rep = alias.eliminated.get(n, (n, 1.0))[0]
                if rep is not None:
                    pref[rep] = max(pref.get(rep, level), level)
    for rep, (_, prio, _) in alias.starts.items():
        if prio == "high":
            pref[rep] = pref.get(rep, 0.0) + 0.5
    return {n: v for n, v in pref.items() if v}


class _OnDemand(Mapping):
    """A mapping built on first read: for data that only error messages need."""

    def __init__(self, build):
        self._build, self._data = build, None

    def _get(self) -> dict:
        if self._data is None:
            self._data = self._build()
        return self._data

    def __getitem__(self, key):
        return self._get()[key]

    def __iter__(self):
        return iter(self._get())

    def __len__(self) -> int:
        return len(self._get())

    def __bool__(self) -> bool:     # present, whatever it will hold: not built to test
        return True


def _port_roles(flat, alias) -> dict[str, tuple[str, str, str, bool]]:
    """For each alias representative that stands for port variables: whether they are
    across or through variables, the quantity's name, singular and plural (from the
    domain of the port: "current", "currents"), and True; a component variable in the
    unit of one quantity of the model's domains (a branch voltage ``v`` in V) counts as
    that quantity, with False (not a port). For messages about network topology."""
    domain_of = {}
    for members in getattr(flat, "connection_sets", None) or []:
        for member in members:
            domain_of[member[0]] = member[1]
    by_unit: dict[str, set] = {}
    for domain in set(domain_of.values()):
        for kind in ("across", "through"):
            text = getattr(domain, kind, "") or ""
            if text.endswith(")") and " (" in text:
                by_unit.setdefault(text.rpartition(" (")[2][:-1], set()).add(
                    (kind, text))
    roles: dict[str, tuple[str, str, str, bool]] = {}
    for n, var in flat.variables.items():
        if var.kind not in ("across", "through"):
            continue
        rep = alias.eliminated.get(n, (n, 1.0))[0]
        if rep is None or rep in roles:
            continue
        domain = domain_of.get(n.rpartition(".")[0])
        text = getattr(domain, var.kind, "") if domain is not None else ""
        if domain is None:          # a port wired by a subsystem's plan: by its unit
            match = [t for k, t in by_unit.get(var.unit, ()) if k == var.kind]
            text = match[0] if len(match) == 1 else ""
        one = _quantity(text) or f"{var.kind} variable"
        roles[rep] = (var.kind, one, _plural(one), True)
    for n in alias.unknowns:
        match = by_unit.get(flat.variables[n].unit, ())
        if n not in roles and len(match) == 1:
            kind, text = next(iter(match))
            one = _quantity(text)
            roles[n] = (kind, one, _plural(one), False)
    return roles


def _quantity(text: str) -> str:
    """"angular velocity w (rad/s)" -> "angular velocity"."""
    words = text.split(" (")[0].split(",")[0].split()
    return " ".join(words[:-1] if len(words) > 1 else words)


def _plural(word: str) -> str:
    if word.endswith("y") and not word.endswith(("ay", "ey", "oy")):
        return word[:-1] + "ies"
    if word.endswith(("x", "s")):
        return word + "es"
    return word + "s"


def _input_default(flat, name: str) -> float:
    start = flat.variables[name].start
    return float("nan") if start is None else float(start)


def _guess(flat, alias, name: str) -> float:
    if name in alias.starts:
        return alias.starts[name][0]
    var = flat.variables.get(name)
    if var is not None and var.start is not None:
        return var.start
    return 0.0
