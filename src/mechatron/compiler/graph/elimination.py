"""Exact elimination of the constant-coefficient linear part of a system.

Structural analysis counts incidences, not values: it takes ``c.i + r.i = I`` and
``c.i + r.i = l.i`` (the Kirchhoff current law at the two nodes of a resistor and a
capacitor in parallel, fed by a current source and drained by an inductor) as two
equations for the two unknowns ``c.i`` and ``r.i``. Their difference, ``l.i = I``, holds
no unknown at all: the inductor current is fixed by the source and the system has a
higher index than the incidence shows. Network equations (current laws, ``v = p.v - n.v``
of every branch) are linear with coefficients of ±1, and whenever a cut set of current
sources and inductors or a loop of voltage sources and capacitors closes, a combination
of them cancels exactly.

`exact_elimination` finds these combinations. Its input is, for each equation, the
variables that appear in it linearly with a numeric coefficient (as exact integers or
fractions, so that no rounding decides anything) and which columns may be eliminated
(the unknowns). Gaussian elimination with a Markowitz pivot order (singleton rows and
columns first, so a tree-like network is reduced without fill-in) brings every equation
either to a pivot (it determines an unknown) or to a *reduced* form: the equation plus a
combination of pivot equations in which no eliminable column is left. A reduced
equation whose other terms hold no unknown either is a constraint among the remaining
variables (states, parameters, time) that the incidence could not show.

Reference: the same idea underlies the Bareiss-based alias elimination of
ModelingToolkit (Ma et al., "ModelingToolkit: a composable graph transformation system
for equation-based modeling", 2021) and the linear-combination conversion of Tan,
Nedialkov and Pryce ("Conversion methods for improving structural analysis of
differential-algebraic equation systems", BIT 57, 2017).
"""

from __future__ import annotations

import heapq
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from itertools import chain
from numbers import Rational

import numpy as np

from mechatron.compiler.graph.arrays import segments
from mechatron.compiler.graph.polynomial import Laurent

__all__ = ["LinearElimination", "SparseRows", "exact_elimination", "exact"]

Coefficient = int | Fraction | Laurent


def exact(value: float) -> Coefficient:
    """The float `value` as an exact integer or fraction (every float is a dyadic
    rational, so nothing is rounded)."""
    return int(value) if float(value).is_integer() else Fraction(value)


@dataclass
class LinearElimination:
    """Result of `exact_elimination`.

    Attributes
    ----------
    pivots : dict of int to int
        ``pivots[e] == v``: equation ``e`` was used to eliminate column ``v``; it is kept
        as given.
    rows : dict of int to dict
        For every other equation ``e`` taking part: its reduced linear part
        ``{column: coefficient}`` (no eliminable column left, exact zeros dropped; the
        given mapping itself when the elimination left it as it was).
    updates : dict of int to list
        ``updates[e]``: the ``(pivot equation, multiplier, scale)`` steps applied to
        equation ``e``, in order: ``e := scale * e - multiplier * pivot``, each pivot
        equation in the form it had when it became a pivot. The scale is 1 except after
        a pivot on a coefficient that depends on parameters (fraction-free: no
        division by a parameter expression). `combination` turns them into multipliers
        of the given equations.
    """

    pivots: dict[int, int]
    rows: dict[int, dict[int, Coefficient]]
    updates: dict[int, list[tuple[int, Coefficient, Coefficient]]] = \
        field(default_factory=dict)
    _memo: dict[int, dict[int, Coefficient]] = field(default_factory=dict, repr=False)

    def changed(self, e: int) -> bool:
        """Whether the elimination changed equation `e`."""
        return bool(self.updates.get(e))

    def combination(self, e: int) -> dict[int, Coefficient]:
        """Multipliers ``{equation: m}`` of the given equations whose sum is the reduced
        (or, for a pivot, the pivoting) form of equation `e`; `e` itself has m = 1,
        or the product of the scales of its fraction-free steps.

        Computed on demand, from the pivot equations `e` depends on only: a long chain
        of pivots that no reduced equation touches costs nothing."""
        order: list[int] = []
        stack = [(e, False)]
        seen = set()
        while stack:
            f, done = stack.pop()
            if done:
                order.append(f)
                continue
            if f in seen or f in self._memo:
                continue
            seen.add(f)
            stack.append((f, True))
            for p, _, _ in self.updates.get(f, ()):
                if p not in self._memo and p not in seen:
                    stack.append((p, False))
        for f in order:
            comb: dict[int, Coefficient] = {f: 1}
            for p, m, s in self.updates.get(f, ()):
                if s != 1:
                    comb = {g: s * c for g, c in comb.items()}
                for g, b in self._memo[p].items():
                    new = _norm(comb.get(g, 0) - m * b)
                    if new:
                        comb[g] = new
                    else:
                        comb.pop(g, None)
            self._memo[f] = comb
        return self._memo[e]


