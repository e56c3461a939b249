"""The physical connection sets of a model formed on arrays (part of pass 2, connections).

When every physical port is bound in bulk, the physical sets are the connected components
of the graph of the connects' elements (a port with its side,
:mod:`mechatron.core.connections`), ordered as `connection_sets` orders them: members by
path, the inside element first, sets by their first member (`physical_nodes`); the
signal sets, formed set by set, take their places among them. With subsystems wired by
their class's plan (:mod:`mechatron.compiler.folding`), the nodes are the components of
that graph with each plan's sets added instance by instance, each joined to its folded
port's inside element, the folded ports themselves left out (`planned_nodes`), as
`folding.join_planned` joins them set by set. The sets' records, aliases and flow sums
are read off arrays of the members' rows, for these nodes as for those joined set by set
(`joined_nodes`), and the flat model is the same as set by set
(`flatten._physical_set`): Python runs per member only to read each port's attributes,
once, and per set only to write its origin.
"""

from __future__ import annotations

from itertools import chain, repeat
from operator import attrgetter, itemgetter

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph

from mechatron.core.component import Connector

__all__ = ["physical_nodes", "planned_nodes", "joined_nodes", "Joined"]

_PARENT = attrgetter("_parent")        # (flatten's reference check reads it too)
_PATH = attrgetter("_path_cache")       # set by flatten's walk
_SYMS = attrgetter("_syms")
_CHILDREN = attrgetter("_children")
_ROW = attrgetter("row")
_PORT = attrgetter("port")              # of a Member
_OUTSIDE = attrgetter("outside")
_MEMBER_PATH = attrgetter("path")


class Nodes:
    """The physical connection sets, members in order: ``ports[k]``, ``outside[k]``,
    ``paths[k]`` and ``port_ids[k]`` of member ``k``; set ``s`` holds members
    ``ptr[s]:ptr[s + 1]``."""

    __slots__ = ("ports", "outside", "paths", "port_ids", "ptr")

    def __init__(self, ports: list, outside: np.ndarray, paths: list,
                 port_ids: np.ndarray, ptr: np.ndarray):
        self.ports, self.outside, self.paths = ports, outside, paths
        self.port_ids, self.ptr = port_ids, ptr


def physical_nodes(flat, joined: list, signals: list = (), signal_set=None) -> Nodes | None:
    """Record the connection sets of ``joined`` (``(writer, ports)`` of each connect) in
    ``flat`` as `flatten._connections` does set by set: the sets, and the aliases and
    flow sums of each; return them. The model's signal sets ``signals`` (`ConnectionSet`
    each) take their places among them, each recorded by ``signal_set(cset)``. None,
    having changed nothing, when the model is not one this path reads (a connect of
    signals in ``joined``, a port without rows, a member of a class without the first
    member's variables): the caller then goes set by set."""
    formed = _formed(joined)
    if formed is None:
        return None
    nodes, rows = formed       # (what forming them held is freed by now)
    return nodes if _record(flat, nodes, rows, signals, signal_set) else None


def _formed(joined: list) -> tuple[Nodes, np.ndarray] | None:
    """The physical sets of ``joined`` and their members' rows (see `physical_nodes`);
    None if a connect joins signals or a port was not bound in bulk."""
    written = _elements(joined)
    if written is None:
        return None
    got = _components(*written)
    if got is None:
        return None
    nodes = got[0]
    rows = _bulk_rows(nodes.ports)
    return None if rows is None else (nodes, rows)


def _elements(joined: list) -> tuple[list, np.ndarray, np.ndarray] | None:
    """The elements of the connects ``joined`` (``(writer, ports)`` each): each port, its
    side (outside when the connect's writer owns it) and the place of its connect's first
    element, to which it is joined; None if a connect joins signals."""
    writers = list(map(itemgetter(0), joined))
    lists = list(map(itemgetter(1), joined))
    refs = list(chain.from_iterable(lists))
    if not refs or not all(issubclass(t, Connector) for t in set(map(type, refs))):
        return None
    counts = np.fromiter(map(len, lists), dtype=np.intp, count=len(lists))
    n_ref = len(refs)
    outside = np.fromiter(map(id, map(_PARENT, refs)), dtype=np.int64, count=n_ref) == \
        np.repeat(np.fromiter(map(id, writers), dtype=np.int64, count=len(writers)),
                  counts)
    return refs, outside, np.repeat(_starts(counts), counts)


