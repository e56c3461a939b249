"""Pass 1b: the dimension check of every equation (Simscape checks every equation's units).

Every parameter and variable declares a unit; from them the pass infers the physical
dimension of both sides of every equation and reports each equation whose sides differ,
e.g. ``v == L*i`` for an inductor (a missing ``der``: volt against weber).

Rules, applied to the CasADi expression graph:

* ``+ - min max fmod hypot`` and relations ``< <= == !=`` need operands of one dimension;
  ``* / sq sqrt inv`` and ``pow`` with a constant exponent combine them; ``der(x)`` has
  the unit of ``x`` per second, ``time`` is in s; ``abs``, ``floor``, ``ceil``,
  ``copysign`` keep the dimension of their (first) argument; ``sign`` and the relations
  give a dimensionless value; ``atan2(y, x)`` needs ``y`` and ``x`` alike and gives an
  angle; ``if_else`` branches must agree (CasADi writes ``if_else(c, a, b)`` as
  ``(c ? a : 0) + (!c ? b : 0)``).
* Transcendental functions (``sin``, ``exp``, ``log``, ``tanh``, ``erf``, ...) need a
  dimensionless argument and give a dimensionless result; so does ``pow`` with a variable
  exponent (base and exponent dimensionless). Radians are dimensionless (pint's rule).
* A numeric constant is a wildcard: it takes the dimension of what it is added to or
  compared with (``x == 0``, ``v + 1e-3``), and is dimensionless in a product.
* A *free signal* is a wildcard too, in sums and in products (its dimension is unknown,
  as a Simulink signal carries none): a signal input or output declared with unit ``"1"``
  (the default of causal blocks), and every variable of unit ``"1"`` of a component
  without physical ports (a signal block: a transfer function's states, a PID's
  integral; or plain ODEs written without units). Parameters are never wildcards: a gain
  of unit ``"1"`` is dimensionless. Variables of unit ``"1"`` of a component with
  physical ports are dimensionless and checked; signals and variables declared with a
  unit are checked everywhere.
* Event actions (``sample``/``when``) are checked too: an assignment ``x := e`` as the
  equation ``x == e``, a ``when`` condition as a relation, a clock's period and offset
  as times.

Opting out: a component class with ``check_dimensions = False`` (inherited by its
subclasses) is exempt for its own equations; ``compile_model(model,
check_dimensions=False)`` skips the pass.

Speed: one CasADi function over the residuals of all equations, built without reuse of
the work vector, with the model's stacked variables as its input (parameters,
derivatives and time are its free symbols, their dimensions looked up by name for the
few it meets), is read instruction by instruction (``instruction_id`` /
``instruction_input``) in one Python loop; a dimension is a single integer (the seven SI
base exponents, in 1/2520ths, packed in bit fields), so combining two is one integer
addition. Equations that fail are walked a second time, their left and right sides
apart, only to word the message.
"""

from __future__ import annotations

import functools
import re
from fractions import Fraction
from itertools import repeat

import casadi as ca
import numpy as np

from mechatron.compiler.flatten import (FlatEquations, FlatModel, _bind_symbols,
                                        _collect_equations, _SumEquation,
                                        _TemplateEquation, _walk,
                                        column_of, stack_columns, stack_residuals)
from mechatron.core.component import Component
from mechatron.core.context import BuildContext
from mechatron.core.events import Clock
from mechatron.errors import UnitError
from mechatron.units import dimensionality

__all__ = ["check_dimensions", "dimension_problems", "component_dimension_problems",
           "unit_dimension", "format_dimension"]

# -- dimensions as packed integers ------------------------------------------------------
_BASE = ("[length]", "[mass]", "[time]", "[current]", "[temperature]", "[substance]",
         "[luminosity]")
_SYMBOL = ("m", "kg", "s", "A", "K", "mol", "cd")
_DEN = 2520                # exponents in 1/2520ths: halves, thirds, ..., tenths are exact
_BITS = 48                 # bits per base exponent (signed fields)
_FIELD = 1 << _BITS
_HALF = _FIELD >> 1
#: dimensionless
ONE = 0
#: one second (the dimension of ``time``; ``der`` subtracts it)
SECOND = _DEN << (_BITS * 2)


