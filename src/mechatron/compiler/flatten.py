"""Passes 1 and 2: flatten the instance tree, bind symbols, collect equations, turn
connections into equations, and check the model's topology.

The result is a :class:`FlatModel`: every parameter and variable by instance path with its
CasADi symbol, every equation as a residual with its origin, and the alias pairs that
connections imply (handed to alias elimination rather than written as equations).
"""

from __future__ import annotations

import functools
from collections.abc import (ItemsView, Mapping, MutableMapping, MutableSequence,
                             ValuesView)
from dataclasses import dataclass, field
from itertools import chain, repeat
from operator import attrgetter, itemgetter

import casadi as ca
import numpy as np
from scipy import sparse
from scipy.sparse import csgraph

from mechatron.compiler.folding import join_planned, plan_subsystems
from mechatron.compiler.graph.arrays import segments as _segments
from mechatron.compiler.nodes import _PARENT, joined_nodes, physical_nodes, planned_nodes
from mechatron.core.component import Component, Connect, Connector, Element, SignalRef
from mechatron.core.connections import connection_sets, is_driver, port_key
from mechatron.core.context import BuildContext
from mechatron.core.declarations import (Across, Discrete, Input, Output, Parameter,
                                         ParameterExpression, Start, Through, Variable)
from mechatron.core.domains import SIGNAL
from mechatron.core.events import EventAction
from mechatron.errors import ConnectError, ModelError, ParameterError, UnitError
from mechatron.units import dimensionality, to_si, ureg

__all__ = ["FlatModel", "FlatVariable", "FlatParameter", "FlatEquation", "Origins", "flatten"]


@dataclass(slots=True)
class FlatParameter:
    name: str
    sym: ca.SX
    value: float
    unit: str
    doc: str
    owner: str
    bounds: tuple = (None, None)
    #: an external input of the model (a signal Input of the root component): a slot of
    #: ``p`` that ``simulate(inputs=...)`` fills with a signal of time
    is_input: bool = False


@dataclass(slots=True)
class BoundParameter:
    """A part's parameter given as an expression of its parent's parameters
    (``r = Resistor(R=R / 2)`` in the parent's class): not a slot of ``p`` of its own."""

    name: str
    expr: ca.SX        # of the parent's parameter symbols
    value: float
    unit: str
    doc: str
    owner: str
    binding: str       # as written, e.g. "(R / 2) of 'motor'"


@dataclass(slots=True)
class FlatVariable:
    name: str
    sym: ca.SX
    unit: str
    doc: str
    kind: str          # "variable", "across", "through", "input", "output"
    owner: str         # path of the owning component (for ports: the component)
    start: float | None = None
    priority: str = "none"
    hint: str = ""     # what to try when this variable is left unmatched
    state_select: str = "default"   # "avoid" / "default" / "prefer" (state selection hint)


class _ColumnVariable:
    """A variable bound in bulk (`_bind_symbols`), read as a `FlatVariable`: its symbol
    is the row ``row`` of the column of all variables' symbols, formed as a Python
    object only when read (most are never read one by one: the passes take the column,
    `FlatModel.stack_variables`); what its class declares (kind, unit, doc, hint, state
    selection) is read off the class's entry ``plan`` (`_declaration_plan`), shared by
    every instance. 8 slots, not 12: a million variables are 32 MB less."""

    __slots__ = ("name", "_sym", "column", "row", "plan", "owner", "start", "priority")

    def __init__(self, name, column, row, plan, owner):
        self.name, self.column, self.row, self.plan, self.owner = (name, column, row,
                                                                   plan, owner)
        self._sym = None
        self.start, self.priority = plan[4], plan[5]

    @property
    def sym(self):
        s = self._sym
        if s is None:
            s = self._sym = self.column[self.row]
        return s

    @sym.setter
    def sym(self, value):
        self._sym = value

    # what the class declares, by its place in the plan entry (`_declaration_plan`)
    kind = property(lambda self: self.plan[1], doc="variable, across, through, ...")
    unit = property(lambda self: self.plan[2])
    doc = property(lambda self: self.plan[3])
    hint = property(lambda self: self.plan[6], doc="what to try when left unmatched")
    state_select = property(lambda self: self.plan[7], doc="avoid, default or prefer")

    def __repr__(self) -> str:
        return (f"_ColumnVariable({self.name!r}, row={self.row}, unit={self.unit!r}, "
                f"kind={self.kind!r}, start={self.start!r})")


_PAR_SYM_SLOT = FlatParameter.__dict__["sym"]


def _formed_on_read(slot, form) -> property:
    """A property over the slot ``slot`` (its descriptor) that, while the slot holds None,
    forms the value by ``form(self)`` on the first read and keeps it; set, it holds what
    it is given."""
    def get(self):
        value = slot.__get__(self)
        if value is None:
            value = form(self)
            slot.__set__(self, value)
        return value

    return property(get, slot.__set__)


class _ColumnParameter(FlatParameter):
    """A parameter bound in bulk (`_bind_symbols`): its symbol is the row ``row`` of the
    column of all parameters' symbols, formed as a Python object only when read (from
    ``store``, a `ColumnRows` of that column shared with the elements' symbols); the
    compiler takes the column (`FlatModel.parameter_column`)."""

    __slots__ = ("store", "row")

    def __init__(self, name, store, row, value, unit, doc, owner, bounds=(None, None)):
        _PAR_SYM_SLOT.__set__(self, None)
        self.name, self.store, self.row, self.value = name, store, row, value
        self.unit, self.doc, self.owner, self.bounds = unit, doc, owner, bounds
        self.is_input = False

    sym = _formed_on_read(_PAR_SYM_SLOT, lambda q: q.store[q.row])


_BOUND_EXPR_SLOT = BoundParameter.__dict__["expr"]


class _RowBoundParameter(BoundParameter):
    """A part's parameter passed on unchanged (``R=R``) by an element bound in bulk: its
    expression is its parent's symbol, the row ``row`` of the parameter column (``store``,
    a `ColumnRows`), formed as a Python object only when read."""

    __slots__ = ("store", "row")

    def __init__(self, name, store, row, value, unit, doc, owner, binding):
        _BOUND_EXPR_SLOT.__set__(self, None)
        self.name, self.store, self.row, self.value = name, store, row, value
        self.unit, self.doc, self.owner, self.binding = unit, doc, owner, binding

    expr = _formed_on_read(_BOUND_EXPR_SLOT, lambda q: q.store[q.row])


class ColumnRows(MutableSequence):
    """The scalars of an SX column as a list whose items become Python objects when
    read, not all at once. A model of 10^5 components has a million residuals and
    unknowns; the structural analysis works on their columns and reads few of them one
    by one, and each scalar formed from Python costs about 260 bytes. Once more than one
    row in `BULK` has been read alone, the rest are formed together (one ``vertsplit``),
    so a pass that reads them all costs what a list would have. Items may be replaced
    and appended as in a list; `copy` shares the column."""

    __slots__ = ("column", "_items", "_reads", "_formed")

    BULK = 16

    def __init__(self, column: ca.SX, items: list | None = None):
        self.column = column
        self._items = [None] * column.numel() if items is None else items
        self._reads = 0
        self._formed = False

    def __len__(self) -> int:
        return len(self._items)

    def __getitem__(self, k):
        if isinstance(k, slice):
            return [self[i] for i in range(*k.indices(len(self._items)))]
        x = self._items[k]
        if x is None:
            self._reads += 1
            if self._reads * self.BULK > len(self._items):
                self._form_all()
                return self._items[k]
            x = self._items[k] = self.column[k]
        return x

    def _form_all(self) -> None:
        if not self._formed:
            items = self._items
            for i, x in enumerate(ca.vertsplit(self.column)):
                if items[i] is None:
                    items[i] = x
            self._formed = True

    def __iter__(self):
        self._form_all()
        return iter(self._items)

    def __setitem__(self, k, value) -> None:
        if isinstance(k, slice):
            self._form_all()
        self._items[k] = value

    def __delitem__(self, k) -> None:
        self._form_all()          # the rows after it would move against the column
        del self._items[k]

    def insert(self, i: int, value) -> None:
        if i < len(self._items):
            self._form_all()
        self._items.insert(i, value)

    def copy(self) -> ColumnRows:
        out = ColumnRows(self.column, list(self._items))
        out._reads, out._formed = self._reads, self._formed
        return out


class _Variables(MutableMapping):
    """`FlatModel.variables`: name -> record, in declaration order, held as two lists
    (the names, the records). The dictionary by name (name -> place) is built on the
    first read by name; iterating, counting and reading the records in order never build
    it. A compile reads its variables by row (`_first_row`, template slots, alias
    numbers), so a model bound in bulk is compiled without entering every name in a
    dictionary: at 10^6 variables, 40 MB and a lookup's cache misses per name. Replacing
    or deleting a name already there finds its place by a search (rare: flattening only
    appends).

    Variables bound in bulk (`extend_bulk`) have no record until one is read (`at`, by
    name, or all of them by `records`, `values`, `items`): what a record reads is held
    by the class's plan entry, shared by every instance, and a pass that reads one
    attribute of every variable takes it from there (`column_of`). A million records are
    some 130 MB that most compiles never read one by one."""

    __slots__ = ("_names", "_records", "_index", "_bulk", "_formed", "_ints")

    def __init__(self, items=()):
        self._names: list[str] = []
        self._records: list = []
        self._index: dict | None = None
        # the first len(plans) variables, bound in bulk: their column, each one's plan
        # entry, owner's path and row in the column; None once every record is formed.
        # A place among them whose record was given holds no plan.
        self._bulk: tuple[ca.SX, list, list, list | range] | None = None
        self._formed: list[int] = []    # the places among them that hold a record
        # the integers 0, 1, ... as shared objects (`_bind_symbols`'), if given: the
        # places of the dictionary by name and the rows of the records formed
        self._ints: list[int] | None = None
        self.update(items)

    def extend(self, names: list[str], records: list) -> None:
        """Append the new ``names`` with their ``records``; the lists are taken as they
        are when there is nothing yet."""
        if not self._names and self._index is None:
            self._names, self._records = names, records
            return
        for name, record in zip(names, records):
            self[name] = record

    def extend_bulk(self, names: list[str], column: ca.SX, plans: list,
                    owners: list, ints: list[int] | None = None) -> None:
        """Append ``names``, the variables of rows 0, 1, ... of ``column``
        (`_bind_symbols`), each read as a `_ColumnVariable` of its ``plans`` entry and
        owner's path (``owners``); their records are formed when read if there is
        nothing yet, else now. ``ints``: the integers 0 .. len(names) - 1 as objects to
        share. The lists are taken as they are."""
        shared = ints if ints is not None and len(ints) >= len(names) else None
        rows = range(len(names)) if shared is None else shared
        if self._names or self._index is not None:
            self.extend(names, list(map(_ColumnVariable, names, repeat(column), rows,
                                        plans, owners)))
            return
        self._names, self._records = names, [None] * len(names)
        self._bulk = (column, plans, owners, rows)
        self._ints = shared

    def reordered(self, places: list[int]) -> _Variables:
        """The variables in places ``places`` (each once), in that order: those bound
        in bulk stay unformed (`_declaration_order`)."""
        new = _Variables()
        new._names = list(map(self._names.__getitem__, places))
        new._records = list(map(self._records.__getitem__, places))
        if self._bulk is not None:
            column, plans, owners, rows = self._bulk
            n = len(plans)
            # every place read as bound in bulk; one whose record was given (bound
            # after them) holds no plan and is read off its record
            new._bulk = (column, [plans[p] if p < n else _NO_PLAN for p in places],
                         [owners[p] if p < n else None for p in places],
                         [rows[p] if p < n else -1 for p in places])
            new._formed = [k for k, r in enumerate(new._records) if r is not None]
            new._ints = self._ints
        return new

    def at(self, k: int):
        """The record of the variable in place ``k`` (its row in declaration order)."""
        record = self._records[k]
        if record is None:
            column, plans, owners, rows = self._bulk
            record = self._records[k] = _ColumnVariable(
                self._names[k], column, rows[k], plans[k], owners[k])
            self._formed.append(k)
        return record

    def records(self) -> list:
        """The records in declaration order (by row): the list held, not a copy, every
        record formed."""
        if self._bulk is not None:
            at = self.at
            for k in range(len(self._bulk[1])):
                at(k)
            self._bulk, self._formed = None, []
        return self._records

    def column_of(self, attribute: str) -> list:
        """Each variable's ``attribute`` (``name``, ``owner``, or what the class's plan
        entry holds: ``kind``, ``unit``, ``doc``, ``start``, ``priority``, ``hint``,
        ``state_select``), in order, as its record reads it: read off the plan entries
        for the variables bound in bulk whose record is not formed, so no record is."""
        if attribute == "name":
            return list(self._names)
        if self._bulk is None:
            return list(map(attrgetter(attribute), self._records))
        _, plans, owners, _ = self._bulk
        if attribute == "owner":
            out = list(owners)
        else:
            out = list(map(itemgetter(_PLAN_PLACE[attribute]), plans))
        records = self._records
        out += map(attrgetter(attribute), records[len(out):])
        for k in self._formed:      # a start or priority given to the instance
            out[k] = getattr(records[k], attribute)
        return out

    def symbol_sources(self):
        """Each variable's symbol in order, as `_gather` takes it: ``(column, row)`` of
        a record that still reads it from its column, else ``(None, symbol)``."""
        if self._bulk is not None:
            column, rows = self._bulk[0], self._bulk[3]
            return ((column, rows[k]) if r is None else _symbol_source(r)
                    for k, r in enumerate(self._records))
        return map(_symbol_source, self._records)

    def _by_name(self) -> dict:
        index = self._index
        if index is None:
            n, ints = len(self._names), self._ints
            index = self._index = dict(zip(self._names, ints if ints is not None and
                                           len(ints) >= n else range(n)))
        return index

    def __getitem__(self, name):
        return self.at(self._by_name()[name])

    def get(self, name, default=None):
        k = self._by_name().get(name)
        return default if k is None else self.at(k)

    def __contains__(self, name) -> bool:
        return name in self._by_name()

    def __setitem__(self, name, record) -> None:
        index = self._by_name()
        k = index.get(name)
        if k is None:
            index[name] = len(self._names)
            self._names.append(name)
            self._records.append(record)
        else:
            self.at(k)      # noted as formed: `column_of` reads the record given
            self._records[k] = record

    def __delitem__(self, name) -> None:
        k = self._by_name()[name]
        self.records()          # the places after it move
        del self._names[k]
        del self._records[k]
        self._index = None

    def __iter__(self):
        return iter(self._names)

    def __len__(self) -> int:
        return len(self._names)

    def values(self):
        return _RecordsView(self)

    def items(self):
        return _NamedRecordsView(self)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({dict(zip(self._names, self.records()))!r})"


#: where a `_ColumnVariable`'s attributes are in its class's plan entry
#: (`_declaration_plan`)
_PLAN_PLACE = {"kind": 1, "unit": 2, "doc": 3, "start": 4, "priority": 5, "hint": 6,
               "state_select": 7}
#: the plan entry of a place whose record was given (`_Variables.reordered`)
_NO_PLAN = (None,) * 8


def column_of(variables, attribute: str) -> list:
    """Each of ``variables``' (`FlatModel.variables`) ``attribute`` in order, without
    forming the records of variables bound in bulk (`_Variables.column_of`)."""
    if type(variables) is _Variables:
        return variables.column_of(attribute)
    return [getattr(v, attribute) for v in variables.values()]


def _symbol_source(v) -> tuple:
    return (v.column, v.row) if type(v) is _ColumnVariable and v._sym is None \
        else (None, v.sym)


class _RecordsView(ValuesView):
    """The records in order, read off their list (no lookup by name)."""

    def __iter__(self):
        return iter(self._mapping.records())


class _NamedRecordsView(ItemsView):
    """``(name, record)`` in order, read off the two lists."""

    def __iter__(self):
        return zip(self._mapping._names, self._mapping.records())


class _Components(MutableMapping):
    """`FlatModel.components`, path -> class name, held as two lists in tree order (a
    path and a name per component, appended by flattening) and made a dictionary only
    when something reads it: messages and reports read a few, and entering every path
    of 10^5 components costs more per entry the more there are."""

    __slots__ = ("_paths", "_names", "_dict")

    def __init__(self):
        self._paths: list = []
        self._names: list = []
        self._dict: dict | None = None

    def _formed(self) -> dict:
        if self._dict is None:
            self._dict = dict(zip(self._paths, self._names))
            self._paths = self._names = None
        return self._dict

    def add(self, path: str, name: str) -> None:
        """``self[path] = name`` for a path not in it yet, without forming the dictionary."""
        if self._dict is None:
            self._paths.append(path)
            self._names.append(name)
        else:
            self._dict[path] = name

    def __getitem__(self, path):
        return self._formed()[path]

    def __setitem__(self, path, name) -> None:
        self._formed()[path] = name

    def __delitem__(self, path) -> None:
        del self._formed()[path]

    def __iter__(self):
        return iter(self._formed())

    def __len__(self) -> int:
        return len(self._paths) if self._dict is None else len(self._dict)

    def __repr__(self) -> str:
        return repr(self._formed())


