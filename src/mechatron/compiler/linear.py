"""Constraints hidden in the linear network equations, found before index reduction.

Kirchhoff's laws and the branch relations ``v = p.v - n.v`` are linear with coefficients
of ±1. When a cut set of current sources and inductors (or a loop of voltage sources and
capacitors, or a mechanical analogue: a torque source and springs) closes, a combination
of these equations cancels every algebraic unknown and leaves a constraint among states
and inputs, e.g. ``l.i == I`` for an inductor in series with a current source. The
incidence does not show it: each equation still mentions unknowns, the matching
succeeds, Pantelides differentiates nothing and the resulting algebraic loop is
singular. Whether that happened depended on port orientation and declaration order,
through alias elimination and the matching's choices.

`reveal` reduces the *purely linear* equations (every unknown with a numeric
coefficient) exactly, see `mechatron.compiler.graph.elimination`. A reduced equation
whose dependency the incidence hides is shown to index reduction in its reduced form;
if index reduction differentiates it, it is replaced by that form
(`Reduction.residual`), else it stays as written. Both are equivalent: a reduced
equation is the given one plus a combination of pivot equations, which stay. Reduced
equations whose dependency the incidence shows already are left alone, so models
without hidden constraints compile exactly as before.

A combination that leaves no variable at all is a dependency among the equations:
ideal sources that form a loop or a cut set by themselves, or a part of a network with
no path to a reference. `reveal` reports it in physical terms.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from itertools import chain

import casadi as ca
import numpy as np

from mechatron.compiler.graph import maximum_matching
from mechatron.compiler.graph.elimination import (LinearElimination, SparseRows, exact,
                                                  exact_elimination)
from mechatron.compiler.graph.matching import augment_from
from mechatron.compiler.graph.polynomial import Laurent, atom
from mechatron.errors import StructuralError

__all__ = ["Reduction", "Combined", "reveal", "owner_of", "sparse_jacobian",
           "jacobian_apart", "DENSE_ROW"]

DENSE_ROW = 64   # rows with more variables are differentiated apart (sparse_jacobian)


def sparse_jacobian(expr: ca.SX, syms: ca.SX, sparsity: ca.Sparsity | None = None) -> ca.SX:
    """``casadi.jacobian(expr, syms)``, with the rows that hold more than `DENSE_ROW`
    variables differentiated apart from the others.

    One dense row (the flow balance of a reference node that every branch of a ladder
    meets) makes every column of the Jacobian clash with every other in CasADi's graph
    colouring: the whole Jacobian then costs time quadratic in its size, its two parts
    linear. `sparsity` is ``jacobian_sparsity(expr, syms)`` if the caller has it."""
    if sparsity is None:
        sparsity = ca.jacobian_sparsity(expr, syms)
    count = np.diff(np.asarray(sparsity.get_crs()[0], dtype=np.int64))
    dense = np.flatnonzero(count > DENSE_ROW)
    if dense.size == 0 or dense.size == count.size:
        return ca.jacobian(expr, syms)
    return jacobian_apart(expr, syms, dense)


def jacobian_apart(expr: ca.SX, syms: ca.SX, dense: np.ndarray) -> ca.SX:
    """``casadi.jacobian(expr, syms)``, the rows ``dense`` (a sorted array of row
    numbers) differentiated apart from the others, each part at once: the others in
    place, with zeros in the rows ``dense`` (rows without entries), those rows then set
    to their own Jacobian. The nonzeros are copied once so (a copy of an entry counts a
    reference on its node, which is cold on a large graph), where stacking the two
    parts and putting the rows back in order copies them twice: 20 % of the whole at
    5 * 10^5 rows."""
    rows = dense.tolist()
    others = ca.SX(expr)
    others[rows] = ca.SX.zeros(len(rows))
    jac = ca.jacobian(others, syms)
    jac[rows, :] = ca.jacobian(expr[rows], syms)
    return jac


@dataclass
class Reduction:
    """Result of `reveal`.

    Attributes
    ----------
    adj : list of list of int
        Incidence for index reduction: the given one with every *changed* equation
        replaced by the incidence of its reduced form (the other rows are the given
        lists themselves).
    reduced : dict of int to tuple
        For each equation that the exact elimination reduced (a combination of the
        purely linear equations that leaves no unknown in their linear part):
        ``(linear, combination, incidence)``, the reduced linear part
        ``{column: coef}``, the multipliers ``{equation: coef}`` of the given
        equations whose sum it is, and the variables of that sum.
    changed : list of int
        The reduced equations whose constraint the incidence hides (see `reveal`):
        index reduction sees their reduced form.
    const : list of set of int
        Columns in which each equation is linear with a coefficient free of unknowns
        (a number, or an expression of parameters).
    atoms : list of SX
        The parameter (or parameter expression) that each atom of a `Laurent`
        coefficient stands for.
    jacobian : SX or None
        The Jacobian of the given equations in the variables (None without equations).
    entries : (ndarray, ndarray) or None
        Its entries' rows and columns, in CasADi's order (column by column).
    """

    adj: list[list[int]]
    reduced: dict[int, tuple[dict, dict, list[int]]] = field(default_factory=dict)
    changed: list[int] = field(default_factory=list)
    const: list[set[int]] = field(default_factory=list)
    atoms: list = field(default_factory=list)
    jacobian: ca.SX | None = None
    entries: tuple[np.ndarray, np.ndarray] | None = None

    def expression(self, a) -> ca.SX:
        """Coefficient `a` (a number or a `Laurent` polynomial) as an expression."""
        return _expression(a, self.atoms)

    def residual(self, e: int, res: list[ca.SX], var_syms: list[ca.SX]) -> ca.SX:
        """The reduced form of equation `e`: its linear part plus the other terms of the
        equations it combines (each with its numeric-linear columns set to zero)."""
        linear, comb, _ = self.reduced[e]
        out = ca.SX(0)
        for v, a in sorted(linear.items()):
            out = out + self.expression(a) * var_syms[v]
        for k, m in sorted(comb.items()):
            cols = sorted(self.const[k])
            rest = ca.substitute(res[k], ca.vertcat(*[var_syms[v] for v in cols]),
                                 ca.DM.zeros(len(cols))) if cols else res[k]
            if not rest.is_zero():
                out = out + self.expression(m) * rest
        return out


class Combined:
    """Origin of a reduced equation: the sum of the equations it combines."""

    __slots__ = ("where", "parts")

    def __init__(self, parts: list):
        self.parts = parts
        owners = []
        for p in parts:
            w = owner_of(p)
            if w not in owners:
                owners.append(w)
        self.where = ", ".join(owners)

    def __str__(self) -> str:
        return f"{self.where}: combination of {len(self.parts)} equations " \
               f"({'; '.join(str(p) for p in self.parts[:4])}" \
               f"{' ...' if len(self.parts) > 4 else ''})"

    __repr__ = __str__


def owner_of(origin) -> str:
    """Component (or connection set) an equation comes from."""
    where = getattr(origin, "where", None)
    if where:
        return str(where)
    text = str(origin)
    if text.startswith("connect("):
        return text[:text.index(")") + 1] if ")" in text else text
    return text.split(":")[0]


def reveal(name: str, res: list[ca.SX], orig: list, var_syms: list[ca.SX],
           var_names: list[str], var_to_diff: list[int], adj: list[list[int]],
           roles: dict[str, tuple[str, str, str, bool]] | None = None,
           classes: dict[str, str] | None = None,
           parameters: list[ca.SX] | None = None,
           stacked: tuple[ca.SX, ca.SX] | None = None,
           sparsity: ca.Sparsity | None = None,
           jacobian: ca.SX | None = None,
           symbols: ca.SX | None = None) -> Reduction:
    """Reduce the linear part of the equations exactly; raise on a dependency.

    An unknown's coefficient takes part when it is a number or an expression of
    `parameters` alone (a transformer's ratio ``N``, ``-N``, ``1/N``): such
    coefficients are exact `Laurent` polynomials in the parameters, so a cut set
    closed through an ideal transformer or gear cancels exactly as one of ±1 does.

    Parameters
    ----------
    res, orig, var_syms, var_names, var_to_diff, adj
        Equations, their origins, the variables (unknowns and derivatives), the
        derivative links and the incidence, as in `mechatron.compiler.structure.lower`.
    roles : dict, optional
        ``roles[name] = ("across" | "through", quantity, plural, is_port)`` for
        unknowns that stand for port variables (``is_port`` True) or for a branch
        quantity in the same unit, e.g. ``("through", "current", "currents", True)``;
        for messages.
    classes : dict, optional
        Class name of each component path, for messages ("sources v1 and v2").
    parameters : list of SX, optional
        The parameter symbols: coefficients that depend on them alone are exact
        symbolic coefficients; default: only numeric coefficients are.
    stacked : (SX, SX), optional
        ``vertcat(*res)`` and ``vertcat(*var_syms)``, if the caller has them already.
    sparsity, jacobian : Sparsity, SX, optional
        Their Jacobian's sparsity, and the Jacobian, if the caller has them; `adj`
        must then list that sparsity's pattern.
    symbols : SX, optional
        A column of the symbols the equations hold (the variables, the parameters,
        time): the Jacobian's entries are then told numbers or not by one function of
        them (else, or if an entry holds another symbol, by the symbols they hold).

    Raises
    ------
    StructuralError
        If a combination of the equations holds no variable: the equations are
        dependent (a loop of ideal across sources, a cut set of ideal through sources).
    """
    n = len(var_syms)
    if not res:
        return Reduction(list(adj))
    jac = jacobian if jacobian is not None else sparse_jacobian(
        *(stacked if stacked is not None else (ca.vertcat(*res), ca.vertcat(*var_syms))),
        sparsity)
    rows, cols = (np.asarray(a, dtype=np.int64) for a in jac.sparsity().get_triplet())
    values = _numbers(jac, symbols)
    fixed = ~np.isnan(values)        # a coefficient free of unknowns: a number, ...
    take = np.flatnonzero(fixed & (values != 0))
    coefs = _exact_numbers(values[take])
    symbolic = np.flatnonzero(~fixed).tolist()
    atoms: list = []
    if parameters and symbolic:      # ... or an expression of the parameters alone
        found = list(_parameter_coefficients(ca.vertsplit(jac.nz[symbolic]),
                                             parameters, atoms))
        fixed[[symbolic[k] for k, _ in found]] = True
        by_parameters = [(symbolic[k], a) for k, a in found if a]
        if by_parameters:
            take = np.concatenate([take, np.array([k for k, _ in by_parameters],
                                                  dtype=np.int64)])
            coefs += [a for _, a in by_parameters]
    const = _Columns(len(res), rows[fixed], cols[fixed])
    linear = _linear_rows(len(res), rows[take], cols[take], coefs)
    eliminable = [d == -1 for d in var_to_diff]
    nonlinear = {}

    def other_terms(k: int) -> list[int]:
        if k not in nonlinear:
            own = const[k]
            nonlinear[k] = [v for v in adj[k] if v not in own]
        return nonlinear[k]

    # the purely linear equations: every unknown in them has a numeric coefficient
    # (Kirchhoff's laws, v = p.v - n.v, v = V(t)); only their combinations cancel
    # exactly, the other terms of c.i == C*der(c.v) are taken as generic
    if sparsity is not None and jac.sparsity() == sparsity:
        # adj is that pattern (as in lower): read the entries, not the lists
        pure = _purely_linear_entries(rows, cols, fixed, eliminable, len(res))
    else:
        pure = _purely_linear(adj, eliminable, const, n)
    elim = exact_elimination(linear, eliminable, rows=pure)
    out = Reduction(list(adj), const=const, atoms=atoms, jacobian=jac,
                    entries=(rows, cols))
    for e, row in elim.rows.items():
        comb = elim.combination(e) if elim.changed(e) else {e: 1}
        inc = dict.fromkeys(sorted(row))
        for k in sorted(comb):
            inc.update(dict.fromkeys(other_terms(k)))
        out.reduced[e] = (row, comb, list(inc))
    out.changed = _hidden(n, elim, linear, eliminable)
    for e in out.changed:
        out.adj[e] = out.reduced[e][2]
    _check_dependencies(name, res, orig, var_syms, var_names, eliminable, out,
                        linear, roles or {}, classes or {}, n)
    return out


def _exact_numbers(values: np.ndarray) -> list:
    """`exact` of each of ``values`` (``int`` where integral, else ``Fraction``): the
    integral ones of fewer than 63 bits converted by NumPy at once."""
    out = np.zeros(values.size, dtype=np.int64)
    whole = np.isfinite(values) & (np.abs(values) < 2.0 ** 62)
    whole[whole] = values[whole] == np.floor(values[whole])
    out[whole] = values[whole]
    coefs = out.tolist()
    for k in np.flatnonzero(~whole).tolist():
        coefs[k] = exact(float(values[k]))
    return coefs


class _Columns:
    """``const[e]``: the set of columns in which equation ``e`` is linear with a
    coefficient free of unknowns, formed on request from the entries ``(rows, cols)``
    (every equation's in one pair of arrays, not a set per equation)."""

    __slots__ = ("_ptr", "_cols")

    def __init__(self, n: int, rows: np.ndarray, cols: np.ndarray):
        order = np.lexsort((cols, rows))
        self._cols = cols[order]
        self._ptr = np.searchsorted(rows[order], np.arange(n + 1)).tolist()

    def __len__(self) -> int:
        return len(self._ptr) - 1

    def __getitem__(self, e: int) -> set[int]:
        return set(self._cols[self._ptr[e]:self._ptr[e + 1]].tolist())

    def keys(self, n_col: int) -> np.ndarray:
        """Every entry as ``e * n_col + column``, sorted."""
        rows = np.repeat(np.arange(len(self), dtype=np.int64), np.diff(self._ptr))
        return rows * n_col + self._cols


def _linear_rows(n: int, rows: np.ndarray, cols: np.ndarray, coefs: list) -> SparseRows:
    """``linear[e]``: column -> coefficient of the entries ``(rows, cols, coefs)``, each
    row's in the order given (held as arrays, a dictionary formed per row read)."""
    order = np.argsort(rows, kind="stable")
    ptr = np.searchsorted(rows[order], np.arange(n + 1))
    return SparseRows(ptr, cols[order], [coefs[k] for k in order.tolist()])


def _purely_linear(adj, eliminable, const: _Columns, n_col: int) -> list[int]:
    """The equations in which every eliminable variable of ``adj`` is in ``const``."""
    length = np.fromiter(map(len, adj), dtype=np.int64, count=len(adj))
    if not length.sum():
        return list(range(len(adj)))
    col = np.fromiter(chain.from_iterable(adj), dtype=np.int64, count=int(length.sum()))
    row = np.repeat(np.arange(len(adj), dtype=np.int64), length)
    bad = np.asarray(eliminable, dtype=bool)[col]
    bad[bad] = ~np.isin(row[bad] * n_col + col[bad], const.keys(n_col))
    return np.flatnonzero(np.bincount(row[bad], minlength=len(adj)) == 0).tolist()


def _purely_linear_entries(rows: np.ndarray, cols: np.ndarray, fixed: np.ndarray,
                           eliminable, n_rows: int) -> list[int]:
    """`_purely_linear` when the incidence is the Jacobian's entries ``(rows, cols)``:
    the equations with no entry of an eliminable variable whose coefficient is not
    ``fixed`` (one pass over the arrays, no list per equation read)."""
    bad = np.asarray(eliminable, dtype=bool)[cols] & ~fixed
    return np.flatnonzero(np.bincount(rows[bad], minlength=n_rows) == 0).tolist()


def _depending(f: ca.Function, n_in: int) -> np.ndarray:
    """The entries of the output of ``f`` (one column of ``n_in`` inputs, one output) that
    depend on its inputs at all: the pattern of the derivative of ``f(s, s, ..., s)``
    in one scalar ``s``, one sweep of dependency bits with every input marked. The
    pattern input by input (``f.sparsity_jac``) colours its columns first: 2.85 us per
    section of the RC ladder at N = 100000 (1.3 * 10^6 entries), this sweep 1.5."""
    s = ca.MX.sym("s")
    return np.asarray(ca.jacobian_sparsity(f(ca.repmat(s, n_in, 1)), s).get_triplet()[0],
                      dtype=np.int64)


def _numbers(jac: ca.SX, symbols: ca.SX | None = None) -> np.ndarray:
    """The nonzeros of `jac` that are numbers, NaN for the others (expressions of
    symbols): read in bulk, with one dependency pattern and one evaluation. With
    ``symbols`` (a column of every symbol the entries may hold), both come from one
    function of them, evaluated at zero where nothing depends on them."""
    nz = jac.nz[:]
    if symbols is not None:
        try:
            f = ca.Function("coefficients", [symbols], [nz], {"allow_free": True})
        except RuntimeError:        # not a column of distinct symbols: the other path
            f = None
        if f is not None and not f.has_free():
            depends = np.zeros(nz.numel(), dtype=bool)
            depends[_depending(f, symbols.numel())] = True
            with np.errstate(all="ignore"):
                values = np.asarray(f(np.zeros(symbols.numel())), dtype=float).ravel()
            values[depends] = np.nan
            return values
    out = np.full(nz.numel(), np.nan)
    free = ca.symvar(nz)
    depends = np.zeros(nz.numel(), dtype=bool)
    if free:
        depends[ca.jacobian_sparsity(nz, ca.vertcat(*free)).get_triplet()[0]] = True
    fixed = np.flatnonzero(~depends)
    if fixed.size:
        try:
            out[fixed] = np.asarray(ca.evalf(nz[fixed.tolist()]), dtype=float).ravel()
        except RuntimeError:     # a symbol the pattern missed: ask entry by entry
            for k in fixed.tolist():
                z = nz[k]
                out[k] = float(z) if z.is_constant() else np.nan
    return out


def _parameter_coefficients(exprs: list[ca.SX], parameters: list[ca.SX], atoms: list):
    """``(k, coefficient)`` for each of `exprs` that depends on `parameters` alone: a
    `Laurent` polynomial in atoms (appended to `atoms`, each a parameter or a
    parameter expression that is not a sum, product or quotient by a single term)."""
    stack = ca.vertcat(*exprs)
    names = {p.name() for p in parameters}
    others = [s for s in ca.symvar(stack) if s.name() not in names]
    if others:
        sp = ca.jacobian_sparsity(stack, ca.vertcat(*others))
        ptr, _ = sp.get_crs()
        keep = [k for k in range(len(exprs)) if ptr[k] == ptr[k + 1]]
    else:
        keep = list(range(len(exprs)))
    index: dict[str, int] = {}

    def leaf(z: ca.SX):
        key = str(z)
        if key not in index:
            index[key] = len(atoms)
            atoms.append(z)
        return atom(index[key])

    def convert(z: ca.SX):
        if z.is_constant():
            return exact(float(z))
        if z.is_symbolic():
            return leaf(z)
        op = z.op()
        try:
            if op == ca.OP_ADD:
                return convert(z.dep(0)) + convert(z.dep(1))
            if op == ca.OP_SUB:
                return convert(z.dep(0)) - convert(z.dep(1))
            if op == ca.OP_MUL:
                return convert(z.dep(0)) * convert(z.dep(1))
            if op == ca.OP_DIV:
                return _divide(convert(z.dep(0)), convert(z.dep(1)))
            if op == ca.OP_NEG:
                return -convert(z.dep(0))
            if op == ca.OP_SQ:
                a = convert(z.dep(0))
                return a * a
            if op == ca.OP_TWICE:
                return 2 * convert(z.dep(0))
            if op == ca.OP_INV:
                return _divide(1, convert(z.dep(0)))
        except ZeroDivisionError:
            pass
        return leaf(z)

    for k in keep:
        try:
            yield k, convert(exprs[k])
        except (ZeroDivisionError, OverflowError, ValueError):   # 1/0, inf, nan
            continue


def _divide(a, b):
    """``a / b`` exactly (`ZeroDivisionError` where not exact or `b` is 0)."""
    if isinstance(a, Laurent) or isinstance(b, Laurent):
        return a / b
    return _norm(Fraction(a) / b)


def _norm(x):
    return x.numerator if type(x) is Fraction and x.denominator == 1 else x


def _expression(a, atoms: list) -> ca.SX:
    if not isinstance(a, Laurent):
        return ca.SX(float(a))
    out = ca.SX(0)
    for mono, c in sorted(a.terms.items()):
        term = ca.SX(float(c))
        for k, e in mono:
            term = term * (atoms[k] ** e if e != 1 else atoms[k])
        out = out + term
    return out


def _hidden(n: int, elim: LinearElimination, linear, eliminable) -> list[int]:
    """The reduced equations whose dependency the incidence does not show.

    The exact rank of the purely linear equations in their unknowns is the number of
    pivots; their structural rank (a maximum matching) can be larger, and then the
    matching pairs equations with unknowns that cancel. Starting from the pivot
    equations, each other equation is added back with its unknowns: if that grows the
    matching, the incidence would count it as independent, so it is hidden and index
    reduction must see its reduced form; if not, its dependency is visible in the
    incidence already (e.g. a kinematic loop closed by a ground), and it stays as
    written, with the state selection it had."""
    if not elim.rows:      # every equation is a pivot: nothing is reduced
        return []
    rows: list[list[int]] = [[] for _ in linear]
    for e in elim.pivots:
        rows[e] = [v for v in linear[e] if eliminable[v]]
    m = maximum_matching(n, rows, allowed=eliminable)
    eq_to_var, var_to_eq = m.eq_to_var, m.var_to_eq
    mark = [0] * n
    hidden = []
    for stamp, e in enumerate(sorted(elim.rows), start=1):
        rows[e] = [v for v in linear[e] if eliminable[v]]
        if rows[e] and augment_from(e, rows, eliminable, eq_to_var, var_to_eq, mark,
                                    stamp):
            hidden.append(e)
            var_to_eq[eq_to_var[e]] = -1
            eq_to_var[e] = -1
            rows[e] = []
    return hidden


def _check_dependencies(name, res, orig, var_syms, var_names, eliminable,
                        out: Reduction, linear, roles, classes, n) -> None:
    """Raise for an equation, or a combination of equations, that holds no variable,
    and for state-only constraints (``c.v == V``) dependent among themselves."""
    empty = [e for e in range(len(res)) if not adj_or_reduced(out, e)]
    for e in empty:
        comb = out.reduced[e][1] if e in out.reduced else {e: 1}
        value = out.residual(e, res, var_syms) if e in out.reduced else res[e]
        if value.is_zero():
            # equations that add up to 0 == 0: one too few, some unknowns are free
            _raise_floating(name, orig, var_names, eliminable, out, e, comb, roles)
        _raise_dependency(name, orig, var_names, comb, linear, roles, classes)
    # constraints linear in states only, with nothing else: dependent among themselves?
    pure = [e for e, (row, _, inc) in out.reduced.items()
            if inc and len(row) == len(inc) and not any(eliminable[v] for v in inc)]
    if len(pure) < 2:
        return
    dense = [out.reduced[e][0] if e in out.reduced else {} for e in range(len(res))]
    second = exact_elimination(dense, [True] * n, rows=pure)
    for e, row in second.rows.items():
        if row:
            continue
        total: dict = {}
        for g, m in second.combination(e).items():
            for k, b in out.reduced[g][1].items():
                total[k] = total.get(k, 0) + m * b
        total = {k: a for k, a in total.items() if a}
        _raise_dependency(name, orig, var_names, total, linear, roles, classes)


def adj_or_reduced(out: Reduction, e: int) -> list[int]:
    """Variables of equation `e`, reduced if the elimination reduced it."""
    return out.reduced[e][2] if e in out.reduced else out.adj[e]


def _raise_floating(name, orig, var_names, eliminable, out: Reduction, dependent: int,
                    comb, roles) -> None:
    """Equations that add up to ``0 == 0`` leave unknowns free: name the nodes whose
    across variables are among them (a part of a network with no path to a
    reference), or the free unknowns."""
    rows = [adj_or_reduced(out, e) if e != dependent else [] for e in range(len(out.adj))]
    m = maximum_matching(len(var_names), rows, allowed=eliminable)
    cols: dict[int, list[int]] = {}
    for e, r in enumerate(rows):
        for v in r:
            cols.setdefault(v, []).append(e)
    free = [v for v in range(len(var_names)) if eliminable[v] and m.var_to_eq[v] == -1]
    seen = dict.fromkeys(free)
    queue = list(free)
    for v in queue:                      # alternating paths from the free unknowns
        for e in cols.get(v, ()):
            u = m.eq_to_var[e]
            if u != -1 and u not in seen:
                seen[u] = None
                queue.append(u)
    names = [var_names[v] for v in seen]
    across = [x for x in names if roles.get(x, ("",))[0] == "across" and roles[x][3]]
    eqs = [str(orig[e]) for e in sorted(comb)]
    involved: set[str] = set()
    for e in comb:
        w = owner_of(orig[e])
        if w.startswith("connect("):
            for port in w[len("connect("):-1].split(","):
                involved.update((port.strip(), port.strip().rpartition(".")[0]))
        else:
            involved.add(w)
    inside = [x for x in across if x.rpartition(".")[0] in involved
              or x.rpartition(".")[0].rpartition(".")[0] in involved]
    across = inside or across
    if across:
        _, one, many, _ = roles[across[0]]
        nodes = sorted({x.rpartition(".")[0] or x for x in across})
        raise StructuralError(
            f"model '{name}': the {many} at {', '.join(nodes[:8])}"
            f"{' ...' if len(nodes) > 8 else ''} are not determined: this part of the "
            "network has no path to a reference (a floating node). Connect a reference "
            f"to it, or a resistance from it to one (e.g. at {nodes[0]}).",
            equations=eqs, variables=across, path=name)
    through = [x for x in names if roles.get(x, ("",))[0] == "through" and roles[x][3]]
    if through:
        _, one, many, _ = roles[through[0]]
        ports = sorted({x.rpartition(".")[0] or x for x in through})
        owners = sorted({owner_of(orig[e]) for e in comb})
        raise StructuralError(
            f"model '{name}': the {many} at {', '.join(ports[:8])}"
            f"{' ...' if len(ports) > 8 else ''} are not determined: the equations of "
            f"{_enumerate(owners)} fix a quantity that is fixed already (two references "
            "on one node, or ideal sources in a loop). Keep one reference per node, or "
            "put a resistance between them.",
            equations=eqs, variables=through, path=name)
    raise StructuralError(
        f"model '{name}': {len(eqs)} equations add up to 0 == 0, so one equation is "
        f"missing for the unknowns {', '.join(names[:8])}"
        f"{' ...' if len(names) > 8 else ''}. Redundant equations: "
        f"{'; '.join(eqs[:6])}{' ...' if len(eqs) > 6 else ''}. Remove one, or add the "
        "equation that determines these unknowns.",
        equations=eqs, variables=names, path=name)


def _raise_dependency(name, orig, var_names, comb, linear, roles, classes) -> None:
    eqs = sorted(comb)
    owners: list[str] = []
    for e in eqs:
        w = owner_of(orig[e])
        if not w.startswith("connect(") and w not in owners:
            owners.append(w)
    unknowns = sorted({v for e in eqs for v in linear[e]})
    names = [var_names[v] for v in unknowns]
    kinds = {roles[x][0] for x in names if x in roles}
    what = {"through": "cut set", "across": "loop"}.get(kinds.pop()) if len(kinds) == 1 \
        else None
    if what is not None:
        _, one, many, _ = next(roles[x] for x in names if x in roles)
    parts = [classes.get(w, "") for w in owners]
    noun = "sources" if parts and all("Source" in c or c.startswith("Constant")
                                      for c in parts) else "components"
    who = _enumerate(owners) if owners else "equations"
    if what is not None and len(owners) > 1:
        head = f"{noun} {who} form a {what}: their {many} are not independent"
    elif what is not None:
        short = "a short circuit" if what == "loop" else "an open circuit"
        head = (f"{noun[:-1]} {who} forms a {what} by itself ({short}?): its {one} is "
                "not free")
    else:
        head = f"the equations of {who} are not independent"
    single = len(owners) == 1
    if what == "cut set":
        advice = (("Connect it" if single else "Remove one source, or") +
                  f" give the {one} another path (a resistance, or a damper or spring in "
                  "mechanics, in parallel with " + ("it)." if single else "a source)."))
    elif what == "loop":
        advice = (("Remove the connection that shorts it, or" if single else
                   "Remove one source, or") + " put a resistance (a damper or spring in "
                  "mechanics) in series in the loop.")
    else:
        advice = "Remove a redundant equation or component."
    texts = [str(orig[e]) for e in eqs]
    raise StructuralError(
        f"model '{name}': {head}. {len(eqs)} equations for {len(unknowns)} unknowns "
        f"({', '.join(names[:8])}{' ...' if len(names) > 8 else ''}). Potential extra "
        f"equation(s): {'; '.join(texts[:6])}{' ...' if len(texts) > 6 else ''}. "
        f"{advice}",
        equations=texts, variables=owners or names, path=name)


def _enumerate(items: list[str]) -> str:
    if len(items) == 1:
        return items[0]
    return ", ".join(items[:-1]) + " and " + items[-1]
