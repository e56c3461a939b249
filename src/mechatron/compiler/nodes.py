"""The physical connection sets of a model formed on arrays (part of pass 2, connections).

When every physical port is bound in bulk and no subsystem is wired by its class's plan
(:mod:`mechatron.compiler.folding`), the physical sets are the connected components of
the graph of the connects' elements (a port with its side,
:mod:`mechatron.core.connections`), ordered as `connection_sets` orders them: members by
path, the inside element first, sets by their first member (`physical_nodes`); the
signal sets, formed set by set, take their places among them. The physical sets'
records, aliases and flow sums are read off arrays of the members' rows, for these sets
as for the nodes joined across folded ports (`joined_nodes`), and the flat model is the
same as set by set (`flatten._physical_set`): Python runs per member only to read each
port's attributes, once, and per set only to write its origin.
"""

from __future__ import annotations

from itertools import chain, repeat
from operator import attrgetter, itemgetter

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph

from mechatron.core.component import Connector

__all__ = ["physical_nodes", "joined_nodes"]

_PARENT = attrgetter("_parent")        # (flatten's reference check reads it too)
_PATH = attrgetter("_path_cache")       # set by flatten's walk
_SYMS = attrgetter("_syms")
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
    writers = list(map(itemgetter(0), joined))
    lists = list(map(itemgetter(1), joined))
    refs = list(chain.from_iterable(lists))
    if not refs or not all(issubclass(t, Connector) for t in set(map(type, refs))):
        return None
    counts = np.fromiter(map(len, lists), dtype=np.intp, count=len(lists))
    n_ref = len(refs)
    ids = np.fromiter(map(id, refs), dtype=np.int64, count=n_ref)
    # an element is a port with its side: outside when the connect's writer owns it
    outside = np.fromiter(map(id, map(_PARENT, refs)), dtype=np.int64, count=n_ref) == \
        np.repeat(np.fromiter(map(id, writers), dtype=np.int64, count=len(writers)),
                  counts)
    _, first, inverse = np.unique(ids * 2 + outside, return_index=True,
                                  return_inverse=True)
    m = len(first)
    ports = _objects(refs)[first].tolist()     # (no integer object per element)
    rows = _bulk_rows(ports)
    if rows is None:
        return None                     # a port bound one by one: rows by name
    try:
        paths = list(map(_PATH, ports))
    except AttributeError:              # a port outside the walked tree
        return None
    if None in paths:
        return None
    side = outside[first]
    # each element joined to the first of its connect: the sets are the components
    start = np.repeat(_starts(counts), counts)
    graph = sparse.coo_matrix((np.ones(n_ref, dtype=np.int8), (inverse, inverse[start])),
                              shape=(m, m))
    _, label = csgraph.connected_components(graph, directed=False)
    # members by path, the inside element of a port first (the elements are numbered by
    # port, inside before outside, and the sort is stable); sets by their first member
    order = sorted(range(m), key=paths.__getitem__)
    rank = np.empty(m, dtype=np.int64)
    rank[order] = np.arange(m)
    by_rank = label[order]
    _, seen = np.unique(by_rank, return_index=True)
    set_rank = np.empty(len(seen), dtype=np.int64)
    set_rank[by_rank[np.sort(seen)]] = np.arange(len(seen))
    of_member = set_rank[label]
    mem = np.lexsort((rank, of_member))
    ptr = _starts(np.bincount(of_member, minlength=len(seen)), total=True)
    return Nodes(_objects(ports)[mem].tolist(), side[mem], _objects(paths)[mem].tolist(),
                 ids[first][mem], ptr), rows[mem]


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
                return False            # a member without the variable: by path
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
    sets = _set_records(nodes) if records else None
    if signals:
        _in_order(flat, nodes, sets, aliases, alias_set, signals, signal_set)
    else:
        if records:
            flat.connection_sets += sets
        flat.aliases += aliases
    if sums:
        _sums(flat, sums, sign, origins, uniform)
    return True


def _in_order(flat, nodes: Nodes, sets: list, aliases: list, alias_set: np.ndarray,
              signals: list, signal_set) -> None:
    """The physical sets' records and aliases (``aliases[k]`` of set ``alias_set[k]``)
    and the signal sets (each recorded by ``signal_set``) in the order of their first
    members, as set by set."""
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
