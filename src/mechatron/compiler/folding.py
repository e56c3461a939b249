"""Subsystems wired once per class, their ports folded into the nodes they join (part of
pass 2, connections).

A subsystem's port (``Stage.p``, wired inside with ``connect(self.p, self.r.p)``) is one
node of the network seen from two sides: an *outside* element of the subsystem's own
connection set and an *inside* element of its parent's (:mod:`mechatron.core.connections`).
Written out, each such port adds its across and through variables as unknowns and one
equation for each, which alias elimination then removes again, and every instance of the
subsystem repeats the same connections. A model built from a subsystem used a thousand
times would carry half again as many unknowns through flattening as the same model built
flat.

Here a subsystem class whose equations are connections only is wired once: its *plan*
lists the sets its connections form, by relative path, from its first instance. Every
instance then joins each of its sets into the node outside its port (the set holding no
port of its own stays a node of its own), as Modelica tools merge inside and outside
connection sets, and the port's variables never become unknowns. They are still logged:

- each across variable equals the node's (the first member's) across variable;
- each through variable is the sum of the through variables of the inside members of
  its set (what flows into the port flows on into the parts), a nested subsystem's port
  standing for its own set's sum.

A plan requires each set to hold at most one port of the subsystem itself (so that the
sums above are well defined and the joined sets form a tree), every port of its parts to
be connected inside, physical connections only, no signal inputs on its parts and no
attributes of the instance beyond its declarations. Any other subsystem is flattened
connection by connection as before, which keeps the messages about such models unchanged.
A planned port that an equation reads (``s.p.v`` in the parent's equations) is bound as a
variable on first read and stays a member of its node (see ``flatten._FoldedSymbols``).
"""

from __future__ import annotations

from operator import attrgetter

from mechatron.core.component import Component, Connect, Connector, System
from mechatron.core.connections import Member, connection_sets
from mechatron.core.declarations import Input

__all__ = ["ClassPlan", "plan_subsystems", "join_planned"]

class ClassPlan:
    """The connection sets of a subsystem class, by path relative to an instance: for
    each set, the name of the class's own port in it (or None) and the other members as
    tuples of names from the instance (``("r", "p")``), ordered by path."""

    __slots__ = ("own", "sets", "has_time_scales", "inner", "keys")

    def __init__(self, own, sets, has_time_scales, keys):
        self.own = own                  # own port name -> index of its set
        self.sets = sets                # [(own port name | None, [names])]
        self.has_time_scales = has_time_scales
        # a set that holds no port of the class: a node inside every instance
        self.inner = any(owner is None for owner, _ in sets)
        # what an instance's __dict__ may hold (the first instance's children)
        self.keys = keys


def plan_subsystems(model: Component, components) -> tuple[dict, dict]:
    """``(planned, folded)``: the instances among ``components`` (the model's, in tree
    order) wired by their class's plan, ``id -> (instance, plan)``, and their ports
    folded, ``id -> Connector`` in tree order. ``planned.inside`` holds the ids of the
    components within planned instances."""
    from mechatron.compiler.flatten import _PLAIN_KEYS
    plans: dict[type, ClassPlan | None] = {}
    planned = _Planned()
    inside, where = planned.inside, planned.where
    folded: dict[int, Connector] = {}
    for el in components:           # parents first
        if el is model:
            continue
        parent = id(el._parent)
        if parent in planned or parent in inside:
            inside.add(id(el))
        if isinstance(el, System):
            continue
        cls = type(el)
        plan = plans.get(cls, 0)
        if plan is None:
            continue
        children = el._children
        # an instance with attributes of its own may connect differently; the plan is
        # read off the first instance without, and holds the keys it allows
        keys = _PLAIN_KEYS | children.keys() if plan == 0 else plan.keys
        if not el.__dict__.keys() <= keys:
            continue
        if plan == 0:
            plan = plans[cls] = _plan(el, keys)
            if plan is None:
                continue
        ports = [children[name] for name in plan.own]
        if any(map(_STARTS, ports)):
            continue                    # a start value on a port: written out
        planned[id(el)] = (el, plan)
        planned.by_plan.setdefault(plan, []).append(el)
        planned.inner = planned.inner or plan.inner
        planned.nested = planned.nested or id(el) in inside
        for port, k in zip(ports, plan.own.values()):
            folded[id(port)] = port
            where[id(port)] = (el, plan, k)
    return planned, folded