class _RowsOf:
    """Variable name -> its row in the column of all variables, read off the records
    (`_ColumnVariable.row`) when every variable was bound in bulk: no second dictionary
    of every name. Few names are looked up (most passes go by number)."""

    __slots__ = ("variables",)

    def __init__(self, variables: dict):
        self.variables = variables

    def get(self, name, default=None):
        record = self.variables.get(name)
        return default if record is None else record.row

    def __getitem__(self, name) -> int:
        return self.variables[name].row

    def __contains__(self, name) -> bool:
        return name in self.variables

    def __len__(self) -> int:
        return len(self.variables)


class FoldedColumns:
    """The variables of the folded subsystem ports, in bulk, ordered by ``position``
    (tree order), a port's variables together in declaration order: their ``names``,
    ``units`` and ``docs``, each one's ``position`` (logged after the first ``position``
    variables of the model), its port's ``order`` in the tree (to place ports bound late,
    `_declaration_order`) and its terms, the rows of the model variables it sums (an
    across variable the node's first member's, a through variable those of the inside
    members of its set): variable ``k``'s are ``term_rows[term_ptr[k]:term_ptr[k + 1]]``
    (compressed rows, as a CSR matrix's)."""

    __slots__ = ("names", "units", "docs", "position", "order", "term_ptr", "term_rows")

    def __init__(self, names: list, units: list, docs: list, position: list,
                 order: list, term_ptr: np.ndarray, term_rows: np.ndarray):
        self.names, self.units, self.docs = names, units, docs
        self.position, self.order = position, order
        self.term_ptr, self.term_rows = term_ptr, term_rows

    def __len__(self) -> int:
        return len(self.names)

    @property
    def ports(self) -> list[str]:
        """The paths of the folded ports, in order (for messages and tests)."""
        return list(dict.fromkeys(name.rpartition(".")[0] for name in self.names))


def _offsets(counts: np.ndarray) -> np.ndarray:
    """Compressed-row pointers (as a CSR matrix's) of segments of ``counts`` entries."""
    return np.concatenate([[0], np.cumsum(counts)]).astype(np.intp)


@dataclass(slots=True)
class FlatEquation:
    residual: ca.SX
    origin: object     # "r1: v == R*i" or "connect(r1.n, c1.p)"; str() formats it
    owner: str = ""    # path of the component the equation belongs to
    #: what alias elimination would read off the residual, known from the class's
    #: template: ("pair", a, b, s) for a == s*b, ("const", a, value), or ("none",);
    #: a and b are variable names, or numbers (their place in `FlatModel.variables`)
    alias: tuple | None = None


_RESIDUAL_SLOT = FlatEquation.__dict__["residual"]     # the slots, under the properties
_ORIGIN_SLOT = FlatEquation.__dict__["origin"]


class _TemplateEquation(FlatEquation):
    """An equation of a `_Template` instance: its residual is the row ``row`` of its
    class's stacked residuals (`_Template.column`), formed as a scalar only when read.
    Alias elimination gathers the rows it keeps from the columns instead
    (`stack_residuals`): no Python object per equation on the way. Its origin (a
    `_TemplateOrigin`) is likewise formed when read."""

    __slots__ = ("row", "template")

    def __init__(self, template, owner, alias, row):
        _RESIDUAL_SLOT.__set__(self, None)
        _ORIGIN_SLOT.__set__(self, None)
        self.template, self.owner, self.alias, self.row = template, owner, alias, row

    @property
    def origin(self):
        o = _ORIGIN_SLOT.__get__(self)
        if o is None:
            tpl = self.template
            instance, k = divmod(self.row, tpl.n_eq)
            o = _TemplateOrigin(self.owner or tpl.model_name, tpl,
                                tpl.instances[instance], k)
            _ORIGIN_SLOT.__set__(self, o)
        return o

    @origin.setter
    def origin(self, value):
        _ORIGIN_SLOT.__set__(self, value)

    @property
    def residual(self):
        r = _RESIDUAL_SLOT.__get__(self)
        if r is None:
            tpl = self.template
            if tpl.column is None and tpl.pending is None and not tpl.replaced:
                return None                     # not instantiated, or let go
            column, r = _row_of(tpl, self.row)
            if column is not None:
                r = column[r]
            _RESIDUAL_SLOT.__set__(self, r)
        return r

    @residual.setter
    def residual(self, value):
        _RESIDUAL_SLOT.__set__(self, value)


class _SumEquation(FlatEquation):
    """A flow sum of a connection set (`_flow_sums`): its residual is the row ``row`` of
    the column of all flow sums, formed as a scalar only when read; alias elimination
    gathers the rows from the column (`stack_residuals`). A sum of three terms or more
    is no alias, and says so (``alias``), so that its residual is not read for that."""

    __slots__ = ("row", "column", "uniform", "terms")

    def __init__(self, column: ca.SX, row: int, origin, alias, uniform: bool,
                 terms: int):
        _RESIDUAL_SLOT.__set__(self, None)
        self.column, self.row, self.origin, self.owner, self.alias = \
            column, row, origin, "", alias
        #: every term the same variable of the same connector class: the same unit, so
        #: the sum agrees in its dimensions by construction (the dimension check skips it)
        self.uniform = uniform
        #: how many variables the sum holds; alias elimination puts a representative
        #: or a number in the place of each, so no more after it
        self.terms = terms

    residual = _formed_on_read(_RESIDUAL_SLOT, lambda eq: eq.column[eq.row])


_NO_ALIAS = ("none",)


class Origins(MutableSequence):
    """The origin of each of a list of equations, as a list whose items are formed when
    read: a class template's equation (`_TemplateEquation`) is held as two numbers,
    its template's and its row, and its origin (`_TemplateOrigin`) formed on each read;
    any other origin is held as given. Only messages read origins, a few of a million;
    `templates` and `which` tell which rows come from which template without forming
    any (`mechatron.compiler.relations`), and `terms` how many variables a flow sum's
    row holds at most. Items may be replaced and appended as in a list; `copy` shares
    the numbers."""

    __slots__ = ("templates", "which", "rows", "given", "_extra", "formed", "terms")

    def __init__(self, eqs=()):
        if type(eqs) is not EquationRows:
            eqs = EquationRows.of(list(eqs))
        templates = list(eqs.templates)
        number = {id(t): k for k, t in enumerate(templates)}    # their places
        which = eqs.which.astype(np.int32)
        rows = eqs.rows.astype(np.int64)
        given, sum_rows, sum_terms = {}, [], []
        held = np.flatnonzero(which < 0).tolist()
        for k, eq in zip(held, [eqs.objects[r] for r in rows[held].tolist()]):
            if type(eq) is _TemplateEquation and _ORIGIN_SLOT.__get__(eq) is None:
                tpl = eq.template
                t = number.get(id(tpl))
                if t is None:
                    t = number[id(tpl)] = len(templates)
                    templates.append(tpl)
                which[k], rows[k] = t, eq.row
            else:
                rows[k] = 0
                given[k] = eq.origin
                if type(eq) is _SumEquation and _RESIDUAL_SLOT.__get__(eq) is None:
                    sum_rows.append(k)
                    sum_terms.append(eq.terms)
        self.templates = templates
        #: each row's template (its place in `templates`), -1 for an origin held as given
        self.which = which
        self.rows = rows                # its row in the template's column
        self.given = given              # row -> origin, for rows held or replaced
        #: the variables a flow sum's row holds at most (its terms), -1 for other rows
        #: and for a row replaced since
        self.terms = np.full(len(which), -1, dtype=np.int32)
        self.terms[sum_rows] = sum_terms
        self._extra: list = []          # appended after the rows
        self.formed: list | None = None     # all, after a deletion or an insertion

    def __len__(self) -> int:
        if self.formed is not None:
            return len(self.formed)
        return len(self.which) + len(self._extra)

    def _at(self, k) -> int:
        """``k`` counted from the start (IndexError out of range)."""
        n = len(self)
        if k < 0:
            k += n
        if not 0 <= k < n:
            raise IndexError("origin index out of range")
        return k

    def __getitem__(self, k):
        if self.formed is not None:
            return self.formed[k]
        if isinstance(k, slice):
            return [self[i] for i in range(*k.indices(len(self)))]
        k, n = self._at(k), len(self.which)
        if k >= n:
            return self._extra[k - n]
        origin = self.given.get(k)
        if origin is None:
            tpl = self.templates[self.which[k]]
            instance, j = divmod(int(self.rows[k]), tpl.n_eq)
            origin = _TemplateOrigin(tpl.paths[instance] or tpl.model_name, tpl,
                                     tpl.instances[instance], j)
        return origin

    def __setitem__(self, k, value) -> None:
        if self.formed is None and isinstance(k, slice):
            self._form_all()
        if self.formed is not None:
            self.formed[k] = value
            return
        k, n = self._at(k), len(self.which)
        if k >= n:
            self._extra[k - n] = value
        else:
            self.given[k] = value
            self.terms[k] = -1          # (its residual may be another now)

    def _form_all(self) -> None:
        if self.formed is None:
            self.formed = [self[k] for k in range(len(self))]

    def __delitem__(self, k) -> None:
        self._form_all()          # the rows after it move against the numbers
        del self.formed[k]

    def insert(self, i: int, value) -> None:
        if self.formed is None and i >= len(self):
            self._extra.append(value)
            return
        self._form_all()
        self.formed.insert(i, value)

    def copy(self) -> Origins:
        out = Origins()
        out.templates, out.which, out.rows = self.templates, self.which, self.rows
        out.given, out._extra = dict(self.given), list(self._extra)
        out.terms = self.terms.copy()
        out.formed = None if self.formed is None else list(self.formed)
        return out


class FlatEquations(MutableSequence):
    """`FlatModel.equations`: the model's equations in order. A class template's
    equation is held as two numbers, its template's place in `templates` and its row in
    the template's column (`_Template.add` appends them: no object per equation), and
    formed as a `_TemplateEquation` when read, then held as given so that what is set on
    it stays; any other equation is held as given. Alias elimination and the dimension
    check read the numbers in bulk (`numbered`). Reading, replacing, appending and
    deleting the last ones keep the numbers; any other deletion or insertion holds every
    equation as given (`plain`)."""

    __slots__ = ("templates", "_place", "which", "rows", "given", "plain")

    def __init__(self, items=()):
        self.templates: list = []
        self._place: dict = {}          # id(template) -> its place in templates
        #: each equation's template (its place in `templates`), -1 if held as given
        self.which: list = []
        #: and its row in the template's column, or its place in `given`
        self.rows: list = []
        #: the equations held as given (None where one was deleted)
        self.given: list = []
        #: every equation as a list, after a deletion or an insertion (then the only
        #: store)
        self.plain: list | None = None
        self.extend(items)

    def add_rows(self, tpl, first: int, last: int, ints) -> None:
        """Append rows ``first .. last - 1`` of template ``tpl``; ``ints`` holds their
        numbers (`_integers`)."""
        if self.plain is not None:
            self.plain.extend(map(tpl.equation, range(first, last)))
            return
        t = self._place.get(id(tpl))
        if t is None:
            t = self._place[id(tpl)] = len(self.templates)
            self.templates.append(tpl)
        self.which += repeat(t, last - first)
        self.rows += ints[first:last]

    def numbered(self) -> tuple[np.ndarray, np.ndarray] | None:
        """``(which, rows)`` as arrays (see the attributes); None once `plain`."""
        if self.plain is not None:
            return None
        return (np.array(self.which, dtype=np.int32), np.array(self.rows, dtype=np.int64))

    def held(self) -> list:
        """The equations held as objects (any order): those not of a class template,
        and the template equations formed since."""
        return self.plain if self.plain is not None else \
            [eq for eq in self.given if eq is not None]

    def __len__(self) -> int:
        return len(self.plain) if self.plain is not None else len(self.which)

    def __getitem__(self, k):
        if self.plain is not None:
            return self.plain[k]
        if isinstance(k, slice):
            return [self[i] for i in range(*k.indices(len(self.which)))]
        t = self.which[k]
        if t < 0:
            return self.given[self.rows[k]]
        eq = self.templates[t].equation(self.rows[k])
        self.which[k], self.rows[k] = -1, len(self.given)
        self.given.append(eq)
        return eq

    def __setitem__(self, k, value) -> None:
        if self.plain is None and isinstance(k, slice):
            self._form_all()
        if self.plain is not None:
            self.plain[k] = value
        elif self.which[k] < 0:
            self.given[self.rows[k]] = value
        else:
            self.which[k], self.rows[k] = -1, len(self.given)
            self.given.append(value)

    def __delitem__(self, k) -> None:
        if self.plain is None and isinstance(k, slice) and k.step in (None, 1) and \
                (k.stop is None or k.stop >= len(self.which)):
            start = k.indices(len(self.which))[0]       # the last ones: numbers kept
            for t, r in zip(self.which[start:], self.rows[start:]):
                if t < 0:
                    self.given[r] = None
            del self.which[start:], self.rows[start:]
            return
        self._form_all()
        del self.plain[k]

    def insert(self, i: int, value) -> None:
        if self.plain is None and i >= len(self.which):
            self.append(value)
            return
        self._form_all()
        self.plain.insert(i, value)

    def append(self, value) -> None:
        if self.plain is not None:
            self.plain.append(value)
            return
        self.which.append(-1)
        self.rows.append(len(self.given))
        self.given.append(value)

    def extend(self, values) -> None:
        if self.plain is not None:
            self.plain.extend(values)
            return
        values = list(values)
        n = len(self.given)
        self.which += repeat(-1, len(values))
        self.rows += range(n, n + len(values))
        self.given += values

    def __iter__(self):
        if self.plain is not None:
            return iter(self.plain)
        return map(self.__getitem__, range(len(self.which)))

    def __add__(self, other) -> list:
        return list(self) + list(other)

    def __repr__(self) -> str:
        return repr(list(self))

    def _form_all(self) -> None:
        if self.plain is None:
            plain = list(self)
            self.which, self.rows, self.given, self.plain = [], [], [], plain


class EquationRows:
    """Equations in order, as `FlatEquations` holds them: ``which`` the template of each
    (its place in ``templates``) or -1 for one held as an object, ``rows`` its row in
    the template's column or its place in ``objects`` (the objects in order)."""

    __slots__ = ("templates", "which", "rows", "objects")

    def __init__(self, templates: list, which: np.ndarray, rows: np.ndarray,
                 objects: list):
        self.templates, self.which, self.rows, self.objects = \
            templates, which, rows, objects

    @classmethod
    def of(cls, eqs: list) -> EquationRows:
        """``eqs``, every one held as an object."""
        n = len(eqs)
        return cls([], np.full(n, -1, dtype=np.int32), np.arange(n, dtype=np.int64),
                   list(eqs))

    def __len__(self) -> int:
        return len(self.which)

    def __iter__(self):
        """Each equation as an object, a template's row formed (`_Template.equation`)."""
        templates, objects = self.templates, self.objects
        for t, r in zip(self.which.tolist(), self.rows.tolist()):
            yield objects[r] if t < 0 else templates[t].equation(r)

    def by_template(self):
        """``(template, places)`` for each template with rows here, the places
        ascending."""
        which = self.which
        numbered = np.flatnonzero(which >= 0)
        if not len(numbered):
            return
        order = numbered[np.argsort(which[numbered], kind="stable")]
        cut = np.flatnonzero(np.diff(which[order])) + 1
        for places in np.split(order, cut):
            yield self.templates[which[places[0]]], places


def _held(eqs) -> list:
    """The equations of ``eqs`` (`FlatModel.equations`) held as objects, in any order:
    all but the class templates' rows not read yet, which are never those looked for."""
    return eqs.held() if type(eqs) is FlatEquations else eqs


def stack_residuals(eqs) -> ca.SX:
    """``vertcat`` of the residuals of ``eqs``: the rows of template equations and flow
    sums gathered from their columns by one index (a residual set since, e.g. by `pre`'s
    replacement, is taken as it is), the others stacked."""
    return _gather(map(_residual_of, eqs))


def _residual_of(eq) -> tuple:
    """``(column, row)`` of ``eq``'s residual, or ``(None, residual)`` (see `_gather`)."""
    if type(eq) is _TemplateEquation and _RESIDUAL_SLOT.__get__(eq) is None:
        return _row_of(eq.template, eq.row)
    if type(eq) is _SumEquation and _RESIDUAL_SLOT.__get__(eq) is None:
        return eq.column, eq.row
    return None, eq.residual


def _row_of(tpl, row: int) -> tuple:
    """``(column, row)`` of the residual of row ``row`` of template ``tpl``: a row of
    the first instance of a template not formed yet is read off that instance alone
    (the dimension check reads no other), any other from the column of all instances."""
    if tpl.replaced:
        return None, tpl.own_row(row)
    if tpl.column is None and row < tpl.n_eq:
        return tpl.first_rows(), row
    return tpl.formed(), row