def _pack(exponents) -> int:
    return sum(int(e) << (_BITS * k) for k, e in enumerate(exponents))


def _unpack(value: int) -> list[int]:
    out = []
    for _ in _BASE:
        r = value % _FIELD
        if r >= _HALF:
            r -= _FIELD
        out.append(r)
        value = (value - r) >> _BITS
    return out


class _Wildcard:
    """A value whose dimension adapts: a numeric constant or a free signal."""

    __slots__ = ("name",)

    def __init__(self, name: str):
        self.name = name

    def __repr__(self) -> str:
        return self.name


#: a numeric constant: dimensionless in a product, adapts in a sum or a comparison
NUMBER = _Wildcard("number")
#: a free signal (unit "1" of a causal signal): unknown dimension, adapts everywhere
FREE = _Wildcard("free signal")


@functools.lru_cache(maxsize=None)
def unit_dimension(unit: str):
    """The packed dimension of a unit string (``"V"`` -> kg*m^2/(A*s^3)), or ``None`` if
    pint's dimensionality holds a base outside the seven SI ones."""
    dims = dimensionality(unit)
    exps = [0] * len(_BASE)
    for key, power in dims.items():
        if key not in _BASE:
            return None
        exps[_BASE.index(key)] = round(Fraction(power).limit_denominator(10**6) * _DEN)
    return _pack(exps)


def format_dimension(value: int) -> str:
    """``kg*m^2/(A*s^3)``: a packed dimension in SI base units (``1`` if dimensionless)."""
    num, den = [], []
    for sym, e in sorted(zip(_SYMBOL, _unpack(value)), key=lambda se: se[0].lower()):
        if e == 0:
            continue
        p = Fraction(abs(e), _DEN)
        text = sym if p == 1 else (f"{sym}^{p}" if p.denominator == 1 else f"{sym}^({p})")
        (num if e > 0 else den).append(text)
    if not num and not den:
        return "1"
    top = "*".join(num) or "1"
    if not den:
        return top
    return f"{top}/{den[0]}" if len(den) == 1 else f"{top}/({'*'.join(den)})"


#: names for messages, first match wins after the units declared in the model
_NAMED = ("V", "A", "Ohm", "S", "F", "H", "Wb", "T", "C", "W", "J", "N", "Pa", "kg",
          "m", "s", "m/s", "m/s^2", "1/s", "1/s^2", "m^2", "m^3", "m^3/s", "kg/m^3",
          "kg*m^2", "N/m", "N*s/m", "N*m*s", "K", "W/K", "J/K", "N/A", "A/s", "V/s",
          "Pa*s", "m^3/Pa", "A/Wb", "H/m")


@functools.lru_cache(maxsize=None)
def _standard_names() -> dict[int, str]:
    names: dict[int, str] = {}
    for unit in _NAMED:
        d = unit_dimension(unit)
        if d is not None:
            names.setdefault(d, unit)
    return names


# -- the walk over CasADi's instruction list ---------------------------------------------
_UNITLESS_FUNCTIONS = {
    ca.OP_EXP: "exp", ca.OP_LOG: "log", ca.OP_SIN: "sin", ca.OP_COS: "cos",
    ca.OP_TAN: "tan", ca.OP_ASIN: "asin", ca.OP_ACOS: "acos", ca.OP_ATAN: "atan",
    ca.OP_SINH: "sinh", ca.OP_COSH: "cosh", ca.OP_TANH: "tanh", ca.OP_ASINH: "asinh",
    ca.OP_ACOSH: "acosh", ca.OP_ATANH: "atanh", ca.OP_ERF: "erf", ca.OP_ERFINV: "erfinv",
    ca.OP_LOG1P: "log1p", ca.OP_EXPM1: "expm1"}
_KEEP = {ca.OP_NEG, ca.OP_TWICE, ca.OP_ASSIGN, ca.OP_FABS, ca.OP_FLOOR, ca.OP_CEIL}
_AGREE = {ca.OP_FMIN: "min", ca.OP_FMAX: "max", ca.OP_FMOD: "fmod",
          ca.OP_REMAINDER: "remainder", ca.OP_HYPOT: "hypot"}
