"""Maximum matching of the equation–variable bipartite graph.

A system of ``n_eq`` equations in ``n_var`` variables is described by its incidence:
``adj[e]`` lists the variables (integers ``0 .. n_var - 1``) that appear in equation
``e``. A matching pairs equations with variables, at most one partner each; the pair
``(e, v)`` reads "equation ``e`` is solved for variable ``v``". Unmatched entries are
``-1`` in both directions.

`maximum_matching` first matches greedily (Karp–Sipser when a plain greedy pass
leaves many equations free), then grows the matching along shortest augmenting paths
in phases (Hopcroft–Karp), so its cost is ``O(m sqrt(n))`` for ``m`` incidences.
Every search is iterative: paths of any length are fine. A large graph whose maximum
matching is unique (a network without algebraic loops has one) gets it from SciPy's
Hopcroft–Karp on arrays instead: the same matching, without a Python step per incidence
(`_unique_matching`).

The private helper `augment_from` grows a matching by one augmenting path from a
single root and reports what it visited when there is none; Pantelides' algorithm
and the dummy-derivative selection are built on it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence, Set as AbstractSet
from dataclasses import dataclass
from itertools import chain

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components, maximum_bipartite_matching

__all__ = ["UNMATCHED", "Matching", "maximum_matching"]

UNMATCHED = -1
"""Marker of an equation or variable without a partner."""

DEAD = 1 << 62
"""Mark of a vertex that no augmenting path can ever pass again (see `augment_from`)."""

UNIQUE_MIN_EQUATIONS = 500
"""From this many equations on, `maximum_matching` first tries `_unique_matching`."""


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
                     allowed: Sequence[bool] | AbstractSet[int] | Callable[[int], bool]
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
        array), a set of variable indices, or a predicate ``allowed(v)``. Other
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
    Greedy start (first free variable of each equation); when that leaves more than 1 %
    of the nonempty equations free, a Karp–Sipser start instead (pairs forced by a
    vertex of degree one first, else the free variable of least degree). Then
    Hopcroft–Karp phases: a breadth-first search layers the graph from the free
    equations, and iterative depth-first searches augment along vertex-disjoint
    shortest paths. Cost ``O(m sqrt(n))``. From `UNIQUE_MIN_EQUATIONS` equations on
    (without ``initial``), a graph whose maximum matching is unique is matched on arrays
    first (`_unique_matching`): the same matching, found without a Python step per
    incidence.
    """
    flat = checked_entries(n_var, adj)
    rows = adj
    mask = None if allowed is None else allowed_mask(n_var, allowed)
    if initial is None and flat is not None and len(adj) >= UNIQUE_MIN_EQUATIONS:
        unique = _unique_matching(n_var, adj, flat, mask)
        if unique is not None:
            return unique
    if mask is not None:
        rows = allowed_rows(adj, mask, flat)
    if initial is None:
        eq_to_var = [UNMATCHED] * len(rows)
        var_to_eq = [UNMATCHED] * n_var
        free = _greedy(rows, eq_to_var, var_to_eq)
        if free > max(100, len(rows) // 100):
            eq_to_var, var_to_eq = _karp_sipser(n_var, rows)
    else:
        eq_to_var, var_to_eq = _copy_initial(initial, n_var, rows)
        _greedy(rows, eq_to_var, var_to_eq)
    _hopcroft_karp(rows, eq_to_var, var_to_eq)
    return Matching(eq_to_var, var_to_eq)


def _unique_matching(n_var: int, adj: Sequence[Sequence[int]], flat: np.ndarray,
                     mask: list[bool] | None) -> Matching | None:
    """The maximum matching of the graph when it has exactly one, else None.

    SciPy's Hopcroft–Karp finds a maximum matching on the incidence as arrays (``flat``
    holds the entries of `adj` row after row; ``mask`` the allowed variables, if not
    all). It is the only one, and so the one `maximum_matching` would find by its own
    steps, when no other matching has as many pairs: every equation that has a variable
    and every variable that appears is matched (no alternating path can start at a free
    vertex), and no cycle alternates between matched and unmatched pairs, i.e. the
    equations ordered by "uses the variable matched to" form no cycle (every strongly
    connected component one equation: the block-triangular form has no algebraic loop).
    """
    n_eq = len(adj)
    lens = np.fromiter(map(len, adj), dtype=np.int64, count=n_eq)
    eqs, var = np.repeat(np.arange(n_eq), lens), flat
    if mask is not None:
        keep = np.asarray(mask, dtype=bool)[var]
        eqs, var = eqs[keep], var[keep]
    ones = np.ones(var.size, dtype=np.int32)
    eq_to_var = maximum_bipartite_matching(
        csr_matrix((ones, (eqs, var)), shape=(n_eq, n_var)), perm_type="column")
    has = np.zeros(n_eq, dtype=bool)
    has[eqs] = True
    if (eq_to_var[has] < 0).any():
        return None
    matched = np.flatnonzero(eq_to_var >= 0)
    var_to_eq = np.full(n_var, UNMATCHED, dtype=np.int64)
    var_to_eq[eq_to_var[matched]] = matched
    to = var_to_eq[var]
    if (to < 0).any():          # a variable that appears is free
        return None
    other = to != eqs           # an equation's own variable is no edge of the order
    order = csr_matrix((ones[other], (eqs[other], to[other])), shape=(n_eq, n_eq))
    if connected_components(order, directed=True, connection="strong")[0] != n_eq:
        return None
    return Matching(eq_to_var.astype(np.int64).tolist(), var_to_eq.tolist())


def check_adjacency(n_var: int, adj: Sequence[Sequence[int]]) -> None:
    """Raise `ValueError` if `adj` names a variable outside ``0 .. n_var - 1``."""
    checked_entries(n_var, adj)


def checked_entries(n_var: int, adj: Sequence[Sequence[int]]) -> np.ndarray | None:
    """`check_adjacency`, returning the entries of `adj` row after row as one integer
    array (None if they do not fit in 64 bits)."""
    if n_var < 0:
        raise ValueError(f"n_var must be >= 0, got {n_var}.")
    total = sum(map(len, adj))
    flat = None
    if not total:
        return np.zeros(0, dtype=np.int64)
    try:   # the entries in one array: two reductions instead of one per row
        flat = np.fromiter(chain.from_iterable(adj), dtype=np.int64, count=total)
        low, high = int(flat.min()), int(flat.max())
    except OverflowError:
        low = min(map(min, filter(len, adj)))
        high = max(map(max, filter(len, adj)))
    if low < 0 or high >= n_var:
        bad = low if low < 0 else high
        raise ValueError(f"adj names variable {bad}, outside 0 .. {n_var - 1}.")
    return flat


def allowed_rows(adj: Sequence[Sequence[int]], ok: list[bool],
                 flat: np.ndarray | None) -> list[Sequence[int]]:
    """The rows of `adj` with the variables that are not `ok` left out; rows without
    such variables are shared with `adj`, not copied. `flat` is
    ``checked_entries(n_var, adj)``."""
    if flat is None:
        return [[v for v in row if ok[v]] for row in adj]
    rows = list(adj)
    mask = np.array(ok, dtype=bool)
    banned = ~mask[flat]
    if not banned.any():
        return rows
    lens = np.fromiter(map(len, adj), dtype=np.int64, count=len(adj))
    owner = np.repeat(np.arange(len(adj)), lens)
    for e in np.unique(owner[banned]).tolist():
        rows[e] = [v for v in adj[e] if ok[v]]
    return rows


def allowed_mask(n_var: int, allowed: Sequence[bool] | AbstractSet[int]
                 | Callable[[int], bool] | None) -> list[bool]:
    """Turn the accepted forms of an ``allowed`` argument into a list of bool."""
    if allowed is None:
        return [True] * n_var
    if callable(allowed):
        return [bool(allowed(v)) for v in range(n_var)]
    if isinstance(allowed, AbstractSet):
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


def _copy_initial(initial: Matching, n_var: int,
                  rows: Sequence[Sequence[int]]) -> tuple[list[int], list[int]]:
    """Validate `initial` against the allowed incidence `rows`; return copies of it."""
    eq_to_var = list(initial.eq_to_var)
    var_to_eq = list(initial.var_to_eq)
    if len(eq_to_var) != len(rows) or len(var_to_eq) != n_var:
        raise ValueError(f"initial matching has sizes ({len(eq_to_var)}, "
                         f"{len(var_to_eq)}), expected ({len(rows)}, {n_var}).")
    for e, v in enumerate(eq_to_var):
        if v == UNMATCHED:
            continue
        if not (0 <= v < n_var and var_to_eq[v] == e and v in rows[e]):
            raise ValueError(f"initial matching pairs equation {e} with variable {v}, "
                             "which is not an allowed incidence of a consistent matching.")
    for v, e in enumerate(var_to_eq):
        if e != UNMATCHED and not (0 <= e < len(rows) and eq_to_var[e] == v):
            raise ValueError(f"initial matching is inconsistent at variable {v}.")
    return eq_to_var, var_to_eq


def _greedy(rows: Sequence[Sequence[int]], eq_to_var: list[int],
            var_to_eq: list[int]) -> int:
    """Match each free equation to its first free variable.

    Returns the number of equations left free although they have variables.
    """
    free = 0
    for e, row in enumerate(rows):
        if eq_to_var[e] != UNMATCHED:
            continue
        for v in row:
            if var_to_eq[v] == UNMATCHED:
                eq_to_var[e] = v
                var_to_eq[v] = e
                break
        else:
            free += len(row) > 0
    return free


def _karp_sipser(n_var: int, rows: Sequence[Sequence[int]]) -> tuple[list[int], list[int]]:
    """Karp–Sipser matching: forced pairs first, else the variable of least degree.

    A variable left in a single equation (or an equation left with a single variable)
    is matched there, which no maximum matching regrets; otherwise the next free
    equation takes its free variable of least remaining degree (the first such in its
    row). Degrees count the free vertices only. ``O(m)``.

    The forced pairs are taken last found, first matched: variables before equations,
    of each the one whose degree fell to one most recently; those of degree one at the
    start come after all of these, the highest index first.
    """
    n_eq = len(rows)
    cols = _transpose(n_var, rows)
    eq_deg = list(map(len, rows))
    var_deg = list(map(len, cols))
    eq_to_var = [UNMATCHED] * n_eq
    var_to_eq = [UNMATCHED] * n_var
    lone_vars = [v for v in range(n_var) if var_deg[v] == 1]
    lone_eqs = [e for e in range(n_eq) if eq_deg[e] == 1]
    pop_var, push_var = lone_vars.pop, lone_vars.append
    pop_eq, push_eq = lone_eqs.pop, lone_eqs.append
    scan = 0
    while True:
        if lone_vars:
            v = pop_var()
            if var_deg[v] != 1 or var_to_eq[v] != UNMATCHED:
                continue
            for e in cols[v]:
                if eq_to_var[e] == UNMATCHED:
                    break
        elif lone_eqs:
            e = pop_eq()
            if eq_deg[e] != 1 or eq_to_var[e] != UNMATCHED:
                continue
            row = rows[e]
            for v in row:
                if var_to_eq[v] == UNMATCHED:
                    break
        else:
            while scan < n_eq and (eq_to_var[scan] != UNMATCHED or eq_deg[scan] == 0):
                scan += 1
            if scan == n_eq:
                return eq_to_var, var_to_eq
            e = scan
            row = rows[e]
            v, least = UNMATCHED, DEAD          # the first free variable of least degree
            for u in row:
                if var_to_eq[u] == UNMATCHED and var_deg[u] < least:
                    v, least = u, var_deg[u]
        eq_to_var[e] = v
        var_to_eq[v] = e
        for u in rows[e]:
            if var_to_eq[u] == UNMATCHED:
                d = var_deg[u] - 1
                var_deg[u] = d
                if d == 1:
                    push_var(u)
        for f in cols[v]:
            if eq_to_var[f] == UNMATCHED:
                d = eq_deg[f] - 1
                eq_deg[f] = d
                if d == 1:
                    push_eq(f)


def _transpose(n_var: int, rows: Sequence[Sequence[int]]) -> list[list[int]]:
    """``cols[v]``: the equations whose rows hold ``v``, in increasing order (once per
    occurrence)."""
    cols: list[list[int]] = [[] for _ in range(n_var)]
    for e, row in enumerate(rows):
        for v in row:
            cols[v].append(e)
    return cols


def _hopcroft_karp(rows: Sequence[Sequence[int]], eq_to_var: list[int],
                   var_to_eq: list[int]) -> None:
    """Augment along shortest paths, phase by phase, until none is left."""
    n_eq = len(rows)
    unset = n_eq + 1
    dist = [unset] * n_eq
    pos = [0] * n_eq
    free = [e for e in range(n_eq) if eq_to_var[e] == UNMATCHED and len(rows[e])]
    while free:
        layered, limit = _layers(rows, var_to_eq, free, dist, unset)
        if limit != unset:
            for root in free:
                _layered_augment(root, rows, eq_to_var, var_to_eq, dist, pos, limit, unset)
        for e in layered:
            dist[e] = unset
            pos[e] = 0
        if limit == unset:
            return
        free = [e for e in free if eq_to_var[e] == UNMATCHED]


def _layers(rows: Sequence[Sequence[int]], var_to_eq: list[int], free: list[int],
            dist: list[int], unset: int) -> tuple[list[int], int]:
    """Breadth-first layering from the free equations.

    Sets ``dist[e]`` for every equation reached and returns them with the length of
    the shortest augmenting path (``unset`` if there is none).
    """
    queue = list(free)
    for e in queue:
        dist[e] = 0
    limit = unset
    for e in queue:
        d = dist[e] + 1
        if d > limit:
            break
        for v in rows[e]:
            f = var_to_eq[v]
            if f == UNMATCHED:
                limit = d
            elif dist[f] == unset:
                dist[f] = d
                queue.append(f)
    return queue, limit


def _layered_augment(root: int, rows: Sequence[Sequence[int]], eq_to_var: list[int],
                     var_to_eq: list[int], dist: list[int], pos: list[int], limit: int,
                     unset: int) -> bool:
    """Depth-first search for a shortest augmenting path in the layered graph."""
    eqs = [root]
    via: list[int] = []
    while eqs:
        e = eqs[-1]
        row = rows[e]
        d = dist[e] + 1
        i = pos[e]
        n = len(row)
        while i < n:
            v = row[i]
            i += 1
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