class SparseRows(Sequence):
    """Rows ``{column: coefficient}`` held as arrays (compressed rows: row ``e`` holds
    ``cols[ptr[e]:ptr[e + 1]]`` with ``coefs`` at the same places, each column once, as
    a dictionary holds it), each formed as a dictionary when read, not all at once;
    `exact_elimination` reads the columns of the rows as arrays."""

    __slots__ = ("ptr", "cols", "coefs")

    def __init__(self, ptr: np.ndarray, cols: np.ndarray, coefs: list):
        self.ptr, self.cols, self.coefs = ptr, cols, coefs

    def __len__(self) -> int:
        return len(self.ptr) - 1

    def __getitem__(self, e):
        if isinstance(e, slice):
            return [self[k] for k in range(*e.indices(len(self)))]
        if e < 0:
            e += len(self)
        if not 0 <= e < len(self):
            raise IndexError("row index out of range")
        a, b = int(self.ptr[e]), int(self.ptr[e + 1])
        return dict(zip(self.cols[a:b].tolist(), self.coefs[a:b])) if a != b else {}


def _column_singles(linear: SparseRows, ok: list, rows: Sequence[int],
                    n_var: int) -> dict[int, int] | None:
    """The pivots of `exact_elimination` (in the order it takes them) when each is a
    column left in a single active equation, so that no equation is updated (a
    tree-like network: every current law and branch relation a pivot); None when some
    other pivot would follow. The same steps as `exact_elimination`'s first branch, on
    the rows' columns as arrays: the columns held by one active equation on a stack
    (the lowest first), each pivot retiring its equation and pushing the columns it
    leaves held by one."""
    ptr, cols = linear.ptr, linear.cols
    taking = np.asarray(rows, dtype=np.int64)
    if not len(taking):
        return {}
    if not all(linear.coefs):
        return None                 # an exact zero: a column that is not there
    at, owner = segments(ptr, taking)   # the entries of the rows taking part, in order
    col = cols[at]
    eligible = np.asarray(ok, dtype=bool)[col] if len(col) else np.zeros(0, dtype=bool)
    col = col[eligible]
    row = taking[owner][eligible]
    count = np.bincount(col, minlength=n_var)
    active = np.zeros(len(linear), dtype=np.int8)
    active[taking] = 1
    if int(active.sum()) != len(taking):
        return None                 # a row taking part twice
    # each column's rows
    by_col = np.argsort(col, kind="stable")
    col_rows = row[by_col].tolist()
    col_ptr = np.searchsorted(col[by_col], np.arange(n_var + 1)).tolist()
    stack = np.flatnonzero(count == 1)[::-1].tolist()
    left = count.tolist()           # active equations holding each column, -1: pivoted
    active = bytearray(active.tobytes())
    ptr_l, cols_l = ptr.tolist(), cols.tolist()
    pivots: dict[int, int] = {}
    while stack:
        v = stack.pop()
        if left[v] != 1:
            continue
        k = col_ptr[v]
        e = col_rows[k]
        while not active[e]:
            k += 1
            e = col_rows[k]
        pivots[e] = v
        left[v] = -1
        active[e] = 0
        for u in cols_l[ptr_l[e]:ptr_l[e + 1]]:
            if ok[u] and left[u] > 0:
                left[u] -= 1
                if left[u] == 1:
                    stack.append(u)
    return pivots if max(left, default=0) <= 0 else None


