"""Structural index reduction by Pantelides' algorithm.

Input: the incidence ``adj`` of ``n_var`` variables in the equations (see
`mechatron.compiler.graph.matching`) and ``var_to_diff``, which links each variable to
the variable that is its time derivative: ``var_to_diff[x] == dx`` when ``dx`` stands
for ``der(x)``, and -1 when the derivative of ``x`` does not appear. A variable with a
derivative is integrated, not solved for; the unknowns of the matching are the
*highest derivatives*, the variables ``v`` with ``var_to_diff[v] == -1`` (algebraic
variables included).

Output: an `IndexReduction`. Its incidence keeps the original equations first, at
their indices, and appends each differentiated equation; its variables keep the
original ones first and append the derivatives created on the way. ``eq_to_diff[e]``
is the equation obtained by differentiating ``e`` (-1 if ``e`` was not), with the same
convention as ``var_to_diff``. The incidence of ``der(e)`` is every variable ``v`` of
``e`` together with ``der(v)`` (``v`` stays, as it may appear nonlinearly).

References: C. C. Pantelides, "The consistent initialization of
differential-algebraic systems", SIAM J. Sci. Stat. Comput. 9(2), 1988; J. D. Pryce,
"A simple structural analysis method for DAEs", BIT 41(2), 2001.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from itertools import chain

import numpy as np

from mechatron.errors import StructuralError

from .matching import UNMATCHED, Matching, augment_from, checked_entries, maximum_matching

__all__ = ["IndexReduction", "pantelides", "derivative_chains"]


@dataclass
class IndexReduction:
    """The extended system produced by `pantelides`.

    Attributes
    ----------
    adj : list of list of int
        Incidence of the extended system: the original equations first, at their
        original indices, then the differentiated equations in order of creation.
    n_var : int
        Number of variables of the extended system (original ones first).
    n_var_original : int
        Number of variables given to `pantelides`; those from this index on are the
        derivatives it created.
    var_to_diff : list of int
        ``var_to_diff[v]`` is the variable standing for ``der(v)``, or -1.
    eq_to_diff : list of int
        ``eq_to_diff[e]`` is the equation ``der(e)``, or -1.
    matching : Matching
        Matching of the highest-derivative equations (``eq_to_diff[e] == -1``) to
        highest-derivative variables (``var_to_diff[v] == -1``); every such equation
        is matched. Lower-order equations and variables are left unmatched. When no
        equation is differentiated, it is ``maximum_matching(n_var, adj,
        allowed=[d == -1 for d in var_to_diff])`` of the given system, pair for pair.
    differentiated : list of tuple of (int, int)
        ``(e, k)`` for each original equation ``e`` differentiated ``k >= 1`` times,
        in increasing order of ``e``.
    """

    adj: list[list[int]]
    n_var: int
    n_var_original: int
    var_to_diff: list[int]
    eq_to_diff: list[int]
    matching: Matching
    differentiated: list[tuple[int, int]] = field(default_factory=list)

    @property
    def n_eq(self) -> int:
        """Number of equations of the extended system."""
        return len(self.adj)

    @property
    def diff_to_var(self) -> list[int]:
        """``diff_to_var[dv]`` is the variable ``v`` with ``der(v) == dv``, or -1."""
        return _inverse(self.var_to_diff)

    @property
    def diff_to_eq(self) -> list[int]:
        """``diff_to_eq[de]`` is the equation ``e`` with ``der(e) == de``, or -1."""
        return _inverse(self.eq_to_diff)


def pantelides(n_var: int, adj: Sequence[Sequence[int]], var_to_diff: Sequence[int], *,
               max_rounds: int = 100) -> IndexReduction:
    """Find the equations to differentiate so that the highest derivatives can be matched.

    Parameters
    ----------
    n_var : int
        Number of variables.
    adj : sequence of sequence of int
        ``adj[e]`` lists the variables of equation ``e`` (derivative variables
        included, e.g. ``dx`` for ``der(x)``).
    var_to_diff : sequence of int
        ``var_to_diff[v]`` is the variable standing for ``der(v)``, or -1. A variable
        is the derivative of at most one variable; chains (``x -> dx -> ddx``) are fine.
    max_rounds : int, optional
        Most times one equation may be differentiated (a bound on the index).

    Returns
    -------
    IndexReduction
        The extended system and its matching; inputs are not modified.

    Raises
    ------
    StructuralError
        If the system is structurally singular, with the suspect equations in
        ``.equations`` and the undifferentiated variables they involve in
        ``.variables`` (both as indices); or if an equation would need more than
        `max_rounds` differentiations.
    ValueError
        If `adj` or `var_to_diff` are malformed.

    Notes
    -----
    Every equation in turn is given an augmenting path onto the highest derivatives.
    When there is none, the search has visited a minimally structurally singular set:
    equations ``E`` whose allowed variables ``V`` number ``|E| - 1``. Each equation of
    ``E`` is differentiated, each variable of ``V`` gets its derivative (created if
    missing), which replaces it among the unknowns, ``der(v)`` is matched to
    ``der(eq(v))``, and the search resumes from the derivative of the equation.

    Singularity criterion: before any differentiation, the equations are matched to
    variable *families* (a variable with all its derivatives counts once). When some
    equation is left out, the equations that alternating paths reach from the
    unmatched ones (the over-determined part of the Dulmage–Mendelsohn decomposition)
    are reported. The criterion is necessary for termination, since the final matching
    maps distinct equation families to distinct variable families; it is also the
    structural nonsingularity under which the method is known to terminate
    (Pantelides, 1988; Pryce, 2001), and `max_rounds` guards the rest.
    """
    rows = _copy_adjacency(n_var, adj)
    var_to_diff = _checked_var_to_diff(n_var, var_to_diff)
    system = _Extension(n_var, rows, var_to_diff)
    # a matching of every equation onto distinct highest derivatives is one onto
    # distinct families (each family has one highest derivative): the check can only
    # fail when the first matching leaves an equation out
    if UNMATCHED in system.eq_to_var:
        _check_nonsingular(n_var, rows, var_to_diff)
    n_original = len(rows)
    for k in range(n_original):
        if system.eq_to_diff[k] == UNMATCHED and system.eq_to_var[k] == UNMATCHED:
            system.match(k, max_rounds)
    return system.result(n_original)


def derivative_chains(var_to_diff: Sequence[int]) -> tuple[list[int], list[int]]:
    """Root and order of each variable in the derivative chains of `var_to_diff`.

    Parameters
    ----------
    var_to_diff : sequence of int
        ``var_to_diff[v]`` is ``der(v)``, or -1.

    Returns
    -------
    root : list of int
        ``root[v]`` is the undifferentiated variable ``x`` with ``v = der^k(x)``.
    order : list of int
        ``order[v]`` is that ``k``.

    Raises
    ------
    ValueError
        If the links form a cycle or a variable is the derivative of two variables.
    """
    n = len(var_to_diff)
    diff_to_var = _inverse(var_to_diff)
    root = [UNMATCHED] * n
    order = [0] * n
    for x in range(n):
        if diff_to_var[x] != UNMATCHED:
            continue
        v, k = x, 0
        while v != UNMATCHED:
            root[v] = x
            order[v] = k
            v = var_to_diff[v]
            k += 1
    if UNMATCHED in root:
        v = root.index(UNMATCHED)
        raise ValueError(f"var_to_diff links variable {v} into a cycle of derivatives.")
    return root, order


class _Extension:
    """The growing system of one `pantelides` run: incidence, links and matching."""

    def __init__(self, n_var: int, adj: list[list[int]], var_to_diff: list[int]):
        self.adj = adj
        self.var_to_diff = var_to_diff
        self.eq_to_diff = [UNMATCHED] * len(adj)
        self.ok = [d == UNMATCHED for d in var_to_diff]
        start = maximum_matching(n_var, adj, allowed=self.ok)
        self.eq_to_var = start.eq_to_var
        self.var_to_eq = start.var_to_eq
        self.mark = [0] * n_var
        self.stamp = 0
        self.n_var_original = n_var

    def match(self, k: int, max_rounds: int) -> None:
        """Match original equation `k`, differentiating as long as no path exists."""
        e = k
        for rounds in range(max_rounds + 1):
            self.stamp += 1
            eqs: list[int] = []
            variables: list[int] = []
            if augment_from(e, self.adj, self.ok, self.eq_to_var, self.var_to_eq,
                            self.mark, self.stamp, eqs, variables):
                return
            if rounds == max_rounds:
                break
            self._differentiate(eqs, variables)
            e = self.eq_to_diff[e]
        raise StructuralError(
            f"equation {k}: still structurally singular after {max_rounds} "
            "differentiations. Is the index really this high? Raise max_rounds if so.",
            equations=[k])

    def _differentiate(self, eqs: list[int], variables: list[int]) -> None:
        """Differentiate the singular set `eqs` and promote `variables` to derivatives."""
        for v in variables:
            self._derivative_variable(v)
        for e in eqs:
            self._derivative_equation(e)
        for v in variables:
            dv = self.var_to_diff[v]
            de = self.eq_to_diff[self.var_to_eq[v]]
            self.var_to_eq[dv] = de
            self.eq_to_var[de] = dv

    def _derivative_variable(self, v: int) -> int:
        """Return ``der(v)``, created if missing; it replaces `v` among the unknowns."""
        dv = self.var_to_diff[v]
        if dv == UNMATCHED:
            dv = len(self.var_to_diff)
            self.var_to_diff[v] = dv
            self.var_to_diff.append(UNMATCHED)
            self.ok.append(True)
            self.var_to_eq.append(UNMATCHED)
            self.mark.append(0)
        self.ok[v] = False
        return dv

    def _derivative_equation(self, e: int) -> int:
        """Append ``der(e)``: every variable of `e` and its derivative."""
        row = dict.fromkeys(self.adj[e])
        for v in self.adj[e]:
            dv = self.var_to_diff[v]
            row[dv if dv != UNMATCHED else self._derivative_variable(v)] = None
        de = len(self.adj)
        self.adj.append(list(row))
        self.eq_to_diff[e] = de
        self.eq_to_diff.append(UNMATCHED)
        self.eq_to_var.append(UNMATCHED)
        return de

    def result(self, n_original: int) -> IndexReduction:
        """Package the final system, keeping only highest-derivative pairs matched."""
        eq_to_var = [v if self.eq_to_diff[e] == UNMATCHED else UNMATCHED
                     for e, v in enumerate(self.eq_to_var)]
        var_to_eq = [UNMATCHED] * len(self.var_to_diff)
        for e, v in enumerate(eq_to_var):
            if v != UNMATCHED:
                var_to_eq[v] = e
        counts = []
        for e in range(n_original):
            k, d = 0, self.eq_to_diff[e]
            while d != UNMATCHED:
                k, d = k + 1, self.eq_to_diff[d]
            if k:
                counts.append((e, k))
        return IndexReduction(adj=self.adj, n_var=len(self.var_to_diff),
                              n_var_original=self.n_var_original,
                              var_to_diff=self.var_to_diff, eq_to_diff=self.eq_to_diff,
                              matching=Matching(eq_to_var, var_to_eq),
                              differentiated=counts)


def _inverse(links: Sequence[int]) -> list[int]:
    """Invert a partial injective map given as a list with -1 for "none"."""
    inverse = [UNMATCHED] * len(links)
    for a, b in enumerate(links):
        if b != UNMATCHED:
            if inverse[b] != UNMATCHED:
                raise ValueError(f"{b} is the derivative of both {inverse[b]} and {a}.")
            inverse[b] = a
    return inverse


def _copy_adjacency(n_var: int, adj: Sequence[Sequence[int]]) -> list[list[int]]:
    """Validated rows of `adj` in a new list, each row without repeated variables. A
    row given as a list of ints that needs no change is that list itself, not a copy:
    index reduction appends rows and never changes one (a million rows of a large
    network are not copied again)."""
    flat = checked_entries(n_var, adj)
    if flat is None:
        return [list(dict.fromkeys(int(v) for v in row)) for row in adj]
    lens = np.fromiter(map(len, adj), dtype=np.int64, count=len(adj))
    ptr = np.concatenate([np.zeros(1, dtype=np.int64), np.cumsum(lens)])
    if all(type(row) is list for row in adj) and \
            set(map(type, chain.from_iterable(adj))) <= {int}:
        rows = list(adj)
    else:
        values = flat.tolist()
        rows = [values[a:b] for a, b in zip(ptr[:-1].tolist(), ptr[1:].tolist())]
    # a row whose entries increase repeats none; the others are deduplicated
    falls = np.diff(flat) <= 0
    starts = ptr[1:-1]
    falls[starts[(starts > 0) & (starts < flat.size)] - 1] = False   # row boundaries
    if falls.any():
        owner = np.repeat(np.arange(len(adj)), lens)
        for e in np.unique(owner[:-1][falls]).tolist():
            rows[e] = list(dict.fromkeys(rows[e]))
    return rows


def _checked_var_to_diff(n_var: int, var_to_diff: Sequence[int]) -> list[int]:
    """Validated copy of `var_to_diff` (length, range, injective, acyclic)."""
    links = [int(d) for d in var_to_diff]
    if len(links) != n_var:
        raise ValueError(f"var_to_diff must have one entry per variable ({n_var}), "
                         f"got {len(links)}.")
    for v, d in enumerate(links):
        if d == v or (d != UNMATCHED and not 0 <= d < n_var):
            raise ValueError(f"var_to_diff[{v}] = {d} is not another variable.")
    derivative_chains(links)
    return links


def _check_nonsingular(n_var: int, adj: list[list[int]], var_to_diff: list[int]) -> None:
    """Raise `StructuralError` unless every equation matches a distinct variable family."""
    root, _ = derivative_chains(var_to_diff)
    families = [list(dict.fromkeys(root[v] for v in row)) for row in adj]
    found = maximum_matching(n_var, families)
    unmatched = found.unmatched_equations
    if not unmatched:
        return
    eqs, roots = _overdetermined(families, found, unmatched)
    raise StructuralError(
        f"structurally singular system: equations {eqs} involve only {len(roots)} "
        f"unknown(s) {roots} (a variable and its derivatives count once), "
        f"{len(eqs) - len(roots)} equation(s) too many. Is an equation redundant, or "
        "an unknown declared as a parameter?",
        equations=eqs, variables=roots)


def _overdetermined(families: list[list[int]], found: Matching,
                    unmatched: list[int]) -> tuple[list[int], list[int]]:
    """Equations and families that alternating paths reach from the unmatched equations."""
    seen_eq = set(unmatched)
    seen_family: set[int] = set()
    queue = list(unmatched)
    for e in queue:
        for x in families[e]:
            if x in seen_family:
                continue
            seen_family.add(x)
            f = found.var_to_eq[x]
            if f != UNMATCHED and f not in seen_eq:
                seen_eq.add(f)
                queue.append(f)
    return sorted(seen_eq), sorted(seen_family)
