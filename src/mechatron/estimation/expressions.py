"""Measured outputs as expressions of model variables (``[outputs] w = "abs(motor.w)"``).

A sensor rarely measures one model variable as it is: a tachometer gives ``|w|``, a
load cell the sum of two forces, a current probe ``0.1 * i``. An output may therefore be
an arithmetic expression of logged variables (instance paths), numbers, ``+ - * / **``
and the functions of :data:`FUNCTIONS`; ``rate(expr)`` compares the increment of the
expression over each sample interval divided by its length (see
:func:`~mechatron.estimation.problem.EstimationProblem`).

The text is parsed by :mod:`ast` and only the node types above are accepted: names,
attribute chains (paths), numbers, the four operations and powers, unary signs and calls
of the listed functions. Nothing is evaluated as Python (no ``eval``), so
``__import__('os')`` or ``x.__class__`` are refused with a message naming the output.
The expression becomes a CasADi function of the variables with its gradient, evaluated
on all samples at once; the unit is the expression's own, computed by pint (adding volts
to amperes is an error; a number added to a quantity is in its SI unit).
"""

from __future__ import annotations

import ast
from dataclasses import dataclass

import casadi as ca

from mechatron.errors import DataError

__all__ = ["OutputExpression", "parse_output", "FUNCTIONS"]

#: Functions an output expression may call: name -> (CasADi, pint/numpy) implementation.
FUNCTIONS = {
    "abs": (ca.fabs, abs),
    "sqrt": (ca.sqrt, None),
    "exp": (ca.exp, None),
    "log": (ca.log, None),
    "sin": (ca.sin, None),
    "cos": (ca.cos, None),
    "tan": (ca.tan, None),
    "tanh": (ca.tanh, None),
    "atan2": (ca.atan2, None),
    "min": (ca.fmin, None),
    "max": (ca.fmax, None),
}
_BINOPS = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b,
           ast.Mult: lambda a, b: a * b, ast.Div: lambda a, b: a / b,
           ast.Pow: lambda a, b: a ** b}


@dataclass
class OutputExpression:
    """One measured output: ``kind`` ``"value"`` or ``"rate"``, the ``paths`` of the
    variables it reads (in order) and ``function(v) -> (y, dy/dv)``."""

    text: str
    kind: str
    paths: list
    function: ca.Function
    plain: bool

    @property
    def path(self) -> str:
        """The variable of a plain output (or the first one of an expression)."""
        return self.paths[0] if self.paths else ""

    def __iter__(self):                     # (path, kind), as before expressions
        return iter((self.path, self.kind))

    def __getitem__(self, k):
        return (self.path, self.kind)[k]

    def unit(self, units: dict) -> str:
        """The expression's unit from the variables' units (pint); ``DataError`` when
        the dimensions do not combine."""
        if self.plain:
            return units[self.path]
        from mechatron.units import ureg
        tree = ast.parse(_inner(self.text)[0], mode="eval").body
        try:
            q = _walk(tree, lambda path: ureg.Quantity(1.0, units[path] or
                                                       "dimensionless"), numeric=True)
            return format(q.to_base_units().units, "~C") or ""
        except Exception as exc:
            raise DataError(f"output '{self.text}': the units do not combine ({exc}). "
                            "Add or compare quantities of one dimension only.") from None


def _inner(text: str) -> tuple[str, str]:
    text = text.strip()
    if text.startswith("rate(") and text.endswith(")"):
        return text[5:-1].strip(), "rate"
    return text, "value"