def exact_elimination(linear: Sequence[Mapping[int, Rational]],
                      eliminable: Sequence[bool], *,
                      rows: Sequence[int] | None = None) -> LinearElimination:
    """Eliminate the eliminable columns from the linear parts of the equations, exactly.

    Parameters
    ----------
    linear : sequence of mapping
        ``linear[e]`` maps each column (variable index) that appears in equation ``e``
        linearly with a coefficient free of unknowns to that coefficient: ``int`` or
        ``Fraction`` (use `exact` on floats), or a `Laurent` polynomial in parameters.
        Other terms of the equation are the caller's business: they ride along
        unchanged in the combinations.
    eliminable : sequence of bool
        ``eliminable[v]``: whether column ``v`` may be eliminated (a pivot column).
    rows : sequence of int, optional
        The equations taking part; default: every equation with an eliminable column.

    Returns
    -------
    LinearElimination
        Pivot equations and the reduced form of the others. The number of pivots is the
        exact rank of the eliminable columns.

    Notes
    -----
    Pivot order: a column left in a single active equation first (no other equation
    changes), then an equation left with a single eliminable column (no fill-in), else
    the column of fewest active equations with, in it, the equation of fewest eliminable
    columns (Markowitz). Among equations, those changed least so far go first: a pivot
    equation spreads its own combination into every equation it updates, so pivoting
    on the given equations keeps each reduced equation a short combination (in a
    network: the elements of one loop or cut set, not a path across the whole circuit).
    Ties go to the lowest index, so the result depends only on the input. Arithmetic is
    exact (``int``, ``Fraction`` and `Laurent`).

    A coefficient that depends on parameters is pivoted on only where no numeric one
    is left in its column; it is then taken as nonzero (as Modelica tools take a
    parameter that a structural decision divides by: a transformer ratio or a gear
    ratio of 0 is no transformer or gear), and the step is fraction-free
    (``f := a * f - b * e``), so no reduced equation divides by a parameter.
    """
    n_var = len(eliminable)
    ok = [bool(x) for x in eliminable]
    if type(linear) is SparseRows and rows is not None:
        _check_sparse_columns(linear, n_var)
        pivots = _column_singles(linear, ok, rows, n_var)
        if pivots is not None:      # no equation updated: the others as given
            return LinearElimination(pivots=pivots, rows={
                e: linear[e] for e in rows if e not in pivots})
    else:
        _check_columns(linear, n_var)
    if rows is None:
        rows = [e for e, row in enumerate(linear) if any(ok[v] for v in row)]
    work: dict[int, dict[int, Coefficient]] = {}
    updates: dict[int, list[tuple[int, Coefficient]]] = {}
    col_rows: dict[int, dict[int, None]] = {}
    count: dict[int, int] = {}          # eliminable columns left in each active row
    given: set[int] = set()             # rows still the caller's mappings (not changed)
    for e in rows:
        row = linear[e]
        if all(row.values()):
            given.add(e)
        else:
            row = {v: a for v, a in row.items() if a}
        work[e] = row
        n = 0
        for v in row:
            if ok[v]:
                col = col_rows.get(v)
                if col is None:
                    col_rows[v] = {e: None}
                else:
                    col[e] = None
                n += 1
        count[e] = n
    pivots: dict[int, int] = {}
    active = dict.fromkeys(rows)
    col_singles = [v for v in sorted(col_rows) if len(col_rows[v]) == 1]
    row_singles = [(0, e) for e in rows if count[e] == 1]   # (updates so far, row)
    # Markowitz choices come from a heap of (equations in column, column), stale entries
    # skipped; the columns whose count changed are pushed only when a choice is made
    heap: list[tuple[int, int]] = []
    dirty = list(col_rows)
    col_singles.reverse()

    def retire(e: int) -> None:
        """Equation `e` becomes a pivot: it leaves the active set."""
        del active[e]
        for v in work[e]:
            if ok[v] and v in col_rows:
                col = col_rows[v]
                col.pop(e, None)
                if len(col) == 1:
                    col_singles.append(v)
                if col:
                    dirty.append(v)

    def pivot(e: int, v: int) -> None:
        pivots[e] = v
        others = [f for f in col_rows[v] if f != e]
        retire(e)
        del col_rows[v]
        prow = work[e]
        a = prow[v]
        symbolic = isinstance(a, Laurent)
        for f in others:
            frow = work[f]
            if f in given:          # copied before its first change
                given.discard(f)
                frow = work[f] = dict(frow)
            if symbolic:            # fraction-free: f := a * f - frow[v] * e
                s, m = a, frow[v]
                for u in frow:
                    if u not in prow:
                        frow[u] = a * frow[u]
            else:
                s, m = 1, _ratio(frow[v], a)
            updates.setdefault(f, []).append((e, m, s))
            for u, b in prow.items():
                new = _norm(s * frow.get(u, 0) - m * b) if symbolic else \
                    _norm(frow.get(u, 0) - m * b)
                was = u in frow
                if new:
                    frow[u] = new
                    if not was and ok[u] and u in col_rows:
                        col_rows[u][f] = None
                        count[f] += 1
                        dirty.append(u)
                elif was:
                    del frow[u]
                    if ok[u] and u != v and u in col_rows:
                        col = col_rows[u]
                        col.pop(f, None)
                        count[f] -= 1
                        if len(col) == 1:
                            col_singles.append(u)
                        if col:
                            dirty.append(u)
            count[f] -= 1                  # column v is gone from f
            if count[f] == 1:
                heapq.heappush(row_singles, (len(updates[f]), f))

    while active:
        if col_singles:
            v = col_singles.pop()
            col = col_rows.get(v)
            if col is None or len(col) != 1:
                continue
            # pivot(e, v) when no other equation holds v: e retires, nothing is updated
            e = next(iter(col))
            pivots[e] = v
            del col_rows[v]
            retire(e)
            continue
        if row_singles:
            _, e = heapq.heappop(row_singles)
            if e not in active or count[e] != 1:
                continue
            pivot(e, next(v for v in work[e] if ok[v]))
            continue
        fresh = [(len(col), u) for u in dirty if (col := col_rows.get(u))]
        dirty.clear()
        if len(fresh) > len(heap):
            heap += fresh
            heapq.heapify(heap)
        else:
            for item in fresh:
                heapq.heappush(heap, item)
        chosen = None
        while heap:
            n, v = heapq.heappop(heap)
            if v in col_rows and len(col_rows[v]) == n and n:
                chosen = v
                break
        if chosen is None:
            break
        e = min(col_rows[chosen], key=lambda f: (isinstance(work[f][chosen], Laurent),
                                                 count[f], len(updates.get(f, ())), f))
        pivot(e, chosen)
    reduced = {e: work[e] for e in rows if e not in pivots}
    return LinearElimination(pivots=pivots, rows=reduced, updates=updates)