_RELATION = {ca.OP_LT: "<", ca.OP_LE: "<=", ca.OP_EQ: "==", ca.OP_NE: "!="}
_LOGIC = {ca.OP_NOT, ca.OP_AND, ca.OP_OR}
_INPUT, _CONST, _OUTPUT, _PARAM = ca.OP_INPUT, ca.OP_CONST, ca.OP_OUTPUT, ca.OP_PARAMETER

# the instruction accessors, called once per instruction: CasADi's own entry points skip
# the Python wrapper (about 1.5 times faster); the public methods otherwise
try:
    from casadi import _casadi
    _OP_OF, _INPUTS_OF, _OUTPUTS_OF, _CONSTANT_OF = (
        _casadi.Function_instruction_id, _casadi.Function_instruction_input,
        _casadi.Function_instruction_output, _casadi.Function_instruction_constant)
except (ImportError, AttributeError):     # pragma: no cover - other CasADi builds
    _OP_OF, _INPUTS_OF, _OUTPUTS_OF, _CONSTANT_OF = (
        ca.Function.instruction_id, ca.Function.instruction_input,
        ca.Function.instruction_output, ca.Function.instruction_constant)
_ADD, _SUB, _MUL, _DIV = ca.OP_ADD, ca.OP_SUB, ca.OP_MUL, ca.OP_DIV


def _agree(a, b, what: str):
    """The common dimension of two operands that must agree; a problem if they differ."""
    ta, tb = type(a), type(b)
    if ta is int:
        if tb is int:
            return a if a == b else ("mismatch", what, a, b)
        return b if tb is tuple else a
    if ta is tuple:
        return a
    if tb is int or tb is tuple:
        return b
    return FREE if (a is FREE or b is FREE) else NUMBER


def _product(a, b, sign: int):
    """Dimension of ``a * b`` (``sign`` 1) or ``a / b`` (``sign`` -1)."""
    ta, tb = type(a), type(b)
    if ta is tuple:
        return a
    if tb is tuple:
        return b
    if a is FREE or b is FREE:
        return FREE
    if ta is int:
        if tb is int:
            return a + b if sign > 0 else a - b
        return a                     # times or over a number
    if tb is int:
        return b if sign > 0 else -b
    return NUMBER


def _power(a, c: float):
    """Dimension of ``a ** c`` for a constant ``c``."""
    if type(a) is not int or a == 0:
        return a
    exps = _unpack(a)
    out = []
    for e in exps:
        x = e * c
        r = round(x)
        if abs(x - r) > 1e-6 * max(1.0, abs(x)):
            return ("power", a, c)
        out.append(r)
    return _pack(out)


def _dimensionless(a, what):
    """Check that the argument of a function is dimensionless; the result's dimension."""
    if type(a) is int:
        return ONE if a == 0 else ("function", what, a)
    if a is NUMBER:
        return NUMBER
    return a if type(a) is tuple else ONE


def _unary(op, a):
    if op in _KEEP:
        return a
    if op == ca.OP_SQ:
        return a + a if type(a) is int else a
    if op == ca.OP_INV:
        return -a if type(a) is int else a
    if op == ca.OP_SQRT:
        return _power(a, 0.5)
    if op in _UNITLESS_FUNCTIONS:
        return _dimensionless(a, _UNITLESS_FUNCTIONS[op])
    if op == ca.OP_SIGN or op in _LOGIC:
        return a if type(a) is tuple else ONE
    return FREE                      # an operator this pass does not know: unchecked


