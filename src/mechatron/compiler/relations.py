"""Relations (``<``, ``<=``, ``sign``) become event-generating modes.

Every relation whose value may change during a simulation is replaced by a placeholder
symbol. Later the placeholder is bound to a *mode* ``s`` in {-1, +1}: constant between
events, flipped when the indicator ``s * d`` crosses zero (located by the variable-step
solver, or checked at each step end by the fixed-step solvers). This is how Modelica tools
and Simscape keep the integrator away from discontinuities.

The rewrite walks CasADi's instruction list of the equations that contain relations and
rebuilds them with ``SX.unary``/``SX.binary``, so no Python source is parsed.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import repeat

import casadi as ca
import numpy as np


try:      # CasADi's own entry point, without the Python wrapper: once per instruction
    from casadi._casadi import Function_instruction_id as _OP_OF
except ImportError:     # pragma: no cover - other CasADi builds
    _OP_OF = ca.Function.instruction_id

__all__ = ["Relation", "extract_relations"]

_REL_OPS = {ca.OP_LT: "<", ca.OP_LE: "<=", ca.OP_SIGN: "sign"}


@dataclass
class Relation:
    """One relation: value ``(s+1)/2`` for ``<``/``<=`` (or ``s`` for sign), where
    ``s = +1`` while ``d > 0`` (``d >= 0`` for ``<=``)."""

    placeholder: ca.SX
    op: str          # "<", "<=", "sign"
    d: ca.SX         # the distance whose sign is the mode
    owner: str       # component path, for event statistics
    text: str = ""   # the relation as written (``a < b``), for messages


def extract_relations(residuals: list[ca.SX], owners: list[str],
                      stacked: ca.SX | None = None, origins: list | None = None
                      ) -> tuple[list[ca.SX], list[Relation]]:
    """Replace the relations in ``residuals`` by placeholders.

    Parameters
    ----------
    residuals : list of SX
        Scalar expressions.
    owners : list of str
        Component path of each residual.
    stacked : SX, optional
        ``vertcat(*residuals)``, if the caller has it.
    origins : list, optional
        The origin of each residual. A residual instantiated from the template of a
        component class (:mod:`mechatron.compiler.flatten`) whose expression graph holds
        no relation holds none either (instantiation and alias substitution put
        expressions in place of symbols, they add no operation): only the others are
        scanned.
    """
    if not residuals:
        return residuals, []
    rows = _candidates(origins) if origins is not None else None
    if rows is not None and not rows:
        return residuals, []
    column = stacked if stacked is not None else ca.vertcat(*residuals)
    if rows is not None and len(rows) < len(residuals):
        column = column[rows]
    else:
        rows = range(len(residuals))
    f = ca.Function("scan", [], [column], {"allow_free": True, "live_variables": False})
    n = f.n_instructions()
    ops = list(map(_OP_OF, repeat(f, n), range(n)))
    if _REL_OPS.keys().isdisjoint(ops):
        return residuals, []
    # which outputs depend on a relation: propagate a flag through the work vector
    flagged_work: dict[int, bool] = {}
    touched: set[int] = set()
    for k, op in enumerate(ops):
        if op == ca.OP_OUTPUT:
            ins = f.instruction_input(k)
            if flagged_work.get(ins[0]):
                touched.add(rows[f.instruction_output(k)[1]])
            continue
        if op in (ca.OP_INPUT, ca.OP_CONST, ca.OP_PARAMETER):
            flagged_work[f.instruction_output(k)[0]] = False
            continue
        ins = f.instruction_input(k)
        arity = 1 if _is_unary(op) else 2
        flag = op in _REL_OPS or any(flagged_work.get(i, False) for i in ins[:arity])
        flagged_work[f.instruction_output(k)[0]] = flag
    out = list(residuals)
    relations: list[Relation] = []
    for j in sorted(touched):
        out[j] = _rebuild(residuals[j], owners[j], relations)
    return out, relations


def _candidates(origins) -> list[int] | None:
    """The residuals that may hold relations: all but those of class templates without
    any (read once per template); None if that cannot be told. An `Origins` tells each
    row's template by number, without forming the origins."""
    free: dict[int, bool] = {}          # template -> holds no relation

    def holds_none(template) -> bool:
        fun = getattr(template, "fun", None)
        if not isinstance(fun, ca.Function):
            return False
        key = id(template)
        none = free.get(key)
        if none is None:
            m = fun.n_instructions()
            none = free[key] = _REL_OPS.keys().isdisjoint(map(_OP_OF, repeat(fun, m),
                                                               range(m)))
        return none

    # imported here: estimation reads this module without the compiler's passes
    from mechatron.compiler.flatten import Origins
    if isinstance(origins, Origins) and origins.formed is None:
        # the rows of the templates that may hold one, and every row held as given
        # (read one by one, as below), in order
        scan = np.array([not holds_none(t) for t in origins.templates] + [True])
        maybe = scan[origins.which]            # which == -1: the last entry, True
        for k, origin in origins.given.items():
            maybe[k] = not holds_none(getattr(origin, "template", None))
        n = len(origins.which)
        return np.flatnonzero(maybe).tolist() + list(range(n, len(origins)))
    return [k for k, origin in enumerate(origins)
            if not holds_none(getattr(origin, "template", None))]


