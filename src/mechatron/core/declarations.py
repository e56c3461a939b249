"""Declarations: what a component or connector class says it has.

Each declaration is a descriptor. Outside compilation it describes (unit, default, doc);
while the model compiles, reading it on an instance gives the CasADi symbol bound to that
instance's variable or parameter, so equations read like the textbook: ``self.v == self.R *
self.i``.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

from mechatron.errors import ModelError
from mechatron.units import check_unit

__all__ = ["Parameter", "ParameterExpression", "Variable", "Discrete", "Across", "Through",
           "Input", "Output", "Start", "PRIORITIES", "DISCRETE_KINDS"]

PRIORITIES = ("high", "low", "none")
STATE_SELECT = ("avoid", "default", "prefer")
_order = itertools.count()


@dataclass(frozen=True)
class Start:
    """A start value with an initialization priority, Simscape's variable target.

    ``high`` targets are met exactly (an error if they conflict), ``low`` ones as closely
    as the constraints allow, ``none`` is only a guess for the initial solve.
    """

    value: float
    priority: str = "high"

    def __post_init__(self):
        if self.priority not in PRIORITIES:
            raise ValueError(f"Start: priority must be one of {PRIORITIES}, "
                             f"got {self.priority!r}.")


class _Arithmetic:
    """Arithmetic on parameters in a class body, giving a :class:`ParameterExpression`."""

    def _expr(self) -> "ParameterExpression":
        raise NotImplementedError

    def _op(self, other, fn, op, reverse=False):
        a = self._expr()
        b = other._expr() if isinstance(other, _Arithmetic) else \
            ParameterExpression(lambda look, v=other: v, (), lambda v=other: repr(v))
        if reverse:
            a, b = b, a
        return ParameterExpression(lambda look: fn(a.evaluate(look), b.evaluate(look)),
                                   a.parameters + b.parameters,
                                   lambda: f"({a.text} {op} {b.text})")

    def __add__(self, o):
        return self._op(o, lambda x, y: x + y, "+")

    def __radd__(self, o):
        return self._op(o, lambda x, y: x + y, "+", True)

    def __sub__(self, o):
        return self._op(o, lambda x, y: x - y, "-")

    def __rsub__(self, o):
        return self._op(o, lambda x, y: x - y, "-", True)

    def __mul__(self, o):
        return self._op(o, lambda x, y: x * y, "*")

    def __rmul__(self, o):
        return self._op(o, lambda x, y: x * y, "*", True)

    def __truediv__(self, o):
        return self._op(o, lambda x, y: x / y, "/")

    def __rtruediv__(self, o):
        return self._op(o, lambda x, y: x / y, "/", True)

    def __pow__(self, o):
        return self._op(o, lambda x, y: x ** y, "**")

    def __neg__(self):
        a = self._expr()
        return ParameterExpression(lambda look: -a.evaluate(look), a.parameters,
                                   lambda: f"-{a.text}")


class ParameterExpression(_Arithmetic):
    """A parameter value given as an expression of the enclosing component's parameters,
    Modelica's ``Resistor r(R=R/2)``: written in a class body as ``r = Resistor(R=R / 2)``
    where ``R`` is a :class:`Parameter` of the class being defined.

    The compiler evaluates it on the enclosing instance's parameter symbols, so the part
    follows its parent's value, also when that value is changed between runs.
    """

    def __init__(self, fn, parameters: tuple, text):
        self._fn = fn
        self.parameters = tuple(parameters)    # the Parameter declarations it reads
        self._text = text

    @property
    def text(self) -> str:
        return self._text()

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.parameters)

    def _expr(self) -> "ParameterExpression":
        return self

    def __deepcopy__(self, memo):
        return self              # immutable; shared by every copy of a template

    def evaluate(self, lookup):
        """The value with each parameter replaced by ``lookup(name)`` (a symbol, a float
        or a quantity)."""
        return self._fn(lookup)

    def __repr__(self) -> str:
        return f"ParameterExpression({self.text})"


class Declaration:
    """Base of all declarations: a unit, a one-line description, a name and an order."""

    kind = "declaration"

    def __init__(self, unit: str = "1", *, doc: str = ""):
        self.unit = check_unit(unit, "declaration")
        self.doc = doc
        self.name = ""
        self.order = next(_order)

    def __set_name__(self, owner, name):
        self.name = name

    def __get__(self, obj, owner=None):
        if obj is None:
            return self
        return obj._symbol(self.name)

    def __set__(self, obj, value):
        raise AttributeError(f"'{type(obj).__name__}.{self.name}' is a {self.kind}; set it "
                             f"with the constructor, e.g. {type(obj).__name__}"
                             f"({self.name}=...).")

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.unit!r}, doc={self.doc!r})"


class Parameter(_Arithmetic, Declaration):
    """A parameter: a value fixed during a simulation, tunable between runs.

    In the body of a composite component's class, a parameter can be passed on to a part,
    alone or in an expression: ``r = Resistor(R=R / 2)`` (see
    :class:`ParameterExpression`).

    Parameters
    ----------
    unit : str
        SI unit of the value, e.g. ``"Ohm"``.
    default : float or str, optional
        Default value (a number in ``unit`` or a quantity string). No default means the
        user must give one.
    min, max : float, optional
        Inclusive bounds, checked when the model is compiled.
    doc : str
        One-line description.
    """

    kind = "parameter"

    def __init__(self, unit: str = "1", default=None, *, min: float | None = None,
                 max: float | None = None, doc: str = ""):
        super().__init__(unit, doc=doc)
        self.default = default
        self.min = min
        self.max = max

    def _expr(self) -> ParameterExpression:
        # the name is set when the class body ends: read it when evaluated
        return ParameterExpression(lambda look: look(self.name), (self,), lambda: self.name)


class Variable(Declaration):
    """An unknown of the component's equations.

    Parameters
    ----------
    unit : str
        SI unit.
    start : float, optional
        Start value (initial value for a state, initial guess otherwise).
    priority : {"high", "low", "none"}
        How strongly initialization must meet ``start`` (Simscape's variable priority).
        Defaults to ``"none"``; a start value given by the user on an instance is ``high``.
    state_select : {"avoid", "default", "prefer"}
        Hint for state selection after index reduction (Modelica's ``StateSelect``):
        ``"prefer"`` keeps the variable as a state when the constraints allow a choice
        (joint coordinates), ``"avoid"`` makes it algebraic first.
    doc : str
        One-line description.
    """

    kind = "variable"

    def __init__(self, unit: str = "1", *, start: float | None = None,
                 priority: str = "none", state_select: str = "default", doc: str = ""):
        super().__init__(unit, doc=doc)
        if priority not in PRIORITIES:
            raise ValueError(f"Variable: priority must be one of {PRIORITIES}, "
                             f"got {priority!r}.")
        if state_select not in STATE_SELECT:
            raise ValueError(f"Variable: state_select must be one of {STATE_SELECT}, "
                             f"got {state_select!r}.")
        self.start = start
        self.priority = priority
        self.state_select = state_select


DISCRETE_KINDS = ("real", "integer", "boolean")


class Discrete(Variable):
    """A discrete variable: constant between events, changed only by ``when`` and
    ``sample`` actions (Modelica's ``discrete Real``, ``Integer`` and ``Boolean``).

    Parameters
    ----------
    unit : str
        SI unit (``"1"`` for counters and flags).
    start : float, int or bool
        Value before the first event (``True``/``False`` for a Boolean).
    kind : {"real", "integer", "boolean"}
        What an assignment stores: a ``real`` stores the value, an ``integer`` the value
        rounded to the nearest integer, a ``boolean`` 1 for any nonzero value and 0 for
        zero. In equations and conditions a Boolean is 0 or 1 (``mt.if_else(self.on, a, b)``
        reads it without generating an event: it changes only at events).
    doc : str
        One-line description.
    """

    kind = "discrete variable"

    def __init__(self, unit: str = "1", *, start=0.0, kind: str = "real", doc: str = ""):
        if kind not in DISCRETE_KINDS:
            raise ValueError(f"Discrete: kind must be one of {DISCRETE_KINDS}, got {kind!r}.")
        super().__init__(unit, start=float(start), priority="none", doc=doc)
        self.discrete_kind = kind


class Across(Variable):
    """The across variable of a connector (equal at all connected ports)."""

    kind = "across variable"

    def __init__(self, unit: str = "1", *, doc: str = "", hint: str = "", **kw):
        super().__init__(unit, doc=doc, **kw)
        self.hint = hint


class Through(Variable):
    """The through variable of a connector (sums to zero over connected ports).

    Positive when it flows into the component at this port.
    """

    kind = "through variable"


class Input(Variable):
    """A causal signal input port (Simulink style). Connect an :class:`Output` to it."""

    kind = "signal input"


class Output(Variable):
    """A causal signal output port, defined by the component's equations."""

    kind = "signal output"


def check_symbolic(obj, name):
    raise ModelError(f"{obj!r}: {name} has no symbol outside compilation. Read variables "
                     "in equations(); read values from a SimResult.")
