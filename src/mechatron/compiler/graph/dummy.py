"""Dummy derivatives and state selection after index reduction.

After `pantelides`, the extended system has more equations than the original one, and
some derivatives can no longer be integrated independently: ``x**2 + y**2 = L**2`` and
its derivatives tie ``x``, ``y`` and their velocities together. The dummy-derivative
method (Mattsson & Söderlind, 1993) turns as many derivatives into plain algebraic
unknowns, *dummy derivatives*, as there are differentiated equations, so that the
extended system becomes square in the remaining unknowns.

Conventions (see `mechatron.compiler.graph.pantelides` for ``var_to_diff``):

- `dummy_derivatives` returns derivative variables, e.g. ``der(y)``; a dummy is a
  variable ``dv`` with an integral ``v`` (``var_to_diff[v] == dv``) that is solved
  algebraically instead of integrated.
- `state_selection` returns the variables ``v`` with ``var_to_diff[v] != -1`` whose
  derivative is not a dummy: the states integrated by the solver.

After the selection, the unknowns are all variables except the states; they number
exactly the equations of the extended system, and generically match them one to one.

Reference: S. E. Mattsson and G. Söderlind, "Index reduction in differential-algebraic
equations using dummy derivatives", SIAM J. Sci. Comput. 14(3), 1993.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from mechatron.errors import StructuralError

from .matching import DEAD, UNMATCHED, augment_from
from .pantelides import IndexReduction, derivative_chains

__all__ = ["dummy_derivatives", "state_selection"]

Selector = Callable[[list[int], list[int], int], Sequence[int]]
"""``select(eqs, candidates, k)``: pick `k` of `candidates` for the rows `eqs`."""


def dummy_derivatives(ir: IndexReduction, *, select: Selector | None = None,
                      priority: Sequence[float] | None = None,
                      rank: Sequence[int] | None = None) -> list[int]:
    """Choose the derivatives that become algebraic unknowns (dummy derivatives).

    Parameters
    ----------
    ir : IndexReduction
        Result of `pantelides`.
    select : callable, optional
        ``select(eqs, candidates, k) -> list[int]`` picks `k` variables of
        `candidates` (a list of variable indices, most preferred dummy first) such
        that the Jacobian of the equations `eqs` with respect to them is nonsingular,
        e.g. by pivoting a numeric Jacobian. ``k == len(eqs)``. Returning fewer than
        `k` means the Jacobian is singular. Default: a structural choice, see Notes.
    priority : sequence of float, optional
        Dummy preference per variable: among candidates, those whose value is
        *higher* are made dummy first, so a *lower* value means "rather keep as a
        state". The value is read at the undifferentiated variable of each derivative
        chain (for ``der(der(x))`` it is ``priority[x]``), so a list over the original
        variables suffices; missing entries count as 0.
    rank : sequence of int, optional
        Declaration order per variable, read at the undifferentiated variable of each
        chain like `priority`: among otherwise equal candidates, the one whose variable
        was declared *later* (higher rank) is made dummy first. Default: the variable
        index. Giving it keeps the choice when the variables are renumbered.

    Returns
    -------
    list of int
        The dummy derivatives, in increasing order.

    Raises
    ------
    StructuralError
        If no `k` columns with a nonsingular Jacobian exist at some level.
    ValueError
        If `select` returns variables that are not candidates, or too many.

    Notes
    -----
    The equations are processed in independent groups (connected components of the
    highest-level equations through their candidates). For each group:

    1. Rows: the differentiated equations of highest order (``eq_to_diff[e] == -1``
       and ``e`` is the derivative of some equation). Candidates: the highest
       derivatives (``var_to_diff[v] == -1``) that appear in them and are themselves
       derivatives.
    2. Pick as many candidates as rows, with a nonsingular Jacobian; they are dummy.
    3. Go down one level: the rows become the equations the current rows are
       derivatives of, keeping those that are themselves derivatives; the candidates
       become the integrals of the picked columns. Repeat from 2 until no row is left.

    The candidates are ordered by a fixed rule, most preferred dummy first: higher
    `priority`; then derivatives created by `pantelides` (index ``>=
    ir.n_var_original``) before those of the original system, so that a variable whose
    derivative the model itself uses stays a state; then higher derivative order; then
    later declaration (higher `rank`). The order is total and independent of how
    equations and variables are numbered when `rank` is given. The default picker
    keeps each candidate, in this order, that enlarges a matching of candidates to rows
    (a greedy basis of the transversal matroid, so it always finds `k` when the rows
    are structurally nonsingular). A custom `select` receives the same order and
    should give ties to the first candidate (see
    `mechatron.compiler.pivoting.pivot_columns`).
    """
    root, order = derivative_chains(ir.var_to_diff)
    diff_to_var = ir.diff_to_var
    diff_to_eq = ir.diff_to_eq
    weights = list(priority) if priority is not None else []
    ranks = list(rank) if rank is not None else list(range(ir.n_var))
    if len(ranks) < ir.n_var_original:
        raise ValueError(f"rank must give every original variable a rank "
                         f"({ir.n_var_original}), got {len(ranks)}.")

    def preference(v: int) -> tuple[float, bool, int, int]:
        x = root[v]
        return (-(weights[x] if x < len(weights) else 0.0), v < ir.n_var_original,
                -order[v], -ranks[x])

    def is_candidate(v: int) -> bool:
        return ir.var_to_diff[v] == UNMATCHED and diff_to_var[v] != UNMATCHED

    rows = [e for e in range(ir.n_eq)
            if ir.eq_to_diff[e] == UNMATCHED and diff_to_eq[e] != UNMATCHED]
    dummies: list[int] = []
    for eqs, candidates in _groups(rows, ir.adj, is_candidate):
        while eqs:
            candidates.sort(key=preference)
            chosen = _pick(eqs, candidates, ir.adj, select)
            dummies.extend(chosen)
            eqs = [diff_to_eq[e] for e in eqs if diff_to_eq[diff_to_eq[e]] != UNMATCHED]
            candidates = [diff_to_var[v] for v in chosen if diff_to_var[v] != UNMATCHED]
    return sorted(dummies)


def state_selection(ir: IndexReduction, dummies: Sequence[int]) -> list[int]:
    """Variables integrated as states once `dummies` are algebraic.

    Parameters
    ----------
    ir : IndexReduction
        Result of `pantelides`.
    dummies : sequence of int
        Dummy derivatives, as returned by `dummy_derivatives`.

    Returns
    -------
    list of int
        In increasing order, every ``v`` with ``var_to_diff[v] != -1`` and
        ``var_to_diff[v]`` not among `dummies`.
    """
    dummy = set(dummies)
    return [v for v, dv in enumerate(ir.var_to_diff)
            if dv != UNMATCHED and dv not in dummy]


def _groups(rows: list[int], adj: Sequence[Sequence[int]],
            is_candidate: Callable[[int], bool]) -> list[tuple[list[int], list[int]]]:
    """Split `rows` into connected components linked by shared candidate variables."""
    parent = list(range(len(rows)))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    owner: dict[int, int] = {}
    for i, e in enumerate(rows):
        for v in adj[e]:
            if not is_candidate(v):
                continue
            j = owner.setdefault(v, i)
            a, b = find(i), find(j)
            if a != b:
                parent[max(a, b)] = min(a, b)
    groups: dict[int, tuple[list[int], list[int]]] = {}
    for i, e in enumerate(rows):
        groups.setdefault(find(i), ([], []))[0].append(e)
    for v, i in owner.items():
        groups[find(i)][1].append(v)
    return list(groups.values())


def _pick(eqs: list[int], candidates: list[int], adj: Sequence[Sequence[int]],
          select: Selector | None) -> list[int]:
    """Pick ``len(eqs)`` dummy columns among `candidates`, structurally or by `select`."""
    k = len(eqs)
    if select is None:
        chosen = _structural_pick(eqs, candidates, adj)
    else:
        chosen = [int(v) for v in select(list(eqs), list(candidates), k)]
        allowed = set(candidates)
        if len(set(chosen)) != len(chosen) or not allowed.issuperset(chosen) \
                or len(chosen) > k:
            raise ValueError(f"select must return at most {k} distinct variables among "
                             f"{candidates}, got {chosen}.")
    if len(chosen) < k:
        raise StructuralError(
            f"equations {eqs} are singular with respect to the derivatives {candidates}: "
            f"only {len(chosen)} of {k} dummy derivatives found. Is a constraint "
            "redundant?", equations=list(eqs), variables=list(candidates))
    return chosen


def _structural_pick(eqs: list[int], candidates: list[int],
                     adj: Sequence[Sequence[int]]) -> list[int]:
    """Greedy transversal basis: keep each candidate (in order) that grows the matching."""
    column = {v: j for j, v in enumerate(candidates)}
    col_rows: list[list[int]] = [[] for _ in candidates]
    for i, e in enumerate(eqs):
        for v in adj[e]:
            j = column.get(v)
            if j is not None:
                col_rows[j].append(i)
    col_to_row = [UNMATCHED] * len(candidates)
    row_to_col = [UNMATCHED] * len(eqs)
    ok = [True] * len(eqs)
    mark = [0] * len(eqs)
    chosen: list[int] = []
    for j, v in enumerate(candidates):
        visited: list[int] = []
        if augment_from(j, col_rows, ok, col_to_row, row_to_col, mark, j + 1,
                        visited_vars=visited):
            chosen.append(v)
            if len(chosen) == len(eqs):
                break
        else:
            for i in visited:
                mark[i] = DEAD
    return chosen
