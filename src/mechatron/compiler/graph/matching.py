"""Maximum matching of the equation–variable bipartite graph.

A system of ``n_eq`` equations in ``n_var`` variables is described by its incidence:
``adj[e]`` lists the variables (integers ``0 .. n_var - 1``) that appear in equation
``e``. A matching pairs equations with variables, at most one partner each; the pair
``(e, v)`` reads "equation ``e`` is solved for variable ``v``". Unmatched entries are
``-1`` in both directions.

`maximum_matching` first matches greedily, then grows the matching along shortest
augmenting paths in phases (Hopcroft–Karp), so its cost is ``O(m sqrt(n))`` for ``m``
incidences. Every search is iterative: paths of any length are fine.

The private helper `augment_from` grows a matching by one augmenting path from a
single root and reports what it visited when there is none; Pantelides' algorithm
and the dummy-derivative selection are built on it.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass

__all__ = ["UNMATCHED", "Matching", "maximum_matching"]

UNMATCHED = -1
"""Marker of an equation or variable without a partner."""

DEAD = 1 << 62
"""Mark of a vertex that no augmenting path can ever pass again (see `augment_from`)."""


@dataclass
class Matching:
    """A matching of equations to variables.

    Attributes
    ----------
    eq_to_var : list of int
        ``eq_to_var[e]`` is the variable matched to equation ``e``, or -1.
    var_to_eq : list of int
        ``var_to_eq[v]`` is the equation matched to variable ``v``, or -1.
    """

    eq_to_var: list[int]
    var_to_eq: list[int]

    @property
    def unmatched_equations(self) -> list[int]:
        """Equations without a variable, in increasing order."""
        return [e for e, v in enumerate(self.eq_to_var) if v == UNMATCHED]

    @property
    def unmatched_variables(self) -> list[int]:
        """Variables without an equation, in increasing order."""
        return [v for v, e in enumerate(self.var_to_eq) if e == UNMATCHED]

    @property
    def size(self) -> int:
        """Number of matched pairs."""
        return len(self.eq_to_var) - self.eq_to_var.count(UNMATCHED)


def maximum_matching(n_var: int, adj: Sequence[Sequence[int]], *,
                     allowed: Sequence[bool] | Collection[int] | Callable[[int], bool]
                     | None = None,
                     initial: Matching | None = None) -> Matching:
    """Match as many equations to distinct variables as possible.

    Parameters
    ----------
    n_var : int
        Number of variables; variables are ``0 .. n_var - 1``.
    adj : sequence of sequence of int
        ``adj[e]`` lists the variables of equation ``e``.
    allowed : sequence of bool, set of int or callable, optional
        Variables that may be matched: a mask of length `n_var` (a list or a numpy
        array), a collection of variable indices, or a predicate ``allowed(v)``. Other
        variables are ignored, as if absent from `adj`. Default: all variables.
    initial : Matching, optional
        A valid matching to extend (it is copied, not modified). Every pair must be an
        incidence of `adj` between an allowed variable and its equation.

    Returns
    -------
    Matching
        A maximum matching: no other matching has more pairs.

    Raises
    ------
    ValueError
        If `adj` names a variable outside ``0 .. n_var - 1``, if `allowed` has the
        wrong length, or if `initial` is not a valid matching of this graph.

    Notes
    -----
    Greedy start, then Hopcroft–Karp phases: a breadth-first search layers the graph
    from the free equations, and iterative depth-first searches augment along
    vertex-disjoint shortest paths. Cost ``O(m sqrt(n))``.
    """
    check_adjacency(n_var, adj)
    ok = allowed_mask(n_var, allowed)
    if initial is None:
        eq_to_var = [UNMATCHED] * len(adj)
        var_to_eq = [UNMATCHED] * n_var
    else:
        eq_to_var, var_to_eq = _copy_initial(initial, n_var, adj, ok)
    _greedy(adj, ok, eq_to_var, var_to_eq)
    _hopcroft_karp(adj, ok, eq_to_var, var_to_eq)
    return Matching(eq_to_var, var_to_eq)


def check_adjacency(n_var: int, adj: Sequence[Sequence[int]]) -> None:
    """Raise `ValueError` if `adj` names a variable outside ``0 .. n_var - 1``."""
    if n_var < 0:
        raise ValueError(f"n_var must be >= 0, got {n_var}.")
    rows = [row for row in adj if len(row)]
    if not rows:
        return
    low = min(min(row) for row in rows)
    high = max(max(row) for row in rows)
    if low < 0 or high >= n_var:
        bad = low if low < 0 else high
        raise ValueError(f"adj names variable {bad}, outside 0 .. {n_var - 1}.")


def allowed_mask(n_var: int, allowed) -> list[bool]:
    """Turn the accepted forms of an ``allowed`` argument into a list of bool."""
    if allowed is None:
        return [True] * n_var
    if callable(allowed):
        return [bool(allowed(v)) for v in range(n_var)]
    if isinstance(allowed, (set, frozenset, dict)):
        mask = [False] * n_var
        for v in allowed:
            if not 0 <= v < n_var:
                raise ValueError(f"allowed names variable {v}, outside 0 .. {n_var - 1}.")
            mask[v] = True
        return mask
    mask = [bool(a) for a in allowed]
    if len(mask) != n_var:
        raise ValueError(f"allowed must have one entry per variable ({n_var}), "
                         f"got {len(mask)}.")
    return mask


def augment_from(root: int, adj: Sequence[Sequence[int]], ok: Sequence[bool],
                 eq_to_var: list[int], var_to_eq: list[int], mark: list[int],
                 stamp: int, visited_eqs: list[int] | None = None,
                 visited_vars: list[int] | None = None) -> bool:
    """Grow a matching by one augmenting path that starts at the free equation `root`.

    Depth-first search with lookahead (a free variable of the current equation is
    taken at once), iterative. A variable ``v`` counts as visited in this search when
    ``mark[v] >= stamp``; the search sets ``mark[v] = stamp`` on every variable it
    enters, so a caller uses a new, larger `stamp` for each search. Setting
    ``mark[v] = DEAD`` excludes ``v`` from all later searches (sound for variables a
    failed search visited while the graph does not change).

    Parameters
    ----------
    root : int
        An unmatched equation.
    adj, ok, eq_to_var, var_to_eq
        Incidence, allowed-variable mask and the matching, updated in place on success.
    mark : list of int
        Per-variable visit marks, see above.
    stamp : int
        Mark of this search.
    visited_eqs, visited_vars : list of int, optional
        Receive, in visiting order, the equations (starting with `root`) and the
        variables the search entered. On failure these are the whole alternating tree
        of `root`: equations ``E`` and variables ``V = N(E) ∩ allowed`` with
        ``|V| = |E| - 1``, every variable of ``V`` matched into ``E``.

    Returns
    -------
    bool
        Whether an augmenting path was found (and the matching grown by one).
    """
    if visited_eqs is not None:
        visited_eqs.append(root)
    eqs = [root]
    via: list[int] = []
    pos = [0]
    while eqs:
        e = eqs[-1]
        row = adj[e]
        i = pos[-1]
        if i == 0:
            for v in row:
                if ok[v] and var_to_eq[v] == UNMATCHED:
                    via.append(v)
                    _flip(eqs, via, eq_to_var, var_to_eq)
                    return True
        n = len(row)
        while i < n:
            v = row[i]
            i += 1
            if ok[v] and mark[v] < stamp:
                mark[v] = stamp
                if visited_vars is not None:
                    visited_vars.append(v)
                f = var_to_eq[v]
                pos[-1] = i
                via.append(v)
                eqs.append(f)
                pos.append(0)
                if visited_eqs is not None:
                    visited_eqs.append(f)
                break
        else:
            eqs.pop()
            pos.pop()
            if via:
                via.pop()
    return False


def _flip(eqs: list[int], via: list[int], eq_to_var: list[int],
          var_to_eq: list[int]) -> None:
    """Match ``eqs[k]`` with ``via[k]`` along an augmenting path."""
    for e, v in zip(eqs, via):
        eq_to_var[e] = v
        var_to_eq[v] = e


def _copy_initial(initial: Matching, n_var: int, adj: Sequence[Sequence[int]],
                  ok: list[bool]) -> tuple[list[int], list[int]]:
    """Validate `initial` against the graph and return copies of its two arrays."""
    eq_to_var = list(initial.eq_to_var)
    var_to_eq = list(initial.var_to_eq)
    if len(eq_to_var) != len(adj) or len(var_to_eq) != n_var:
        raise ValueError(f"initial matching has sizes ({len(eq_to_var)}, "
                         f"{len(var_to_eq)}), expected ({len(adj)}, {n_var}).")
    for e, v in enumerate(eq_to_var):
        if v == UNMATCHED:
            continue
        if not (0 <= v < n_var and var_to_eq[v] == e and ok[v] and v in adj[e]):
            raise ValueError(f"initial matching pairs equation {e} with variable {v}, "
                             "which is not an allowed incidence of a consistent matching.")
    for v, e in enumerate(var_to_eq):
        if e != UNMATCHED and not (0 <= e < len(adj) and eq_to_var[e] == v):
            raise ValueError(f"initial matching is inconsistent at variable {v}.")
    return eq_to_var, var_to_eq


def _greedy(adj: Sequence[Sequence[int]], ok: list[bool], eq_to_var: list[int],
            var_to_eq: list[int]) -> None:
    """Match each free equation to its first free allowed variable."""
    for e, row in enumerate(adj):
        if eq_to_var[e] != UNMATCHED:
            continue
        for v in row:
            if ok[v] and var_to_eq[v] == UNMATCHED:
                eq_to_var[e] = v
                var_to_eq[v] = e
                break


def _hopcroft_karp(adj: Sequence[Sequence[int]], ok: list[bool], eq_to_var: list[int],
                   var_to_eq: list[int]) -> None:
    """Augment along shortest paths, phase by phase, until none is left."""
    n_eq = len(adj)
    unset = n_eq + 1
    dist = [unset] * n_eq
    pos = [0] * n_eq
    free = [e for e in range(n_eq) if eq_to_var[e] == UNMATCHED and len(adj[e])]
    while free:
        layered, limit = _layers(adj, ok, var_to_eq, free, dist, unset)
        if limit != unset:
            for root in free:
                _layered_augment(root, adj, ok, eq_to_var, var_to_eq, dist, pos,
                                 limit, unset)
        for e in layered:
            dist[e] = unset
            pos[e] = 0
        if limit == unset:
            return
        free = [e for e in free if eq_to_var[e] == UNMATCHED]


def _layers(adj: Sequence[Sequence[int]], ok: list[bool], var_to_eq: list[int],
            free: list[int], dist: list[int], unset: int) -> tuple[list[int], int]:
    """Breadth-first layering from the free equations.

    Sets ``dist[e]`` for every equation reached and returns them with the length of
    the shortest augmenting path (``unset`` if there is none).
    """
    queue = list(free)
    for e in queue:
        dist[e] = 0
    limit = unset
    head = 0
    while head < len(queue):
        e = queue[head]
        head += 1
        d = dist[e] + 1
        if d > limit:
            break
        for v in adj[e]:
            if not ok[v]:
                continue
            f = var_to_eq[v]
            if f == UNMATCHED:
                limit = d
            elif dist[f] == unset:
                dist[f] = d
                queue.append(f)
    return queue, limit


def _layered_augment(root: int, adj: Sequence[Sequence[int]], ok: list[bool],
                     eq_to_var: list[int], var_to_eq: list[int], dist: list[int],
                     pos: list[int], limit: int, unset: int) -> bool:
    """Depth-first search for a shortest augmenting path in the layered graph."""
    eqs = [root]
    via: list[int] = []
    while eqs:
        e = eqs[-1]
        row = adj[e]
        d = dist[e] + 1
        i = pos[e]
        n = len(row)
        while i < n:
            v = row[i]
            i += 1
            if not ok[v]:
                continue
            f = var_to_eq[v]
            if f == UNMATCHED:
                if d == limit:
                    pos[e] = i
                    via.append(v)
                    _flip(eqs, via, eq_to_var, var_to_eq)
                    return True
            elif d < limit and dist[f] == d:
                pos[e] = i
                via.append(v)
                eqs.append(f)
                break
        else:
            pos[e] = i
            dist[e] = unset
            eqs.pop()
            if via:
                via.pop()
    return False
