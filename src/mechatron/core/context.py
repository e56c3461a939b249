"""The language functions used inside ``equations()``: ``der``, ``connect``, and the
compile context that gives them meaning.

``der(x)`` of a variable is a derivative symbol; of an expression, the chain rule over the
variables it contains (parameters are constant, time has derivative 1).
"""

from __future__ import annotations

import contextvars

import casadi as ca

from mechatron.core.component import Connect
from mechatron.errors import ModelError

__all__ = ["der", "connect", "current", "if_else", "logic_and", "logic_or", "logic_not",
           "BuildContext"]

_current: contextvars.ContextVar = contextvars.ContextVar("mechatron_build", default=None)


class BuildContext:
    """State of one model build: the time symbol and the derivative symbols."""

    def __init__(self):
        self.time = ca.SX.sym("time")
        self.derivative: dict[str, ca.SX] = {}   # variable name -> der symbol
        self.unknowns: dict[str, ca.SX] = {}     # variable name -> symbol (differentiable)
        self.integral: dict[str, str] = {}       # der symbol name -> variable name
        self.pre: dict[str, ca.SX] = {}          # variable name -> pre() symbol
        self.special: dict[str, ca.SX] = {}      # "initial"/"terminal" -> condition symbol

    def pre_symbol(self, name: str) -> ca.SX:
        sym = self.pre.get(name)
        if sym is None:
            sym = self.pre[name] = ca.SX.sym(f"pre({name})")
        return sym

    def special_symbol(self, key: str) -> ca.SX:
        sym = self.special.get(key)
        if sym is None:
            sym = self.special[key] = ca.SX.sym(f"{key}()")
        return sym

    def der_symbol(self, name: str) -> ca.SX:
        sym = self.derivative.get(name)
        if sym is None:
            key = f"der({name})"            # the symbol's name
            sym = ca.SX.sym(key)
            self.derivative[name] = sym
            self.integral[key] = name
            self.unknowns[key] = sym
        return sym

    def __enter__(self):
        self._token = _current.set(self)
        return self

    def __exit__(self, *exc):
        _current.reset(self._token)


def current() -> BuildContext:
    ctx = _current.get()
    if ctx is None:
        raise ModelError("der() and time exist only inside equations() while a model "
                         "compiles.")
    return ctx


def der(expr):
    """Time derivative of a variable or of an expression of variables."""
    ctx = current()
    expr = ca.SX(expr)
    if expr.is_scalar() and expr.is_symbolic():
        name = expr.name()
        if name not in ctx.unknowns:
            if name == ctx.time.name():
                return ca.SX(1)
            return ca.SX(0)  # a parameter
        return ctx.der_symbol(name)
    syms = [s for s in ca.symvar(expr) if s.name() in ctx.unknowns]
    dt = ca.jacobian(expr, ctx.time) if ca.depends_on(expr, ctx.time) else 0
    if not syms:
        return ca.SX(dt) if not isinstance(dt, int) else ca.SX.zeros(expr.shape)
    v = ca.vertcat(*syms)
    dv = ca.vertcat(*[ctx.der_symbol(s.name()) for s in syms])
    return ca.jtimes(expr, v, dv) + dt


def connect(*ports) -> Connect:
    """Connect ports: across variables equal, through variables summing to zero; or a
    signal output to one or more signal inputs."""
    if len(ports) < 2:
        raise ModelError("connect needs at least two ports.")
    return Connect(ports)


def if_else(cond, a, b):
    """``a`` where ``cond`` holds, else ``b``; a relation in ``cond`` generates events."""
    return ca.if_else(cond, a, b)


def logic_and(*conditions):
    """True where every condition holds (relations in it generate events)."""
    out = conditions[0]
    for c in conditions[1:]:
        out = ca.logic_and(out, c)
    return out


def logic_or(*conditions):
    """True where any condition holds (relations in it generate events)."""
    out = conditions[0]
    for c in conditions[1:]:
        out = ca.logic_or(out, c)
    return out


def logic_not(condition):
    """True where ``condition`` does not hold."""
    return ca.logic_not(condition)