def _binary(op, a, b, b_const):
    if op in _RELATION:
        r = _agree(a, b, "comparison")
        return r if type(r) is tuple else ONE
    if op in _AGREE:
        return _agree(a, b, _AGREE[op])
    if op == ca.OP_POW or op == ca.OP_CONSTPOW:
        if b_const is not None:
            return _power(a, b_const)
        if type(a) is tuple:
            return a
        e = _dimensionless(b, "the exponent of pow")
        if type(e) is tuple:
            return e
        base = _dimensionless(a, "the base of pow with a variable exponent")
        if type(base) is tuple:
            return base
        return FREE if a is FREE else ONE
    if op == ca.OP_IF_ELSE_ZERO:
        return a if type(a) is tuple else b
    if op == ca.OP_ATAN2:
        r = _agree(a, b, "atan2")
        return r if type(r) is tuple else ONE
    if op == ca.OP_COPYSIGN:
        return b if type(b) is tuple else a
    if op in _LOGIC:
        return a if type(a) is tuple else (b if type(b) is tuple else ONE)
    return FREE


def infer(f: ca.Function, in_dims: list, free_dims: list | None = None) -> list:
    """Dimension of every output nonzero of ``f`` (one SX input, one vector output), with
    ``in_dims[j]`` the dimension of input nonzero ``j`` and ``free_dims[j]`` that of
    free symbol ``j`` of ``f`` (``f.free_sx()``; default: free signals). An entry is a
    packed dimension (int), :data:`NUMBER`, :data:`FREE`, or a tuple describing the
    first inconsistency met on the way (a *problem*, propagated to every output that
    depends on it)."""
    n = f.n_instructions()
    ids = list(map(_OP_OF, repeat(f, n), range(n)))
    args = list(map(_INPUTS_OF, repeat(f, n), range(n)))
    n_out = f.nnz_out(0)
    out: list = [None] * n_out
    w: list = []
    consts: dict[int, float] = {}
    append = w.append
    # CasADi lists the free symbols in the order of their instructions
    if free_dims is not None and ids.count(_PARAM) != len(free_dims):
        raise RuntimeError("dimension check: unexpected CasADi layout of free symbols; "
                           "please report this with the CasADi version.")
    free = iter(free_dims if free_dims is not None else ())
    out_nz = _OUTPUTS_OF        # [output, nonzero] of an output instruction
    for k, op in enumerate(ids):
        arg = args[k]
        if op == _INPUT:
            append(in_dims[arg[1]])
        elif op == _ADD or op == _SUB:
            a, b = w[arg[0]], w[arg[1]]
            append(a if (a == b and type(a) is int) else _agree(a, b, "sum"))
        elif op == _MUL:
            a, b = w[arg[0]], w[arg[1]]
            append(a + b if type(a) is int and type(b) is int else _product(a, b, 1))
        elif op == _OUTPUT:
            out[out_nz(f, k)[1]] = w[arg[0]]
        elif op == _CONST:
            consts[len(w)] = _CONSTANT_OF(f, k)
            append(NUMBER)
        elif op == _DIV:
            a, b = w[arg[0]], w[arg[1]]
            append(a - b if type(a) is int and type(b) is int else _product(a, b, -1))
        elif op == _PARAM:
            append(next(free, FREE))
        elif len(arg) == 1:
            append(_unary(op, w[arg[0]]))
        else:
            append(_binary(op, w[arg[0]], w[arg[1]], consts.get(arg[1])))
    # without live-variable reuse every instruction writes the next slot of the work
    # vector; check it once rather than trusting it silently
    last = n - 1
    while last >= 0 and ids[last] == _OUTPUT:
        last -= 1
    if last >= 0 and f.instruction_output(last)[0] != len(w) - 1:
        raise RuntimeError("dimension check: unexpected CasADi work-vector layout; "
                           "please report this with the CasADi version.")
    return out


def _function(exprs: list | ca.SX, syms: ca.SX) -> ca.Function:
    body = exprs if isinstance(exprs, ca.SX) else ca.vertcat(*exprs) if exprs else \
        ca.SX(0, 1)
    return ca.Function("dimensions", [syms], [body],
                       {"live_variables": False, "allow_free": True,
                        "cse": False})