def stack_columns(*parts: ca.SX) -> ca.SX:
    """``vertcat(*parts)`` of SX columns. When every part is a dense column (each row an
    expression), their elements are copied into one column of zeros by slices: the same
    column at a sixth to a seventh of the cost on long columns, as CasADi's `vertcat`
    transposes every part and the result (about 45 ns a row against 200-300 ns from 10^4
    to 10^6 rows). One part is returned as it is."""
    if len(parts) == 1 and isinstance(parts[0], ca.SX) and parts[0].size2() == 1:
        return parts[0]
    if len(parts) < 2 or any(p.size2() != 1 or p.nnz() != p.size1() for p in parts):
        return ca.vertcat(*parts)
    out = ca.SX.zeros(sum(p.size1() for p in parts))
    k = 0
    for p in parts:
        m = p.size1()
        if m:
            out.nz[k:k + m] = p
            k += m
    return out


def _gather(items) -> ca.SX:
    """The scalars ``items`` stacked, each ``(column, row)``, row ``row`` of ``column``,
    or ``(None, scalar)``: the rows gathered from their columns by one index, the loose
    scalars stacked after them."""
    parts: dict = {}            # id(column) -> its number among the columns
    columns, loose, where = [], [], []
    for column, item in items:
        if column is None:
            where.append((-1, len(loose)))
            loose.append(item)
            continue
        k = parts.get(id(column))
        if k is None:
            k = parts[id(column)] = len(columns)
            columns.append(column)
        where.append((k, item))
    if not columns:
        return ca.vertcat(*loose) if loose else ca.SX(0, 1)
    offset = np.cumsum([0] + [c.numel() for c in columns]).tolist()
    index = [offset[k] + r if k >= 0 else offset[-1] + r for k, r in where]
    return stack_columns(*columns, *([ca.vertcat(*loose)] if loose else []))[index]


@dataclass
class FlatModel:
    name: str
    context: BuildContext
    parameters: dict[str, FlatParameter] = field(default_factory=dict)
    #: the parts' parameters bound to expressions of their parents' parameters, in
    #: binding order: records, or what forms one (`bound_parameters`)
    bindings: list = field(default_factory=list, repr=False)
    variables: MutableMapping[str, FlatVariable] = field(default_factory=_Variables)
    equations: MutableSequence = field(default_factory=FlatEquations)
    aliases: list[tuple[str, str, float, str]] = field(default_factory=list)
    components: MutableMapping = field(default_factory=_Components)  # path -> class name
    #: the class of every element of the tree (a pass that few classes need skips the
    #: walk over the elements when none of them is there)
    classes: frozenset = frozenset()
    time_scales: list = field(default_factory=list)           # SX of parameters
    #: Each connection set as a list of (port path, Domain, is_output); ``is_output`` is
    #: True for a signal output driving the set. For diagrams and reports.
    connection_sets: list = field(default_factory=list)
    #: Event actions (``mt.sample``/``mt.when``) as (EventAction, owner path).
    events: list = field(default_factory=list)
    #: Discrete variables (see _discrete_declarations): name -> "real"/"integer"/"boolean".
    discrete: dict = field(default_factory=dict)
    #: Equations of ``initial_equations()``, holding at the initial time only.
    initial_equations: list = field(default_factory=list)
    #: Subsystem ports folded into the nodes they join (:mod:`mechatron.compiler.folding`):
    #: their variables are never unknowns, and are logged from their node.
    folded: FoldedColumns | None = None

    def folded_columns(self) -> tuple[list, list, list, np.ndarray,
                                      tuple[np.ndarray, np.ndarray]]:
        """The variables of the folded ports (`FoldedColumns`): their names, units and
        docs, each one's position and the rows of the model's variables it sums, as
        compressed rows ``(ptr, rows)``."""
        f = self.folded
        if f is None:
            empty = np.zeros(0, dtype=np.intp)
            return [], [], [], empty, (np.zeros(1, dtype=np.intp), empty)
        position = np.array(f.position, dtype=np.intp)
        if np.any(position[1:] < position[:-1]):    # (tree order keeps them sorted)
            k = np.argsort(position, kind="stable")
            at, _ = _segments(f.term_ptr, k)
            ptr = _offsets(np.diff(f.term_ptr)[k])
            k_list = k.tolist()
            return ([f.names[i] for i in k_list], [f.units[i] for i in k_list],
                    [f.docs[i] for i in k_list], position[k], (ptr, f.term_rows[at]))
        return f.names, f.units, f.docs, position, (f.term_ptr, f.term_rows)

    @property
    def bound_parameters(self) -> dict[str, BoundParameter]:
        """The parameters of parts bound to expressions of their parents' parameters, by
        path. No pass reads them (the equations hold the parent's symbols); the record of
        one passed on unchanged (``R=R``: one per instance of a reused subsystem) is
        formed on the first read, from what `_bind_expression` noted."""
        out = self.__dict__.get("_bound_parameters")
        if out is None or len(out) != len(self.bindings):
            out = self.__dict__["_bound_parameters"] = {}
            for k, item in enumerate(self.bindings):
                if type(item) is tuple:
                    item = self.bindings[k] = _row_bound(self, *item)
                out[item.name] = item
        return out

    def binding_sources(self) -> list[tuple]:
        """What each bound parameter is bound to, in plain values (for messages, kept by
        the compiled model): ``(owner, key, parent path, parent's parameter)`` for one
        passed on unchanged (``R=R``), ``(path, None, None, binding as written)`` for an
        expression; no record formed, no string joined."""
        return [(b[0], b[1], b[4], b[3].parameters[0].name) if type(b) is tuple else
                (b.name, None, None, b.binding) for b in self.bindings]

    @property
    def n_folded(self) -> int:
        """How many variables the folded ports hold."""
        return len(self.folded) if self.folded is not None else 0

    @property
    def time(self) -> ca.SX:
        return self.context.time

    def stack_variables(self, names=None) -> ca.SX:
        """The symbols of the variables ``names`` (default: all, in declaration order)
        as one column, taken from the column of all variable symbols, which is stacked
        once: a ``vertcat`` converts each scalar from Python (about 1 us each), indexing
        stays in CasADi."""
        column, index = self._stacked()
        if names is None:
            return column
        rows = [index[n] for n in names]
        return column[rows] if rows else ca.SX(0, 1)

    def stack_rows(self, rows: list[int]) -> ca.SX:
        """The symbols of the variables in ``rows`` of `stack_variables`' column."""
        return self._stacked()[0][rows] if rows else ca.SX(0, 1)

    def variable_rows(self) -> Mapping[str, int]:
        """Each variable's row in `stack_variables`' column (its place in declaration
        order): ``rows[name]``, ``rows.get(name)``, ``name in rows``."""
        return self._stacked()[1]

    def _stacked(self) -> tuple[ca.SX, Mapping[str, int]]:
        cache = self.__dict__.get("_variable_stack")
        if cache is None or cache[0] != len(self.variables):
            index = {n: k for k, n in enumerate(self.variables)}
            column = _gathered(self.variables) if index else ca.SX(0, 1)
            cache = self.__dict__["_variable_stack"] = (len(index), column, index)
        return cache[1], cache[2]

    def derivatives_by_row(self, rows: list[int]) -> tuple[list, ca.SX] | None:
        """The derivative symbol of each variable in ``rows`` (None for a variable whose
        derivative does not appear) and the column of those that are not None, read by
        row when every derivative of the build context was made in bulk for an instance
        of a class template (`_Template.add` notes their rows); else None, and they are
        read by name."""
        state = self.__dict__
        bulk = state.get("_derivative_bulk")
        if not bulk or len(bulk) != len(self.context.derivative):
            return None
        column, syms = state["_derivative_column"]
        noted = np.array(bulk, dtype=np.int64)
        at = np.full(max(len(self.variables), int(noted[:, 0].max()) + 1), -1, np.int64)
        at[noted[:, 0]] = noted[:, 1]
        k = at[np.asarray(rows, dtype=np.int64)]
        taken = k[k >= 0].tolist()
        return ([syms[j] if j >= 0 else None for j in k.tolist()],
                column[taken] if taken else ca.SX(0, 1))

    def parameter_column(self) -> ca.SX:
        """The symbols of `parameters` stacked, in their order: those bound in bulk
        (`_ColumnParameter`) gathered from the column of all parameters by one index."""
        params = self.parameters.values()
        return _gather((q.store.column, q.row)
                       if type(q) is _ColumnParameter and _PAR_SYM_SLOT.__get__(q) is None
                       else (None, q.sym) for q in params) if params else ca.SX(0, 1)

    @functools.cached_property
    def physical_owners(self) -> frozenset:
        """Paths of the components that have physical (conserving) ports."""
        return frozenset(owner for owner, kind in zip(column_of(self.variables, "owner"),
                                                      column_of(self.variables, "kind"))
                         if kind == "across" or kind == "through")


def _walk(root: Element):
    """Every element, parents first; each one's path is cached for the build."""
    root._path_cache = ""
    stack = [root]
    while stack:
        el = stack.pop()
        yield el
        children = el._children
        if children:
            kids = list(children.values())
            path = el._path_cache
            if path:
                path += "."
                for child in kids:
                    child._path_cache = path + child._name
            else:
                for child in kids:
                    child._path_cache = child._name
            kids.reverse()
            stack += kids


class _Origin:
    """Where an equation comes from; formatted only when a message needs it."""

    __slots__ = ("where", "lhs", "rhs")

    def __init__(self, where, lhs, rhs):
        self.where, self.lhs, self.rhs = where, lhs, rhs

    def __str__(self) -> str:
        return f"{self.where}: {_short(self.lhs)} == {_short(self.rhs)}"

    __repr__ = __str__


def _as_equations(items):
    out = []
    stack = [items]
    while stack:
        item = stack.pop()
        if isinstance(item, (list, tuple)):
            stack.extend(reversed(item))
        elif item is None:
            continue
        else:
            out.append(item)
    return out


def flatten(model: Component, name: str | None = None) -> FlatModel:
    """Flatten ``model``: bind symbols, collect equations and connections, validate.

    All problems with values, connections and references are collected and raised once.
    """
    if not isinstance(model, Component):
        raise TypeError(f"compile_model: expected a Component instance, got {model!r}.")
    name = name or model._name or type(model).__name__
    flat = FlatModel(name=name, context=BuildContext())
    problems = _Problems()
    elements = list(_walk(model))
    add_component = flat.components.add
    # each class met: whether its elements declare discrete variables or write initial
    # equations (`_discrete_declarations` reads those elements alone, picked here)
    marked: dict[type, bool] = {}
    discrete = []
    parts = []                      # the components, in tree order
    for el in elements:
        cls = type(el)
        mark = marked.get(cls)
        if mark is None:
            mark = marked[cls] = _discrete_or_initial(cls)
        if mark:
            discrete.append(el)
        if isinstance(el, Component):
            if el._partial and el is not model:
                problems.append(f"{el.describe()}: {cls.__name__} is a partial "
                                "class (an interface); use a concrete component.")
            add_component(el._path_cache, cls.__name__)
            parts.append(el)
    flat.classes = frozenset(marked)
    planned, folded = plan_subsystems(model, parts)
    _bind_symbols(flat, elements, problems, folded)
    _external_inputs(flat, model)
    try:
        with flat.context:
            connects = _collect_equations(flat, parts, problems, planned)
            _discrete_declarations(flat, discrete, problems)
        _connections(flat, model, elements, connects, problems, planned, folded)
    finally:
        for el in elements:
            el._syms = None
            el._path_cache = None
    flat.__dict__.pop("_ints", None)     # its integers live on where they are held
    if problems:
        raise problems.error_class()(_summary(name, problems), problems=list(problems),
                                     path=name)
    _declaration_order(flat)
    return flat


def _declaration_order(flat: FlatModel) -> None:
    """Move the variables of ports bound on first read (`_FoldedSymbols`) back to where
    they are declared: declaration order breaks ties in later passes."""
    late = flat.__dict__.pop("_late", None)
    if not late:
        return
    # the instances of class templates read their variables by rows of the old order
    for tpl in flat.__dict__.pop("_pending_templates", ()):
        tpl.formed()
    # rows of differentiated variables in the old order (see `_Template.add`): moved below
    der_rows = flat.__dict__.pop("_derivative_rows", None)
    der_bulk = flat.__dict__.pop("_derivative_bulk", None)
    late.sort(key=lambda item: item[:2])
    moved = {n for *_, names in late for n in names}
    rest = [n for n in flat.variables if n not in moved]
    order = []
    start = 0
    for position, _, names in late:
        order.extend(rest[start:position])
        order.extend(names)
        start = max(start, position)
    order.extend(rest[start:])
    variables = flat.variables
    number = dict(zip(variables, range(len(variables))))
    if type(variables) is _Variables:       # those bound in bulk stay unformed
        flat.variables = variables.reordered([number[n] for n in order])
    else:
        flat.variables = _Variables([(n, variables[n]) for n in order])
    if type(flat.context.unknowns) is _Unknowns:
        flat.context.unknowns.variables = flat.variables
    flat.__dict__.pop("_variable_stack", None)     # stacked in the old order
    # alias hints given by variable number (`_Template.add`) follow their variables
    moved_to = [0] * len(order)
    for new, n in enumerate(order):
        moved_to[number[n]] = new
    if der_rows:
        flat.__dict__["_derivative_rows"] = {n: moved_to[r] for n, r in der_rows.items()}
    if der_bulk:
        flat.__dict__["_derivative_bulk"] = [(moved_to[r], k) for r, k in der_bulk]
    equations = flat.equations
    if type(equations) is FlatEquations and equations.plain is None:
        # the templates' rows give their hints from their instances' first rows
        # (`_Template.hint`): an element's variables move together, so its first row
        # moves them all
        for tpl in equations.templates:
            tpl.bases = [moved_to[b] if b >= 0 else b for b in tpl.bases]
        equations = equations.held()
    for eq in equations:
        hint = eq.alias
        if hint is not None and hint[0] != "none" and type(hint[1]) is int:
            eq.alias = (hint[0], moved_to[hint[1]], moved_to[hint[2]], hint[3]) \
                if hint[0] == "pair" else (hint[0], moved_to[hint[1]], hint[2])
    flat.aliases = [(moved_to[a] if type(a) is int else a,
                     moved_to[b] if type(b) is int else b, k, origin)
                    for a, b, k, origin in flat.aliases]
    folded = flat.folded
    if folded is not None:      # still folded: after the ports declared before it
        folded.position = [p + sum(len(names) for position, k, names in late
                                   if (position, k) < (p, o))
                           for p, o in zip(folded.position, folded.order)]
        folded.term_rows = np.asarray(moved_to, dtype=np.intp)[folded.term_rows]


class _Problems(list):
    """Messages collected by the validators, each with the error class it belongs to;
    ``append`` records a model problem, ``add`` one of a given class."""

    def __init__(self):
        super().__init__()
        self.kinds: list[type] = []

    def append(self, message: str) -> None:
        self.add(ModelError, message)

    def add(self, kind: type, message: str) -> None:
        super().append(message)
        self.kinds.append(kind)

    def error_class(self) -> type:
        """UnitError if every problem is a unit problem, ParameterError if every one is
        about values, ConnectError if any connection failed, else ModelError."""
        kinds = set(self.kinds)
        if kinds == {UnitError}:
            return UnitError
        if kinds <= {UnitError, ParameterError}:
            return ParameterError
        return ConnectError if ConnectError in kinds else ModelError


def _summary(name: str, problems: list[str]) -> str:
    if len(problems) == 1:
        return problems[0]
    return f"model '{name}': {len(problems)} problems:\n  " + "\n  ".join(problems)


def _gathered(variables) -> ca.SX:
    """``vertcat`` of the symbols of ``variables`` (`FlatModel.variables`): those still
    in a column (`_ColumnVariable`, or bound in bulk and not formed) gathered from it by
    one index, the others stacked."""
    if type(variables) is _Variables:
        return _gather(variables.symbol_sources())
    return _gather(map(_symbol_source, variables.values()))


class _ColumnSyms(dict):
    """The symbols of an element bound in bulk (its ``_syms``), each read from a column
    on first read: its variables' from the column of all variables (``offsets``: each
    variable's row after ``base``), its parameters' from the column of all parameters
    (``par_rows``: each one's row, in declaration order; a parameter bound to an
    expression of its parent's is held as bound). A class template's instance never
    reads them one by one (`_Template.add` takes their rows). ``row`` is the row of its
    first variable among the model's variables (`_first_row`); an element with
    parameters alone has no ``column`` and the row -1. ``par_values`` holds its
    parameters' values while flattening, for its parts' bindings (`_bind_expression`)."""

    __slots__ = ("column", "base", "offsets", "row", "par_store", "par_rows",
                 "par_places", "par_values")

    def __missing__(self, key):
        at = self.offsets.get(key)
        if at is not None:
            sym = self.column[self.base + at]
        else:       # a parameter (KeyError for a key that is neither)
            sym = self.par_store[self.par_rows[self.par_places[key]]]
        self[key] = sym
        return sym

    def filled(self) -> "_ColumnSyms":
        """Every symbol read, in declaration order (parameters, then variables)."""
        offsets, places = self.offsets, self.par_places
        unread = any(not dict.__contains__(self, k) for k in offsets)
        if unread or any(not dict.__contains__(self, k) for k in places):
            params = [(k, self[k]) for k in places]
            given = [(k, v) for k, v in self.items() if k not in offsets and k not in places]
            if unread:
                syms = ca.vertsplit(self.column[self.base:self.base + len(offsets)])
            else:
                syms = [dict.__getitem__(self, k) for k in offsets]
            self.clear()
            self.update(params)
            self.update(given)
            self.update(zip(offsets, syms))
        return self


