"""Pass 3: alias elimination.

Equations of the form ``a = b``, ``a = -b`` and ``a = c`` (a numeric constant) are removed
and their variables replaced by one representative (or the constant) in every remaining
equation: a class template's instances take their variable arguments from one column of
the replaced variables (`Replacements`), the other equations one bulk substitution.
Connections produce most aliases; component equations such as ``i == p.i`` produce the
rest. The eliminated variables stay in the simulation log, computed from their
representative.

Speed: the variables are numbered in declaration order; the union-find runs on integer
lists, and the classes, their representatives and the factors of their members are
read off NumPy arrays for all classes at once (the representative is the first member
of highest rank in one sorted order of keys). The remaining residuals are stacked once,
substituted in one CasADi call and kept stacked for the passes after this one.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from itertools import repeat
from operator import attrgetter

import casadi as ca
import numpy as np

from mechatron.compiler.flatten import (ColumnRows, EquationRows, FlatEquation,
                                       FlatEquations, FlatModel, Origins,
                                       _TemplateEquation, _gather, _residual_of, _row_of,
                                       column_of, stack_columns)
from mechatron.errors import InitializationError

__all__ = ["AliasResult", "eliminate_aliases"]

_PRIORITY_RANK = {"high": 3, "low": 2, "none": 1}
_KIND_RANK = {"variable": 3, "output": 2, "across": 1, "through": 1, "input": 0}


@dataclass
class AliasResult:
    """What alias elimination leaves: the remaining equations (as parallel lists and
    stacked in one column), the remaining variables, and how to recover the others."""

    residuals: Sequence[ca.SX]      # remaining residuals, in order (a ColumnRows)
    origins: Sequence                                 # origin of each (Origins)
    owners: list[str]                                 # owner of each
    unknowns: list[str]                               # remaining variable names
    eliminated: Mapping[str, tuple[str | None, float]] = field(default_factory=dict)
    # name -> (representative or None for a constant, factor or constant value)
    starts: dict[str, tuple[float, str, str]] = field(default_factory=dict)
    # representative -> (start, priority, the variable the target was given on)
    n_before: int = 0
    #: ``vertcat(*residuals)``, or None without residuals
    stacked: ca.SX | None = None
    #: for each model variable (in declaration order) the number of the variable it is
    #: read from (itself if kept, its representative if eliminated, -1 for a constant)
    representative: np.ndarray | None = None
    #: and the factor: ``x = scale * x[representative]``, or the constant ``x = scale``
    scale: np.ndarray | None = None
    #: the number of each of ``unknowns`` among the model's variables
    unknown_index: np.ndarray | None = None

    @property
    def equations(self) -> list[FlatEquation]:
        """The remaining equations as :class:`FlatEquation` (formed on request)."""
        return [FlatEquation(r, o, w)
                for r, o, w in zip(self.residuals, self.origins, self.owners)]


@dataclass
class Replacements:
    """What takes the place of the eliminated variables: ``old`` -> ``new`` as two
    columns for one substitution (the eliminated variables, then the derivatives of
    those that are differentiated); the model's variables in declaration order with
    each eliminated one replaced (``variables``), from which arguments known by their
    rows are gathered, not substituted (a substitution walks every symbol of ``old``
    once per call); and the derivatives' pairs alone (``der_old`` -> ``der_new``, None
    if none), for arguments that are derivatives."""

    old: ca.SX
    new: ca.SX
    variables: ca.SX
    der_old: ca.SX | None = None
    der_new: ca.SX | None = None


def _signed_symbol(expr: ca.SX, unknowns) -> tuple[str, float] | None:
    sign = 1.0
    while expr.is_op(ca.OP_NEG):
        expr, sign = expr.dep(0), -sign
    if expr.is_symbolic() and expr.name() in unknowns:
        return expr.name(), sign
    return None


def _read_alias(r: ca.SX, unknowns) -> tuple | None:
    """What a residual without a template hint says: ("pair", a, b, s) for a = s*b,
    ("const", a, value) for a = value, or None."""
    if r.is_op(ca.OP_SUB) or r.is_op(ca.OP_ADD):
        lhs = r.dep(0)
        la = _signed_symbol(lhs, unknowns)
        if la is None and not lhs.is_constant():
            return None             # a sum of more terms, a product, ...: not an alias
        rhs = r.dep(1)
        sign = -1.0 if r.is_op(ca.OP_SUB) else 1.0
        ra = _signed_symbol(rhs, unknowns)
        if la and ra:
            # la_s*a + sign*ra_s*b = 0 -> a = -(sign*rs/ls) b
            return "pair", la[0], ra[0], -sign * ra[1] / la[1]
        if la and rhs.is_constant():
            return "const", la[0], -sign * float(rhs) / la[1]
        if ra and lhs.is_constant():
            return "const", ra[0], -float(lhs) / (sign * ra[1])
        return None
    one = _signed_symbol(r, unknowns)
    return ("const", one[0], 0.0) if one else None


def eliminate_aliases(flat: FlatModel) -> AliasResult:
    """Find alias classes, pick representatives, substitute in bulk."""
    unknowns = flat.variables      # read only
    names = list(unknowns)
    n = len(names)
    parent = list(range(n))        # a root is its own parent
    factor = [1.0] * n             # x[k] = factor[k] * x[parent[k]]
    const: dict[int, float] = {}   # root -> constant value (root = const)
    # the number of each variable: its row in the model's stacked variables (the
    # mapping flattening keeps, not a copy); a name that is not a variable is numbered
    # on first use
    index = _Numbers(flat.variable_rows(), parent, factor)

    def find(a: int) -> tuple[int, float]:
        """Root of ``a`` and the factor with a = factor * root (path compressed)."""
        up = parent[a]
        if up == a:
            return a, 1.0
        if parent[up] == up:           # a child of its root: nothing to compress
            return up, factor[a]
        path = []
        while parent[a] != a:
            path.append(a)
            a = parent[a]
        acc = 1.0
        for node in reversed(path):
            acc = factor[node] * acc
            parent[node], factor[node] = a, acc
        return a, factor[path[0]]

    def union(a: int, b: int, s: float) -> bool:
        """Record a = s*b (variable numbers); return False if that adds nothing new (a
        redundant equation)."""
        ra, fa = find(a)
        rb, fb = find(b)
        if ra == rb:
            return False
        k = s * fb / fa  # ra = k * rb
        if const and ra in const and rb in const and abs(const[ra] - k * const[rb]) > 0:
            return False
        parent[ra], factor[ra] = rb, k
        if ra in const:
            const[rb] = const.pop(ra) / k
        return True

    def fix(a: int, value: float) -> bool:
        """Record a = value; False if the class of ``a`` has a value already."""
        root, f = find(a)
        if root in const:
            return False
        const[root] = value / f
        return True

    redundant: list[FlatEquation] = []
    for a, b, s, origin in flat.aliases:     # by number, or by name
        ia = a if type(a) is int else index[a]
        ib = b if type(b) is int else index[b]
        if not union(ia, ib, s):
            redundant.append(FlatEquation(unknowns[names[ia]].sym -
                                          s * unknowns[names[ib]].sym, origin))

    def absorbed(eq) -> bool:
        """Whether ``eq`` is an alias (or a constant) recorded now: not kept."""
        hint = eq.alias              # read off the class's template once (flatten)
        if hint is None:
            hint = _read_alias(eq.residual, unknowns)
            if hint is None:
                return False
        return recorded(hint)

    def recorded(hint) -> bool:
        """Whether the alias ``hint`` is recorded now (see `absorbed`)."""
        tag = hint[0]
        if tag == "pair":
            a, b = hint[1], hint[2]
            if type(a) is not int:          # by name; a template's by number
                a, b = index[a], index[b]
            return union(a, b, hint[3])
        if tag == "const":
            a = hint[1]
            return fix(a if type(a) is int else index[a], hint[2])
        return False

    equations = flat.equations
    numbered = equations.numbered() if type(equations) is FlatEquations else None
    if numbered is None:
        kept = EquationRows.of(redundant + [eq for eq in equations if not absorbed(eq)])
    else:
        kept = _scan(equations, numbered, redundant, union, fix, absorbed, recorded)
    origins = Origins(kept)                 # each formed when read (messages)
    owners = _owners(kept)
    n_before = len(flat.equations) + len(flat.aliases)
    # class templates whose residuals are not formed yet: formed below on the
    # replacements, only the rows kept (see `flatten._Template.defer`)
    pending = [t for t in flat.__dict__.pop("_pending_templates", ())
               if t.pending is not None]
    result = AliasResult([], origins, owners, [], n_before=n_before)
    replaced = None
    if n:
        # the numbers of the differentiated variables, read by both steps below
        derived = _differentiated(flat, index, n)
        gone = _classes(flat, names, index, parent, factor, const, result, derived)
        replaced = _replacements(flat, names, index, gone, result, derived) \
            if len(kept) else None
    stacked = _kept_residuals(kept, pending, flat, replaced) if len(kept) else None
    for tpl in pending:     # a residual read now is formed as written, alone
        tpl.pending, tpl.replaced = None, True
    # the union-find is done: the numbering lives on in `result.eliminated` (read with
    # `get` alone), its forest and factors (a number and a float per variable) do not
    index.parent = index.factor = None
    if len(kept):
        result.residuals = ColumnRows(stacked)     # each formed when read
        result.stacked = stacked
    return result


def _scan(equations: FlatEquations, numbered: tuple, redundant: list, union, fix,
          absorbed, recorded) -> EquationRows:
    """Alias elimination over the equations as `FlatEquations` holds them: the alias
    hints of the class templates' rows read as arrays (`flatten._Template.hint_arrays`),
    each pair and constant recorded in the equations' order (``union``, ``fix``), a
    template's row whose hint names its variables by path read alone (``recorded``,
    no equation formed), any other equation read one by one (``absorbed``). The
    equations kept, after ``redundant``."""
    which, rows = numbered
    n = len(which)
    tag = np.full(n, 3, dtype=np.int8)       # 3: read one by one
    a = np.zeros(n, dtype=np.int64)
    b = np.zeros(n, dtype=np.int64)
    s = np.zeros(n)
    for tpl, places in EquationRows(equations.templates, which, rows, []).by_template():
        t_tag, t_a, t_b, t_s = tpl.hint_arrays()
        r = rows[places]
        tag[places], a[places], b[places], s[places] = t_tag[r], t_a[r], t_b[r], t_s[r]
    keep = tag == 0
    look = np.flatnonzero(~keep)
    templates, given = equations.templates, equations.given
    for k, g, x, y, f, t, r in zip(look.tolist(), tag[look].tolist(), a[look].tolist(),
                                   b[look].tolist(), s[look].tolist(),
                                   which[look].tolist(), rows[look].tolist()):
        if g == 1:
            if not union(x, y, f):
                keep[k] = True
        elif g == 2:
            if not fix(x, f):
                keep[k] = True
        elif t >= 0:                # a template's row whose hint names paths
            if not recorded(templates[t].hint(r)):
                keep[k] = True
        elif not absorbed(given[r]):   # an equation held as an object
            keep[k] = True
    places = np.flatnonzero(keep)
    which, rows = which[places], rows[places]
    held = which < 0
    objects = redundant + [given[r] for r in rows[held].tolist()]
    m = len(redundant)
    rows[held] = np.arange(m, m + int(held.sum()))
    return EquationRows(equations.templates,
                        np.concatenate([np.full(m, -1, dtype=np.int32), which]),
                        np.concatenate([np.arange(m, dtype=np.int64), rows]), objects)


def _owners(kept: EquationRows) -> list[str]:
    """The owner of each of ``kept``: a template's row read off its instance's path."""
    out = np.empty(len(kept), dtype=object)
    held = kept.which < 0
    if held.any():
        out[held] = np.fromiter(map(_OWNER, kept.objects), dtype=object,
                                count=len(kept.objects))
    for tpl, places in kept.by_template():
        out[places] = np.array(tpl.paths, dtype=object)[kept.rows[places] // tpl.n_eq]
    return out.tolist()


class _Eliminated(Mapping):
    """The eliminated variables, name -> (representative, or None for a constant; the
    factor, or the constant), read off alias elimination's arrays on request: a
    dictionary of every one is formed only if they are all read. In the order of the
    classes, members in declaration order."""

    def __init__(self, names: list[str], index: dict, gone: np.ndarray,
                 is_gone: np.ndarray, rep: np.ndarray, scale: np.ndarray):
        self._names, self._index, self._gone = names, index, gone
        self._is_gone, self._rep, self._scale = is_gone, rep, scale
        self._all: dict | None = None

    def _number(self, name) -> int | None:
        j = self._index.get(name)   # a plain lookup: no number for a new name
        if j is None or j >= len(self._names) or not self._is_gone[j]:
            return None
        return j

    def __getitem__(self, name):
        j = self._number(name)
        if j is None:
            raise KeyError(name)
        r = int(self._rep[j])
        return (None if r < 0 else self._names[r], float(self._scale[j]))

    def __contains__(self, name) -> bool:
        return self._number(name) is not None

    def __len__(self) -> int:
        return len(self._gone)

    def _dict(self) -> dict:
        if self._all is None:
            names, gone = self._names, self._gone
            reps = [names[r] if r >= 0 else None for r in self._rep[gone].tolist()]
            self._all = dict(zip([names[j] for j in gone.tolist()],
                                 zip(reps, self._scale[gone].tolist())))
        return self._all

    def __iter__(self):
        return iter(self._dict())

    def items(self):
        return self._dict().items()

    def __repr__(self) -> str:
        return repr(self._dict())


_OWNER = attrgetter("owner")


class _Numbers:
    """Variable name -> number for the union-find: a model variable's row ``rows[name]``;
    a name that is not a model variable gets a number past theirs on first use (it
    joins classes, but is neither kept nor eliminated)."""

    __slots__ = ("rows", "extra", "parent", "factor")

    def __init__(self, rows: Mapping, parent: list, factor: list):
        self.rows, self.extra = rows, {}
        self.parent, self.factor = parent, factor

    def get(self, name, default=None):
        j = self.rows.get(name)
        return self.extra.get(name, default) if j is None else j

    def __contains__(self, name) -> bool:
        return name in self.rows or name in self.extra

    def __getitem__(self, name: str) -> int:
        j = self.get(name)
        if j is None:
            j = self.extra[name] = len(self.parent)
            self.parent.append(j)
            self.factor.append(1.0)
        return j


def _classes(flat, names, index, parent, factor, const, result, derived) -> np.ndarray:
    """Every alias class with its representative: the unknowns, the eliminated
    variables (returned, by number, in order) and the start values of ``result``, class
    by class in the order of each class's first member, members in declaration order.
    ``derived``: the numbers of the differentiated variables (`_differentiated`)."""
    n = len(names)
    up = np.array(parent, dtype=np.intp)
    f = np.array(factor)
    while True:                       # pointer jumping: every node onto its root
        nxt = up[up]
        if np.array_equal(nxt, up):
            break
        # the factors are signs (a == b, a == -b): products exact in any order
        f = f * f[up]
        up = nxt
    up, f = up[:n], f[:n]             # the model's variables (see node())
    # a class's place: its first member (the least number that has the root; one pass,
    # where a sort to find the first of each costs n log n)
    k = np.arange(n)
    position = np.full(len(parent), n, dtype=np.intp)
    np.minimum.at(position, up, k)
    cls = position[up]
    is_const = np.zeros(len(parent), dtype=bool)
    value = np.zeros(len(parent))     # the constant of a class, at its root
    if const:
        is_const[list(const)] = True
        value[list(const)] = list(const.values())
    is_const = is_const[up]

    # _rank of every variable as sortable integers: its first three entries (priority
    # of a start value, differentiated, kind) packed in one; the declared attributes
    # take few distinct values, one code per combination
    table: dict = {}

    def code(start, priority, kind) -> int:
        key = (start is not None, priority, kind)
        c = table.get(key)
        if c is None:
            c = table[key] = len(table)
        return c

    # (one key at a time, not a list of a tuple per variable: the tuples are freed as
    # they are read; each attribute read off the class plans, no record formed)
    variables = flat.variables
    codes = np.fromiter(map(code, column_of(variables, "start"),
                            column_of(variables, "priority"),
                            column_of(variables, "kind")), dtype=np.intp, count=n)
    has_start = np.array([key[0] for key in table], dtype=bool)[codes]
    rank = np.array([8 * (_PRIORITY_RANK.get(key[1], 0) if key[0] else 0) +
                     _KIND_RANK.get(key[2], 0) for key in table], dtype=np.int64)[codes]
    rank[derived] += 4
    # each class together, in class order; in a class the best member first (highest
    # rank, the first declared among equals): one stable sort of class and rank packed
    # in one integer (a lexsort sorts once per key)
    span = int(rank.max()) + 1 if n else 1
    ranked = np.argsort(cls * span + (span - 1 - rank), kind="stable")
    head = np.r_[True, cls[ranked][1:] != cls[ranked][:-1]]
    is_best = np.zeros(n, dtype=bool)
    is_best[ranked[head]] = True
    is_best &= ~is_const
    # classes whose best members tie on those: the fewest dots in the path, then the
    # shortest (_rank's last entries), read off the names of the tied members only
    top = np.zeros(n, dtype=np.int64)
    top[cls[ranked[head]]] = rank[ranked[head]]
    tied = (rank == top[cls]) & ~is_const
    count = np.bincount(cls[tied], minlength=n)
    tied &= count[cls] > 1
    if tied.any():
        members = np.flatnonzero(tied)
        member_names = [names[j] for j in members.tolist()]
        dots = np.array(list(map(str.count, member_names, repeat("."))), dtype=np.int64)
        length = np.array(list(map(len, member_names)), dtype=np.int64)
        c = cls[members]
        again = np.lexsort((members, length, dots, c))
        first = np.r_[True, c[again][1:] != c[again][:-1]]
        is_best[members] = False
        is_best[members[again[first]]] = True
    best_of = np.zeros(n, dtype=np.intp)       # the representative of each class
    best_of[cls[is_best]] = np.flatnonzero(is_best)
    order = np.argsort(cls, kind="stable")     # classes in order, members in order

    result.unknown_index = order[is_best[order]]
    result.unknowns = [names[j] for j in result.unknown_index.tolist()]
    # each variable read from its representative (itself if kept), -1 for a constant,
    # times scale: x = scale * x[rep], or x = scale
    rep = np.where(is_const, -1, best_of[cls])
    scale = np.where(is_const, f * value[up], f / f[np.where(is_const, k, rep)])
    result.representative, result.scale = rep, scale
    gone = order[~is_best[order]]
    result.eliminated = _Eliminated(names, index, gone, ~is_best, rep, scale)

    # start values, class by class (the members that have one, in order)
    with_start = order[has_start[order] & ~is_const[order]]
    if len(with_start):
        groups: dict[int, list] = {}
        for j, c in zip(with_start.tolist(), cls[with_start].tolist()):
            groups.setdefault(c, []).append(j)
        record = _record_at(flat)
        for c, members in groups.items():
            b = int(best_of[c])
            _merge_starts(result, flat, names[b],
                          [(names[j], float(f[j] / f[b]), record(j)) for j in members])
    return gone


def _kept_residuals(kept: EquationRows, pending: list, flat,
                    replaced: Replacements | None) -> ca.SX:
    """The residuals of ``kept`` stacked (a class template's rows gathered from its
    column), with the eliminated variables replaced (`Replacements`, if any): the
    templates of ``pending`` formed on their instances' replaced arguments, each with
    only the rows some instance keeps, and the other residuals substituted at once."""
    waiting = {id(t): t for t in pending}
    rows: dict = {}                  # id(template) -> its rows that are kept
    # a kept equation object that is a row of a template formed here: (its place, it)
    from_template = [(k, eq) for k, eq in
                     zip(np.flatnonzero(kept.which < 0).tolist(), kept.objects)
                     if type(eq) is _TemplateEquation and id(eq.template) in waiting]
    for _, eq in from_template:
        rows.setdefault(id(eq.template), set()).add(eq.row % eq.template.n_eq)
    groups = list(kept.by_template())
    for tpl, places in groups:
        if id(tpl) in waiting:
            rows.setdefault(id(tpl), set()).update(
                np.unique(kept.rows[places] % tpl.n_eq).tolist())
    place = {}     # id(template) -> (its column, n_eq, rows kept, each row's place)
    for key, tpl in waiting.items():
        if key in rows:
            keep = sorted(rows[key])
            tpl.instantiate(flat, replaced, keep)
            at = np.full(tpl.n_eq, -1, dtype=np.int64)
            at[keep] = np.arange(len(keep))
            place[key] = (tpl.column, tpl.n_eq, len(keep), at)
    # the rest, in order: the objects and the rows of templates not formed here
    n = len(kept)
    index = np.full(n, -1, dtype=np.int64)
    columns, offset, start = [], {}, 0
    for key, (column, _, _, _) in place.items():
        offset[key] = start
        columns.append(column)
        start += column.numel()
    for tpl, places in groups:
        got = place.get(id(tpl))
        if got is not None:
            instance, k = np.divmod(kept.rows[places], got[1])
            index[places] = offset[id(tpl)] + instance * got[2] + got[3][k]
    for k, eq in from_template:
        key = id(eq.template)
        _, n_eq, m, at = place[key]
        instance, j = divmod(eq.row, n_eq)
        index[k] = offset[key] + instance * m + at[j]
    rest_at = np.flatnonzero(index < 0)
    if not len(rest_at):
        rest = None
    else:
        templates, objects = kept.templates, kept.objects
        rest = _gather([_row_of(templates[t], r) if t >= 0 else _residual_of(objects[r])
                        for t, r in zip(kept.which[rest_at].tolist(),
                                        kept.rows[rest_at].tolist())])
        if replaced is not None:
            rest = ca.substitute(rest, replaced.old, replaced.new)
    if not place:                   # no template formed here: every residual is rest
        return rest
    index[rest_at] = start + np.arange(len(rest_at))
    parts = columns + ([rest] if rest is not None else [])
    return stack_columns(*parts)[index.tolist()]


def _differentiated(flat, index, n: int) -> list[int]:
    """The numbers of the model's variables (below ``n``) whose derivative appears, in
    the order of the derivatives: the rows class templates noted as they bound them
    (`flatten._Template.add`), else by name."""
    rows = flat.__dict__.get("_derivative_rows") or {}
    out = []
    for d in flat.context.derivative:
        j = rows.get(d)
        if j is None:
            j = index.get(d, n)
        if j < n:
            out.append(j)
    return out


def _replacements(flat, names, index, gone, result, derived) -> Replacements | None:
    """What replaces the eliminated variables and their derivatives (see
    `Replacements`); None if nothing is replaced."""
    if not len(gone):
        return None
    derivative = flat.context.derivative
    rep, scale = result.representative, result.scale
    column = flat.stack_variables()          # every variable, in declaration order
    variables = ca.SX(column)
    old, new = [], []
    fixed = rep[gone] < 0
    scaled = gone[~fixed]
    if len(scaled):
        rows = scaled.tolist()
        old.append(column[rows])
        new.append(column[rep[scaled].tolist()] * ca.DM(scale[scaled].tolist()))
        variables[rows] = new[-1]
    if fixed.any():
        constants = gone[fixed]
        rows = constants.tolist()
        old.append(column[rows])
        new.append(ca.SX(ca.DM(scale[constants].tolist())))
        variables[rows] = new[-1]
    # derivatives of eliminated variables, in the order of the eliminated
    der_old, der_new = [], []
    if derivative:
        differentiated = np.zeros(len(names), dtype=bool)
        differentiated[derived] = True
        for j in gone[differentiated[gone]].tolist():
            der_old.append(derivative[names[j]])
            r = rep[j]
            der_new.append(ca.SX(0.0) if r < 0 else
                           float(scale[j]) * flat.context.der_symbol(names[r]))
    ders = (ca.vertcat(*der_old), ca.vertcat(*der_new)) if der_old else (None, None)
    if der_old:
        old.append(ders[0])
        new.append(ders[1])
    return Replacements(stack_columns(*old), stack_columns(*new), variables, *ders)


def _rank(var, differentiated: bool):
    """How well a variable represents its class (the highest wins): a start value by its
    priority, differentiated, its kind, then the shortest path."""
    return (_PRIORITY_RANK.get(var.priority, 0) if var.start is not None else 0,
            differentiated, _KIND_RANK.get(var.kind, 0), -var.name.count("."),
            -len(var.name))


def _record_at(flat: FlatModel):
    """A function of a row that gives the record of the variable there (in declaration
    order), without reading a name or forming the others (`_Variables.at`)."""
    variables = flat.variables
    if hasattr(variables, "at"):
        return variables.at
    return list(variables.values()).__getitem__


def _merge_starts(result: AliasResult, flat: FlatModel, rep: str, members) -> None:
    """The start value of the class of ``rep`` from its ``members`` (name, factor,
    record) that have one: the highest priority; two high ones must agree."""
    best = None
    for name, k, var in members:
        if var.start is None:
            continue
        value = var.start / k
        cand = (_PRIORITY_RANK[var.priority], value, var.priority, name)
        if best is not None and var.priority == "high" and best[2] == "high" and \
                abs(best[1] - value) > 1e-12 * max(1.0, abs(value)):
            raise InitializationError(
                f"model '{flat.name}': conflicting high-priority start values on "
                f"'{best[3]}' and '{name}', which are the same quantity "
                f"(alias). Keep one target, or lower the priority of the other.",
                variables=[best[3], name])
        if best is None or cand[0] > best[0]:
            best = cand
    if best is not None:
        result.starts[rep] = (best[1], best[2], best[3])