# -- the pass --------------------------------------------------------------------------
class _Symbols:
    """The model's variables in one vector (the input of the walk) and the dimension of
    each; the dimension of any other symbol (a parameter, a derivative, time: free
    symbols of the walk) by its name, looked up only for the symbols met."""

    def __init__(self, flat):
        self.flat = flat
        self.declared: dict[int, str] = {}
        physical = flat.physical_owners
        # one dimension per distinct unit, mapped over the variables in C
        # each attribute read off the class plans (no record formed: `column_of`)
        units = column_of(flat.variables, "unit")
        dim_of = {u: self._dim(u) for u in dict.fromkeys(units)}
        dims = list(map(dim_of.__getitem__, units))
        kinds = owners = None
        for u, d in dim_of.items():
            if d != ONE:
                continue
            if kinds is None:
                kinds = column_of(flat.variables, "kind")
                owners = column_of(flat.variables, "owner")
            for k in [k for k, unit in enumerate(units) if unit == u]:
                if _free_signal(kinds[k], owners[k], physical):
                    dims[k] = FREE
        self.dims = dims
        # the variables' column is stacked once per model (shared with other passes)
        self.vector = flat.stack_variables()
        # a differentiated variable's row, noted by its class template (by name else)
        self.derived_rows = flat.__dict__.get("_derivative_rows") or {}

    def _dim(self, unit: str):
        d = unit_dimension(unit)
        if d is None:
            return FREE
        self.declared.setdefault(d, unit)
        return d

    def free(self, f: ca.Function) -> list:
        """The dimension of each free symbol of ``f`` (in the order of ``free_sx``)."""
        return [self.of(s.name()) for s in f.free_sx()]

    def of(self, name: str):
        """The dimension of the symbol ``name``: a parameter, a variable, a derivative,
        time; a symbol of none of these is a free signal."""
        flat = self.flat
        ctx = flat.context
        if name == ctx.time.name():
            return SECOND
        p = flat.parameters.get(name)      # a parameter's symbol is named by its path
        if p is not None:
            d = self._dim(p.unit)
            # a model's external input of unit "1": a free signal
            return FREE if p.is_input and d == ONE else d
        base = ctx.integral.get(name)      # "der(x)" -> "x"
        if base is not None:
            # a variable that a class template differentiated: its dimension by its row
            row = self.derived_rows.get(base)
            return _der(self.dims[row] if row is not None else self.of(base))
        v = flat.variables.get(name)
        if v is not None:           # not met: the variables are the walk's input
            d = self._dim(v.unit)
            free = d == ONE and _free_signal(v.kind, v.owner, flat.physical_owners)
            return FREE if free else d
        return FREE


def _free_signal(kind: str, owner: str, physical) -> bool:
    """Whether a dimensionless variable of ``kind`` whose component is ``owner`` is a
    free signal: a signal input or output, or a variable of a component without
    physical ports (``physical``)."""
    return kind == "input" or kind == "output" or \
        (kind == "variable" and owner not in physical)


def _der(d):
    return d - SECOND if type(d) is int else d


def _event_rows(flat) -> tuple[list, list]:
    """Event actions as extra rows: ``x - e`` for an assignment, the condition of a
    ``when``, ``period - time`` and ``offset - time`` of a clock."""
    rows, origins = [], []
    t = flat.context.time
    for action, owner in flat.events:
        for var, expr in list(action.outputs) + list(action.updates):
            rows.append(ca.SX(var) - expr)
            origins.append((owner, f"{_short(var)} := {_short(expr)} (event action)"))
        branches = getattr(action, "branches", None)
        triggers = [c for conds, _ in branches for c in conds] if branches else \
            [action.trigger]
        for trig in triggers:
            clock = getattr(trig, "clock", trig)       # sample(start, interval)
            if isinstance(clock, Clock):
                for what, value in (("period", clock.period), ("offset", clock.offset)):
                    rows.append(value - t)
                    origins.append((owner, f"the sample clock's {what} {_short(value)}, "
                                           "a time"))
            else:
                rows.append(ca.SX(trig))
                origins.append((owner, f"when {_short(trig)} (event condition)"))
    return rows, origins