def _components(refs: list, side: np.ndarray, head: np.ndarray,
                drop: np.ndarray | None = None, outer: int = 0) -> tuple | None:
    """The sets of the elements ``refs[k]`` (a port; its outside element with
    ``side[k]``), each element joined to that of ``refs[head[k]]``: the connected
    components, members ordered by path, the inside element of a port first, sets by
    their first member. The elements of the ports whose ids are in ``drop`` join sets
    but are no members. Returns the sets, each element's key (``2 id + side``, sorted),
    the set it is in (-1: a set of dropped elements alone), and with ``outer`` the sets
    the first ``outer`` refs form by themselves (no member dropped), else None; None if
    a port lies outside the walked tree (it has no path)."""
    n_ref = len(refs)
    ids = np.fromiter(map(id, refs), dtype=np.int64, count=n_ref)
    keys, first, inverse = np.unique(ids * 2 + side, return_index=True,
                                     return_inverse=True)
    m = len(first)
    ports = _objects(refs)[first]              # (no integer object per element)
    try:
        paths = list(map(_PATH, ports.tolist()))
    except AttributeError:              # a port outside the walked tree
        return None
    if None in paths:
        return None
    # the elements by path, the inside element of a port first (they are numbered by
    # port, inside before outside, and the sort is stable)
    by_path = np.array(sorted(range(m), key=paths.__getitem__), dtype=np.intp)
    items = (ports, side[first], _objects(paths), ids[first])

    def labels(k: int) -> tuple[int, np.ndarray]:   # the components of the first k refs
        graph = sparse.coo_matrix((np.ones(k, dtype=np.int8),
                                   (inverse[:k], inverse[head[:k]])), shape=(m, m))
        return csgraph.connected_components(graph, directed=False)

    if drop is None:
        members = by_path
    else:               # each element of a dropped port (the keys are sorted)
        gone = np.zeros(m + 1, dtype=bool)
        for sided in (drop * 2, drop * 2 + 1):
            at = np.searchsorted(keys, sided)
            gone[np.where(keys[np.minimum(at, m - 1)] == sided, at, m)] = True
        members = by_path[~gone[by_path]]
    n_label, label = labels(n_ref)
    nodes, set_of = _grouped(members, label, n_label, items)
    if not outer:
        return nodes, keys, set_of, None
    mine = np.zeros(m, dtype=bool)
    mine[inverse[:outer]] = True
    n_label, label = labels(outer)
    return nodes, keys, set_of, _grouped(by_path[mine[by_path]], label, n_label, items)[0]


def _grouped(members: np.ndarray, label: np.ndarray, n_label: int,
             items: tuple) -> tuple[Nodes, np.ndarray]:
    """The sets of the elements ``members`` (numbers, in order of path) by their
    ``label``, sets by their first member; ``items``: each element's port, side, path
    and port id. Returns the sets and each element's set (-1: none)."""
    by_rank = label[members]
    _, seen = np.unique(by_rank, return_index=True)
    set_rank = np.full(n_label, -1, dtype=np.int64)
    set_rank[by_rank[np.sort(seen)]] = np.arange(len(seen))
    of_member = set_rank[by_rank]
    mem = members[np.argsort(of_member, kind="stable")]
    ptr = _starts(np.bincount(of_member, minlength=len(seen)), total=True)
    ports, side, paths, port_ids = items
    return Nodes(ports[mem].tolist(), side[mem], paths[mem].tolist(), port_ids[mem],
                 ptr), set_rank[label]


def joined_nodes(flat, groups: list[list]) -> bool:
    """The aliases and flow sums of the nodes ``groups`` (lists of `Member`, as
    `folding.join_planned` forms them) recorded in ``flat`` as set by set; False, having
    changed nothing, when a member's port was not bound in bulk or lacks a variable of
    its node's first member's class."""
    members = list(chain.from_iterable(groups))
    if not members:
        return True
    ports = list(map(_PORT, members))
    rows = _bulk_rows(ports)
    if rows is None:
        return False
    n = len(members)
    nodes = Nodes(ports, np.fromiter(map(_OUTSIDE, members), dtype=bool, count=n),
                  list(map(_MEMBER_PATH, members)),
                  np.fromiter(map(id, ports), dtype=np.int64, count=n),
                  _starts(np.fromiter(map(len, groups), dtype=np.intp, count=len(groups)),
                          total=True))
    return _record(flat, nodes, rows, records=False)