def _bind_symbols(flat: FlatModel, elements, problems, folded=None) -> None:
    """Bind a CasADi symbol to every parameter and variable; ports in ``folded`` get a
    mapping that binds them on first read (see `_FoldedSymbols`) instead.

    The names (instance paths) are listed first, then the symbols of all parameters and
    of all variables are made in one CasADi call each (`_symbols`) and every variable's
    record in one pass; values and start values are then read element by element. The
    column of the variables is kept as `FlatModel.stack_variables`' column, and the row
    of each element's first variable in it on the element's symbols (`_first_row`)."""
    ctx = flat.context
    variables, parameters = flat.variables, flat.parameters
    shared = (flat, folded, problems)
    par_names: list[str] = []
    var_names: list[str] = []
    var_plain: list[tuple] = []         # each variable's entry of its class's plan
    var_owner: list[str] = []
    bound = []
    for order, el in enumerate(elements):
        if folded and id(el) in folded:
            el._syms = _FoldedSymbols(shared, el, len(var_names), order)
            continue
        params, plain, par_keys, var_keys, offsets = _binding_plan(type(el))
        path = el._path_cache         # set by _walk
        if path:
            prefix = path + "."
            if params:
                par_names.extend([prefix + k for k in par_keys])
            if plain:
                var_names.extend([prefix + k for k in var_keys])
        else:
            par_names.extend(par_keys)
            var_names.extend(var_keys)
        if plain:
            owner = el._parent if isinstance(el, Connector) else el
            var_plain.extend(plain)
            var_owner.extend([owner._path_cache if owner is not None else ""] * len(plain))
        bound.append((el, params, plain, offsets))
    par_column = _symbols(par_names, split=False)[0]
    flat.__dict__["_parameter_column"] = par_column
    # the parameters' symbols as Python objects, each formed on first read and shared
    # by the element's symbols and the record; all at once when many are read alone
    # (passed on to parts, R=R: each read alone costs 5 us)
    par_store = ColumnRows(par_column)
    var_column = _symbols(var_names, split=False)[0]
    # the integers 0 .. n-1 as objects, once: the records' rows, and every row or
    # number that flattening keeps later (an element's first row, a template instance's
    # variable rows, alias hints, equation rows) refers to these instead of holding an
    # integer object of its own (32 bytes each; see `_Template.add`)
    ints = list(range(len(var_names)))
    base = len(variables)            # variables bound before (none in flatten)
    if not base:
        flat.__dict__["_ints"] = ints
    if type(variables) is _Variables:
        # each record formed when read (`_ColumnVariable`: one per variable)
        variables.extend_bulk(var_names, var_column, var_plain, var_owner, ints)
        record_at, first = variables.at, base
    else:
        records = list(map(_ColumnVariable, var_names, repeat(var_column), ints,
                           var_plain, var_owner))
        variables.update(zip(var_names, records))
        record_at, first = records.__getitem__, 0
    pi = vi = 0
    for el, params, plain, offsets in bound:
        if params:
            own_values = {}         # its parameters' values, read by its parts'
            # each parameter's symbol read from the column on first read
            syms = _ColumnSyms()
            owner = el._parent if isinstance(el, Connector) else el
            owner_path = owner._path_cache if owner is not None else ""
            # the row of each parameter in the column, in declaration order: its own,
            # or for a parameter passed on unchanged (R=R) its parent's; -1 for an
            # expression
            el_rows = list(range(pi, pi + len(params)))
            syms.par_store, syms.par_rows = par_store, el_rows
            syms.par_values = own_values
            syms.par_places = _parameter_places(type(el))
            for j, (key, decl) in enumerate(params):
                path = par_names[pi]
                row = el_rows[j]
                pi += 1
                raw = el._values.get(key, decl.default)
                if isinstance(raw, ParameterExpression):
                    sym, own_values[key], el_rows[j] = _bind_expression(
                        flat, el, key, decl, raw, problems, par_store)
                    if sym is not None:     # else read from the column by its row
                        syms[key] = sym
                    continue
                value = float("nan")
                if raw is None:
                    problems.add(ParameterError,
                                 f"{el.describe()}: parameter {key} has no value and no "
                                 f"default. Give one, e.g. {type(el).__name__}({key}=...).")
                else:
                    try:
                        value = raw if type(raw) is float else to_si(raw, decl.unit, path)
                    except UnitError as exc:
                        problems.add(UnitError, str(exc))
                    else:
                        _check_range(el, key, decl, value, problems)
                own_values[key] = value
                parameters[path] = _ColumnParameter(path, par_store, row, value, decl.unit,
                                                    decl.doc, owner_path,
                                                    (decl.min, decl.max))
        elif plain:
            syms = _ColumnSyms()
            syms.par_store, syms.par_rows, syms.par_places = None, (), _NO_PLACES
            syms.par_values = None
        else:
            syms = {}
        if plain:
            syms.column, syms.base, syms.offsets = var_column, ints[vi], offsets
            syms.row = base + vi if base else syms.base
            starts = el._starts
            if starts:
                for j, (key, _, unit, *_) in enumerate(plain):
                    given = starts.get(key)
                    if isinstance(given, Start):
                        record = record_at(first + vi + j)
                        try:
                            record.start = to_si(given.value, unit, record.name)
                        except UnitError as exc:
                            problems.add(UnitError, str(exc))
                        record.priority = given.priority
            vi += len(plain)
        elif params:        # parameters alone: no variables of its own
            syms.column, syms.base, syms.offsets, syms.row = None, 0, _NO_PLACES, -1
        el._syms = syms
    if type(ctx.unknowns) is not _Unknowns:
        ctx.unknowns = _Unknowns(variables, ctx.unknowns)
    if not base and len(variables) == len(var_names):   # the column holds them all
        flat.__dict__["_variable_stack"] = (len(var_names), var_column,
                                            _RowsOf(variables))


def _integers(shared: list, top: int):
    """The integers 0 .. ``top`` to index: ``shared`` (the objects `_bind_symbols`
    made, each held by a record) when it holds them all, else a range (whose items
    are made on reading, as any sum is)."""
    return shared if top < len(shared) else range(top + 1)


def _parameter_rows(syms) -> list | None:
    """The rows of an element's parameters in the column of the parameters (-1 for one
    bound to an expression), kept on its symbols (``_ColumnSyms.par_rows``: no
    dictionary of every element keyed by ``id``); None if it has none."""
    return (syms.par_rows or None) if type(syms) is _ColumnSyms else None


def _first_row(el, late: dict) -> int:
    """The row of ``el``'s first variable among the model's variables: kept on its
    symbols when bound in bulk (`_bind_symbols`), else in ``late`` (``flat._rows``,
    by ``id``: `_bind_variables`); -1 if it has none. A dictionary entry and two integers
    per element at 10^5 elements are what this saves."""
    syms = el._syms
    return syms.row if type(syms) is _ColumnSyms else late.get(id(el), -1)


def _bind_variables(flat, el, syms, prefix, owner_path, plain, problems) -> None:
    """Bind the variables of ``el`` one by one (a port bound on first read)."""
    variables = flat.variables
    flat.__dict__.setdefault("_rows", {})[id(el)] = len(variables)
    starts = el._starts
    for key, kind, unit, doc, start, priority, hint, select in plain:
        path = prefix + key
        sym = syms[key] = ca.SX.sym(path)
        given = starts.get(key) if starts else None
        if isinstance(given, Start):
            try:
                start = to_si(given.value, unit, path)
            except UnitError as exc:
                problems.add(UnitError, str(exc))
            priority = given.priority
        variables[path] = FlatVariable(path, sym, unit, doc, kind, owner_path, start,
                                       priority, hint, select)


class _Unknowns(dict):
    """The build context's unknowns (`BuildContext.unknowns`), name -> symbol: the
    model's variables read through ``flat.variables`` (no second dictionary of every
    variable), the others (derivatives) held here."""

    __slots__ = ("variables",)

    def __init__(self, variables: dict, others: dict):
        super().__init__(others)
        self.variables = variables

    def __missing__(self, name):
        return self.variables[name].sym

    def __contains__(self, name) -> bool:
        return dict.__contains__(self, name) or name in self.variables

    def get(self, name, default=None):
        if dict.__contains__(self, name):
            return dict.__getitem__(self, name)
        var = self.variables.get(name)
        return default if var is None else var.sym


# -- symbols in bulk ------------------------------------------------------------------------
# CasADi makes one named symbol per call (``SX.sym(name)``, about 3 us each from Python)
# and names the elements of a vector symbol ``name_0, name_1, ...``, while every symbol
# here must be named by its instance path (later passes look symbols up by name). A
# column of symbols with given names is read instead from CasADi's own serialized form
# of such a column (`casadi.SX.deserialize`), written here: a header with the column's
# sparsity, then one record per symbol holding its name. The layout is checked against
# ``SX.serialize`` once per process; if it ever differs, the symbols are made one by one.
_SX_HEADER = bytes.fromhex("79df0d8648700000030000000000000000") + b"d"
_SX_RECORD = b"d/" + bytes(7)
_BULK: list = []        # [True/False] once checked
_SYMBOLS_PER_TEXT = 32768   # names serialized at once by _symbols


def _serialized_column(names: list[str]) -> str:
    """CasADi's serialized text of the column of the symbols ``names``."""
    n = len(names)
    sparsity = np.concatenate([[4 + n, n, 1, 0, n], np.arange(n), [n]]).astype("<i8")
    data = np.frombuffer(_SX_HEADER + sparsity.tobytes() + _records(names),
                         dtype=np.uint8)
    text = np.empty(2 * data.size, dtype=np.uint8)     # each byte as two letters a-p,
    text[0::2] = (data & 15) + 97                      # low half first
    text[1::2] = (data >> 4) + 97
    return text.tobytes().decode("ascii")


def _records(names: list[str]) -> bytes:
    """The records of the symbols ``names``: each the fixed prefix, the length of the
    name in bytes (4 bytes, little-endian), the name (UTF-8). Names in ASCII (instance
    paths) are laid out by NumPy, without a Python step per name."""
    joined = "".join(names)
    if not joined.isascii():
        return b"".join([_SX_RECORD + len(raw).to_bytes(4, "little") + raw
                         for raw in [name.encode() for name in names]])
    n, head = len(names), len(_SX_RECORD) + 4
    length = np.fromiter(map(len, names), dtype=np.int64, count=n)
    start = np.zeros(n, dtype=np.int64)             # where each record starts
    np.cumsum(length[:-1] + head, out=start[1:])
    total = int(length.sum()) + head * n
    # each record's head (prefix, length) where `is_head` is set, the names elsewhere
    edge = np.zeros(total + 1, dtype=np.int8)
    edge[start] = 1
    edge[start + head] -= 1
    is_head = np.cumsum(edge[:-1], dtype=np.int8).view(bool)
    heads = np.empty((n, head), dtype=np.uint8)
    heads[:, :len(_SX_RECORD)] = np.frombuffer(_SX_RECORD, dtype=np.uint8)
    heads[:, len(_SX_RECORD):] = length.astype("<u4").view(np.uint8).reshape(n, 4)
    out = np.empty(total, dtype=np.uint8)
    out[is_head] = heads.ravel()
    out[~is_head] = np.frombuffer(joined.encode("ascii"), dtype=np.uint8)
    return out.tobytes()


def _bulk_ok() -> bool:
    if not _BULK:
        probes = (["a.b", "r1.p.v", "x" * 300], ["a.b", "\u00e9" * 3, "x" * 300])
        try:
            ok = all(_serialized_column(probe) == ca.vertcat(
                *[ca.SX.sym(n) for n in probe]).serialize() for probe in probes)
        except Exception:   # noqa: BLE001 - any failure: one call per symbol instead
            ok = False
        _BULK.append(ok)
    return _BULK[0]


def _symbols(names: list[str], split: bool = True) -> tuple[ca.SX, list[ca.SX] | None]:
    """The column of new symbols named ``names`` and its elements (None if not
    ``split``), in few CasADi calls."""
    if not names:
        return ca.SX(0, 1), []
    if len(names) > 8 and _bulk_ok():
        # in pieces: the text of a piece (a few MB) is made and freed again in the same
        # memory, where one text of a million names would be fresh pages every time
        step = _SYMBOLS_PER_TEXT
        column = stack_columns(*[ca.SX.deserialize(_serialized_column(names[k:k + step]))
                                 for k in range(0, len(names), step)])
        return column, ca.vertsplit(column) if split else None
    syms = [ca.SX.sym(n) for n in names]
    return ca.vertcat(*syms), syms


class _FoldedSymbols(dict):
    """The symbols of a port that may be folded (:mod:`mechatron.compiler.folding`):
    empty until an equation reads one, which binds the port's variables as any other
    port's and takes it off the folded ports."""

    __slots__ = ("shared", "port", "position", "order")

    def __init__(self, shared, port, position, order):
        self.shared = shared            # (flat, folded, problems)
        self.port = port
        # where its variables are declared: after this many model variables, and the
        # port's place in the tree (for ports at the same place)
        self.position = position
        self.order = order

    def unfold(self) -> None:
        flat, folded, problems = self.shared
        port = self.port
        if folded.pop(id(port), None) is None:
            return
        _, plain = _declaration_plan(type(port))
        before = len(flat.variables)
        _bind_variables(flat, port, self, f"{port.path}.", port._parent.path, plain,
                        problems)
        # bound late: put back in declaration order at the end of flattening
        flat.__dict__.setdefault("_late", []).append(
            (self.position, self.order, list(flat.variables)[before:]))

    def __missing__(self, key):
        self.unfold()
        return dict.__getitem__(self, key)


@functools.lru_cache(maxsize=None)
def _folded_plan(cls) -> tuple:
    """The keys, units and docs of a connector class's variables, and whether each is an
    across variable (once per class)."""
    plain = _declaration_plan(cls)[1]
    return tuple(tuple(e[k] for e in plain) for k in (0, 2, 3)) + \
        (tuple(e[1] == "across" for e in plain),)


@functools.lru_cache(maxsize=None)
def _declaration_plan(cls):
    """A class's parameters ``[(key, decl)]`` and variables with what flattening copies of
    each (kind, unit, doc, start, priority, hint, state_select), worked out once per class,
    in declaration order."""
    params, plain = [], []
    hint = (_class_hint(cls) or (cls.domain.hint if cls.domain else "")) \
        if issubclass(cls, Connector) else ""
    for key, decl in cls._declarations.items():
        if isinstance(decl, Parameter):
            params.append((key, decl))
            continue
        kind = ("across" if isinstance(decl, Across) else
                "through" if isinstance(decl, Through) else
                "input" if isinstance(decl, Input) else
                "output" if isinstance(decl, Output) else "variable")
        plain.append((key, kind, decl.unit, decl.doc, decl.start, decl.priority, hint,
                      getattr(decl, "state_select", "default")))
    return tuple(params), tuple(plain)


_NO_PLACES: dict = {}


@functools.lru_cache(maxsize=None)
def _parameter_places(cls) -> dict:
    """Each parameter key of ``cls`` -> its place among the class's parameters."""
    keys = _binding_plan(cls)[2]
    return dict(zip(keys, range(len(keys))))


@functools.lru_cache(maxsize=None)
def _binding_plan(cls):
    """`_declaration_plan` of ``cls`` with the keys of its parameters and variables."""
    params, plain = _declaration_plan(cls)
    var_keys = tuple(p[0] for p in plain)
    return params, plain, tuple(p[0] for p in params), var_keys, \
        dict(zip(var_keys, range(len(var_keys))))


