"""Why a compiled function gave a value that is not finite: which operation, on which
values, and which of the model's variables it reaches.

Only called once something has gone wrong, never inside a solver: it replays the
function's SX algorithm one instruction at a time with NumPy at the failing point and
stops at the first instruction whose operands are finite but whose result is not (a
logarithm of a negative number, a division by zero, a square root of a negative number,
an overflow). Taint is tracked forward so that the message names the first output the
failure reaches, e.g.::

    y: log of a negative number, log(-0.01), at t = 1.01 s
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

__all__ = ["first_nonfinite", "describe_nonfinite"]


def _safe(fn):
    def run(*a):
        with np.errstate(all="ignore"):
            return float(fn(*a))
    return run


_UNARY = {
    ca.OP_NEG: ("negation", lambda a: -a), ca.OP_EXP: ("exp", np.exp),
    ca.OP_LOG: ("log", np.log), ca.OP_SQRT: ("sqrt", np.sqrt), ca.OP_SQ: ("square", np.square),
    ca.OP_TWICE: ("doubling", lambda a: 2 * a), ca.OP_SIN: ("sin", np.sin),
    ca.OP_COS: ("cos", np.cos), ca.OP_TAN: ("tan", np.tan), ca.OP_ASIN: ("asin", np.arcsin),
    ca.OP_ACOS: ("acos", np.arccos), ca.OP_ATAN: ("atan", np.arctan),
    ca.OP_SINH: ("sinh", np.sinh), ca.OP_COSH: ("cosh", np.cosh),
    ca.OP_TANH: ("tanh", np.tanh), ca.OP_ASINH: ("asinh", np.arcsinh),
    ca.OP_ACOSH: ("acosh", np.arccosh), ca.OP_ATANH: ("atanh", np.arctanh),
    ca.OP_FABS: ("abs", np.abs), ca.OP_SIGN: ("sign", np.sign),
    ca.OP_FLOOR: ("floor", np.floor), ca.OP_CEIL: ("ceil", np.ceil),
    ca.OP_INV: ("reciprocal", lambda a: 1.0 / a), ca.OP_NOT: ("not", lambda a: float(not a)),
    ca.OP_ERF: ("erf", lambda a: math.erf(a)), ca.OP_ASSIGN: ("copy", lambda a: a),
    ca.OP_LOG1P: ("log1p", np.log1p), ca.OP_EXPM1: ("expm1", np.expm1),
}
_BINARY = {
    ca.OP_ADD: ("addition", lambda a, b: a + b), ca.OP_SUB: ("subtraction", lambda a, b: a - b),
    ca.OP_MUL: ("multiplication", lambda a, b: a * b),
    ca.OP_DIV: ("division", lambda a, b: a / b), ca.OP_POW: ("power", np.power),
    ca.OP_CONSTPOW: ("power", np.power), ca.OP_LT: ("<", lambda a, b: float(a < b)),
    ca.OP_LE: ("<=", lambda a, b: float(a <= b)), ca.OP_EQ: ("==", lambda a, b: float(a == b)),
    ca.OP_NE: ("!=", lambda a, b: float(a != b)),
    ca.OP_AND: ("and", lambda a, b: float(bool(a) and bool(b))),
    ca.OP_OR: ("or", lambda a, b: float(bool(a) or bool(b))),
    ca.OP_FMIN: ("min", np.fmin), ca.OP_FMAX: ("max", np.fmax),
    ca.OP_FMOD: ("fmod", np.fmod), ca.OP_ATAN2: ("atan2", np.arctan2),
    ca.OP_COPYSIGN: ("copysign", np.copysign), ca.OP_HYPOT: ("hypot", np.hypot),
    ca.OP_IF_ELSE_ZERO: ("if_else", lambda c, a: a if c else 0.0),
}
_UNARY = {k: (n, _safe(f)) for k, (n, f) in _UNARY.items()}
_BINARY = {k: (n, _safe(f)) for k, (n, f) in _BINARY.items()}


def _what(name: str, args: list[float]) -> str:
    a = args[0]
    if name == "log" and a < 0:
        return f"log of a negative number, log({a:g})"
    if name == "log" and a == 0:
        return "log of zero"
    if name == "sqrt" and a < 0:
        return f"square root of a negative number, sqrt({a:g})"
    if name in ("division", "reciprocal") and args[-1] == 0:
        return f"division by zero ({args[0]:g} / 0)" if name == "division" else \
            "division by zero (1 / 0)"
    if name == "power":
        return f"power {args[0]:g} ** {args[1]:g} is not finite"
    if name in ("asin", "acos", "atanh", "acosh"):
        return f"{name}({a:g}) is outside its domain"
    if name == "exp" or name == "multiplication":
        return f"overflow in {name} of {', '.join(f'{v:g}' for v in args)}"
    return f"{name} of {', '.join(f'{v:g}' for v in args)} is not finite"


def first_nonfinite(f: ca.Function, args: list) -> tuple[str, int | None, int] | None:
    """Replay SX function ``f`` at ``args``. Returns ``(what, output element, n_reached)``
    for the first operation that turned finite operands into a non-finite value: what it
    was, the first output element it reaches (flat index over the outputs, in order),
    and how many output elements it reaches; or None if every operation stayed finite
    (the non-finite value came in through an input)."""
    if not f.is_a("SXFunction"):
        return None
    inputs = [np.asarray(ca.DM(a)).ravel(order="F") if not np.isscalar(a)
              else np.array([float(a)]) for a in args]
    offsets = np.cumsum([0] + [f.nnz_out(i) for i in range(f.n_out())])
    work = np.zeros(f.sz_w())
    taint = np.zeros(f.sz_w(), dtype=bool)
    culprit, reached, first = None, 0, None
    for k in range(f.n_instructions()):
        op = f.instruction_id(k)
        ins, outs = f.instruction_input(k), f.instruction_output(k)
        if op == ca.OP_INPUT:
            work[outs[0]] = inputs[ins[0]][ins[1]]
            taint[outs[0]] = False
            continue
        if op == ca.OP_OUTPUT:
            if taint[ins[0]]:
                reached += 1
                if first is None:
                    first = int(offsets[outs[0]] + outs[1])
            continue
        if op == ca.OP_CONST:
            work[outs[0]] = f.instruction_constant(k)
            taint[outs[0]] = False
            continue
        if op in _UNARY:
            name, fn = _UNARY[op]
            operands = [work[ins[0]]]
            tainted = bool(taint[ins[0]])
        elif op in _BINARY:
            name, fn = _BINARY[op]
            operands = [work[ins[0]], work[ins[1]]]
            tainted = bool(taint[ins[0]] or taint[ins[1]])
        else:
            return None      # an operation this replay does not know: say nothing wrong
        value = fn(*operands)
        work[outs[0]] = value
        if not tainted and not math.isfinite(value) and \
                all(math.isfinite(v) for v in operands):
            # the same failure may be computed more than once (no common subexpressions)
            culprit = culprit or _what(name, operands)
            tainted = True
        taint[outs[0]] = tainted
    if culprit is None:
        return None
    return culprit, first, reached


def describe_nonfinite(f: ca.Function, args: list, names: list[str] | None,
                       t: float) -> str:
    """A sentence for an error message, or "" when the replay finds no single cause."""
    found = first_nonfinite(f, args)
    if found is None:
        return ""
    what, first, reached = found
    where = names[first] if names is not None and first is not None and \
        first < len(names) else "an intermediate value"
    more = f" (and {reached - 1} more variable(s) that depend on it)" if reached > 1 else ""
    return f"{where}: {what}, at t = {t:g} s{more}"
