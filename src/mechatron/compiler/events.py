"""Event actions (``mt.sample``, ``mt.when``) and event iteration, lowered to CasADi.

The integration state is ``X = [x; s; c; te]`` (see :mod:`mechatron.compiler.compiled`).
Events add no new kind of state; every entry of ``s`` is the mode of a *relation*:

- an ordinary relation (``<``, ``<=``, ``sign``) of an equation or of a when condition:
  mode -1/+1, flipped when the indicator ``s * d`` crosses zero (located by the solver);
- a **clock** (op ``"clock"``, of ``mt.sample(Clock, ...)`` or of a condition
  ``sample(start, interval)``): distance ``t - t_next`` with ``t_next = offset + c * period``
  and ``c`` its event counter (the index of the next tick; no drift over many ticks). Its
  mode stays -1, so its indicator crosses zero exactly at ``t_next``;
- the **memory** of a when condition (op ``"mem"``): its mode is the condition's value
  after the last event (+1 true), its "distance" the condition's current value (``2 c -
  1``, constant between events, so it never crosses). A when branch fires in a round in
  which its condition is true and its memory false (a rising edge);
- ``initial()`` and ``terminal()`` (ops ``"initial"``, ``"terminal"``): modes set by the
  initialization and at the end of the run.

Event iteration. An event (or the end of a fixed step, or the initial time) runs *rounds*
until nothing changes: re-read every ordinary relation (the one that crossed keeps its
flipped mode while its distance is unchanged), evaluate the when conditions, fire the
clocks that are due and the branches whose conditions rose, apply their assignments,
update the memories. A when made true by another action fires in the next round of the
same instant. After :data:`MAX_ROUNDS` rounds that still change something the event is a
*loop*: the state before the event is kept and the counters of the relations that changed
in the last round are marked with :data:`LOOP_FLAG`; the simulation then reports them.

The rounds run natively without unrolling: one round is an SX function; a flat function
makes 10 conditional calls (CasADi ``Switch``: a round, a sweep that re-reads the modes one
at a time when they cycle with period two, or a copy once settled), and another makes 10
conditional calls of that one (at most 100 rounds; usually two are computed, the rest are
copies). It is embedded in the transition as a call node (``never_inline``), so CasADi's
virtual machine, the integrators' transition and the generated C evaluate the same code,
and the work memory stays small (about 1,400 doubles for a 23-state controller with 14
relations, compiled for a Cortex-M3).

Chattering: a relation whose event comes within :data:`CHATTER_TIME` of its previous one,
or which is driven straight back across its switching surface, is a sliding mode: its
counter is marked with :data:`CHATTER_FLAG` and the simulation reports the component.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca

from mechatron.compiler.compiled import CHATTER_FLAG, LOOP_FLAG
from mechatron.compiler.flatten import _TemplateEquation, _held
from mechatron.compiler.relations import Relation, _rebuild
from mechatron.core.events import MAX_ROUNDS, Clock, Reinit, SampleCondition
from mechatron.errors import StructuralError

__all__ = ["EventPlan", "prepare_events", "CHATTER_FLAG", "CHATTER_TIME", "LOOP_FLAG",
           "ORDINARY"]

CHATTER_TIME = 1e-9      # s: a relation crossed again within this time is chattering
DUE_TOL = 1e-9           # a tick is due when t >= t_next - DUE_TOL * period
CHAIN = 10               # rounds per conditional chain (MAX_ROUNDS = CHAIN * CHAIN)
ORDINARY = ("<", "<=", "sign")


@dataclass
class _Group:
    owner: str
    kind: str                       # "clock" (a sample action) or "when" (one branch)
    relation: Relation | None       # the clock of a sample action
    outputs: list                   # [(target name, expr index)]
    updates: list
    sources: list = field(default_factory=list)   # when: mem or clock relations
    chain: int = -1                 # when: index of its when (branches share it)


@dataclass
class EventPlan:
    """Event actions of a model between the flattener and the lowering."""

    groups: list[_Group] = field(default_factory=list)
    exprs: list[ca.SX] = field(default_factory=list)   # right-hand sides, pile order
    targets: list[str] = field(default_factory=list)   # assigned variable per expr
    reinit: list[bool] = field(default_factory=list)   # written with reinit() per expr
    clocks: dict = field(default_factory=dict)         # id(relation) -> (period, offset)
    triggers: list = field(default_factory=list)       # relations of when conditions
    labels: dict = field(default_factory=dict)         # id(relation) -> text for messages
    pre: dict = field(default_factory=dict)            # pre() symbol name -> variable name

    def __bool__(self) -> bool:
        return bool(self.groups)


def _alias_map(flat, alias):
    old, new = [], []
    for name, (rep, k) in alias.eliminated.items():
        old.append(flat.variables[name].sym)
        new.append(ca.SX(k) if rep is None else k * flat.variables[rep].sym)
    return old, new


def replace_pre(flat) -> None:
    """``pre(v)`` is ``v`` in equations and initial equations (they differ only inside
    the event iteration, where equations are not evaluated)."""
    ctx = flat.context
    if not ctx.pre:
        return
    old = list(ctx.pre.values())
    new = [ctx.unknowns[name] for name in ctx.pre]
    # a class template's equations hold no pre() (see `flatten._Template`): their
    # residuals are not formed for this
    eqs = [eq for eq in [*_held(flat.equations), *flat.initial_equations]
           if type(eq) is not _TemplateEquation
           and ca.depends_on(eq.residual, ca.vertcat(*old))]
    if eqs:
        res = ca.substitute([eq.residual for eq in eqs], old, new)
        for eq, r in zip(eqs, res):
            eq.residual = r


def _label(expr) -> str:
    text = str(expr)
    return text if len(text) <= 60 else text[:57] + "..."


def prepare_events(flat, alias, relations: list[Relation]) -> EventPlan:
    """Read the event actions of ``flat``; append their relations to ``relations``
    (relations of when conditions, their memories, initial/terminal, then the clocks)."""
    plan = EventPlan()
    for r in relations:
        plan.labels[id(r)] = r.text or (f"{_label(r.d)} {'>' if r.op == '<' else '>='} 0"
                                        if r.op != "sign" else f"sign({_label(r.d)})")
    if not flat.events:
        return plan
    ctx = flat.context
    old, new = _alias_map(flat, alias)
    pre_old = list(ctx.pre.values())
    pre_new = [ctx.unknowns[name] for name in ctx.pre]
    plan.pre = {sym.name(): name for name, sym in ctx.pre.items()}

    def subst(exprs, keep_pre=False):
        exprs = list(exprs)
        if pre_old and not keep_pre and exprs:
            exprs = ca.substitute(exprs, pre_old, pre_new)
        if not old or not exprs:
            return exprs
        return ca.substitute(exprs, old, new)

    triggers: list[Relation] = []
    mems: list[Relation] = []
    special: dict[str, Relation] = {}
    clocks: list[Relation] = []

    def clock_relation(clock: Clock, owner: str, j: int) -> Relation:
        rel = Relation(ca.SX.sym(f"clock{j}[{owner}]"), "clock", ca.SX(0), owner)
        plan.clocks[id(rel)] = (clock.period, clock.offset)
        plan.labels[id(rel)] = f"sample({clock.offset}, {clock.period})"
        clocks.append(rel)
        return rel

    def condition_source(cond, owner: str, j: int) -> Relation:
        if isinstance(cond, SampleCondition):
            return clock_relation(cond.clock, owner, j)
        c = subst([cond])[0]
        for key, sym in ctx.special.items():
            if ca.depends_on(c, sym) and key not in special:
                rel = Relation(sym, key, ca.SX(1.0 if key == "initial" else -1.0), "")
                plan.labels[id(rel)] = f"{key}()"
                special[key] = rel
        n_before = len(triggers)
        c = _rebuild(c, owner, triggers)
        for r in triggers[n_before:]:
            plan.labels[id(r)] = r.text or f"{_label(r.d)} {'>' if r.op == '<' else '>='} 0"
        mem = Relation(ca.SX.sym(f"when{j}[{owner}]"), "mem", 2 * (c != 0) - 1, owner)
        plan.labels[id(mem)] = _label(cond)
        mems.append(mem)
        return mem

    def add_exprs(pairs):
        out = []
        for item in pairs:
            var, expr = item
            out.append((var.name(), len(plan.exprs)))
            plan.exprs.append(expr)
            plan.targets.append(var.name())
            plan.reinit.append(isinstance(item, Reinit))
        return out

    for j, (action, owner) in enumerate(flat.events):
        branches = getattr(action, "branches", None)
        if branches is None:
            outs, ups = add_exprs(action.outputs), add_exprs(action.updates)
            if isinstance(action.trigger, Clock):
                rel = clock_relation(action.trigger, owner, j)
                plan.groups.append(_Group(owner, "clock", rel, outs, ups))
                continue
            branches = [([action.trigger], action.updates)]   # an EventAction by hand
        for conds, pairs in branches:
            sources = [condition_source(c, owner, j) for c in conds]
            plan.groups.append(_Group(owner, "when", None, [], add_exprs(pairs),
                                      sources, chain=j))
    plan.triggers = list(triggers)
    relations.extend(triggers + mems + list(special.values()) + clocks)
    plan.exprs = subst(plan.exprs, keep_pre=True)
    return plan


def bind_pre(plan: EventPlan, flat, alias, states: list[str], shadow: ca.SX) -> None:
    """``pre(v)`` in an action's right-hand side: the value of ``v`` at the start of the
    round, a ``shadow`` of the states that :func:`_apply` replaces by the round's start;
    ``pre`` of a variable that is not a state is its current value."""
    if not plan.pre or not plan.exprs:
        return
    index = {n: i for i, n in enumerate(states)}
    old, new = [], []
    ctx = flat.context
    for name, sym in ctx.pre.items():
        rep, k = alias.eliminated.get(name, (name, 1.0))
        old.append(sym)
        if rep is None:
            new.append(ca.SX(k))
        elif rep in index:
            new.append(k * shadow[index[rep]])
        else:
            new.append(k * flat.variables[rep].sym)
    plan.exprs = ca.substitute(plan.exprs, old, new)


def direct_relations(exprs: list[ca.SX], relations: list[Relation],
                     dists: list[ca.SX]) -> list[ca.SX]:
    """Replace relation placeholders in ``exprs`` by the relations' values computed from
    their distances (action right-hand sides are evaluated only at an event, where the
    value after the jumps of this event is wanted, not the mode before it)."""
    if not exprs or not relations:
        return exprs
    phs = [r.placeholder for r in relations]
    vals = []
    for r, d in zip(relations, dists):
        if r.op == "<":
            vals.append(ca.if_else(d > 0, 1.0, 0.0))
        elif r.op == "<=":
            vals.append(ca.if_else(d >= 0, 1.0, 0.0))
        elif r.op == "sign":
            vals.append(ca.sign(d))
        else:
            vals.append(ca.SX(0))
    ph_vec = ca.vertcat(*phs)
    for _ in range(8):   # nested relations: a distance that contains a placeholder
        if not any(ca.depends_on(e, ph_vec) for e in exprs):
            break
        exprs = ca.substitute(exprs, phs, vals)
    return exprs


def _order_outputs(plan, targets, x_syms, name):
    """Output assignments in dependency order; a cycle is an algebraic loop of blocks."""
    items = [(g, tgt, e) for g in plan.groups for tgt, e in g.outputs]
    if not items:
        return []
    state_of = {targets[e][0]: i for i, (_, _, e) in enumerate(items)}
    deps = []
    for g, _, e in items:
        syms = {s.name() for s in ca.symvar(plan.exprs[e])}
        deps.append({state_of[j] for j, s in enumerate(x_syms)
                     if j in state_of and s.name() in syms})
    order, done = [], set()
    pending = list(range(len(items)))
    while pending:
        ready = [i for i in pending if deps[i] - {i} <= done]
        if not ready:
            loop = _cycle(pending, deps)
            owners = []
            for i in loop:
                if items[i][0].owner not in owners:
                    owners.append(items[i][0].owner)
            raise StructuralError(
                f"model '{name}': algebraic loop among sampled blocks "
                f"{' -> '.join(owners)}: each one's output at a tick depends on the "
                "others' outputs at the same tick. Break the loop with a unit delay "
                "(blocks.UnitDelay) or a memory.", variables=owners, path=name)
        for i in ready:
            order.append(items[i])
            done.add(i)
        pending = [i for i in pending if i not in done]
    return order


def _cycle(pending, deps):
    """The members of one cycle among ``pending`` (follow dependencies until a repeat)."""
    node = pending[0]
    seen = []
    while node not in seen:
        seen.append(node)
        nxt = [d for d in deps[node] if d in pending and d != node]
        if not nxt:
            return seen
        node = nxt[0]
    return seen[seen.index(node):]

def _targets(plan: EventPlan, flat, alias, states: list[str], name: str):
    """Map every assigned variable to (state index, factor)."""
    index = {n: i for i, n in enumerate(states)}
    by_sym = {n: n for n in flat.variables}     # a variable's symbol is named by its path
    out = []
    for sym_name, is_reinit in zip(plan.targets, plan.reinit):
        var = by_sym[sym_name]
        rep, k = alias.eliminated.get(var, (var, 1.0))
        if is_reinit and sym_name in flat.discrete:
            raise StructuralError(
                f"model '{name}': reinit({var}) needs a continuous state, and '{var}' is "
                "a discrete variable (no der() of it in the equations). Assign it with "
                f"update={{{var}: ...}} instead.", variables=[var], path=name)
        if rep is None or rep not in index:
            why = "it is a constant" if rep is None else "it is computed from the others"
            raise StructuralError(
                f"model '{name}': an event action assigns '{var}', which is not a state "
                f"({why}). Assign a discrete variable or a differentiated variable, or "
                "remove the equation that defines it.", variables=[var], path=name)
        out.append((index[rep], k))
    return out


def _stored(kind: str, val):
    """What a discrete variable of ``kind`` stores when assigned ``val``."""
    if kind == "integer":
        return ca.floor(val + 0.5)
    if kind == "boolean":
        return ca.if_else(val != 0, 1.0, 0.0)
    return val


def _apply(plan, order, targets, kinds, x_syms, shadow, x, fire, gidx, bind):
    """``x`` after the actions of the groups whose ``fire`` flag is 1; ``pre()`` reads
    ``x`` (the round's start). ``bind``: (model symbols, round values) of t, z, p."""
    cur = [x[i] for i in range(x.numel())]
    xs = ca.vertcat(*x_syms)
    exprs = list(plan.exprs)
    if bind[0]:
        exprs = ca.substitute(exprs, bind[0], bind[1])
    for g, _, e in order:
        i, k = targets[e]
        val = ca.substitute([exprs[e]], [xs, shadow], [ca.vertcat(*cur), x])[0]
        cur[i] = ca.if_else(fire[gidx[id(g)]], _stored(kinds[e], val) / k, cur[i])
    ups = [(g, e) for g in plan.groups for _, e in g.updates]
    if ups:
        vals = ca.substitute([exprs[e] for _, e in ups], [xs, shadow],
                             [ca.vertcat(*cur), x])
        for (g, e), val in zip(ups, vals):
            i, k = targets[e]
            cur[i] = ca.if_else(fire[gidx[id(g)]], _stored(kinds[e], val) / k, cur[i])
    return ca.vertcat(*cur) if cur else ca.SX(0, 1)


NEAR_TIME = 1e-11   # s: a distance this close to zero (in time to cross) is on the boundary


def _rule(d, d_dot, ops, reach, d_ddot=None):
    """Mode from a distance; on the boundary the direction decides, at rest the op.

    "On the boundary" is a distance that the current motion crosses within
    :data:`NEAR_TIME` and that is at most ``reach`` (see :func:`_surface_reach`): after an
    event located to the solver's event tolerance, a relation that crosses at the same
    instant (``u > 0`` and ``u < 0`` of one signal, a quantizer's next level) has a
    residual distance of either sign; its direction, not that residual, tells its mode. A
    distance that is large (a diode still off after its switch opened: huge and moving
    fast) keeps its sign.
    """
    return ca.vertcat(*[_rule_one(d, d_dot, ops, reach, d_ddot, k)
                        for k in range(len(ops))])


def _surface_reach(d, d_dot, sel):
    """The largest distance :func:`_rule` reads as "on the boundary", per relation, during
    an event at which the relations have distances ``d`` and rates ``d_dot`` (with the
    modes before the event) and ``sel`` marks the relation located by the solver.

    A relation away from its surface: 1e-9 of its distance before the event, or of 1.
    A relation located on its surface (the selected one, and one whose distance is then
    tiny and crossed within :data:`NEAR_TIME` in a known direction, crossing at the same
    instant): no bound, only the time to cross. Its remaining distance is rounding, and
    the modes switched in this event scale it by their conductances (a diode in series
    with one that turned off: the residual 1e-15 V of its on state, times 1/(R_on G_off),
    is 1e-4 V in its off state), while the time it takes to cross does not change with
    that scale. Bounding the distance instead re-reads that amplified residual as a
    side of the surface, and the mode toggles between the two readings."""
    located = ca.logic_or(sel, ca.logic_and(
        ca.logic_and(ca.fabs(d) <= 1e-9, d_dot != 0),
        ca.fabs(d) <= NEAR_TIME * ca.fabs(d_dot)))
    return ca.if_else(located, ca.inf, 1e-9 * ca.fmax(1.0, ca.fabs(d)))


def _rule_one(d, d_dot, ops, reach, d_ddot, k):
    """:func:`_rule` of relation ``k`` alone."""
    for op in (ops[k],):
        at_rest = 1.0 if op != "<" else -1.0
        if d_ddot is not None:     # at rest to first order: where it goes next
            at_rest = ca.if_else(d_ddot[k] > 0, 1, ca.if_else(d_ddot[k] < 0, -1, at_rest))
        near = ca.logic_and(ca.fabs(d[k]) <= NEAR_TIME * ca.fabs(d_dot[k]),
                            ca.fabs(d[k]) <= reach[k])
        return ca.if_else(ca.logic_and(near, d_dot[k] != 0), ca.sign(d_dot[k]),
                          ca.if_else(d[k] > 0, 1, ca.if_else(d[k] < 0, -1, ca.if_else(
                              d_dot[k] > 0, 1, ca.if_else(d_dot[k] < 0, -1, at_rest)))))


def clock_distances(plan: EventPlan, relations, t, counters, p_syms=None):
    """Distance ``t - t_next`` of every clock, by relation index."""
    out = {}
    for k, r in enumerate(relations):
        if id(r) in plan.clocks:
            period, offset = plan.clocks[id(r)]
            out[k] = t - (offset + counters[k] * period)
    return out


def _any(v) -> ca.SX:
    return ca.sum1(v) > 0 if v.numel() else ca.SX(0)


class Lowering:
    """Builds the transition functions once the symbols of ``X`` exist."""

    def __init__(self, plan, relations, flat, alias, states, x_syms, name, p=None,
                 shadow=None, t=None, z=None):
        self.plan = plan
        self.relations = relations
        self.name = name
        self.ops = [r.op for r in relations]
        self.nr = len(relations)
        self.nx = len(x_syms)
        self.targets = _targets(plan, flat, alias, states, name) if plan else []
        self.kinds = [flat.discrete.get(s, "real") for s in plan.targets]
        self.x_syms = x_syms
        self.shadow = shadow if shadow is not None else ca.SX.sym("pre_x", len(x_syms))
        self.p = p if p is not None else ca.SX(0, 1)
        self.t = t if t is not None else flat.context.time
        self.z = z if z is not None else ca.SX(0, 1)
        self.order = _order_outputs(plan, self.targets, x_syms, name) if plan else []
        index = {id(r): k for k, r in enumerate(relations)}
        self.index = index
        self.is_clock = [op == "clock" for op in self.ops]
        self.is_ordinary = [op in ORDINARY for op in self.ops]
        trig = {index[id(r)] for r in plan.triggers}
        self.is_trigger = [k in trig for k in range(self.nr)]
        # the memories of when conditions and initial(): false before the first event
        self.is_when = [op in ("mem", "initial") for op in self.ops]
        self.labels = [plan.labels.get(id(r), f"{r.op} relation") for r in relations]
        self._chain_fn = None

    # -- one round ----------------------------------------------------------------------
    def _round(self, f_dist, nz: int, npar: int, sweep: bool = False) -> ca.Function:
        """One round of the event iteration, ``(C, K) -> C'``, with the carried
        ``C = [x; modes; counters; modes at the start of the last two rounds; go]`` (``go``
        of the result: the round changed something) and the constants ``K = [t; z; p;
        event times; counters before the event; selected relation; distances at the event;
        reach of the surfaces (:func:`_surface_reach`); fixed-step flag]``. ``sweep``: the
        ordinary relations are re-read one after the other, each seeing the modes already
        re-read (used when re-reading them all at once has fallen into a cycle of period
        two, as two sliding modes that each point into the other)."""
        nx, nr = self.nx, self.nr
        C = ca.SX.sym("C", nx + 4 * nr + 1)
        K = ca.SX.sym("K", 1 + nz + npar + 5 * nr + 1)
        t = K[0]
        z = K[1:1 + nz] if nz else ca.SX(0, 1)
        p = K[1 + nz:1 + nz + npar] if npar else ca.SX(0, 1)
        o = 1 + nz + npar
        te, cnt_pre, sel, d0, reach = (K[o + k * nr:o + (k + 1) * nr] for k in range(5))
        fixed = K[o + 5 * nr]
        x = C[:nx] if nx else ca.SX(0, 1)
        modes, cnt, p1 = C[nx:nx + nr], C[nx + nr:nx + 2 * nr], C[nx + 2 * nr:nx + 3 * nr]
        Xc = ca.vertcat(x, modes, cnt, te)
        d, ddot, d2 = f_dist(t, Xc, z, p)

        def reread(k, d, ddot, d2):
            le = 1.0 if self.ops[k] in ("<=", "sign") else 0.0
            by_sign = ca.if_else(d[k] > 0, 1, ca.if_else(d[k] < 0, -1, 2 * le - 1))
            rule = ca.if_else(fixed, by_sign, _rule_one(d, ddot, self.ops, reach, d2, k))
            heading = ca.if_else(ddot[k] > 0, 1, ca.if_else(ddot[k] < 0, -1, ca.if_else(
                d2[k] > 0, 1, ca.if_else(d2[k] < 0, -1, modes[k]))))
            # the relation that crossed keeps its flipped mode while its distance is
            # unchanged; a when trigger takes the direction it now moves in (a ball
            # that bounced leaves h <= 0 at once, without another event)
            keep = heading if self.is_trigger[k] else modes[k]
            sel_mode = ca.if_else(d[k] == d0[k], keep, rule)
            return ca.if_else(sel[k], sel_mode, rule)

        new = list(ca.vertsplit(modes))
        if sweep:
            dist = self._dist_call(f_dist)
            for k in range(nr):
                if self.is_ordinary[k]:
                    dk, ddk, d2k = dist(t, ca.vertcat(x, *new, cnt, te), z, p)
                    new[k] = reread(k, dk, ddk, d2k)
        else:
            for k in range(nr):
                if self.is_ordinary[k]:
                    new[k] = reread(k, d, ddot, d2)
        new = ca.vertcat(*new)
        Xm = ca.vertcat(x, new, cnt, te)
        dm = f_dist(t, Xm, z, p)[0]
        # clocks due (the event's own clock until it has advanced in this event)
        periods = self._periods(p)
        due = [ca.SX(0)] * nr
        for k in range(nr):
            if self.is_clock[k]:
                due[k] = ca.logic_or(d[k] >= -DUE_TOL * periods[k],
                                     ca.logic_and(sel[k], cnt[k] == cnt_pre[k]))
        rise = [ca.SX(0)] * nr
        mem_new = list(ca.vertsplit(new))
        for k, op in enumerate(self.ops):
            if op == "mem":
                cond = dm[k] > 0
                rise[k] = ca.logic_and(cond, modes[k] < 0)
                mem_new[k] = ca.if_else(cond, 1, -1)
        fire, fired_chain = [], {}
        for g in self.plan.groups:
            if g.kind == "clock":
                f = due[self.index[id(g.relation)]]
            else:
                f = ca.SX(0)
                for r in g.sources:
                    k = self.index[id(r)]
                    f = ca.logic_or(f, due[k] if self.is_clock[k] else rise[k])
                earlier = fired_chain.get(g.chain, ca.SX(0))
                fired_chain[g.chain] = ca.logic_or(earlier, f)
                f = ca.logic_and(f, ca.logic_not(earlier))
            fire.append(f)
        fire = ca.vertcat(*fire) if fire else ca.SX(0, 1)
        gidx = {id(g): k for k, g in enumerate(self.plan.groups)}
        bind = ([s for s in (self.t, self.z, self.p) if s.numel()],
                [v for s, v in zip((self.t, self.z, self.p), (t, z, p)) if s.numel()])
        x_post = _apply(self.plan, self.order, self.targets, self.kinds, self.x_syms,
                        self.shadow, x, fire, gidx, bind) if self.plan else x
        cnt_new = list(ca.vertsplit(cnt))
        for k in range(nr):
            if self.is_clock[k]:
                period, offset = periods[k], self._offsets(p)[k]
                nxt = ca.floor((t - offset) / period + DUE_TOL) + 1
                cnt_new[k] = ca.if_else(due[k], ca.fmax(nxt, cnt[k] + 1), cnt[k])
        modes_out = ca.vertcat(*mem_new)
        cnt_out = ca.vertcat(*cnt_new)
        lastchg = modes_out != modes
        changed = ca.logic_or(_any(lastchg), ca.logic_or(_any(fire),
                                                         _any(cnt_out != cnt)))
        C_new = ca.vertcat(x_post, modes_out, cnt_out, modes, p1, changed)
        return ca.Function("event_sweep" if sweep else "event_round", [C, K], [C_new])

    def _dist_call(self, f_dist) -> ca.Function:
        """``f_dist`` as a call (not inlined): a sweep evaluates it once per relation."""
        args = [ca.SX.sym(f_dist.name_in(i), f_dist.sparsity_in(i))
                for i in range(f_dist.n_in())]
        return ca.Function("dist_call", args, f_dist(*args), {"never_inline": True})

    def _periods(self, p):
        return self._clock_part(p, 0)

    def _offsets(self, p):
        return self._clock_part(p, 1)

    def _clock_part(self, p, which: int):
        out = [ca.SX(0)] * self.nr
        for k, r in enumerate(self.relations):
            if id(r) in self.plan.clocks:
                expr = self.plan.clocks[id(r)][which]
                out[k] = ca.substitute(expr, self.p, p) if self.p.numel() else expr
        return out

    def _iterate(self, f_dist, nz, npar) -> ca.Function:
        """``(C, K) -> C'``: rounds until one changes nothing (``go`` of the result 0),
        at most MAX_ROUNDS (``go`` 1: the iteration did not settle). Ten rounds form one
        flat function of conditional calls (a round, a sweep when the modes are back where
        they were two rounds ago, or a copy once settled), ten of those the iteration: two
        levels of calls, so the work memory stays small (generated C for a
        microcontroller)."""
        if self._chain_fn is None:
            jacobi = self._round(f_dist, nz, npar)
            sweep = self._round(f_dist, nz, npar, sweep=True)
            nx, nr = self.nx, self.nr
            nC = jacobi.size1_in(0)
            C = ca.MX.sym("C", nC)
            K = ca.MX.sym("K", jacobi.size1_in(1))
            skip = ca.Function("event_settled", [C, K], [C])
            # index 0: settled (copy), 1: a round, otherwise: a sweep
            pick = ca.Function.conditional("event_round_if", [skip, jacobi], sweep)
            out = C
            for _ in range(CHAIN):
                modes = out[nx:nx + nr]
                cycling = ca.logic_and(ca.sum1(modes != out[nx + 2 * nr:nx + 3 * nr]) > 0,
                                       ca.sum1(modes != out[nx + 3 * nr:nx + 4 * nr]) == 0)
                out = pick(out[nC - 1] * (1 + cycling), out, K)
            rounds = ca.Function("event_rounds", [C, K], [out])
            more = ca.Function.conditional("event_rounds_if", [skip], rounds)
            out = C
            for _ in range(MAX_ROUNDS // CHAIN):
                out = more(out[nC - 1], out, K)
            self._chain_fn = ca.Function("event_iteration", [C, K], [out],
                                         {"never_inline": True})
        return self._chain_fn

    # -- transitions --------------------------------------------------------------------
    def _event(self, f_dist, sel, fixed, t, x, modes, counters, tlast, z, p, chatter):
        nx, nr = self.nx, self.nr
        X = ca.vertcat(x, modes, counters, tlast)
        ordinary = ca.DM([1.0 if o else 0.0 for o in self.is_ordinary])
        flipped = modes * (1 - 2 * sel * ordinary)
        X1 = ca.vertcat(x, flipped, counters, tlast)
        d0 = f_dist(t, X1, z, p)[0]
        dref, ddot_ref = f_dist(t, X, z, p)[:2]
        reach = _surface_reach(dref, ddot_ref, sel * ordinary)
        K = ca.vertcat(t, z, p, tlast, counters, sel, d0, reach, fixed)
        it = self._iterate(f_dist, z.numel(), p.numel())
        Cf = it(ca.vertcat(x, flipped, counters, ca.DM.zeros(2 * nr), 1), K)
        xf = Cf[:nx] if nx else ca.SX(0, 1)
        modes_f = Cf[nx:nx + nr]
        cnt_f = Cf[nx + nr:nx + 2 * nr]
        te_f = tlast
        lastchg = modes_f != Cf[nx + 2 * nr:nx + 3 * nr]     # in the last round
        looping = Cf[nx + 4 * nr]
        initial = ca.DM([1.0 if op == "initial" else 0.0 for op in self.ops])
        modes_f = initial + (1 - initial) * modes_f          # initial() is over
        # a relation that crossed at the same instant as the located one counts too,
        # even when the iteration brings its mode back (a brake that locks: its gated
        # slip relation returns to its resting mode); such a relation sits on its
        # surface (to the time the solver resolves) and was moving across it
        crossing = ca.logic_and(ca.fabs(dref) <= NEAR_TIME * ca.fabs(ddot_ref),
                                modes * ddot_ref < 0)
        counted = ordinary * ca.logic_or(ca.logic_or(sel, modes_f != modes),
                                         (1 - fixed) * crossing)
        cnt_out = cnt_f + counted
        stamped = ca.logic_or(counted, cnt_f != counters)
        te_out = te_f + stamped * (t - te_f)
        if chatter:
            X_ok = self._chatter(f_dist, sel, t, xf, modes_f, cnt_out, te_out, z, p,
                                 tlast, counters, X)
        else:
            X_ok = ca.vertcat(xf, modes_f, cnt_out, te_out)
        # no fixed point: keep the state before the event and mark what kept changing
        first = lastchg * (counters < 0.75 * LOOP_FLAG)     # the first loop is reported
        X_loop = ca.vertcat(x, modes, counters + LOOP_FLAG * first,
                            tlast + first * (t - tlast))
        return ca.if_else(looping, X_loop, X_ok)

    def transition(self, f_dist, index, t, x, modes, counters, tlast, z, p):
        """Post-event ``X`` for an event of relation ``index`` (variable step; -1: no
        relation crossed, as at the initial time)."""
        sel = ca.vertcat(*[index == k for k in range(self.nr)])
        return self._event(f_dist, sel, 0, t, x, modes, counters, tlast, z, p, True)

    def step_events(self, f_dist, t, x, modes, counters, tlast, z, p):
        """``X`` after the events found at the end of a fixed step (relations read by
        the sign of their distance)."""
        sel = ca.DM.zeros(self.nr)
        return self._event(f_dist, sel, 1, t, x, modes, counters, tlast, z, p, False)

    def _chatter(self, f_dist, sel, t, x, modes, counters, tlast, z, p, tlast_pre,
                 counters_pre, X_pre):
        """Mark the event's relation as chattering (see the module docstring) if

        - it fired again within CHATTER_TIME of its previous event, or
        - it was approaching its switching surface before the event and, with the new
          mode, approaches it again at once (it would be crossed back within
          CHATTER_TIME): the switched dynamics point into the surface from both sides."""
        plain = ca.DM([1.0 if o and not w else 0.0 for o, w in
                       zip(self.is_ordinary, self.is_trigger)])
        rapid = ca.logic_and(counters_pre > 0, t - tlast_pre < CHATTER_TIME)
        ddot_pre = f_dist(t, X_pre, z, p)[1]
        d, ddot = f_dist(t, ca.vertcat(x, modes, counters, tlast), z, p)[:2]
        modes_pre = X_pre[x.numel():x.numel() + len(self.ops)]
        before = modes_pre * ddot_pre < 0
        after = ca.logic_and(modes * ddot < 0, modes * d <= -CHATTER_TIME * modes * ddot)
        flag = sel * plain * ca.logic_or(rapid, ca.logic_and(before, after))
        return ca.vertcat(x, modes, counters + CHATTER_FLAG * flag, tlast)