class Joined:
    """The result of `planned_nodes`: the model's own connection sets (``outer``, its
    subsystems' folded ports members of them), the nodes they join across those ports
    (``nodes``), and for each folded port the first member of its node and the inside
    members whose through variables sum to its own (``firsts`` and ``insides``, in the
    order of the folded ports)."""

    __slots__ = ("outer", "nodes", "firsts", "insides")

    def __init__(self, outer: Nodes, nodes: Nodes, firsts: list, insides: list):
        self.outer, self.nodes, self.firsts, self.insides = outer, nodes, firsts, insides


def planned_nodes(flat, joined: list, planned: dict, folded: dict, signals: list = (),
                  signal_set=None) -> Joined | None:
    """Record the connection sets of ``joined`` (the physical connects not wired by a
    plan) and the nodes they form with the sets of the subsystems ``planned`` (see
    `folding.plan_subsystems`), their ports ``folded``, in ``flat`` as `flatten` does set
    by set (`folding.join_planned`, `joined_nodes`): the model's own sets and its signal
    sets ``signals`` (each recorded by ``signal_set``) in their places, then the nodes'
    aliases and flow sums; return them. The nodes are the connected components of the
    model's elements and each plan's sets, instance by instance (the ports of a class's
    instances gathered name by name, not member by member), each set joined to its
    folded port's inside element; the folded ports are left out. None, having changed
    nothing, when a port is read by an equation, a plan's set holds a port folded itself
    (a subsystem within a subsystem), or a member was not bound in bulk: the caller then
    goes set by set."""
    if len(planned.where) != len(folded):
        return None                     # a port read by an equation: a member itself
    written = _elements(joined)
    if written is None:
        return None
    refs, side, head = written
    n_outer = len(refs)
    sides, heads = [side], [head]
    flows: dict[int, tuple] = {}         # id(folded port) -> its inside members' ports

    def add(col: list, at: int) -> None:      # inside elements, joined to col[k] at + k
        sides.append(np.zeros(len(col), dtype=bool))
        heads.append(np.arange(at, at + len(col)))
        refs.extend(col)

    for plan, instances in planned.by_plan.items():   # a plan per class
        children = list(map(_CHILDREN, instances))
        for owner, names_list in plan.sets:
            cols = [_ports_at(children, names) for names in names_list]
            # a subsystem's port within a subsystem's set (only where one lies within
            # another)
            if planned.nested and any(map(folded.__contains__,
                                          map(id, chain.from_iterable(cols)))):
                return None
            at = len(refs)
            if owner is not None:
                # the set joined to its port's inside element: a folded port's two
                # elements are one node (its outside element is met nowhere else)
                own = list(map(itemgetter(owner), children))
                add(own, at)
                flows.update(zip(map(id, own), zip(*cols)))
            for col in cols:
                add(col, at)
    ports = list(folded.values())
    got = _components(refs, np.concatenate(sides), np.concatenate(heads),
                      np.fromiter(folded, dtype=np.int64, count=len(folded)),
                      n_outer)
    if got is None:
        return None
    nodes, keys, set_of, outer = got
    rows = _bulk_rows(nodes.ports)
    links = None if rows is None else _links(nodes, rows)
    if links is None:
        return None
    inside = np.fromiter(map(id, ports), dtype=np.int64, count=len(ports)) * 2
    node_of = set_of[np.searchsorted(keys, inside)]
    if node_of.size and node_of.min() < 0:
        return None                     # (every node holds a port that is no plan's)
    firsts = [nodes.ports[k] for k in nodes.ptr[node_of].tolist()]
    insides = list(map(flows.__getitem__, folded))
    _in_order(flat, outer, _set_records(outer), [], np.zeros(0, dtype=np.intp), signals,
              signal_set)   # the model's own sets, no alias of their own
    flat.aliases += links[0]
    _sums(flat, *links[2:])
    return Joined(outer, nodes, firsts, insides)


def _ports_at(children: list[dict], names: tuple) -> list:
    """The port at ``names`` (``("r", "p")``) below each instance, whose children are
    ``children``."""
    items = children
    for name in names[:-1]:
        items = map(_CHILDREN, map(itemgetter(name), items))
    return list(map(itemgetter(names[-1]), items))