def parse_output(text: str, names, where: str = "output") -> OutputExpression:
    """Parse an output mapping (``"motor.w"``, ``"rate(load.x)"``, ``"abs(w) * 0.5"``)
    against the logged variables ``names``; ``DataError`` for anything else."""
    body, kind = _inner(str(text))
    known = set(names)
    if body in known:
        x = ca.SX.sym("v")
        return OutputExpression(str(text), kind, [body],
                                ca.Function("out", [x], [x, ca.SX(1)]), True)
    try:
        tree = ast.parse(body, mode="eval").body
    except SyntaxError as exc:
        raise DataError(f"{where}: '{text}' is neither a variable of the model nor an "
                        f"expression ({exc.msg}). Write e.g. \"abs(motor.w)\" or "
                        "\"2 * a.x + b.x\".", path=where) from None
    paths: list[str] = []
    if isinstance(tree, (ast.Name, ast.Attribute)) and _plain_path(tree):
        raise DataError(f"{where} is compared with '{body}', which the model does not "
                        "log.", path=where)

    def var(path):
        if path not in known:
            close = [n for n in names if n.endswith(path.split(".")[-1])][:5]
            raise DataError(f"{where}: '{text}' reads '{path}', which the model does not "
                            f"log" + (f" (similar: {', '.join(close)})" if close else "")
                            + ".", path=where)
        if path not in paths:
            paths.append(path)
        return path

    try:
        _walk(tree, var, numeric=False, check_only=True)
    except _Refused as exc:
        raise DataError(f"{where}: '{text}': {exc} is not allowed in an output expression; "
                        "use variables, numbers, + - * / **, and "
                        f"{', '.join(FUNCTIONS)}.", path=where) from None
    v = ca.SX.sym("v", len(paths))
    y = _walk(tree, lambda path: v[paths.index(path)], numeric=False)
    y = ca.SX(y)
    fn = ca.Function("out", [v], [y, ca.jacobian(y, v)])
    return OutputExpression(str(text), kind, paths, fn, False)


class _Refused(Exception):
    pass


def _plain_path(node) -> bool:
    try:
        return _path(node) is not None
    except _Refused:
        return False


def _path(node) -> str | None:
    """``a.b.c`` as a dotted path, or None for anything but names and attributes."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if isinstance(node, ast.Name):
        parts.append(node.id)
        path = ".".join(reversed(parts))
        if "__" in path:
            raise _Refused(f"the name '{path}'")
        return path
    return None


def _walk(node, leaf, *, numeric: bool, check_only: bool = False):
    """Evaluate the accepted subset of Python expressions with ``leaf(path)`` for the
    variables; refuse every other node."""
    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
            raise _Refused(f"the constant {node.value!r}")
        return float(node.value)
    if isinstance(node, (ast.Name, ast.Attribute)):
        path = _path(node)
        if path is None:
            raise _Refused(f"'{ast.unparse(node)}'")
        return leaf(path)
    if isinstance(node, ast.BinOp) and type(node.op) in _BINOPS:
        a = _walk(node.left, leaf, numeric=numeric, check_only=check_only)
        b = _walk(node.right, leaf, numeric=numeric, check_only=check_only)
        if numeric and isinstance(node.op, (ast.Add, ast.Sub)):
            # a number added to a quantity is in that quantity's (SI) unit
            if isinstance(a, float) and hasattr(b, "units"):
                a = b.__class__(a, b.units)
            elif isinstance(b, float) and hasattr(a, "units"):
                b = a.__class__(b, a.units)
        return None if check_only else _BINOPS[type(node.op)](a, b)
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        a = _walk(node.operand, leaf, numeric=numeric, check_only=check_only)
        return None if check_only else (-a if isinstance(node.op, ast.USub) else a)
    if isinstance(node, ast.Call):
        name = node.func.id if isinstance(node.func, ast.Name) else None
        if name not in FUNCTIONS or node.keywords:
            raise _Refused(f"the call '{ast.unparse(node)}'")
        args = [_walk(a, leaf, numeric=numeric, check_only=check_only) for a in node.args]
        if check_only:
            return None
        if numeric:
            import numpy as np
            return {"abs": abs, "min": min, "max": max}.get(name, getattr(np, name, None)
                                                             )(*args) if name != "atan2" \
                else np.arctan2(*args)
        return FUNCTIONS[name][0](*args)
    raise _Refused(f"'{ast.unparse(node)}'")