def _bind_expression(flat, el, key, decl, expr, problems, store):
    """Bind ``el.key`` to an expression of its parent's parameters: the symbol is the
    expression of the parent's symbols, the value its value; units must agree. Returns
    ``(symbol, value, row)``: ``row`` is the parent parameter's row in the parameter
    column for a parameter passed on unchanged (``R=R``: the same symbol), else -1 (an
    expression, or a problem). A parameter passed on unchanged from a row comes back with
    the symbol None: the element's symbols read it from that column (``store``, its
    `ColumnRows`) when it is read at all (a template instance never reads it), and so
    does its record."""
    parent = el._parent
    if parent is None or parent._syms is None:
        problems.append(f"{_binding_where(el, key, expr)} refers to parameters of an "
                        f"enclosing component, but {el.describe()} has none. Give {key} "
                        "a value.")
        return ca.SX.nan(), float("nan"), -1
    missing, message, name = _binding_check(expr, type(parent), decl.unit)
    if missing:
        problems.append(f"{_binding_where(el, key, expr)}: {', '.join(missing)} is not a "
                        f"parameter of {parent.describe()}. Pass on parameters of the class "
                        "whose body declares the part.")
        return ca.SX.nan(), float("nan"), -1
    if message:
        problems.add(UnitError, f"{_binding_where(el, key, expr)}: {message}")
        return ca.SX.nan(), float("nan"), -1
    pvals = getattr(parent._syms, "par_values", None) or {}
    row = -1
    if name is not None:            # R=R: the parent's symbol and value themselves
        value = float(pvals.get(name, float("nan")))
        rows = _parameter_rows(parent._syms)
        if rows is not None:
            row = rows[_parameter_places(type(parent))[name]]
        if row >= 0:
            _check_range(el, key, decl, value, problems)
            # its record formed when read (FlatModel.bound_parameters); paths, not
            # elements: a flat model holds no element (no cycle through their symbols)
            flat.bindings.append((el._path_cache or "", key, decl, expr,
                                  parent._path_cache, store, row, value))
            return None, value, row
        sym = parent._syms[name]
    else:
        sym = expr.evaluate(lambda n: parent._syms[n])
        sym = sym if isinstance(sym, ca.SX) else ca.SX(sym)
        value = float(expr.evaluate(lambda n: pvals.get(n, float("nan"))))
    _check_range(el, key, decl, value, problems)
    flat.bindings.append(BoundParameter(
        _join(el._path_cache or "", key), sym, value, decl.unit, decl.doc,
        el._path_cache or "", _binding_text(flat, expr, parent._path_cache)))
    return sym, value, row


def _binding_text(flat, expr, parent_path: str | None) -> str:
    """``"(R / 2) of 'motor'"``: a binding as written and where its names are read."""
    return f"{_expression_text(expr)} of '{parent_path or flat.name}'"


def _row_bound(flat, owner: str, key, decl, expr, parent_path, store, row,
               value) -> BoundParameter:
    """The record of parameter ``key`` of the element at ``owner``, passed on unchanged
    from its parent at ``parent_path`` (see `_bind_expression`): the parent's symbol is
    row ``row`` of the column ``store``."""
    return _RowBoundParameter(_join(owner, key), store, row, value, decl.unit, decl.doc,
                              owner, _binding_text(flat, expr, parent_path))


def _binding_where(el, key, expr) -> str:
    """``"Resistor 'h.a': R = R"``: where a binding is, for a message."""
    return f"{el.describe()}: {key} = {_expression_text(expr)}"


_TEXTS: dict = {}
_CHECKS: dict = {}


def _binding_check(expr, parent_cls, unit: str) -> tuple:
    """``(missing, message, name)`` of ``expr`` read in ``parent_cls`` for a parameter in
    ``unit``: the names that are not parameters of the class, why the dimensions do not
    agree ("" if they do), and the parameter's name if ``expr`` is just that parameter.
    Worked out once per expression, class and unit (the entry holds ``expr``, so that its
    id stays unique)."""
    key = (id(expr), parent_cls, unit)
    got = _CHECKS.get(key)
    if got is None:
        decls = parent_cls._declarations
        missing = [n for n in expr.names if not isinstance(decls.get(n), Parameter)]
        message = "" if missing else _binding_dimensions(expr, parent_cls, unit)
        got = _CHECKS[key] = (expr, (missing, message, _plain_reference(expr)))
    return got[1]


def _plain_reference(expr):
    """The parent parameter's name if ``expr`` is that parameter itself (``R=R``), else
    None, read from what it evaluates to (cached by `_binding_check`)."""
    names = expr.names
    if len(names) == 1:
        marker = object()
        try:
            if expr.evaluate(lambda n: marker) is marker:
                return names[0]
        except TypeError:           # arithmetic on the marker: an expression
            pass
    return None


def _expression_text(expr) -> str:
    """``expr.text``, formatted once per expression (shared by every copy of a part)."""
    got = _TEXTS.get(id(expr))
    if got is None or got[0] is not expr:
        got = _TEXTS[id(expr)] = (expr, expr.text)
    return got[1]


_BINDING_CHECKS: dict = {}


def _binding_dimensions(expr, parent_cls, unit: str) -> str:
    """Why ``expr``, read in ``parent_cls``, cannot give a value in ``unit`` ("" if it
    can). One pint evaluation per template and parent class, however many instances."""
    key = (id(expr), parent_cls, unit)
    if key in _BINDING_CHECKS:
        return _BINDING_CHECKS[key][1]
    decls = parent_cls._declarations
    try:
        got = ureg.Quantity(expr.evaluate(lambda n: ureg.Quantity(1.0, decls[n].unit)))
        message = ""
        if got.dimensionality != dimensionality(unit):
            message = (f"the expression is in {got.units:~} "
                       f"({got.dimensionality or 'dimensionless'}), the parameter in "
                       f"{unit} ({dimensionality(unit) or 'dimensionless'}). Pass on a "
                       "parameter of the same dimension.")
    except Exception as exc:  # noqa: BLE001 - pint's dimension errors, reported
        message = f"{exc}."
    _BINDING_CHECKS[key] = (expr, message)     # holds expr: its id stays unique
    return message


def _external_inputs(flat: FlatModel, model: Component) -> None:
    """The root component's own signal inputs are the model's external inputs (as a
    top-level ``input`` of Modelica or a root Inport of Simulink). Each one gets a
    parameter slot ``p_u`` (named like the input; its default is the input's start value,
    0 without one, which ``simulate`` then asks for) and the equation ``u == p_u``; ``u``
    stays a logged variable."""
    for key, decl in type(model)._declarations.items():
        if not isinstance(decl, Input):
            continue
        var = flat.variables[key]
        default = var.start if var.start is not None else 0.0
        # a distinct symbol name: symbols are looked up by name in later passes
        sym = ca.SX.sym(f"{key}#input")
        flat.parameters[key] = FlatParameter(key, sym, float(default), var.unit, var.doc,
                                             "", (None, None), is_input=True)
        flat.equations.append(FlatEquation(var.sym - sym, f"{key} == external input {key}",
                                           ""))


def _check_range(el, key, decl, value, problems) -> None:
    if value != value:
        problems.add(ParameterError, f"{el.describe()}: {key} is NaN.")
    if decl.min is not None and value < decl.min:
        problems.add(ParameterError,
                     f"{el.describe()}: {key} must be >= {decl.min:g}, got {value:g}.")
    if decl.max is not None and value > decl.max:
        problems.add(ParameterError,
                     f"{el.describe()}: {key} must be <= {decl.max:g}, got {value:g}.")


@functools.lru_cache(maxsize=None)
def _own_methods(cls, method: str) -> tuple:
    """``(klass, function)`` of each class in ``cls``'s MRO (bases first, Component left
    out) that defines ``method`` itself: read once per class."""
    return tuple((klass, vars(klass)[method]) for klass in reversed(cls.__mro__)
                 if method in vars(klass) and klass is not Component)


def _class_calls(el, method: str, where: str):
    """``(klass, result)`` of each class's own ``method`` (``equations``,
    ``initial_equations``) on ``el``, parents first, each class once (Modelica's
    ``extends``); a failure inside is a ModelError naming the component and class."""
    for klass, own in _own_methods(type(el), method):
        try:
            items = own(el)
        except ModelError:
            raise
        except Exception as exc:
            raise ModelError(f"{el.describe()}: {klass.__name__}.{method}() failed: "
                             f"{type(exc).__name__}: {exc}", path=where) from exc
        yield klass, items


def _collect_equations(flat: FlatModel, elements, problems,
                       planned=None) -> list[tuple[Connect, str]]:
    """The equations of the components among ``elements`` (in tree order; `flatten`
    passes the components alone) into ``flat``; returns the connects they write, each
    with its writer."""
    connects = []
    templates: dict = {}           # class -> _Template, or None where none applies
    components = []
    for el in elements:
        if isinstance(el, Component):
            if planned and id(el) in planned:
                # wired by its class's plan (folding): met below only for its time scales
                if planned[id(el)][1].has_time_scales:
                    components.append((el, None, True))
            else:
                components.append((el, _template(flat, el, templates), False))
    ders = _template_derivatives(components)
    if ders:
        flat.__dict__["_derivative_column"] = (ders.column, ders.syms)
    for el, tpl, is_planned in components:
        where = el._path_cache or flat.name
        if is_planned:                      # a planned instance with time scales
            flat.time_scales.extend(ca.SX(s) for s in el.time_scales())
            continue
        if tpl is not None:
            if "equations" in vars(type(el)) and _has_time_scales(type(el)):
                flat.time_scales.extend(ca.SX(s) for s in el.time_scales())
            tpl.add(flat, el, ders)
            continue
        for klass, items in _class_calls(el, "equations", where):
            if klass is type(el):
                flat.time_scales.extend(ca.SX(s) for s in el.time_scales())
            for k, item in enumerate(_as_equations(items)):
                if isinstance(item, Connect):
                    connects.append((item, el))
                    continue
                if isinstance(item, EventAction):
                    flat.events.append((item, el.path))
                    continue
                _add_equation(flat, el, klass, k, item, problems)
    for tpl in templates.values():
        if tpl is not None:
            tpl.defer(flat)
    _discrete_states(flat, problems)
    pending = [eq for eq in _held(flat.equations)
               if type(eq) is not _TemplateEquation and eq.residual is None]
    if pending:
        res = ca.vertcat(*[eq.origin.lhs for eq in pending]) - \
            ca.vertcat(*[eq.origin.rhs for eq in pending])
        for eq, r in zip(pending, ca.vertsplit(res)):
            eq.residual = r
    return connects


class _Derivatives(dict):
    """Derivative symbols made in bulk for the template instances, ``{variable name:
    row}`` in ``column``, each symbol in ``syms`` (see `_template_derivatives`)."""

    __slots__ = ("column", "syms")


def _template_derivatives(components) -> dict:
    """The derivative symbols the template instances among ``components`` ``(element,
    template, planned)`` will take, made in one call (`_Derivatives`); each is
    registered with the build context (`BuildContext.der_symbol`) only when its
    instance is added, so that the context lists derivatives in the order they are met,
    and its row is kept for `_Template.instantiate`, which takes the instances'
    derivatives from the column by their rows."""
    names = []
    for el, tpl, _ in components:
        if tpl is not None and tpl.derived:
            rel = tpl.relative
            path = el._path_cache
            if path:
                names.extend([path + rel[i] for i in tpl.derived])
            else:
                names.extend([rel[i][1:] for i in tpl.derived])
    if not names:
        return {}
    out = _Derivatives(zip(names, range(len(names))))
    out.column, out.syms = _symbols([f"der({n})" for n in names])
    return out


@functools.lru_cache(maxsize=None)
def _has_time_scales(cls) -> bool:
    """Whether ``cls`` overrides `Component.time_scales` (which has none)."""
    return cls.time_scales is not Component.time_scales


# -- one expression graph per component class ------------------------------------------------
_PLAIN_KEYS = frozenset(("doc", "_name", "_parent", "_values", "_starts", "_syms",
                         "_children", "_path_cache"))
_TEMPLATE_PREFIX = "@"        # template symbols are named "@.<key>", "@.<port>.<key>"