def dimension_problems(flat, model=None) -> list[str]:
    """Every equation of ``flat`` (a :class:`~mechatron.compiler.flatten.FlatModel`)
    whose dimensions do not agree, as messages; empty when all agree.

    ``model`` is the root instance: with it, equations of a component whose class sets
    ``check_dimensions = False`` are skipped.
    """
    symbols = _Symbols(flat)
    # equations instantiated from one class's template have the same dimensions in
    # every instance (same declarations, bound parameters checked to their units):
    # the first instance stands for all
    eqs = [eq for eq in _first_instances(flat.equations) if _checked(eq)]
    extra, extra_origins = _event_rows(flat)
    # the rows of templates and flow sums gathered from their columns (a vertcat of
    # scalars converts each from Python)
    rows = stack_residuals(eqs) if eqs else ca.SX(0, 1)
    f = _function(stack_columns(rows, ca.vertcat(*extra)) if extra else rows,
                  symbols.vector)
    dims = infer(f, symbols.dims, symbols.free(f))
    failing = [k for k, d in enumerate(dims) if type(d) is tuple]
    if not failing:
        return []
    namer = _Namer(symbols.declared)
    exempt = _Exemptions(model)
    problems = []
    sided = [k for k in failing if k < len(eqs) and hasattr(eqs[k].origin, "lhs")]
    sides = {}
    if sided:
        pairs = []
        for k in sided:
            pairs += [eqs[k].origin.lhs, eqs[k].origin.rhs]
        g = _function(pairs, symbols.vector)
        both = infer(g, symbols.dims, symbols.free(g))
        sides = {k: (both[2 * j], both[2 * j + 1]) for j, k in enumerate(sided)}
    for k in failing:
        if k < len(eqs):
            eq = eqs[k]
            owner = eq.owner
            if exempt(owner):
                continue
            where = _describe(flat, owner)
            if k in sides:
                text = _equation(eq.origin, owner)
                problems.append(f"{where}: {text}: "
                                f"{_explain(dims[k], sides[k], namer)}")
            else:
                problems.append(f"{where}: {_strip(str(eq.origin), owner)}: "
                                f"{namer.problem(dims[k])}. {_HINT}")
        else:
            owner, text = extra_origins[k - len(eqs)]
            if exempt(owner):
                continue
            problems.append(f"{_describe(flat, owner)}: {_strip(text, owner)}: "
                            f"{namer.problem(dims[k])}. {_HINT}")
    return problems


def _first_instances(eqs):
    """``eqs`` (`FlatModel.equations`) without the rows of class templates past their
    first instance (see `_checked`), in order: held as numbers, those are not formed."""
    numbered = eqs.numbered() if type(eqs) is FlatEquations else None
    if numbered is None:
        return eqs
    which, rows = numbered
    n_eq = np.array([t.n_eq for t in eqs.templates] + [0], dtype=np.int64)
    return [eqs[k] for k in np.flatnonzero((which < 0) | (rows < n_eq[which])).tolist()]


def _checked(eq) -> bool:
    """Whether the dimensions of ``eq`` are checked: a class template's equations once,
    in its first instance (read off its row, without forming its origin); a flow sum
    unless all its terms are the same variable of one connector class (the same unit:
    it agrees by construction; a sum over connectors of different classes is checked)."""
    kind = type(eq)
    if kind is _TemplateEquation:
        return eq.row < eq.template.n_eq
    return kind is not _SumEquation or not eq.uniform


def check_dimensions(flat, model=None) -> None:
    """Raise :class:`~mechatron.errors.UnitError` listing every equation of ``flat`` whose
    dimensions do not agree (see :func:`dimension_problems`)."""
    problems = dimension_problems(flat, model)
    if not problems:
        return
    if len(problems) == 1:
        message = problems[0]
    else:
        message = (f"model '{flat.name}': {len(problems)} equations with inconsistent "
                   "dimensions:\n  " + "\n  ".join(problems))
    raise UnitError(message, path=flat.name, problems=problems)


def component_dimension_problems(cls_or_instance) -> list[str]:
    """The dimension check of one component class on its own (its equations and those of
    its parts, without connections): for the library walk and for authors of components.

    A class is instantiated with its defaults; parameters without defaults are left
    without a value (values do not matter here).
    """
    root = cls_or_instance() if isinstance(cls_or_instance, type) else cls_or_instance
    if not isinstance(root, Component):
        raise TypeError(f"component_dimension_problems: expected a Component, got "
                        f"{cls_or_instance!r}.")
    name = root._name or type(root).__name__
    flat = FlatModel(name=name, context=BuildContext())
    elements = list(_walk(root))
    for el in elements:
        if isinstance(el, Component):
            flat.components[el.path] = type(el).__name__
    try:
        _bind_symbols(flat, elements, _Ignore())
        with flat.context:
            _collect_equations(flat, elements, _Ignore())
    finally:
        for el in elements:
            el._syms = None
            el._path_cache = None
    return dimension_problems(flat, root)