def _check_sparse_columns(linear: SparseRows, n_var: int) -> None:
    """`_check_columns` on the rows' arrays."""
    cols = linear.cols
    if len(cols) and (cols.min() < 0 or cols.max() >= n_var):
        bad = int(np.flatnonzero((cols < 0) | (cols >= n_var))[0])
        e = int(np.searchsorted(linear.ptr, bad, side="right")) - 1
        raise ValueError(f"equation {e} names column {int(cols[bad])}, outside 0 .. "
                         f"{n_var - 1}.")


def _check_columns(linear: Sequence[Mapping[int, Rational]], n_var: int) -> None:
    """Raise `ValueError` for a column outside ``0 .. n_var - 1``."""
    total = sum(map(len, linear))
    if total:
        try:
            cols = np.fromiter(chain.from_iterable(linear), dtype=np.int64, count=total)
            if cols.min() >= 0 and cols.max() < n_var:
                return
        except (OverflowError, TypeError, ValueError):
            pass
    for e, row in enumerate(linear):
        for v in row:
            if not 0 <= v < n_var:
                raise ValueError(f"equation {e} names column {v}, outside 0 .. "
                                 f"{n_var - 1}.")


def _ratio(a: Coefficient, b: Coefficient) -> Coefficient:
    """``a / b`` for a numeric `b`."""
    if type(a) is int and type(b) is int:
        q, r = divmod(a, b)
        return q if r == 0 else Fraction(a, b)
    if isinstance(a, Laurent):
        return a / b
    return _norm(Fraction(a) / b)


def _norm(x: Coefficient) -> Coefficient:
    if type(x) is Fraction and x.denominator == 1:
        return x.numerator
    return x
