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

from .matching import UNMATCHED, Matching, check_adjacency

__all__ = ["Block", "strongly_connected_components", "block_lower_triangular"]


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
    if len(succ) != n:
        raise ValueError(f"succ must have one entry per node ({n}), got {len(succ)}.")
    done = n + 1  # index of nodes already in a component: never below a low-link
    index = [UNMATCHED] * n
    low = [0] * n
    stack: list[int] = []
    components: list[list[int]] = []
    emit = components.append
    counter = 0
    for start in range(n):
        if index[start] != UNMATCHED:
            continue
        if not succ[start]:       # a node without successors is a component at once
            index[start] = done
            emit([start])
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
                        emit([w])
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
                    emit([u])
                else:
                    emit(_pop_component(stack, index, u, done))
    return components


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
    check_adjacency(n_var, adj)
    eq_to_var, var_to_eq = matching.eq_to_var, matching.var_to_eq
    if len(eq_to_var) != len(adj) or len(var_to_eq) != n_var:
        raise ValueError(f"matching has sizes ({len(eq_to_var)}, {len(var_to_eq)}), "
                         f"expected ({len(adj)}, {n_var}).")
    # an equation's own variable (a loop onto itself) changes no component
    succ = [[f for v in row if (f := var_to_eq[v]) != UNMATCHED and f != e]
            if eq_to_var[e] != UNMATCHED else [] for e, row in enumerate(adj)]
    partner = eq_to_var.__getitem__
    return [Block(eqs, [eq_to_var[eqs[0]]] if len(eqs) == 1 else list(map(partner, eqs)))
            for eqs in strongly_connected_components(len(adj), succ)
            if eq_to_var[eqs[0]] != UNMATCHED]


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