_STARTS = attrgetter("_starts")


class _Planned(dict):
    """``id -> (instance, plan)``, with the ids of the components within them and where
    each folded port's set is: ``id(port) -> (instance, plan, set index)``."""

    def __init__(self):
        super().__init__()
        self.inside: set[int] = set()
        self.where: dict[int, tuple] = {}
        self.inner = False      # whether a plan has a set inside only
        # each plan's instances, in tree order; whether an instance lies within another
        # (only then can a plan's set hold a folded port)
        self.by_plan: dict[ClassPlan, list] = {}
        self.nested = False


def _plan(el, keys: frozenset) -> ClassPlan | None:
    """The plan of ``el``'s class read from ``el`` (None if the class does not qualify);
    ``keys``: what the ``__dict__`` of an instance wired by it may hold. ``equations()``
    is called before symbols are bound: reading a variable or parameter raises, which
    marks the class as not qualifying."""
    from mechatron.compiler.flatten import _as_equations, _has_time_scales, _own_methods
    children = el._children
    ports = [n for n, c in children.items() if isinstance(c, Connector)]
    parts = [c for c in children.values() if isinstance(c, Component)]
    if not ports or not parts:
        return None
    connects = []
    has_equations = False
    for klass, own in _own_methods(type(el), "equations"):
        has_equations = has_equations or klass is type(el)
        try:
            items = own(el)
        except Exception:       # noqa: BLE001 - reads a symbol: not connections only
            return None
        for item in _as_equations(items):
            if not isinstance(item, Connect) or len(item.ports) < 2 or not all(
                    isinstance(p, Connector) for p in item.ports):
                return None
            a = item.ports[0]
            if any(type(p) is not type(a) for p in item.ports[1:]):
                return None             # the connection-by-connection path words it
            connects.append((el, list(item.ports)))
    if not connects:
        return None
    prefix = len(el.path) + 1 if el.path else 0
    sets, own = [], {}
    wired = set()
    for cset in connection_sets(connects):
        mine = [m for m in cset.members if m.outside]
        if len(mine) > 1:
            return None                 # two own ports on one node: written out
        names = []
        for m in cset.members:
            wired.add(id(m.port))
            if not m.outside:
                names.append(tuple(m.path[prefix:].split(".")))
        if mine:
            own[mine[0].port._name] = len(sets)
        sets.append((mine[0].port._name if mine else None, names))
    for part in parts:
        if any(isinstance(d, Input) for d in type(part)._declarations.values()):
            return None                 # a signal input inside: checked as before
        if any(isinstance(c, Connector) and id(c) not in wired
               for c in part._children.values()):
            return None                 # a port left open inside: reported as before
    own = {name: own[name] for name in ports if name in own}   # declaration order
    # its time scales are read per instance as when written out (by the class that
    # writes equations), where the class has any
    return ClassPlan(own, sets, has_equations and _has_time_scales(type(el)), keys)


class Joining:
    """The result of :func:`join_planned`: the physical nodes (lists of members ordered
    by path), and for each folded port the node's first member and the members whose
    through variables sum to its own."""

    __slots__ = ("groups", "node", "flow")

    def __init__(self):
        self.groups: list[list[Member]] = []
        self.node: dict[int, Member] = {}
        self.flow: dict[int, list[Member]] = {}