class _Template:
    """The equations of a component class, written once over symbols of its own
    (``@.v``, ``@.p.i``, ``@.R``, ``der(@.i)``) and instantiated for every instance of
    the class by one mapped CasADi function: one expression graph built per class,
    not one Python call per scalar operation per instance (issue 17).

    Used for a class whose instances cannot differ in their equations: no attributes
    beyond the declared ones, equations that are plain ``==`` over the component's own
    variables, parameters, ports, their derivatives and time (no connections, events,
    ``pre``, or variables of its parts). Any other class is flattened instance by
    instance, as before."""

    __slots__ = ("keys", "ports", "derived", "svec", "lhs", "rhs", "fun", "instances",
                 "n_eq", "aliases", "relative", "var_slots", "paths",
                 "var_rows", "bases", "hints", "root_hints", "par_slots", "par_bases",
                 "row_hints", "row_bases", "column", "var_column", "model_name",
                 "slots", "slot_keys", "der_rows", "der_column", "par_column",
                 "pending", "replaced", "first")

    def __init__(self, keys, ports, derived, syms, lhs, rhs, variables, var_rows=None,
                 par_slots=(), model_name=""):
        self.keys = keys            # own declaration keys, in template order
        self.ports = ports          # [(port name, [keys])]
        self.derived = derived      # template positions whose derivative appears
        self.svec = ca.vertcat(*syms)
        self.lhs, self.rhs = lhs, rhs
        self.n_eq = len(lhs)
        residuals = ca.vertcat(*lhs) - ca.vertcat(*rhs) if lhs else ca.SX(0, 1)
        self.fun = ca.Function("template", [self.svec], [residuals])
        self.instances: list = []   # SX column of each instance's symbols
        self.paths: list = []       # each instance's path
        #: every instance's residuals stacked, instance after instance (`instantiate`)
        self.column: ca.SX | None = None
        #: the model whose variables the instances read, while their residuals are not
        #: formed yet: alias elimination forms them from its replacements (`defer`)
        self.pending: FlatModel | None = None
        #: whether alias elimination formed the residuals (`column` then holds its
        #: replacements and the rows it keeps, if any): each residual as written is
        #: then formed alone when read (`own_row`)
        self.replaced = False
        #: the first instance's residuals alone, for the dimension check (`first_rows`)
        self.first: ca.SX | None = None
        #: the column of the variables that instances' rows refer to (see `add`)
        self.var_column: ca.SX | None = None
        self.model_name = model_name   # where an equation of the root is
        #: each slot of `relative` as (which symbols: 0 the element's, 1 + j port j's;
        #: key), and as (is a variable, which, its row after the first variable's if a
        #: variable, else its key): how `add` reads an instance's arguments
        self.slot_keys = [(0, k) for k in keys] + \
            [(1 + j, k) for j, (_, ks) in enumerate(ports) for k in ks]
        self.slots = [(True, *var_rows[i]) if var_rows is not None and i in var_rows
                      else (False, w, k) for i, (w, k) in enumerate(self.slot_keys)]
        #: each instance's first rows in the model's variables, its own then its ports',
        #: one instance after the other
        self.bases: list = []
        # each slot's path relative to the instance, and the alias pattern of each
        # equation over the slots (read once here, not once per instance)
        self.relative = [f".{k}" for k in keys] + \
            [f".{port}.{k}" for port, ks in ports for k in ks]
        index = {s.name(): i for i, s in enumerate(syms)}
        # which of the slots of self.relative are variables (not parameters)
        self.var_slots = [syms[i].name() in variables for i in range(len(self.relative))]
        #: for each variable slot, (which base: 0 own, 1 + j port j; row after it)
        self.var_rows = var_rows
        #: the parameter slots, each the same row after the element's first parameter
        self.par_slots = par_slots
        self.par_bases: list = []   # each instance's parameter rows (-1: not known)
        #: the column of the parameters that instances' parameter rows refer to
        self.par_column: ca.SX | None = None
        #: each instance's derivatives by their rows in `der_column` (made in bulk, see
        #: `_template_derivatives`), -1 for a derivative made otherwise
        self.der_rows: list = []
        self.der_column: ca.SX | None = None
        self.aliases = [_alias_pattern(r, index, variables)
                        for r in ca.vertsplit(residuals)] if lhs else []
        rel = self.relative
        # the alias hints by path relative to an instance (".v"), and for the root
        self.hints = [p if p[0] == "none" else
                      ("pair", rel[p[1]], rel[p[2]], p[3]) if p[0] == "pair"
                      else ("const", rel[p[1]], p[2]) for p in self.aliases]
        self.root_hints = [h if h[0] == "none" else
                           (h[0], h[1][1:], h[2][1:], h[3]) if h[0] == "pair" else
                           (h[0], h[1][1:], h[2]) for h in self.hints]
        # and by the place of each variable among the element's and its ports' (which
        # base, row after it): an instance whose variables were bound in bulk gives its
        # hints as variable numbers, without forming their paths (see `add`)
        self.row_hints = None
        read = [i for p in self.aliases if p[0] == "pair" for i in p[1:3]] + \
            [p[1] for p in self.aliases if p[0] == "const"]
        if var_rows is not None and all(i in var_rows for i in read):
            self.row_hints = [p if p[0] == "none" else
                              ("pair", *var_rows[p[1]], *var_rows[p[2]], p[3])
                              if p[0] == "pair" else ("const", *var_rows[p[1]], p[2])
                              for p in self.aliases]
            self.row_bases = sorted({var_rows[i][0] for i in read})    # bases read

    def add(self, flat: FlatModel, el, ders=None) -> None:
        """Add the instance ``el``; ``ders`` holds derivative symbols made beforehand
        (`_template_derivatives`), by variable name."""
        syms = el._syms
        children = el._children
        state = flat.__dict__
        late = state.get("_rows", {})
        shared = state.get("_ints", ())        # the integers of `_bind_symbols`
        bases = self.bases
        bases.append(_first_row(el, late))
        ports = [children[port] for port, _ in self.ports]
        bases.extend([_first_row(port, late) for port in ports])
        own = [syms] + [port._syms for port in ports]
        column = getattr(syms, "column", None)
        if self.var_rows is not None and column is not None and \
                (self.var_column is None or column is self.var_column) and \
                all(type(s) is _ColumnSyms and s.column is column for s in own):
            # variables bound in bulk: each variable slot holds the variable's row in
            # their column (`symbols` forms the symbols if a message needs them;
            # `instantiate` takes them from the model's column by the rows in `bases`)
            base = [s.base for s in own]
            ints = _integers(shared, column.numel() - 1)
            # and each parameter slot laid out as bound (`par_slots`, the first ones)
            # the parameter's row in the column of the parameters, if it has one
            prows = _parameter_rows(syms) if self.par_slots else None
            k = len(self.par_slots) if prows is not None else 0
            args = [ints[base[w] + x] if is_var else
                    prows[i] if i < k and prows[i] >= 0 else own[w][x]
                    for i, (is_var, w, x) in enumerate(self.slots)]
            if k:
                self.par_column = state["_parameter_column"]
            self.var_column = column
        else:
            args = [own[w][k] for w, k in self.slot_keys]
        owner = el._path_cache
        if self.derived:
            rel = self.relative
            names = [owner + rel[i] for i in self.derived] if owner else \
                [rel[i][1:] for i in self.derived]
            ctx = flat.context
            der_rows = self.der_rows
            for name in names:
                sym = ctx.derivative.get(name)
                k = -1
                if sym is None:
                    k = ders.pop(name, -1) if ders else -1
                    if k < 0:
                        sym = ctx.der_symbol(name)
                    else:                   # as der_symbol registers a new one
                        sym = ders.syms[k]
                        key = f"der({name})"
                        ctx.derivative[name] = sym
                        ctx.integral[key] = name
                        ctx.unknowns[key] = sym
                        self.der_column = ders.column   # one column per flattening
                der_rows.append(k)
                args.append(sym)
        args.append(flat.context.time)
        self.instances.append(args)
        self.paths.append(owner)
        if self.par_slots:
            prows = _parameter_rows(syms)
            self.par_bases.append(-1 if prows is None else prows)
        first = (len(self.instances) - 1) * self.n_eq     # this instance's first row
        if self.n_eq:
            equations = flat.equations
            if type(equations) is FlatEquations:    # held as numbers, hints by `hint`
                equations.add_rows(self, first, first + self.n_eq,
                                   _integers(shared, first + self.n_eq - 1))
            else:
                equations += map(self.equation, range(first, first + self.n_eq))
        if self.derived and self.var_rows is not None:
            base = bases[-1 - len(self.ports):]
            # each differentiated variable's row among the model's variables (its
            # element's first row and its place after it), read by alias elimination
            # and the dimension check instead of its name
            slots = self.slots
            noted = [(name, base[slots[i][1]] + slots[i][2], k) for name, i, k
                     in zip(names, self.derived, der_rows[len(der_rows) - len(names):])
                     if slots[i][0] and base[slots[i][1]] >= 0]
            state.setdefault("_derivative_rows", {}).update(
                [(name, row) for name, row, _ in noted])
            # and, for a derivative made in bulk, its row in the column of those
            # (`FlatModel.derivatives_by_row`)
            state.setdefault("_derivative_bulk", []).extend(
                [(row, k) for _, row, k in noted if k >= 0])

    def equation(self, row: int) -> _TemplateEquation:
        """The equation of row ``row`` (instance after instance), with its alias hint
        (`hint`)."""
        return _TemplateEquation(self, self.paths[row // self.n_eq], self.hint(row), row)

    def hint(self, row: int) -> tuple:
        """The alias hint of row ``row``: by variable number (its row in the model's
        variables) where the instance's variables were bound in bulk, else by path."""
        instance, k = divmod(row, self.n_eq)
        width = 1 + len(self.ports)
        base = self.bases[instance * width:(instance + 1) * width]
        if self.row_hints is not None and all(base[w] >= 0 for w in self.row_bases):
            h = self.row_hints[k]
            return h if h[0] == "none" else \
                ("pair", base[h[1]] + h[2], base[h[3]] + h[4], h[5]) if h[0] == "pair" \
                else ("const", base[h[1]] + h[2], h[3])
        owner = self.paths[instance]
        if not owner:
            return self.root_hints[k]
        h = self.hints[k]
        return h if h[0] == "none" else ("pair", owner + h[1], owner + h[2], h[3]) \
            if h[0] == "pair" else ("const", owner + h[1], h[2])

    def hint_arrays(self) -> tuple:
        """The alias hints of every row (see `hint`) as arrays ``(tag, a, b, s)``: tag 0
        for none, 1 for a pair ``a == s*b``, 2 for a constant ``a == s`` (a, b variable
        numbers), 3 for a hint by path (read with `hint`, row by row)."""
        n, m = len(self.paths), self.n_eq
        tag = np.zeros((n, m), dtype=np.int8)
        a = np.zeros((n, m), dtype=np.int64)
        b = np.zeros((n, m), dtype=np.int64)
        s = np.zeros((n, m))
        numbered = np.zeros(n, dtype=bool)
        if self.row_hints is not None:
            bases = np.array(self.bases, dtype=np.int64).reshape(n, -1)
            numbered = (bases[:, self.row_bases] >= 0).all(axis=1)
            for k, h in enumerate(self.row_hints):
                if h[0] == "pair":
                    tag[:, k] = 1
                    a[:, k], b[:, k] = bases[:, h[1]] + h[2], bases[:, h[3]] + h[4]
                    s[:, k] = h[5]
                elif h[0] == "const":
                    tag[:, k] = 2
                    a[:, k], s[:, k] = bases[:, h[1]] + h[2], h[3]
        by_path = [k for k, h in enumerate(self.hints) if h[0] != "none"]
        if by_path and not numbered.all():
            tag[np.ix_(~numbered, by_path)] = 3
        return tag.ravel(), a.ravel(), b.ravel(), s.ravel()

    def defer(self, flat: FlatModel) -> None:
        """Leave the instances' residuals unformed until something reads them: alias
        elimination forms them once, on its replacements of the instances' variables
        (`instantiate` with ``old``, ``new``), and only the rows it keeps. Formed on
        the variables themselves and substituted afterwards, every residual would be
        built twice, the whole model's graph walked once more, and the first graph
        freed."""
        if self.instances and self.n_eq and self.column is None:
            self.pending = flat
            flat.__dict__.setdefault("_pending_templates", []).append(self)

    def formed(self) -> ca.SX | None:
        """`column`, formed on the instances' own variables if it was deferred."""
        if self.column is None and self.pending is not None:
            self.instantiate(self.pending)
        return self.column

    def first_rows(self) -> ca.SX:
        """The first instance's residuals as written (rows ``0 .. n_eq - 1`` of the
        column of all), without forming the others."""
        if self.column is not None and not self.replaced:
            return self.column
        if self.first is None:
            self.first = self._written(0)
        return self.first

    def own_row(self, row: int) -> ca.SX:
        """The residual of equation ``row`` as written, on its instance's variables."""
        instance, k = divmod(row, self.n_eq)
        return (self.first_rows() if instance == 0 else self._written(instance))[k]

    def _written(self, instance: int) -> ca.SX:
        """The residuals of instance ``instance`` as written, formed alone."""
        return self.fun(ca.vertcat(*self.symbols(self.instances[instance])))

    def instantiate(self, flat: FlatModel, replaced=None, rows: list | None = None) -> None:
        """Every instance's residuals from one call of the mapped function; with
        ``replaced`` (alias elimination's `mechatron.compiler.alias.Replacements`), on
        the instances' arguments with the eliminated variables replaced, and with
        ``rows`` (sorted), only those rows of each instance."""
        self.pending = None
        n = len(self.instances)
        if not n or not self.n_eq:
            return
        width = self.svec.numel()
        parts = self._columns(flat, n, width, replaced)
        if parts is None:
            flat_args = [a for args in self.instances for a in self.symbols(args)]
            fun, inputs = self.fun, [ca.reshape(ca.vertcat(*flat_args), width, n)]
            if replaced is not None:
                inputs = ca.substitute(inputs, [replaced.old], [replaced.new])
        else:
            fun, inputs = self._split(*parts)
        if replaced is not None:
            self.replaced = True
        if rows is not None and len(rows) < self.n_eq:
            args = fun.sx_in()
            fun = ca.Function("template_rows", args, [fun(*args)[rows]])
            self.replaced = True
        out = fun.map(n)(*inputs) if n > 1 else fun(*inputs)
        self.column = ca.vec(out)       # column-major: instance after instance

    def _split(self, inputs: list, order: list) -> tuple:
        """The template's function taking ``inputs`` as they are (each a block of rows,
        the slots of ``order`` one after the other) instead of one column in the order
        of its slots; and those inputs. Stacking the blocks and putting their rows in
        slot order would copy every argument of every instance twice more."""
        blocks = [ca.SX.sym(f"in{k}", part.size1()) for k, part in enumerate(inputs)]
        position = [0] * len(order)
        for r, i in enumerate(order):
            position[i] = r
        fun = ca.Function("template_in_blocks", blocks,
                          [self.fun(ca.vertcat(*blocks)[position])])
        return fun, inputs

    def release(self) -> None:
        """Let go of what only instantiation and alias elimination read (the residuals
        of every instance, before alias substitution, and the rows of the instances'
        elements); what messages read stays (`_TemplateOrigin`)."""
        self.column = self.pending = self.first = None
        self.replaced = False
        self.bases = []

    def symbols(self, args: list) -> list:
        """An instance's arguments as symbols: a slot that holds a row (see `add`) read
        from the column of the parameters (the parameter slots, first) or of the
        variables."""
        k = len(self.par_slots)
        return [a if type(a) is not int else self.par_column[a] if i < k
                else self.var_column[a] for i, a in enumerate(args)]

    def _columns(self, flat: FlatModel, n: int, width: int, replaced=None):
        """The instances' arguments in blocks of rows, each block one row per slot and
        one column per instance, and the slots the blocks' rows hold, in order (see
        `_split`). The variable slots are taken from the model's stacked variable
        symbols (`FlatModel.stack_variables`) by the rows of each instance's variables,
        recorded as they were bound; the parameters likewise from the column of the
        parameters, the derivatives from theirs; time is one row for all instances.
        With ``replaced`` (`mechatron.compiler.alias.Replacements`), the eliminated
        variables replaced: the variable slots gathered from its column of replaced
        variables, the derivatives substituted, and, if the parameters' rows are not
        known, the other arguments substituted. None if the rows of the variables are
        not known (then the caller stacks every argument)."""
        slots = [i for i in range(len(self.relative)) if self.var_slots[i]]
        if not slots or self.var_rows is None:
            return None
        bases = np.array(self.bases, dtype=np.int64).reshape(n, -1)
        which = np.array([self.var_rows[i][0] for i in slots], dtype=np.int64)
        offset = np.array([self.var_rows[i][1] for i in slots], dtype=np.int64)
        if (bases[:, which] < 0).any():
            return None
        rows = (bases[:, which] + offset).ravel()
        column = flat.stack_variables() if replaced is None else replaced.variables
        if rows.max() >= column.numel():
            return None
        var_part = ca.reshape(column[rows.tolist()], len(slots), n)
        others = [i for i in range(width) if i >= len(self.relative) or
                  not self.var_slots[i]]
        par_slots = list(self.par_slots)
        k = len(par_slots)
        parameters = flat.__dict__.get("_parameter_column")
        par_rows = None
        if k and parameters is not None and all(isinstance(b, list) for b in self.par_bases):
            par_rows = np.array([b[:k] for b in self.par_bases], dtype=np.int64)
        if par_rows is not None and (par_rows >= 0).all():
            # parameters by their rows, time as one row, only derivatives stacked
            rows = par_rows.ravel()
            ders = [i for i in others if i not in par_slots and i != width - 1]
            parts = [var_part, ca.reshape(parameters[rows.tolist()], len(par_slots), n)]
            if ders:
                bulk = ders == list(range(len(self.relative), width - 1)) and \
                    min(self.der_rows) >= 0
                part = ca.reshape(
                    self.der_column[self.der_rows] if bulk else ca.vertcat(
                        *[args[i] for args in self.instances for i in ders]),
                    len(ders), n)
                if replaced is not None and replaced.der_old is not None:
                    part = ca.substitute(part, replaced.der_old, replaced.der_new)
                parts.append(part)
            parts.append(flat.context.time)     # the same for every instance
            order = slots + par_slots + ders + [width - 1]
        else:
            every = [self.symbols(args) for args in self.instances]
            rest = ca.vertcat(*[args[i] for args in every for i in others])
            if replaced is not None:
                rest = ca.substitute(rest, replaced.old, replaced.new)
            parts = [var_part, ca.reshape(rest, len(others), n)]
            order = slots + others          # the rows of the parts hold these slots
        return parts, order


def _alias_pattern(r: ca.SX, index: dict, variables: set) -> tuple:
    """What `mechatron.compiler.alias.eliminate_aliases` reads off a residual, over
    template slots: ("pair", slot_a, slot_b, s) for a == s*b, ("const", slot, value)
    for a == value, else ("none",). The same rules as that pass, applied once per
    class."""
    def signed(expr):
        sign = 1.0
        while expr.is_op(ca.OP_NEG):
            expr, sign = expr.dep(0), -sign
        if expr.is_symbolic() and expr.name() in variables:
            return index[expr.name()], sign
        return None

    if r.is_op(ca.OP_SUB) or r.is_op(ca.OP_ADD):
        lhs, rhs = r.dep(0), r.dep(1)
        sign = -1.0 if r.is_op(ca.OP_SUB) else 1.0
        la, ra = signed(lhs), signed(rhs)
        if la and ra:
            return ("pair", la[0], ra[0], -sign * ra[1] / la[1])
        if la and rhs.is_constant():
            return ("const", la[0], -sign * float(rhs) / la[1])
        if ra and lhs.is_constant():
            return ("const", ra[0], -float(lhs) / (sign * ra[1]))
        return ("none",)
    one = signed(r)
    if one:
        return ("const", one[0], 0.0)
    return ("none",)


class _TemplateOrigin:
    """Origin of an equation instantiated from a `_Template`; its sides are formed (by
    substitution) only when a message needs them."""

    __slots__ = ("where", "template", "args", "k")

    def __init__(self, where, template, args, k):
        self.where, self.template, self.args, self.k = where, template, args, k

    def _side(self, expr):
        return ca.substitute(expr, self.template.svec,
                             ca.vertcat(*self.template.symbols(self.args)))

    @property
    def lhs(self):
        return self._side(self.template.lhs[self.k])

    @property
    def rhs(self):
        return self._side(self.template.rhs[self.k])

    def __str__(self) -> str:
        return f"{self.where}: {_short(self.lhs)} == {_short(self.rhs)}"

    __repr__ = __str__


def _template(flat: FlatModel, el, templates: dict):
    """The `_Template` of ``el``'s class, built from ``el`` on first use; None if the
    class does not qualify (see `_Template`)."""
    cls = type(el)
    if el.__dict__.keys() - _PLAIN_KEYS - el._children.keys():
        return None                 # instance attributes: equations may differ
    if cls in templates:
        return templates[cls]
    templates[cls] = None
    if not all(isinstance(c, Connector) and not c._children for c in el._children.values()):
        return None                 # parts: equations may name their variables
    if not hasattr(cls, "equations") or cls.equations is Component.equations:
        return None
    saved = el._syms
    tsyms = {}
    keys = list(_filled(saved))
    own = []
    for k in keys:
        tsyms[k] = ca.SX.sym(f"{_TEMPLATE_PREFIX}.{k}")
        own.append(tsyms[k])
    ports = []
    port_saved = {}
    for name, c in el._children.items():
        port_saved[name] = _filled(c._syms)
        csyms = {k: ca.SX.sym(f"{_TEMPLATE_PREFIX}.{name}.{k}") for k in c._syms}
        ports.append((name, list(c._syms)))
        own.extend(csyms.values())
        c._syms = csyms
    variables = {s.name() for k, s in tsyms.items()
                 if not isinstance(cls._declarations.get(k), Parameter)}
    variables |= {s.name() for s in own[len(keys):]}
    tctx = BuildContext()
    tctx.time = flat.context.time
    tctx.unknowns = {s.name(): s for s in own if s.name() in variables}
    el._syms = tsyms
    lhs, rhs = [], []
    try:
        with tctx:
            for klass, items in _class_calls(el, "equations", el.path or flat.name):
                for item in _as_equations(items):
                    if not isinstance(item, ca.SX):
                        return None
                    for j in range(item.numel()):
                        e = item if item.is_scalar() else item[j]
                        if not e.is_op(ca.OP_EQ):
                            return None
                        lhs.append(e.dep(0))
                        rhs.append(e.dep(1))
    except ModelError:
        return None
    finally:
        el._syms = saved
        for name, c in el._children.items():
            c._syms = port_saved[name]
    if tctx.pre or tctx.special:
        return None
    index = {s.name(): i for i, s in enumerate(own)}
    derived, ders = [], []
    for name, d in tctx.derivative.items():
        if name not in index:       # der(der(x)): left to the instance-by-instance path
            return None
        derived.append(index[name])
        ders.append(d)
    allowed = set(index) | {d.name() for d in ders} | {flat.context.time.name()}
    if lhs and any(s.name() not in allowed
                   for s in ca.symvar(ca.vertcat(*lhs, *rhs))):
        return None
    # a parameter bound to an expression of the parent's parameters (Resistor(R=R/2))
    # fills its slot with that expression
    # the row of each variable slot after its element's first variable
    var_rows = {}
    own_vars = [p[0] for p in _declaration_plan(cls)[1]]
    for i, k in enumerate(keys):
        if k in own_vars:
            var_rows[i] = (0, own_vars.index(k))
    i = len(keys)
    for j, (name, ks) in enumerate(ports):
        port_vars = [p[0] for p in _declaration_plan(type(el._children[name]))[1]]
        for k in ks:
            var_rows[i] = (1 + j, port_vars.index(k))
            i += 1
    # parameter slots: the first keys, in the order of the class's parameters
    par_keys = [p[0] for p in _declaration_plan(cls)[0]]
    par_slots = tuple(i for i, k in enumerate(keys) if k in par_keys)
    if [keys[i] for i in par_slots] != par_keys[:len(par_slots)] or \
            list(par_slots) != list(range(len(par_slots))):
        par_slots = ()                  # not laid out as bound: stacked one by one
    tpl = _Template(keys, ports, derived, own + ders + [flat.context.time], lhs, rhs,
                    variables, var_rows, par_slots, flat.name)
    templates[cls] = tpl
    return tpl


def _filled(syms):
    """``syms`` with every symbol read (see `_ColumnSyms.filled`)."""
    return syms.filled() if type(syms) is _ColumnSyms else syms


def _discrete_states(flat: FlatModel, problems) -> None:
    """Check the targets of event actions; a target not differentiated anywhere is a
    discrete state: constant between events, ``der(v) == 0``."""
    ctx = flat.context
    by_sym = flat.variables          # a variable's symbol is named by its path
    done: set[str] = set()
    for action, owner in flat.events:
        for var, _ in action.outputs + action.updates:
            name = var.name() if var.is_scalar() and var.is_symbolic() else None
            fv = by_sym.get(name) if name else None
            if fv is None or fv.kind == "input":
                problems.append(f"{owner or flat.name}: an event action assigns "
                                f"{str(var)[:40]}, which is not a variable of the model. "
                                "Assign a Variable or Output of the component.")
                continue
            if name in done or name in ctx.derivative:
                continue
            done.add(name)
            flat.equations.append(FlatEquation(
                ctx.der_symbol(name), f"{owner or flat.name}: der({name}) == 0 "
                "(discrete state, changed only by events)", owner))


def _add_equation(flat, el, klass, k, item, problems) -> None:
    where = el.path or flat.name
    if isinstance(item, (bool, int, float)) or not isinstance(item, (ca.SX, ca.DM)):
        problems.append(f"{el.describe()}: equation {k + 1} of {klass.__name__} is "
                        f"{item!r}, not an equation. Write equations with == between "
                        "expressions of variables.")
        return
    if not isinstance(item, ca.SX):
        item = ca.SX(item)
    for j in range(item.numel()):
        e = item if item.is_scalar() else item[j]
        if not e.is_op(ca.OP_EQ):
            problems.append(f"{el.describe()}: equation {k + 1} of {klass.__name__} is not "
                            f"an equation ({str(e)[:60]}). Write it with ==.")
            continue
        lhs, rhs = e.dep(0), e.dep(1)
        # the residual lhs - rhs is formed in bulk once all equations are in
        flat.equations.append(FlatEquation(None, _Origin(where, lhs, rhs), el.path))


def _short(expr, limit: int = 80) -> str:
    text = str(expr)
    return text if len(text) <= limit else text[:limit - 3] + "..."


def _signal_owners(elements) -> dict[str, SignalRef]:
    """Each signal of the tree by the name of its bound symbol (its path): what a
    ``connect`` given symbols instead of ports resolves them by (`_resolve`). Formed
    only when a connect needs it, not on every compile (a walk over every element)."""
    return {f"{el.path}.{key}" if el.path else key: SignalRef(el, key)
            for el in elements for key in _signal_keys(type(el))}


def _resolve(flat: FlatModel, port, sym_owner):
    """A Connector, a SignalRef, or a bound signal symbol -> Connector or SignalRef."""
    if isinstance(port, (Connector, SignalRef)):
        return port
    if isinstance(port, ca.SX) and port.is_scalar() and port.is_symbolic():
        ref = sym_owner.get(port.name())
        if ref is not None:
            return ref
    return None


def _connections(flat: FlatModel, model, elements, connects, problems, planned=None,
                 folded=None) -> None:
    """Connection sets over the whole tree, with inside and outside connectors
    (:mod:`mechatron.core.connections`), turned into aliases and flow sums; the
    subsystems ``planned`` are wired by their class's plan, their ports ``folded`` into
    the nodes they join (:mod:`mechatron.compiler.folding`)."""
    sym_owner: dict[str, SignalRef] | None = None   # formed for the first bound symbol
    joined = []
    tried: set[tuple] = set()  # ports of a failed connect: not reported again as open
    if planned and _reaches_inside(connects, planned):
        # a connection from outside to a part inside a planned subsystem: wire every
        # subsystem connect by connect, its ports written out (as without plans)
        connects = list(connects)
        for el, _ in planned.values():
            for _, items in _class_calls(el, "equations", el.path):
                connects.extend((item, el) for item in _as_equations(items))
        for port in list(folded.values()):
            port._syms.unfold()
        planned = folded = None
    port_types = (Connector, SignalRef)
    for con, writer in connects:
        # ports as written (the common case), else each resolved to a port or signal
        resolved = con.ports
        if not all(map(isinstance, resolved, repeat(port_types))):
            resolved = []
            for p in con.ports:
                if isinstance(p, port_types):
                    r = p
                else:
                    if sym_owner is None:
                        sym_owner = _signal_owners(elements)
                    r = _resolve(flat, p, sym_owner)
                if r is None:
                    where = writer.path or flat.name
                    problems.append(f"{where}: connect() takes ports, got {p!r}. Pass a "
                                    "port such as r1.p or a signal such as src.y.")
                    continue
                resolved.append(r)
        if len(resolved) == 2 and type(resolved[0]) is type(resolved[1]):
            joined.append((writer, resolved))       # the common case, compatible
            continue
        ok = [resolved[0]] if resolved else []
        for a, b in zip(resolved, resolved[1:]):
            msg = _compatible(a, b)
            if msg:
                problems.add(ConnectError, msg)
                tried.update((port_key(a), port_key(b)))
                continue
            ok.append(b)
        if len(ok) > 1:
            joined.append((writer, ok))
    if not tried and _on_arrays(flat, model, elements, joined, problems, planned, folded):
        return
    sets = connection_sets(joined)
    flow_sums: list = []
    for cset in sets:
        if cset.is_signal:
            flat.connection_sets.append([_set_member(m) for m in cset.members])
            _signal_set(flat, cset, problems, model)
            continue
        flat.connection_sets.append([(m.path, type(m.port).domain, False)
                                     for m in cset.members])     # as _set_member
        if not planned:
            _physical_set(flat, cset, flow_sums)
    if planned:
        joining = join_planned(sets, planned, folded)
        nodes = joining.groups
        if not joined_nodes(flat, nodes):
            for members in nodes:
                _physical_set(flat, _Joined(members), flow_sums)
        _folded_variables(flat, folded, [joining.node[pid].port for pid in folded],
                          [[m.port for m in joining.flow[pid]] for pid in folded])
    else:
        nodes = [cset.members for cset in sets if not cset.is_signal]
    _flow_sums(flat, flow_sums)
    # the ports connected from outside their component (inside_connected(sets) | tried:
    # connectors by id, signals by port_key), and the connectors wired inside their own
    # component, by id
    connected_ports: set[int] = set()
    connected: set[tuple] = set()
    wired_inside: set[int] = set()
    for cset in sets:
        for m in cset.members:
            if isinstance(m.port, SignalRef):
                if not m.outside:
                    connected.add(port_key(m.port))
            elif m.outside:
                wired_inside.add(id(m.port))
            else:
                connected_ports.add(id(m.port))
    for key in tried:
        if key[0] == "port":
            connected_ports.add(key[1])
        else:
            connected.add(key)
    _unconnected(flat, model, elements, connected_ports, connected, wired_inside, problems,
                 planned, folded)
    _check_references([m.port for members in nodes for m in members],
                      list(map(len, nodes)), problems)


def _on_arrays(flat: FlatModel, model, elements, joined: list, problems, planned=None,
               folded=None) -> bool:
    """The connections of ``joined`` with the physical sets formed on arrays
    (:mod:`mechatron.compiler.nodes`), joined across the ports ``folded`` of the
    subsystems ``planned``, the signal sets set by set among them: the same records as
    set by set in `_connections`. False, having changed nothing, when the physical sets
    cannot be read so."""
    signal = [isinstance(ports[0], SignalRef) for _, ports in joined]
    if all(signal):
        return False            # no physical set (the sets are formed once, set by set)
    signal_sets = connection_sets([j for j, s in zip(joined, signal) if s]) \
        if any(signal) else []

    def signal_set(cset) -> None:
        flat.connection_sets.append([_set_member(m) for m in cset.members])
        _signal_set(flat, cset, problems, model)

    physical = [j for j, s in zip(joined, signal) if not s]
    if planned:
        joining = planned_nodes(flat, physical, planned, folded, signal_sets, signal_set)
        if joining is None:
            return False
        outer, nodes = joining.outer, joining.nodes
        _folded_variables(flat, folded, joining.firsts, joining.insides)
    else:
        outer = nodes = physical_nodes(flat, physical, signal_sets, signal_set)
        if nodes is None:
            return False
    ids, outside = outer.port_ids, outer.outside
    connected = {port_key(m.port) for cset in signal_sets for m in cset.members
                 if not m.outside}
    _unconnected(flat, model, elements, set(ids[~outside].tolist()), connected,
                 set(ids[outside].tolist()), problems, planned, folded)
    _check_references(nodes.ports, np.diff(nodes.ptr).tolist(), problems)
    return True


def _unconnected(flat: FlatModel, model, elements, connected_ports: set[int],
                 connected: set[tuple], wired_inside: set[int], problems, planned=None,
                 folded=None) -> None:
    """Each port left open: an open terminal (`_open_port`) if it is the model's own or a
    subsystem's wired inside (``wired_inside``, by id), else an error; each signal input
    of a part that nothing drives, an error. ``connected_ports`` holds the ids of the
    connectors connected from outside their component, ``connected`` the `port_key` of
    such signals."""
    for el in elements:
        if isinstance(el, Connector):
            if id(el) in connected_ports:
                continue
            owner = el._parent
            if planned and (id(el) in folded or id(owner._parent) in planned):
                continue            # folded, or wired inside a planned subsystem
            if planned and id(owner) in planned:
                _open_port(flat, el)    # a planned port an equation reads, open outside
                continue
            if el._parent is model or id(el) in wired_inside:
                # a port of the model, or of a subsystem wired to its parts, left open
                # outside: nothing flows through it
                _open_port(flat, el)
                continue
            problems.append(f"port '{el.path}' ({el.domain}) is not connected. Connect it, "
                            "or remove the component. "
                            f"{_hint(el)}".rstrip())
        elif el is not model:       # a component; the root's inputs: external inputs
            for key in _input_keys(type(el)):
                if port_key(SignalRef(el, key)) not in connected:
                    problems.append(f"signal input '{_join(el.path, key)}' is not "
                                    "connected. Connect a source, e.g. blocks.Constant.")


def _reaches_inside(connects, planned) -> bool:
    """Whether a connect names a port of a part of a planned subsystem (``axis.load.port``
    from outside ``axis``): the subsystem's plan then does not hold all of that node."""
    inside = planned.inside
    return any(isinstance(port, Connector) and id(port._parent) in inside
               for con, _ in connects for port in con.ports)


class _Joined:
    """A node of joined connection sets, read by `_physical_set` as a set."""

    __slots__ = ("members",)

    def __init__(self, members):
        self.members = members


def _folded_variables(flat: FlatModel, folded, firsts: list, insides: list) -> None:
    """Record the variables of the folded ports, for logging them (`FlatModel.folded`, a
    `FoldedColumns`): each one's name, unit, doc and place, and the rows of the model
    variables it sums (`_folded_terms`); ``firsts[i]`` is the first member of the node of
    folded port ``i``, ``insides[i]`` the ports of its inside members. These are maps
    over the ports and array operations."""
    ports = list(folded.values())
    types = list(map(type, ports))
    plans = {cls: _folded_plan(cls) for cls in dict.fromkeys(types)}
    ptr, rows, var_count = _folded_terms(types, plans, firsts, insides,
                                         flat.__dict__.get("_rows", {}))
    suffixes = {cls: ["." + key for key in plan[0]] for cls, plan in plans.items()}
    names = [path + sfx for path, sfxs in zip(map(_PATH_OF, ports),
                                             map(suffixes.__getitem__, types))
             for sfx in sfxs]
    units, docs = (list(chain.from_iterable(plans[cls][k] for cls in types)) for k in (1, 2))
    position = np.repeat(list(map(_POSITION_OF, ports)), var_count).tolist()
    order = np.repeat(list(map(_ORDER_OF, ports)), var_count).tolist()
    flat.folded = FoldedColumns(names, units, docs, position, order, ptr, rows)


def _folded_terms(types: list, plans: dict, firsts: list, insides: list[list],
                  late: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The terms of the folded ports' variables as compressed rows ``(ptr, rows)``, and
    how many variables each port has. Port ``i`` (of class ``types[i]``, its keys and
    which are across in ``plans``, see `_folded_plan`) has each variable in declaration
    order; an across variable's term is the row of that key of the node's first member
    ``firsts[i]``, a through variable's those of the inside members ``insides[i]``. A
    member's row is its first variable's plus the key's place among its own class's
    variables (a subclass may place it elsewhere)."""
    n_in = np.fromiter(map(len, insides), dtype=np.intp, count=len(insides))
    inner = list(chain.from_iterable(insides))
    b_first, b_inner = _rows_of(firsts, late), _rows_of(inner, late)
    # every class met, numbered, and the place of each key among its variables
    number = {cls: k for k, cls in enumerate(dict.fromkeys([*types, *map(type, firsts),
                                                            *map(type, inner)]))}
    key_of = {key: j for j, key in enumerate(dict.fromkeys(
        key for plan in plans.values() for key in plan[0]))}
    place = np.full((len(number), len(key_of)), -1, dtype=np.intp)
    for cls, k in number.items():
        for key, at in _binding_plan(cls)[4].items():
            if key in key_of:
                place[k, key_of[key]] = at

    def numbered(classes: list) -> np.ndarray:
        return np.fromiter(map(number.__getitem__, classes), dtype=np.intp,
                           count=len(classes))

    c_port = numbered(types)
    c_first, c_inner = numbered(list(map(type, firsts))), numbered(list(map(type, inner)))
    per_class = np.zeros(len(number), dtype=np.intp)
    for cls, plan in plans.items():
        per_class[number[cls]] = len(plan[0])
    var_count = per_class[c_port]
    var_start = np.cumsum(var_count) - var_count       # each port's first variable
    in_ptr = _offsets(n_in)
    mine = {cls: np.flatnonzero(c_port == number[cls]) for cls in plans}
    # how many terms each variable has: one across, a term per inside member through
    counts = np.zeros(int(var_count.sum()), dtype=np.intp)
    for cls, (_, _, _, across) in plans.items():
        for j, is_across in enumerate(across):
            counts[var_start[mine[cls]] + j] = 1 if is_across else n_in[mine[cls]]
    ptr = _offsets(counts)
    rows = np.empty(ptr[-1], dtype=np.intp)
    for cls, (keys, _, _, across_of) in plans.items():
        ports = mine[cls]
        members, owner = _segments(in_ptr, ports)
        for j, (key, across) in enumerate(zip(keys, across_of)):
            k = key_of[key]
            if across:
                at = ptr[var_start[ports] + j]
                base, offset = b_first[ports], place[c_first[ports], k]
            else:
                at = ptr[var_start[ports[owner]] + j] + (members - in_ptr[ports[owner]])
                base, offset = b_inner[members], place[c_inner[members], k]
            if offset.size and offset.min() < 0:
                raise AssertionError(f"a member of the node of a folded {cls.__name__} "
                                     f"has no variable {key}")
            rows[at] = base + offset
    return ptr, rows, var_count


_ROW_OF = attrgetter("_syms.row")       # an element's first row, when bound in bulk
_POSITION_OF = attrgetter("_syms.position")  # where a folded port's variables go
_ORDER_OF = attrgetter("_syms.order")
_PATH_OF = attrgetter("_path_cache")    # set by _walk


def _rows_of(ports: list, late: dict) -> np.ndarray:
    """`_first_row` of each of ``ports``: one map over them when every one was bound in
    bulk, else port by port; a port without variables is an error of flattening."""
    try:
        rows = np.fromiter(map(_ROW_OF, ports), dtype=np.intp, count=len(ports))
    except AttributeError:      # a port bound on first read (its rows are in ``late``)
        rows = np.array([_first_row(p, late) for p in ports], dtype=np.intp)
    if rows.size and rows.min() < 0:     # every member of a folded node is bound by now
        bad = ports[int(np.argmin(rows))]
        raise AssertionError(f"port '{bad.path}' of a folded node has no variables")
    return rows


@functools.lru_cache(maxsize=None)
def _signal_keys(cls) -> tuple:
    """The keys of a class's signal inputs and outputs, in declaration order."""
    return tuple(k for k, d in cls._declarations.items() if isinstance(d, (Input, Output)))


@functools.lru_cache(maxsize=None)
def _input_keys(cls) -> tuple:
    """The keys of a class's signal inputs, in declaration order (once per class)."""
    return tuple(k for k, d in cls._declarations.items() if isinstance(d, Input))


def _open_port(flat: FlatModel, port: Connector) -> None:
    """A port of the model itself or of a subsystem, which nothing outside connects: its
    through variables are zero (an open terminal), as for an unconnected Modelica
    connector. A library part's open port stays an error: it is almost always a
    forgotten wire."""
    for t in type(port).through_names():
        name = f"{port.path}.{t}"
        flat.equations.append(FlatEquation(flat.variables[name].sym,
                                           f"{name} == 0 (port '{port.path}' is open "
                                           "outside)", port._parent.path))


def _set_member(m) -> tuple:
    if isinstance(m.port, SignalRef):
        return (m.path, SIGNAL, is_driver(m))
    return (m.path, type(m.port).domain, False)


def _join(a, b):
    return f"{a}.{b}" if a else b


def _hint(port: Connector) -> str:
    return _class_hint(type(port))


@functools.lru_cache(maxsize=None)
def _class_hint(cls) -> str:
    for decl in cls._declarations.values():
        if isinstance(decl, Across) and decl.hint:
            return decl.hint
    return ""


def _compatible(a, b) -> str:
    if type(a) is type(b):
        return ""
    if isinstance(a, SignalRef) != isinstance(b, SignalRef):
        sig, phys = (a, b) if isinstance(a, SignalRef) else (b, a)
        return (f"cannot connect signal '{sig.path()}' with physical port '{phys.path}' "
                f"({phys.domain}). Use a converter between signals and physical "
                "quantities (e.g. a controlled source or a sensor).")
    if isinstance(a, Connector) and type(a).domain is not type(b).domain:
        return (f"cannot connect '{a.path}' ({type(a).domain}) with '{b.path}' "
                f"({type(b).domain}): ports belong to different domains.")
    if isinstance(a, Connector) and type(a) is not type(b) and (
            type(a).across_names() != type(b).across_names()):
        return (f"cannot connect '{a.path}' ({type(a).__name__}) with '{b.path}' "
                f"({type(b).__name__}): the connectors carry different variables.")
    if isinstance(a, Connector) and type(a) is not type(b):
        differ = _unit_clash(type(a), type(b))
        if differ:
            key, ua, ub = differ
            return (f"cannot connect '{a.path}' ({type(a).__name__}) with '{b.path}' "
                    f"({type(b).__name__}): their {key} is declared in {ua} "
                    f"({_dimension_text(ua)}) and in {ub} ({_dimension_text(ub)}). "
                    "Declare the connectors' variables in units of one dimension.")
    return ""


def _dimension_text(unit: str) -> str:
    """``kg*m^2/s^3``: a unit's dimension in SI base units, as the dimension check
    writes it (for a message)."""
    from mechatron.compiler.dimensions import format_dimension, unit_dimension
    packed = unit_dimension(unit)
    return format_dimension(packed) if packed is not None else str(dimensionality(unit))


@functools.lru_cache(maxsize=None)
def _unit_clash(cls_a, cls_b) -> tuple | None:
    """The first across or through variable that two connector classes of one domain
    declare in units of different dimensions, as ``(key, unit_a, unit_b)``, else None
    (once per pair of classes). Joined in a node, such variables would be set equal or
    summed: what the dimension check of equations does not walk (see
    `_SumEquation.uniform`) is checked here."""
    decl_a, decl_b = cls_a._declarations, cls_b._declarations
    for key in (*cls_a.across_names(), *cls_a.through_names()):
        other = decl_b.get(key)
        if other is None:
            continue
        ua, ub = decl_a[key].unit, other.unit
        if ua != ub and dimensionality(ua) != dimensionality(ub):
            return key, ua, ub
    return None


def _signal_set(flat: FlatModel, cset, problems, model) -> None:
    # driven by a part's output, or by the writing component's own input (the root's own
    # inputs are the model's external inputs)
    outputs = [m for m in cset.members if is_driver(m)]
    paths = ", ".join(m.path for m in cset.members)
    if not outputs:
        problems.append(f"signals {paths} are connected without an output to drive them. "
                        "Connect a source or a block output.")
        return
    if len(outputs) > 1:
        own = [o for o in outputs if isinstance(o.port.declaration, Input)]
        note = "."
        if own and own[0].port.owner is model:
            note = (" (an input of the model's root component is an external input: it "
                    "drives what it is connected to).")
        elif own:
            note = (f" ('{own[0].path}' is an input of the subsystem that connects it: it "
                    "drives what it is connected to inside).")
        problems.append(f"signal outputs {', '.join(o.path for o in outputs)} are "
                        "connected together; an input can be driven by one output only"
                        + note)
        return
    driver = outputs[0]
    src = driver.path
    unit = driver.port.declaration.unit
    for m in cset.members:
        if m is driver or m.path == src:
            continue
        g = m.port
        if not _units_compatible(unit, g.declaration.unit):
            problems.add(UnitError,
                         f"cannot connect signal '{src}' ({unit}) to '{m.path}' "
                         f"({g.declaration.unit}): the units have different "
                         f"dimensions ({dimensionality(unit)} vs "
                         f"{dimensionality(g.declaration.unit)}). Convert with a "
                         "physical_signals.PSGain with units, or pass a plain "
                         "signal through PhysicalToSignal/SignalToPhysical.")
            continue
        flat.aliases.append((m.path, src, 1.0, f"connect({src}, {m.path})"))


def _units_compatible(a: str, b: str) -> bool:
    """Signal units match if their dimensions agree; a dimensionless signal (a plain
    causal signal, unit "1") connects to any unit."""
    da, db = dimensionality(a), dimensionality(b)
    return not da or not db or da == db


def _physical_set(flat: FlatModel, cset, flow_sums: list) -> None:
    """The aliases (across variables equal; the through variables of two members
    opposite) and the flow sum (of more members) of a physical connection set. The
    variables are named by number when every member's port has its rows (bound in bulk,
    or bound late): the port's row plus the key's place among its own class's
    variables; else by path."""
    members = cset.members
    first = members[0]
    origin = "connect(" + ", ".join([m.path for m in members]) + ")"
    across, through = _port_variables(type(first.port))
    others = [j for j, m in enumerate(members) if m.port is not first.port]  # one node
    late = flat.__dict__.get("_rows", {})
    row = [_first_row(m.port, late) for m in members]
    offsets = [_binding_plan(type(m.port))[4] for m in members]   # one per class
    uniform = all(o is offsets[0] for o in offsets)     # every member of one class
    if min(row) < 0 or any(o is not offsets[0] and any(k not in o for k in across + through)
                           for o in offsets):
        row = [f"{m.path}." for m in members]       # by path: key appended
        offsets = None

    def var(j, key):
        return row[j] + offsets[j][key] if offsets is not None else row[j] + key

    aliases = flat.aliases
    for a in across:
        target = var(0, a)
        for j in others:
            aliases.append((var(j, a), target, 1.0, origin))
    for t in through:
        if len(members) == 2 and others:
            # first.sign * first.t + m.sign * m.t == 0
            j = others[0]
            aliases.append((var(j, t), var(0, t), -first.sign * members[j].sign, origin))
        else:   # formed in bulk by _flow_sums
            flow_sums.append(([(var(j, t), m.sign) for j, m in enumerate(members)],
                              f"{origin}: sum of {t} == 0", uniform))


@functools.lru_cache(maxsize=None)
def _port_variables(cls) -> tuple:
    """A connector class's across and through keys (once per class)."""
    return tuple(cls.across_names()), tuple(cls.through_names())


def _flow_sums(flat: FlatModel, flow_sums) -> None:
    """The through-variable sums of all sets of three or more members (``(terms, origin,
    uniform)`` each, a term ``(variable, sign)``, a variable by number or by path), as one
    sparse signed incidence matrix times the vector of their variables (`_sum_equations`):
    three CasADi calls in all, not one per term."""
    if not flow_sums:
        return
    index: dict = {}        # each variable (by number or by path) -> its column in A
    rows, cols, vals = [], [], []
    for r, (terms, *_) in enumerate(flow_sums):
        for name, sign in terms:
            rows.append(r)
            cols.append(index.setdefault(name, len(index)))
            vals.append(sign)
    number = flat.variable_rows()
    _sum_equations(flat, np.asarray(rows, dtype=np.int64), np.asarray(cols, dtype=np.int64),
                   np.asarray(vals, dtype=float),
                   [name if type(name) is int else number[name] for name in index],
                   [origin for _, origin, _ in flow_sums],
                   [uniform for _, _, uniform in flow_sums])


def _sum_equations(flat: FlatModel, rows: np.ndarray, cols: np.ndarray, vals: np.ndarray,
                   variables: list[int], origins: list, uniform: list[bool]) -> None:
    """The flow sums as `_SumEquation` rows of one column ``A x``: sum ``rows[k]`` holds
    ``vals[k]`` times variable ``variables[cols[k]]`` (a row of the model's variables),
    each sum's origin and whether its terms are of one class (``uniform``)."""
    n = len(origins)
    A = ca.DM.triplet(rows.tolist(), cols.tolist(), ca.DM(vals.tolist()), n, len(variables))
    sums = ca.mtimes(A, flat.stack_rows(variables))
    # the terms left in each sum (a variable met twice with opposite signs cancels): a
    # sum of three or more is no alias; the others are read off their residuals
    width = max(len(variables), 1)
    uniq, inverse = np.unique(rows * width + cols, return_inverse=True)
    total = np.bincount(inverse, weights=vals)
    terms = np.bincount(uniq[total != 0] // width, minlength=n).tolist()
    flat.equations += [_SumEquation(sums, r, origin, _NO_ALIAS if count > 2 else None, same,
                                    count)
                       for r, (origin, same, count) in enumerate(zip(origins, uniform,
                                                                      terms))]


_DOMAINS: dict = {}


@functools.lru_cache(maxsize=None)
def _domain_id(cls) -> int:
    """A number for a connector class's domain, equal for equal domains (a domain is
    compared by value), worked out once per class."""
    return id(_DOMAINS.setdefault(cls.domain, cls.domain))


def _check_references(ports: list, sizes: list[int], problems) -> None:
    """Every network of a domain that needs a reference must contain one. A network joins
    the physical nodes (``ports``: the members' ports, node after node, ``sizes[k]`` of
    node ``k``; a subsystem's port is one node inside and outside) that meet on a
    component: the ports of one domain on a component are one network (a resistor's two
    pins; a motor's two pins, apart from its shaft).

    Read off the nodes' members alone, not by a walk over every element: each member's
    component and domain get a number, and the networks are the connected components of
    the graph that joins each node to those numbers (a port that is no component's is a
    network of its own). A network is grounded when one of its members belongs to a
    reference component; the others are reported in the order of their first node."""
    if not ports:
        return
    owners = list(map(_PARENT, ports))
    types = list(map(type, ports))
    is_part = np.fromiter(map(isinstance, owners, repeat(Component)), dtype=bool,
                          count=len(owners))
    # a member's key: its component and its domain's number, or (a port that is no
    # component's) the port itself, each object numbered first
    numbers: dict[int, int] = {}
    domain_of = {cls: numbers.setdefault(_domain_id(cls), len(numbers))
                 for cls in dict.fromkeys(types)}
    width = len(numbers) + 1
    domain = np.fromiter(map(domain_of.__getitem__, types), dtype=np.int64,
                         count=len(types))
    _, obj = np.unique(np.where(
        is_part, np.fromiter(map(id, owners), dtype=np.int64, count=len(owners)),
        np.fromiter(map(id, ports), dtype=np.int64, count=len(ports))), return_inverse=True)
    _, at = np.unique(obj * width + np.where(is_part, domain, width - 1),
                      return_inverse=True)
    reference = np.fromiter(map(getattr, owners, repeat("_reference"), repeat(False)),
                            dtype=bool, count=len(owners))
    sizes_a = np.asarray(sizes, dtype=np.intp)
    n = len(sizes_a)
    node_of = np.repeat(np.arange(n), sizes_a)
    grounded = np.zeros(n, dtype=bool)
    grounded[node_of[reference]] = True
    if grounded.all():
        return
    graph = sparse.coo_matrix((np.ones(len(at), dtype=np.int8), (node_of, n + at)),
                              shape=(n + int(at.max()) + 1,) * 2)
    _, label = csgraph.connected_components(graph, directed=False)
    label = label[:n]
    has_reference = np.zeros(label.max() + 1, dtype=bool)
    has_reference[label[grounded]] = True
    ptr = _offsets(sizes_a).tolist()
    networks: dict[int, list] = {}      # in the order of their first node
    for i in np.flatnonzero(~has_reference[label]).tolist():
        networks.setdefault(int(label[i]), []).extend(ports[ptr[i]:ptr[i + 1]])
    for plist in networks.values():
        domain = type(plist[0]).domain
        if domain is None or not domain.needs_reference:
            continue
        owners = sorted({p._parent.path for p in plist if p._parent is not None})
        problems.append(f"{domain.name} network of {', '.join(owners)} has no reference. "
                        f"{domain.hint or 'Add a reference component to it.'}")


# -- hybrid declarations (mt.Discrete, initial_equations); kept apart from the passes above

@functools.lru_cache(maxsize=None)
def _discrete_keys(cls) -> tuple:
    """``(key, declaration)`` of a class's ``Discrete`` declarations (once per class)."""
    return tuple((k, d) for k, d in cls._declarations.items() if isinstance(d, Discrete))


@functools.lru_cache(maxsize=None)
def _writes_initial(cls) -> bool:
    """Whether a class of the tree writes ``initial_equations`` of its own (once per
    class; `mechatron.core.component.System` does, for ``add_initial_equation``)."""
    return issubclass(cls, Component) and bool(_own_methods(cls, "initial_equations"))


def _discrete_or_initial(cls) -> bool:
    """Whether `_discrete_declarations` reads the elements of ``cls``."""
    return bool(_discrete_keys(cls)) or _writes_initial(cls)


def _discrete_declarations(flat: FlatModel, elements, problems) -> None:
    """Record the discrete variables with their kind and collect initial equations.

    A ``Discrete`` declaration is a discrete state even if no action assigns it (then it
    keeps its start value: ``der(v) == 0``); an action target that is not differentiated
    anywhere is a discrete Real (its ``der(v) == 0`` was added by ``_discrete_states``).
    ``elements`` are those of the classes that declare discrete variables or write
    initial equations (`_discrete_or_initial`), picked in tree order while flattening:
    the root of a model built as a `mechatron.core.component.System` is among them, and
    no further walk over every element is made for it.
    """
    ctx = flat.context
    # the equations der(v) == 0 of `_discrete_states`, which only event actions add
    for eq in _held(flat.equations) if flat.events else ():
        if isinstance(eq.origin, str) and eq.origin.endswith("changed only by events)"):
            name = ctx.integral.get(eq.residual.name()) if eq.residual.is_symbolic() else None
            if name:
                flat.discrete[name] = "real"
    for el in elements:
        for key, decl in _discrete_keys(type(el)):
            path = _join(el.path, key)
            sym_name = flat.variables[path].sym.name()
            if sym_name not in flat.discrete and sym_name in ctx.derivative:
                problems.append(f"{el.describe()}: '{key}' is a Discrete variable and is "
                                "differentiated. Declare it as a Variable, or remove der().")
                continue
            if sym_name not in flat.discrete:
                flat.equations.append(FlatEquation(
                    ctx.der_symbol(sym_name), f"{el.path or flat.name}: der({sym_name}) == 0 "
                    "(discrete variable, changed only by events)", el.path))
            flat.discrete[sym_name] = decl.discrete_kind
    for el in elements:
        if not _writes_initial(type(el)):
            continue
        for klass, items in _class_calls(el, "initial_equations", el.path):
            for k, item in enumerate(_as_equations(items)):
                before = len(flat.equations)
                _add_equation(flat, el, klass, k, item, problems)
                for eq in flat.equations[before:]:
                    eq.residual = eq.origin.lhs - eq.origin.rhs
                    flat.initial_equations.append(eq)
                del flat.equations[before:]