def _placeholder(relations: list[Relation], op: str, d: ca.SX, owner: str,
                 text: str = "") -> ca.SX:
    """The placeholder of this relation; one relation written twice is one mode."""
    for r in relations:
        if r.owner == owner and r.op == op and ca.is_equal(r.d, d, 20):
            return r.placeholder
    ph = ca.SX.sym(f"rel{len(relations)}[{owner}]")
    relations.append(Relation(ph, op, d, owner, text))
    return ph


def _text(a: ca.SX, op: str, b: ca.SX) -> str:
    text = f"{a} {op} {b}"
    return text if len(text) <= 60 else text[:57] + "..."


def _is_unary(op: int) -> bool:
    return op in _UNARY


_UNARY = {getattr(ca, n) for n in dir(ca) if n.startswith("OP_") and n in (
    "OP_NEG", "OP_EXP", "OP_LOG", "OP_SQ", "OP_SQRT", "OP_SIN", "OP_COS", "OP_TAN",
    "OP_ASIN", "OP_ACOS", "OP_ATAN", "OP_FLOOR", "OP_CEIL", "OP_FABS", "OP_SIGN",
    "OP_NOT", "OP_INV", "OP_SINH", "OP_COSH", "OP_TANH", "OP_ASINH", "OP_ACOSH",
    "OP_ATANH", "OP_ERF", "OP_ERFINV", "OP_TWICE", "OP_ASSIGN", "OP_LOG1P", "OP_EXPM1")}


def _rebuild(expr: ca.SX, owner: str, relations: list[Relation]) -> ca.SX:
    syms = ca.symvar(expr)
    f = ca.Function("one", syms, [expr])
    work: dict[int, ca.SX] = {}
    result = None
    for k in range(f.n_instructions()):
        op = f.instruction_id(k)
        o = f.instruction_output(k)
        i = f.instruction_input(k)
        if op == ca.OP_INPUT:
            work[o[0]] = syms[i[0]]
        elif op == ca.OP_CONST:
            work[o[0]] = ca.SX(f.instruction_constant(k))
        elif op == ca.OP_OUTPUT:
            result = work[i[0]]
        elif op in _REL_OPS:
            if op == ca.OP_SIGN:
                d = work[i[0]]
                text = f"sign({work[i[0]]})"
            else:
                d = work[i[1]] - work[i[0]]  # a < b  <=>  b - a > 0
                text = _text(work[i[0]], _REL_OPS[op], work[i[1]])
            work[o[0]] = _placeholder(relations, _REL_OPS[op], d, owner, text)
        elif op in _UNARY:
            work[o[0]] = ca.SX.unary(op, work[i[0]])
        else:
            work[o[0]] = ca.SX.binary(op, work[i[0]], work[i[1]])
    return result if result is not None else expr