def join_planned(sets, planned: dict, folded: dict) -> Joining:
    """The nodes of the model: its connection sets ``sets`` (from every connection not
    wired by a plan) with each folded port replaced by its set inside, and the sets
    inside the planned instances that no outside port joins."""
    where = planned.where          # id(folded port) -> (instance, plan, set index)
    if len(where) != len(folded):       # a port read by an equation is a member itself
        where = {pid: at for pid, at in where.items() if pid in folded}
    out = Joining()
    expand = _Expansion(where, out)
    groups = out.groups
    for cset in sets:
        if cset.is_signal:
            continue
        members = cset.members
        node, ports = [], []
        for m in members:
            port = m.port
            if not m.outside and id(port) in where:
                inner, nested = expand.inner_of(port)
                node += inner
                ports += nested
                expand.joined_outside.add(id(port))
            else:
                node.append(m)
        if ports:
            _add(out, node, ports)
        else:                   # no folded port inside it: the set as it is
            groups.append(members)
    # the sets no outside node took in: the sets inside only, and those of ports read
    # by an equation or open outside, instance by instance, parents first (a nested
    # port is joined with its parent's set before its own instance is reached); with
    # no set inside only, the ports left are all there is to visit
    joined = expand.joined_outside
    if planned.inner:
        todo = ((el, plan, k) for el, plan in planned.values()
                for k in range(len(plan.sets)))
    else:
        todo = (at for pid, at in planned.where.items() if pid not in joined)
    for el, plan, k in todo:
        owner, names_list = plan.sets[k]
        if owner is None:               # a node inside the subsystem only
            node, ports = expand.members_of(el, names_list)
        else:
            port = el._children[owner]
            if id(port) not in where:   # read by an equation: a member itself
                node, ports = expand.members_of(el, names_list)
                node.insert(0, Member(port, True))
            elif id(port) in joined:
                continue
            else:                       # open outside: nothing flows through it
                node, ports = expand.inner_of(port)
                node, ports = list(node), list(ports)
        _add(out, node, ports)
    groups.sort(key=lambda g: _order(g[0]))
    return out


class _Expansion:
    """The members that folded ports stand for (see `join_planned`), each port's
    resolved once. (A class, not two closures that call each other: their cells would
    form a cycle that keeps every dictionary here alive until the cyclic garbage
    collector runs.)"""

    __slots__ = ("where", "out", "expanded", "joined_outside")

    def __init__(self, where: dict, out: Joining):
        self.where = where      # id(folded port) -> (instance, plan, set index)
        self.out = out
        self.expanded: dict[int, tuple[list, list]] = {}
        # folded ports joined into a node outside their subsystem (instances come
        # parents first, so a nested port is joined before its own subsystem is reached)
        self.joined_outside: set[int] = set()

    def members_of(self, el, names_list) -> tuple[list, list]:
        """The members of the ports ``names_list`` of ``el``, folded ones resolved, and
        the folded ports met on the way."""
        members: list = []
        ports: list = []
        where = self.where
        for names in names_list:
            port = el
            for name in names:
                port = port._children[name]
            if id(port) in where:
                inner, nested = self.inner_of(port)
                members += inner
                ports += nested
                self.joined_outside.add(id(port))
            else:
                members.append(Member(port, False))
        return members, ports

    def inner_of(self, port) -> tuple[list, list]:
        """The inside members of a folded port's set, nested ports resolved, and the
        folded ports met on the way (itself first)."""
        pid = id(port)
        got = self.expanded.get(pid)
        if got is None:
            el, plan, k = self.where[pid]
            members, nested = self.members_of(el, plan.sets[k][1])
            nested.insert(0, port)
            got = self.expanded[pid] = (members, nested)
            self.out.flow[pid] = members
        return got


#: a member's place in its node: by path, the inside element first
_order = attrgetter("path", "outside")


def _add(out: Joining, node: list, ports: list) -> None:
    node.sort(key=_order)
    out.groups.append(node)
    first = node[0]
    for port in ports:
        out.node[id(port)] = first