class _Ignore(list):
    """A problem list that drops what it is given (values do not matter here)."""

    def append(self, message) -> None:
        pass

    def add(self, kind, message) -> None:
        pass


# -- messages --------------------------------------------------------------------------
class _Namer:
    """Words for dimensions: a unit declared in the model or a common SI name, and the
    SI base form, e.g. ``V (kg*m^2/(A*s^3))``."""

    def __init__(self, declared: dict[int, str]):
        self.names = dict(_standard_names())
        self.names.update({d: u for d, u in declared.items()
                           if d != ONE and u not in ("", "1")})

    def __call__(self, d) -> str:
        if not isinstance(d, int):
            return "a number" if d is NUMBER else "a free signal"
        if d == ONE:
            return "dimensionless"
        base = format_dimension(d)
        name = self.names.get(d)
        return f"{name} ({base})" if name and name != base else base

    def problem(self, p) -> str:
        kind = p[0]
        if kind == "mismatch":
            _, what, a, b = p
            verb = {"sum": "adds", "comparison": "compares"}.get(what)
            if verb == "adds":
                return f"it adds {self(a)} and {self(b)}"
            if verb == "compares":
                return f"it compares {self(a)} with {self(b)}"
            return f"{what}() of {self(a)} and {self(b)}"
        if kind == "function":
            _, what, a = p
            if what.startswith("the "):
                return f"{what} must be dimensionless, got {self(a)}"
            return f"{what}() needs a dimensionless argument, got {self(a)}"
        if kind == "power":
            _, a, c = p
            return (f"{self(a)} to the power {c:g} has no dimension in whole or simple "
                    "fractional powers of the SI base units; normalise the base first, "
                    "e.g. (x/x_ref)**c")
        return str(p)


def _explain(whole, sides, namer: _Namer) -> str:
    left, right = sides
    for side, d in (("left", left), ("right", right)):
        if type(d) is tuple:
            return f"on the {side} side, {namer.problem(d)}. {_HINT}"
    if type(left) is int and type(right) is int and left != right:
        hint = "Is a der() missing?" if abs(left - right) == SECOND else _HINT
        return (f"the left side is {namer(left)}, the right side is {namer(right)}. "
                f"{hint}")
    return f"{namer.problem(whole)}. {_HINT}"


_HINT = "Check the units declared for its variables and parameters."


def _describe(flat, owner: str) -> str:
    cls = flat.components.get(owner)
    if not owner:
        return f"model '{flat.name}'"
    return f"{cls} '{owner}'" if cls else f"'{owner}'"


def _equation(origin, owner: str) -> str:
    return _strip(f"{_short(origin.lhs)} == {_short(origin.rhs)}", owner)


def _strip(text: str, owner: str) -> str:
    """``r1.v == (r1.R*r1.i)`` -> ``v == (R*i)`` in the messages about ``r1``."""
    if owner:
        text = re.sub(rf"(?<![\w.]){re.escape(owner)}\.", "", text)
    return text


def _short(expr, limit: int = 80) -> str:
    text = str(expr)
    return text if len(text) <= limit else text[:limit - 3] + "..."


class _Exemptions:
    """Which owners opted out (``check_dimensions = False`` on their class)."""

    def __init__(self, model):
        self.model = model
        self.cache: dict[str, bool] = {}

    def __call__(self, owner: str) -> bool:
        if self.model is None:
            return False
        hit = self.cache.get(owner)
        if hit is None:
            el = self.model
            for part in owner.split(".") if owner else ():
                el = el._children.get(part)
                if el is None:
                    break
            hit = el is not None and not getattr(type(el), "check_dimensions", True)
            self.cache[owner] = hit
        return hit
