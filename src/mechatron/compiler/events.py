"""Event actions (``mt.sample``, ``mt.when``) lowered into the event machinery.

The integration state is ``X = [x; s; c; te]`` (see :mod:`mechatron.compiler.compiled`).
Event actions add no new kind of state:

- a discrete state is an entry of ``x`` with ``der = 0`` (added by the flattener);
- a **clock** is a relation of op ``"clock"`` with distance ``t - t_next`` where
  ``t_next = offset + c * period`` and ``c`` is the relation's event counter (the index of
  the next tick; computed from the counter, so no drift accumulates over many ticks). Its
  mode stays -1 between ticks, so its indicator ``s * d`` crosses zero exactly at
  ``t_next``;
- a **when** condition is an ordinary relation (``<``/``<=``); its actions run when its
  mode turns from -1 to +1.

:func:`build_transition` returns the variable-step transition (an event at relation
``index``): flip or re-read the modes, fire the due clocks (every clock whose tick is at
this time, so simultaneous ticks of several rates are one event) and the rising whens,
apply their actions, re-read the modes after the jump. :func:`build_step_events` is the
same logic at the end of a fixed step (and at the initial time). Both are CasADi
expressions: events are handled natively, with no Python per event.

Chattering: a relation whose event comes within :data:`CHATTER_TIME` of its previous one
has been driven straight back across its switching surface (a sliding mode, e.g. an ideal
relay in a feedback loop, which would switch without end): its counter is marked with
:data:`CHATTER_FLAG`, the mode stays as it is, and the simulation reports the component
after the run.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca

from mechatron.compiler.relations import Relation
from mechatron.core.events import Clock
from mechatron.errors import StructuralError

__all__ = ["EventPlan", "prepare_events", "CHATTER_FLAG", "CHATTER_TIME"]

CHATTER_FLAG = 1e15      # added to an event counter to mark chattering
CHATTER_TIME = 1e-9      # s: a relation crossed again within this time is chattering
REREAD_ROUNDS = 3        # rounds of re-reading the modes after an event
DUE_TOL = 1e-9           # a tick is due when t >= t_next - DUE_TOL * period


@dataclass
class _Group:
    owner: str
    kind: str                       # "clock" or "when"
    relation: Relation
    outputs: list                   # [(target name, expr index)]
    updates: list
    period: ca.SX | None = None
    offset: ca.SX | None = None


@dataclass
class EventPlan:
    """Event actions of a model between the flattener and the lowering."""

    groups: list[_Group] = field(default_factory=list)
    exprs: list[ca.SX] = field(default_factory=list)   # right-hand sides, pile order
    targets: list[str] = field(default_factory=list)   # assigned variable per expr

    def __bool__(self) -> bool:
        return bool(self.groups)


def _alias_map(flat, alias):
    old, new = [], []
    for name, (rep, k) in alias.eliminated.items():
        old.append(flat.variables[name].sym)
        new.append(ca.SX(k) if rep is None else k * flat.variables[rep].sym)
    return old, new


def prepare_events(flat, alias, relations: list[Relation]) -> EventPlan:
    """Read the event actions of ``flat``; append their relations to ``relations``
    (whens now; clocks last, after every other relation)."""
    plan = EventPlan()
    if not flat.events:
        return plan
    old, new = _alias_map(flat, alias)

    def subst(exprs):
        if not old or not exprs:
            return list(exprs)
        return ca.substitute(list(exprs), old, new)

    clocks = []
    for j, (action, owner) in enumerate(flat.events):
        outs, ups = [], []
        for dest, pairs in ((outs, action.outputs), (ups, action.updates)):
            for var, expr in pairs:
                dest.append((var.name(), len(plan.exprs)))
                plan.exprs.append(expr)
                plan.targets.append(var.name())
        if isinstance(action.trigger, Clock):
            rel = Relation(ca.SX.sym(f"clock{j}[{owner}]"), "clock", ca.SX(0), owner)
            clocks.append(rel)
            plan.groups.append(_Group(owner, "clock", rel, outs, ups,
                                      action.trigger.period, action.trigger.offset))
        else:
            cond = action.trigger
            op = "<" if cond.is_op(ca.OP_LT) else "<="
            d = subst([cond.dep(1) - cond.dep(0)])[0]
            rel = Relation(ca.SX.sym(f"when{j}[{owner}]"), op, d, owner)
            relations.append(rel)
            plan.groups.append(_Group(owner, "when", rel, outs, ups))
    relations.extend(clocks)
    plan.exprs = subst(plan.exprs)
    return plan


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


def _targets(plan: EventPlan, flat, alias, states: list[str], name: str):
    """Map every assigned variable to (state index, factor)."""
    index = {n: i for i, n in enumerate(states)}
    by_sym = {v.sym.name(): n for n, v in flat.variables.items()}
    out = []
    for sym_name in plan.targets:
        var = by_sym[sym_name]
        rep, k = alias.eliminated.get(var, (var, 1.0))
        if rep is None or rep not in index:
            why = "it is a constant" if rep is None else "it is computed from the others"
            raise StructuralError(
                f"model '{name}': an event action assigns '{var}', which is not a state "
                f"({why}). Assign a discrete variable or a differentiated variable, or "
                "remove the equation that defines it.", variables=[var], path=name)
        out.append((index[rep], k))
    return out


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


def _apply(plan, order, targets, x_syms, x, fire):
    """``x`` after the actions of the groups whose ``fire`` flag is 1."""
    gidx = {id(g): k for k, g in enumerate(plan.groups)}
    cur = [x[i] for i in range(x.numel())]
    xs = ca.vertcat(*x_syms)
    for g, _, e in order:
        i, k = targets[e]
        val = ca.substitute([plan.exprs[e]], [xs], [ca.vertcat(*cur)])[0]
        cur[i] = ca.if_else(fire[gidx[id(g)]], val / k, cur[i])
    ups = [(g, e) for g in plan.groups for _, e in g.updates]
    if ups:
        vals = ca.substitute([plan.exprs[e] for _, e in ups], [xs], [ca.vertcat(*cur)])
        for (g, e), val in zip(ups, vals):
            i, k = targets[e]
            cur[i] = ca.if_else(fire[gidx[id(g)]], val / k, cur[i])
    return ca.vertcat(*cur) if cur else ca.SX(0, 1)


NEAR_TIME = 1e-11   # s: a distance this close to zero (in time to cross) is on the boundary


def _rule(d, d_dot, ops, d_ref):
    """Mode from a distance; on the boundary the direction decides, at rest the op.

    "On the boundary" includes a distance that is tiny (at most 1e-9 of its size before
    the event, ``d_ref``, or of 1) and that the current motion crosses within
    :data:`NEAR_TIME`: after an event located to the solver's event tolerance, a relation
    that crosses at the same instant (``u > 0`` and ``u < 0`` of one signal, a
    quantizer's next level) has a residual distance of either sign; its direction, not
    that residual, tells its mode. A distance that is large (a diode still off after its
    switch opened: huge and moving fast) keeps its sign.
    """
    out = []
    for k, op in enumerate(ops):
        at_rest = 1.0 if op != "<" else -1.0
        near = ca.logic_and(ca.fabs(d[k]) <= NEAR_TIME * ca.fabs(d_dot[k]),
                            ca.fabs(d[k]) <= 1e-9 * ca.fmax(1.0, ca.fabs(d_ref[k])))
        out.append(ca.if_else(ca.logic_and(near, d_dot[k] != 0), ca.sign(d_dot[k]),
                   ca.if_else(d[k] > 0, 1, ca.if_else(d[k] < 0, -1, ca.if_else(
                       d_dot[k] > 0, 1, ca.if_else(d_dot[k] < 0, -1, at_rest))))))
    return ca.vertcat(*out)


def clock_distances(plan: EventPlan, relations, t, counters, p_syms=None):
    """Distance ``t - t_next`` of every clock, by relation index."""
    out = {}
    index = {id(r): k for k, r in enumerate(relations)}
    for g in plan.groups:
        if g.kind == "clock":
            k = index[id(g.relation)]
            out[k] = t - (g.offset + counters[k] * g.period)
    return out


class Lowering:
    """Builds the transition functions once the symbols of ``X`` exist."""

    def __init__(self, plan, relations, flat, alias, states, x_syms, name):
        self.plan = plan
        self.relations = relations
        self.ops = [r.op for r in relations]
        self.targets = _targets(plan, flat, alias, states, name) if plan else []
        self.x_syms = x_syms
        self.order = _order_outputs(plan, self.targets, x_syms, name) if plan else []
        index = {id(r): k for k, r in enumerate(relations)}
        self.group_rel = [index[id(g.relation)] for g in plan.groups]
        self.is_clock = [op == "clock" for op in self.ops]
        whens = {k for g, k in zip(plan.groups, self.group_rel) if g.kind == "when"}
        self.is_when = [k in whens for k in range(len(relations))]

    def _fire(self, t, modes_old, modes_new, sel, counters):
        fire = []
        for g, k in zip(self.plan.groups, self.group_rel):
            if g.kind == "clock":
                t_next = g.offset + counters[k] * g.period
                due = t >= t_next - DUE_TOL * g.period
                fire.append(ca.logic_or(sel[k], due) if sel is not None else due)
            else:
                fire.append(ca.logic_and(modes_old[k] < 0, modes_new[k] > 0))
        return ca.vertcat(*fire) if fire else ca.SX(0, 1)

    def _clock_counts(self, t, counters, fire):
        """Clocks that fired advance their counter to the index of the next tick."""
        out = [counters[k] for k in range(counters.numel())]
        for (g, k), f in zip(zip(self.plan.groups, self.group_rel), ca.vertsplit(fire)):
            if g.kind == "clock":
                nxt = ca.floor((t - g.offset) / g.period + DUE_TOL) + 1
                out[k] = ca.if_else(f, ca.fmax(nxt, counters[k] + 1), counters[k])
        return ca.vertcat(*out)

    def transition(self, f_dist, index, t, x, modes, counters, tlast, z, p):
        """Post-event ``X`` for an event of relation ``index`` (variable step)."""
        nr = len(self.relations)
        sel = ca.vertcat(*[index == k for k in range(nr)])
        flipped = modes * (1 - 2 * sel)
        # re-read the other modes, a few rounds: a relation whose distance depends on
        # another mode (a freewheeling diode behind a switch) settles in the next round
        d_ref, _ = f_dist(t, ca.vertcat(x, modes, counters, tlast), z, p)
        modes_a = flipped
        for _ in range(REREAD_ROUNDS):
            d_a, ddot_a = f_dist(t, ca.vertcat(x, modes_a, counters, tlast), z, p)
            modes_a = sel * flipped + (1 - sel) * _rule(d_a, ddot_a, self.ops, d_ref)
        clock = ca.DM([1.0 if c else 0.0 for c in self.is_clock])
        if not self.plan:
            # an event of every relation whose mode changed (the diode that takes over
            # when its switch opens counts, though the switch's relation fired)
            counted = ca.logic_or(sel, modes_a != modes)
            c_post = counters + counted
            te_post = tlast + counted * (t - tlast)
            return self._chatter(f_dist, sel, t, x, modes_a, c_post, te_post, z, p, tlast,
                                 counters, ca.vertcat(x, modes, counters, tlast))
        fire = self._fire(t, modes, modes_a, sel, counters)
        x_post = _apply(self.plan, self.order, self.targets, self.x_syms, x, fire)
        c_post = self._clock_counts(t, counters + (1 - clock) * sel, fire)
        counted = ca.fmin(c_post - counters, 1)
        te_post = tlast + counted * (t - tlast)
        any_fire = ca.sum1(fire) > 0
        modes_b = modes_a
        for _ in range(REREAD_ROUNDS):
            d_b, ddot_b = f_dist(t, ca.vertcat(x_post, modes_b, c_post, te_post), z, p)
            rule_b = _rule(d_b, ddot_b, self.ops, d_ref)
            same = d_b == d_a
            keep = sel * same        # the event's own relation: flip unless it jumped
            modes_b = ca.if_else(any_fire, keep * modes_a + (1 - keep) * rule_b, modes_a)
        # a when condition is only a trigger: after its action it takes the direction in
        # which its distance now moves (a relay's threshold is left at once, no event)
        when = ca.DM([1.0 if w else 0.0 for w in self.is_when])
        heading = ca.if_else(ddot_b > 0, 1, ca.if_else(ddot_b < 0, -1, modes_b))
        turn = sel * when * same
        modes_b = turn * heading + (1 - turn) * modes_b
        changed = (1 - clock) * (modes_b != modes) * (1 - sel)
        c_post = c_post + changed
        te_post = te_post + changed * (t - te_post)
        return self._chatter(f_dist, sel, t, x_post, modes_b, c_post, te_post, z, p, tlast,
                             counters, ca.vertcat(x, modes, counters, tlast))

    def _chatter(self, f_dist, sel, t, x, modes, counters, tlast, z, p, tlast_pre,
                 counters_pre, X_pre):
        """Mark the event's relation as chattering (see the module docstring) if

        - it fired again within CHATTER_TIME of its previous event, or
        - it was approaching its switching surface before the event and, with the new
          mode, approaches it again at once (it would be crossed back within
          CHATTER_TIME): the switched dynamics point into the surface from both sides."""
        plain = ca.DM([0.0 if c or w else 1.0 for c, w in
                       zip(self.is_clock, getattr(self, "is_when", self.is_clock))])
        rapid = ca.logic_and(counters_pre > 0, t - tlast_pre < CHATTER_TIME)
        _, ddot_pre = f_dist(t, X_pre, z, p)
        d, ddot = f_dist(t, ca.vertcat(x, modes, counters, tlast), z, p)
        modes_pre = X_pre[x.numel():x.numel() + len(self.ops)]
        before = modes_pre * ddot_pre < 0
        after = ca.logic_and(modes * ddot < 0, modes * d <= -CHATTER_TIME * modes * ddot)
        flag = sel * plain * ca.logic_or(rapid, ca.logic_and(before, after))
        return ca.vertcat(x, modes, counters + CHATTER_FLAG * flag, tlast)

    def step_events(self, f_dist, t, x, modes, counters, tlast, z, p):
        """``X`` after the events found at the end of a fixed step (or at the start)."""
        d, _ = f_dist(t, ca.vertcat(x, modes, counters, tlast), z, p)
        le = [1.0 if op in ("<=", "sign") else 0.0 for op in self.ops]
        new = ca.vertcat(*[ca.if_else(d[k] > 0, 1, ca.if_else(d[k] < 0, -1, 2 * le[k] - 1))
                           for k in range(len(self.ops))])
        clock = ca.DM([1.0 if c else 0.0 for c in self.is_clock])
        changed = (new != modes) * (1 - clock)
        if not self.plan:
            c_post = counters + changed
            te_post = ca.vertcat(*[ca.if_else(changed[k], t, tlast[k])
                                   for k in range(len(self.ops))])
            return ca.vertcat(x, new, c_post, te_post)
        fire = self._fire(t, modes, new, None, counters)
        x_post = _apply(self.plan, self.order, self.targets, self.x_syms, x, fire)
        c_post = self._clock_counts(t, counters + changed, fire)
        counted = c_post != counters
        te_post = ca.vertcat(*[ca.if_else(counted[k], t, tlast[k])
                               for k in range(len(self.ops))])
        d_b, _ = f_dist(t, ca.vertcat(x_post, new, c_post, te_post), z, p)
        modes_b = ca.vertcat(*[ca.if_else(d_b[k] > 0, 1, ca.if_else(
            d_b[k] < 0, -1, 2 * le[k] - 1)) for k in range(len(self.ops))])
        # a mode changed by the actions (a PWM's rising edge at its tick) is an event too
        again = (modes_b != new) * (1 - clock)
        c_post = c_post + again
        te_post = te_post + again * (t - te_post)
        return ca.vertcat(x_post, modes_b, c_post, te_post)