def _bulk_rows(ports: list) -> np.ndarray | None:
    """The row of each port's first variable among the model's variables
    (`flatten._first_row`), or None unless every port was bound in bulk with rows."""
    from mechatron.compiler.flatten import _ColumnSyms

    syms = list(map(_SYMS, ports))
    if any(type(s) is not _ColumnSyms for s in syms):
        return None
    rows = np.fromiter(map(_ROW, syms), dtype=np.int64, count=len(syms))
    return rows if rows.min() >= 0 else None


def _objects(items: list) -> np.ndarray:
    """``items`` as an array of objects (whatever they are: no sequence is unpacked)."""
    return np.fromiter(items, dtype=object, count=len(items))


def _starts(counts: np.ndarray, total: bool = False) -> np.ndarray:
    """The first index of each of consecutive segments of ``counts`` entries (and the
    end of the last with ``total``)."""
    ends = np.cumsum(counts)
    starts = ends - counts
    return np.append(starts, ends[-1] if len(ends) else 0) if total else starts


def _record(flat, nodes: Nodes, rows: np.ndarray, signals: list = (), signal_set=None,
            records: bool = True) -> bool:
    """The sets' records (with ``records``), aliases and flow sums (see `physical_nodes`)
    from the members' rows, the ``signals`` in their places; False, having changed
    nothing, if a member's class lacks a variable of its set's first member's class."""
    links = _links(nodes, rows)
    if links is None:
        return False
    if records:
        _in_order(flat, nodes, _set_records(nodes), links[0], links[1], signals,
                  signal_set)
    else:
        flat.aliases += links[0]
    _sums(flat, *links[2:])
    return True


def _links(nodes: Nodes, rows: np.ndarray) -> tuple | None:
    """The aliases of the sets ``nodes`` (``(variable, target, scale, origin)`` each, by
    row, set after set) with the set of each, and their flow sums (what `_sums` takes),
    read off the members' rows; None if a member's class lacks a variable of its set's
    first member's class."""
    from mechatron.compiler.flatten import _binding_plan, _port_variables

    ports, ptr = nodes.ports, nodes.ptr
    n_set = len(ptr) - 1
    types = list(map(type, ports))
    classes = list(dict.fromkeys(types))
    number = {cls: k for k, cls in enumerate(classes)}
    kind = np.fromiter(map(number.__getitem__, types), dtype=np.intp, count=len(types))
    heads = ptr[:-1]
    head_kind = kind[heads]
    # each key's place among each class's variables (-1: the class has none of that name)
    keys = list(dict.fromkeys(chain.from_iterable(
        chain(*_port_variables(classes[k])) for k in np.unique(head_kind).tolist())))
    key_no = {key: j for j, key in enumerate(keys)}
    place = np.full((len(classes), len(keys)), -1, dtype=np.int64)
    for cls, k in number.items():
        offsets = _binding_plan(cls)[4]
        for key, j in key_no.items():
            place[k, j] = offsets.get(key, -1)
    size = np.diff(ptr)
    set_of = np.repeat(np.arange(n_set), size)
    sign = np.where(nodes.outside, -1.0, 1.0)
    # a member other than the first's port (a port met on both sides is one node)
    port_ids = nodes.port_ids
    other = port_ids != port_ids[heads][set_of]
    # a set of two elements of two ports: its through variables an alias, not a sum
    pair = ((size == 2) & (np.bincount(set_of, weights=other, minlength=n_set) > 0))[set_of]
    uniform = np.minimum.reduceat(kind, heads) == np.maximum.reduceat(kind, heads) \
        if n_set else np.zeros(0, dtype=bool)
    paths = nodes.paths
    origins = ["connect(" + ", ".join(paths[a:b]) + ")"
               for a, b in zip(ptr[:-1].tolist(), ptr[1:].tolist())]
    # the aliases (set, key, member) and flow sums (set, key) of each class of first member
    found = []          # (sets, key's places, members, alias rows, target rows, scales)
    sums = []           # (sets, key's places, members, rows, key) of the terms
    for k in np.unique(head_kind).tolist():
        across, through = _port_variables(classes[k])
        in_class = head_kind[set_of] == k
        for q, key in enumerate(across + through):
            j = key_no[key]
            var = rows + place[kind, j]
            if (place[kind[in_class], j] < 0).any():
                return None             # a member without the variable: by path
            head_var = var[heads][set_of]
            if q < len(across):
                pick = np.flatnonzero(in_class & other)
                found.append((set_of[pick], np.full(len(pick), q), pick, var[pick],
                              head_var[pick], np.ones(len(pick))))
                continue
            pick = np.flatnonzero(in_class & other & pair)
            found.append((set_of[pick], np.full(len(pick), q), pick, var[pick],
                          head_var[pick], -sign[heads][set_of[pick]] * sign[pick]))
            pick = np.flatnonzero(in_class & ~pair)
            sums.append((set_of[pick], np.full(len(pick), q), pick, var[pick], key))
    aliases, alias_set = [], np.zeros(0, dtype=np.intp)
    if found:
        s, q, at, a, b, scale = (np.concatenate(x) for x in zip(*found))
        order = np.lexsort((at, q, s))
        alias_set = s[order]
        aliases = list(zip(a[order].tolist(), b[order].tolist(), scale[order].tolist(),
                           map(origins.__getitem__, alias_set.tolist())))
    return aliases, alias_set, sums, sign, origins, uniform


