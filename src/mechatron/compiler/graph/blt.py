"""Strongly connected components and block-lower-triangular ordering.

Given a matching of equations to variables (see `mechatron.compiler.graph.matching`),
equation ``e`` depends on equation ``f`` when ``e`` contains the variable matched to
``f``: ``f`` must be solved first. The strongly connected components of this
dependency graph are the blocks of equations that must be solved simultaneously
(algebraic loops), and Tarjan's algorithm emits them in an order in which each depends
only on earlier ones: the block lower triangular (BLT) form.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .matching import UNMATCHED, Matching, check_adjacency

__all__ = ["Block", "BlockOrder", "strongly_connected_components",
           "block_lower_triangular", "block_order"]


@dataclass(slots=True)
class Block:
    """Equations solved together for as many variables.

    Attributes
    ----------
    equations : list of int
        The equations of the block, in increasing order.
    variables : list of int
        ``variables[i]`` is the variable matched to ``equations[i]``.
    """

    equations: list[int]
    variables: list[int]


def strongly_connected_components(n: int, succ: Sequence[Sequence[int]]) -> list[list[int]]:
    """Strongly connected components of a directed graph (Tarjan, iterative).

    Parameters
    ----------
    n : int
        Number of nodes, ``0 .. n - 1``.
    succ : sequence of sequence of int
        ``succ[u]`` lists the nodes ``w`` with an edge ``u -> w``.

    Returns
    -------
    list of list of int
        The components, each in increasing order, in reverse topological order: when
        an edge leads from component ``A`` to another component ``B``, ``B`` comes
        first. Every node is in exactly one component.

    Notes
    -----
    Tarjan (1972), with an explicit stack instead of recursion; ``O(n + m)``.
    """
    nodes, ends = _components(n, succ)
    return [nodes[a:b] for a, b in zip(ends, ends[1:])]


def _components(n: int, succ: Sequence[Sequence[int]]) -> tuple[list[int], list[int]]:
    """`strongly_connected_components` one after another in one list, with the place
    where each ends (``ends[0] = 0``, component ``k`` is ``nodes[ends[k]:ends[k + 1]]``):
    no list per component (a model of 10^5 components has as many blocks of one)."""
    if len(succ) != n:
        raise ValueError(f"succ must have one entry per node ({n}), got {len(succ)}.")
    done = n + 1  # index of nodes already in a component: never below a low-link
    index = [UNMATCHED] * n
    low = [0] * n
    stack: list[int] = []
    nodes: list[int] = []       # the components one after another
    ends: list[int] = [0]       # where each one ends in ``nodes``
    add, end = nodes.append, ends.append
    counter = 0
    for start in range(n):
        if index[start] != UNMATCHED:
            continue
        if not succ[start]:       # a node without successors is a component at once
            index[start] = done
            add(start)
            end(len(nodes))
            continue
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        path = [start]
        edges = [iter(succ[start])]
        while path:
            u = path[-1]
            for w in edges[-1]:
                if index[w] == UNMATCHED:
                    out = succ[w]
                    if not out:   # as if entered and left at once: its own component
                        index[w] = done
                        add(w)
                        end(len(nodes))
                        continue
                    index[w] = low[w] = counter
                    counter += 1
                    stack.append(w)
                    path.append(w)
                    edges.append(iter(out))
                    break
                if index[w] < low[u]:
                    low[u] = index[w]
            else:
                path.pop()
                edges.pop()
                if path and low[u] < low[path[-1]]:
                    low[path[-1]] = low[u]
                if low[u] != index[u]:
                    continue
                if stack[-1] == u:  # the common case of a single node
                    stack.pop()
                    index[u] = done
                    add(u)
                else:
                    nodes.extend(_pop_component(stack, index, u, done))
                end(len(nodes))
    return nodes, ends


def block_lower_triangular(n_var: int, adj: Sequence[Sequence[int]],
                           matching: Matching) -> list[Block]:
    """Order the matched equations into blocks that can be solved one after another.

    Parameters
    ----------
    n_var : int
        Number of variables.
    adj : sequence of sequence of int
        ``adj[e]`` lists the variables of equation ``e``.
    matching : Matching
        A matching of this graph, e.g. from `maximum_matching`.

    Returns
    -------
    list of Block
        Every matched equation in exactly one block. Block ``k`` uses only variables
        matched in blocks ``0 .. k`` and unmatched variables (knowns). Equations left
        unmatched by `matching` are in no block.

    Raises
    ------
    ValueError
        If the sizes of `matching` do not fit `adj` and `n_var`.
    """
    return list(block_order(n_var, adj, matching))


@dataclass(slots=True)
class BlockOrder:
    """The blocks of `block_lower_triangular` as arrays: block ``k`` holds the
    equations ``equations[ptr[k]:ptr[k + 1]]`` (in increasing order) and their matched
    variables at the same places of ``variables``. A model of 10^5 components has as
    many blocks of one equation; as `Block` objects (two lists each) they are some
    160 bytes apiece, here 24. Iterating forms each `Block` as it is read."""

    equations: np.ndarray
    variables: np.ndarray
    ptr: np.ndarray

    def __len__(self) -> int:
        return len(self.ptr) - 1

    def sizes(self) -> np.ndarray:
        return np.diff(self.ptr)

    def block(self, k: int) -> Block:
        a, b = int(self.ptr[k]), int(self.ptr[k + 1])
        return Block(self.equations[a:b].tolist(), self.variables[a:b].tolist())

    def __iter__(self):
        eqs, vs, ptr = self.equations.tolist(), self.variables.tolist(), self.ptr.tolist()
        return (Block(eqs[a:b], vs[a:b]) for a, b in zip(ptr, ptr[1:]))


def block_order(n_var: int, adj: Sequence[Sequence[int]], matching: Matching) -> BlockOrder:
    """`block_lower_triangular` as a `BlockOrder` (arrays, no object per block)."""
    check_adjacency(n_var, adj)
    eq_to_var, var_to_eq = matching.eq_to_var, matching.var_to_eq
    if len(eq_to_var) != len(adj) or len(var_to_eq) != n_var:
        raise ValueError(f"matching has sizes ({len(eq_to_var)}, {len(var_to_eq)}), "
                         f"expected ({len(adj)}, {n_var}).")
    # an equation's own variable (a loop onto itself) changes no component
    succ = [[f for v in row if (f := var_to_eq[v]) != UNMATCHED and f != e]
            if eq_to_var[e] != UNMATCHED else [] for e, row in enumerate(adj)]
    nodes, ends = _components(len(adj), succ)
    del succ
    eqs = np.asarray(nodes, dtype=np.intp)
    ptr = np.asarray(ends, dtype=np.intp)
    partner = np.asarray(eq_to_var, dtype=np.intp)
    # an unmatched equation has no edge in or out: a component of its own, dropped
    matched = partner[eqs[ptr[:-1]]] != UNMATCHED
    if not matched.all():
        sizes = np.diff(ptr)
        eqs = eqs[np.repeat(matched, sizes)]
        ptr = np.concatenate(([0], np.cumsum(sizes[matched]))).astype(np.intp)
    return BlockOrder(eqs, partner[eqs], ptr)


def _pop_component(stack: list[int], index: list[int], root: int, done: int) -> list[int]:
    """Pop the nodes above and including `root` from Tarjan's stack, sorted.

    Their index is set to `done`, so that later edges into them never lower a low-link.
    """
    i = len(stack) - 1
    while stack[i] != root:
        i -= 1
    component = stack[i:]
    del stack[i:]
    for w in component:
        index[w] = done
    component.sort()
    return component
