"""Ports of subsystems folded into the nodes they join (part of pass 2, connections).

A subsystem's port (``Stage.p``, wired inside with ``connect(self.p, self.r.p)``) is one
node of the network seen from two sides: an *outside* element of the subsystem's own
connection set and an *inside* element of its parent's (:mod:`mechatron.core.connections`).
Written out, each such port adds its across and through variables as unknowns and one
equation for each; alias elimination then removes them again. A model built from a
subsystem used a thousand times would carry half again as many unknowns through
flattening and alias elimination as the same model built flat.

Folding joins the two sets of such a port into one node before any equation is written,
as Modelica tools merge inside and outside connection sets, so that the port's variables
never become unknowns. They are still logged:

- each across variable equals the node's (the first member's) across variable;
- each through variable follows from the flow balance of the sets on one side of the
  port. The sets joined by folded ports form a tree (a port joins its inner set to its
  outer one); rooted at its busiest set, the through variable of the port above a set is
  the signed sum of the flows of that set's members and of the ports below it. A port
  left open outside carries nothing.

A port is folded only when folding is exact: its component's equations are connections
and nothing else (so nothing reads the port's symbols but connections), it has no start
value, and the joined sets form a tree in which every node keeps a member of its own.
Anything else (an equation reading the port, a loop of ports, a node of ports alone) is
flattened as before, which also keeps the messages about such models unchanged.
"""

from __future__ import annotations

from collections import deque

from mechatron.core.component import Component, Connect, Connector, System
from mechatron.core.connections import Member

__all__ = ["foldable_ports", "fold_sets"]


def foldable_ports(model: Component, elements) -> tuple[dict, dict]:
    """``(prefetched, folded)``: for each subsystem whose equations are connections
    only, its ``[(klass, items)]`` from ``equations()`` (so that flattening does not call
    it twice) under ``id(component)``, and the ports it wires inside, ``id -> Connector``
    in tree order. ``equations()`` is called before symbols are bound: reading a variable
    or parameter raises, which marks the class as not foldable (once per class)."""
    prefetched: dict[int, list] = {}
    folded: dict[int, Connector] = {}
    refused: set[type] = set()
    for el in elements:
        if el is model or not isinstance(el, Component) or type(el) in refused:
            continue
        children = el._children.values()
        ports = [c for c in children if isinstance(c, Connector) and not c._children]
        if not ports or not any(isinstance(c, Component) for c in children):
            continue
        calls = _connections_only(el)
        if calls is None:
            if not isinstance(el, System):      # a System's equations are per instance
                refused.add(type(el))
            continue
        prefetched[id(el)] = [(klass, items) for klass, items, _ in calls]
        wired = {id(port) for _, _, connects in calls for con in connects
                 for port in con.ports}
        for port in ports:          # in declaration order, as they are logged
            if id(port) in wired and not port._starts:
                folded[id(port)] = port
    return prefetched, folded


def _items(items):
    stack = [items]
    while stack:
        item = stack.pop()
        if isinstance(item, (list, tuple)):
            stack.extend(reversed(item))
        elif item is not None:
            yield item


def _connections_only(el) -> list | None:
    calls = []
    for klass in reversed(type(el).__mro__):
        own = vars(klass).get("equations")
        if own is None or klass is Component:
            continue
        try:
            items = own(el)
        except Exception:       # noqa: BLE001 - read a symbol: flattened as before
            return None
        connects = list(_items(items))
        if not all(isinstance(item, Connect) for item in connects):
            return None
        calls.append((klass, items, connects))
    return calls


class Folding:
    """The result of :func:`fold_sets`: the joined physical sets (members of folded
    ports removed, ordered by path) and, for each folded port, the node its across
    variables equal and the signed member paths its through variables sum."""

    __slots__ = ("groups", "node", "flow")

    def __init__(self):
        self.groups: list[list[Member]] = []
        self.node: dict[int, Member] = {}       # id(port) -> first member of its node
        self.flow: dict[int, dict[str, float]] = {}   # id(port) -> {member path: sign}


def fold_sets(sets, folded: dict) -> Folding | None:
    """Join the physical connection sets ``sets`` through the ports ``folded`` (see the
    module's text); None where folding would not be exact (a folded port in no set of
    its own component, a loop of folded ports, a node left with folded ports only, or a
    port on both sides of one node), and the caller flattens the ports as before."""
    where: dict[tuple, int] = {}
    # per set with folded ports: its other members and its folded ones as (id, sign)
    split: dict[int, tuple[list, list]] = {}
    physical = []
    for k, cset in enumerate(sets):
        if cset.is_signal:
            continue
        physical.append(k)
        members = cset.members
        if not any(id(m.port) in folded for m in members):
            continue
        plain, own = [], []
        for m in members:
            pid = id(m.port)
            if pid in folded:
                where[(pid, m.outside)] = k
                own.append((pid, m.sign))
            else:
                plain.append(m)
        split[k] = (plain, own)
    parent = {k: k for k in split}

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    adjacent: dict[int, list] = {k: [] for k in split}
    out = Folding()
    for pid in folded:
        inner = where.get((pid, True))
        if inner is None:
            return None
        outer = where.get((pid, False))
        if outer is None:           # open outside: nothing flows through it
            out.flow[pid] = {}
            continue
        ra, rb = find(inner), find(outer)
        if ra == rb:
            return None             # a loop of folded ports
        parent[rb] = ra
        adjacent[inner].append((pid, outer))
        adjacent[outer].append((pid, inner))
    trees: dict[int, list[int]] = {}
    for k in split:
        trees.setdefault(find(k), []).append(k)
    groups = []
    for k in physical:
        if k not in split:
            groups.append(sets[k].members)
            continue
        ks = trees.get(k)
        if ks is None:
            continue                # not the root of its tree: joined there
        members = [m for j in ks for m in split[j][0]]
        if not members or len({id(m.port) for m in members}) != len(members):
            return None
        if len(ks) > 1:
            members.sort(key=_order)
            _tree_flows(split, ks, adjacent, out.flow)
        groups.append(members)
        first = members[0]
        for j in ks:
            for pid, _ in split[j][1]:
                out.node[pid] = first
    groups.sort(key=lambda g: _order(g[0]))
    out.groups = groups
    return out


def _order(m: Member) -> tuple:
    return (m.path, m.outside)


def _tree_flows(split, ks, adjacent, flow) -> None:
    """The through sums of the folded ports of one tree of sets, leaves first."""
    root = max(ks, key=lambda k: (len(adjacent[k]), -k))
    up: dict[int, int] = {root: 0}      # set -> the port above it
    order = [root]
    queue = deque([root])
    while queue:
        k = queue.popleft()
        for pid, other in adjacent[k]:
            if other not in up:
                up[other] = pid
                order.append(other)
                queue.append(other)
    for k in reversed(order[1:]):
        above = up[k]
        plain, own = split[k]
        total: dict[str, float] = {}
        for m in plain:
            total[m.path] = total.get(m.path, 0.0) + m.sign
        own_sign = 1.0
        for pid, sign in own:
            if pid == above:
                own_sign = sign
            else:       # a port below (or open outside): its flow, signed in this set
                for path, c in flow[pid].items():
                    total[path] = total.get(path, 0.0) + sign * c
        # own_sign * i_above + total == 0
        flow[above] = {path: -c / own_sign for path, c in total.items() if c}