def _in_order(flat, nodes: Nodes, sets: list, aliases: list, alias_set: np.ndarray | None,
              signals: list, signal_set) -> None:
    """The physical sets' records and aliases (``aliases[k]`` of set ``alias_set[k]``)
    and the signal sets (each recorded by ``signal_set``) in the order of their first
    members, as set by set."""
    if not signals:             # the physical sets are in that order already
        flat.connection_sets += sets
        flat.aliases += aliases
        return
    ptr = nodes.ptr.tolist()
    first = [(nodes.paths[a], bool(nodes.outside[a])) for a in ptr[:-1]]
    first += [(cset.members[0].path, cset.members[0].outside) for cset in signals]
    n = len(sets)
    at = np.searchsorted(alias_set, np.arange(n + 1)).tolist()
    for k in sorted(range(len(first)), key=first.__getitem__):
        if k < n:
            flat.connection_sets.append(sets[k])
            flat.aliases += aliases[at[k]:at[k + 1]]
        else:
            signal_set(signals[k - n])


def _sums(flat, parts: list, sign: np.ndarray, origins: list, uniform: np.ndarray) -> None:
    """The flow sums of the sets that are no pair: ``parts`` holds, for each class of
    first member and through key, the terms' sets, key's place among the class's keys,
    members and variables, and the key; one sum per set and key, ordered as set by set
    (`flatten._sum_equations`)."""
    from mechatron.compiler.flatten import _sum_equations

    if not parts:
        return

    s, q, at, var = (np.concatenate(x) for x in zip(*(p[:4] for p in parts)))
    part = np.repeat(np.arange(len(parts)), [len(p[0]) for p in parts])
    order = np.lexsort((at, q, s))
    s, q, var, sign = s[order], q[order], var[order], sign[at[order]]
    # a sum per (set, key), in order; its columns the variables by first appearance
    new = np.ones(len(s), dtype=bool)
    new[1:] = (s[1:] != s[:-1]) | (q[1:] != q[:-1])
    row = np.cumsum(new) - 1
    heads = np.flatnonzero(new)
    variables, first, inverse = np.unique(var, return_index=True, return_inverse=True)
    by_first = np.argsort(first, kind="stable")
    column = np.empty(len(variables), dtype=np.int64)
    column[by_first] = np.arange(len(variables))
    keys = [parts[i][4] for i in part[order[heads]].tolist()]
    sets = s[heads].tolist()
    _sum_equations(flat, row, column[inverse], sign, variables[by_first].tolist(),
                   [f"{origins[j]}: sum of {k} == 0" for j, k in zip(sets, keys)],
                   uniform[sets].tolist())


def _set_records(nodes: Nodes) -> list[list[tuple]]:
    """`FlatModel.connection_sets` of the sets: each member's path, domain, and False
    (no signal drives a physical set)."""
    types = list(map(type, nodes.ports))
    domain = {cls: cls.domain for cls in set(types)}
    members = list(zip(nodes.paths, map(domain.__getitem__, types), repeat(False)))
    ptr = nodes.ptr.tolist()
    return [members[a:b] for a, b in zip(ptr[:-1], ptr[1:])]
