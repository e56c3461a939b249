"""Connection sets with inside and outside connectors (Modelica 3, section 9.2).

A ``connect`` written in a component ``C`` joins *elements*: each is a port together with
its side. A port of ``C`` itself is an **outside** element there (seen from inside ``C``,
it leads out); a port of one of ``C``'s parts is an **inside** element. The same port of a
subsystem is therefore an outside element in the subsystem's own connections and an inside
element in its parent's: two different elements, in two different sets, which share the
port's variables. Per set:

- across variables are all equal;
- through variables sum to zero with the inside elements counted positive and the outside
  ones negative (what flows into the subsystem's port flows on into its parts), so each
  through variable is summed exactly once per node of the network;
- a signal set is driven by exactly one element: an inside Output (a part's output) or an
  outside Input (the component's own input, seen from inside).

Both the compiler and the local balance check (:mod:`mechatron.core.balance`) build their
sets here, so that they count the same equations.
"""

from __future__ import annotations

from dataclasses import dataclass

from mechatron.core.component import SignalRef
from mechatron.core.declarations import Input, Output

__all__ = ["Member", "ConnectionSet", "connection_sets", "is_driver", "port_key",
           "inside_connected"]


def root_of(parent: list[int], a: int) -> int:
    """The root of ``a`` in the union-find forest ``parent`` (``parent[r] == r`` at a
    root), compressing the path on the way."""
    root = a
    while parent[root] != root:
        root = parent[root]
    while parent[a] != root:
        parent[a], a = root, parent[a]
    return root


class Member:
    """One element of a connection set: a port (a Connector or a SignalRef), whether it
    is an outside connector of the component that wrote the connect, and its path."""

    __slots__ = ("port", "outside", "path")

    def __init__(self, port, outside: bool):
        self.port = port
        self.outside = outside
        self.path = port.path() if isinstance(port, SignalRef) else port.path

    @property
    def sign(self) -> float:
        """+1 for inside, -1 for outside: the factor of its through variables in the sum."""
        return -1.0 if self.outside else 1.0

    def __repr__(self) -> str:
        return f"Member({self.path!r}, {'outside' if self.outside else 'inside'})"


@dataclass(slots=True)
class ConnectionSet:
    members: list[Member]

    @property
    def is_signal(self) -> bool:
        return isinstance(self.members[0].port, SignalRef)


def port_key(port) -> tuple:
    """A hashable identity of a port (connectors by object, signals by owner and name)."""
    if isinstance(port, SignalRef):
        return ("signal", id(port.owner), port.name)
    return ("port", id(port))


def is_driver(member: Member) -> bool:
    """Whether a signal element drives its set: a part's Output, or the writing
    component's own Input (which, seen from inside, brings a value in)."""
    decl = member.port.declaration
    return isinstance(decl, Output) if not member.outside else isinstance(decl, Input)


def connection_sets(connections) -> list[ConnectionSet]:
    """The connection sets of ``connections``, an iterable of ``(writer, ports)``: the
    component that wrote a ``connect`` and the resolved ports it joins (Connectors or
    SignalRefs). Members are ordered by path within a set, sets by their first member, so
    that the result does not depend on the order the connects were written in."""
    # each element by number; a connector's key is its id and side in one integer, a
    # signal's its port_key with the side (no tuple per connector)
    number: dict = {}
    members: list[Member] = []
    parent: list[int] = []

    for writer, ports in connections:
        first = None
        for port in ports:
            if isinstance(port, SignalRef):
                outside = port.owner is writer
                key = ("signal", id(port.owner), port.name, outside)
            else:
                outside = port._parent is writer
                key = 2 * id(port) + outside
            k = number.get(key)
            if k is None:
                k = number[key] = len(members)
                members.append(Member(port, outside))
                parent.append(k)
            if first is None:
                first = root_of(parent, k)
            else:
                root = root_of(parent, k)
                if root != first:
                    parent[root] = first
    groups: dict[int, list[Member]] = {}
    for k, member in enumerate(members):
        groups.setdefault(root_of(parent, k), []).append(member)
    for g in groups.values():
        g.sort(key=_order)
    sets = [ConnectionSet(g) for g in groups.values()]
    sets.sort(key=lambda s: _order(s.members[0]))
    return sets


def _order(m: Member) -> tuple:
    return (m.path, m.outside)


def inside_connected(sets: list[ConnectionSet]) -> set[tuple]:
    """Keys (:func:`port_key`) of the ports that appear as an inside element somewhere:
    those connected from outside their component."""
    return {port_key(m.port) for s in sets for m in s.members if not m.outside}
