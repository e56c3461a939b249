"""Pass 3: alias elimination.

Equations of the form ``a = b``, ``a = -b`` and ``a = c`` (a numeric constant) are removed
and their variables replaced by one representative (or the constant) in one bulk
substitution over every remaining equation. Connections produce most aliases; component
equations such as ``i == p.i`` produce the rest. The eliminated variables stay in the
simulation log, computed from their representative.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca

from mechatron.compiler.flatten import FlatEquation, FlatModel
from mechatron.errors import InitializationError

__all__ = ["AliasResult", "eliminate_aliases"]

_PRIORITY_RANK = {"high": 3, "low": 2, "none": 1}
_KIND_RANK = {"variable": 3, "output": 2, "across": 1, "through": 1, "input": 0}


@dataclass
class AliasResult:
    equations: list[FlatEquation]
    unknowns: list[str]                               # remaining variable names
    eliminated: dict[str, tuple[str | None, float]] = field(default_factory=dict)
    # name -> (representative or None for a constant, factor or constant value)
    starts: dict[str, tuple[float, str, str]] = field(default_factory=dict)
    # representative -> (start, priority, the variable the target was given on)
    n_before: int = 0


def _signed_symbol(expr: ca.SX, unknowns) -> tuple[str, float] | None:
    sign = 1.0
    while expr.is_op(ca.OP_NEG):
        expr, sign = expr.dep(0), -sign
    if expr.is_symbolic() and expr.name() in unknowns:
        return expr.name(), sign
    return None


def eliminate_aliases(flat: FlatModel) -> AliasResult:
    """Find alias classes, pick representatives, substitute in bulk."""
    unknowns = flat.variables      # read only
    parent: dict[str, str] = {}    # never a name to itself: a root has no entry
    factor: dict[str, float] = {}  # name = factor * parent
    const: dict[str, float] = {}   # root -> constant value (root = const)

    def find(a: str) -> tuple[str, float]:
        """Root of ``a`` and the factor with a = factor * root (path compressed)."""
        up = parent.get(a)
        if up is None:
            return a, 1.0
        if up not in parent:           # a child of its root: nothing to compress
            return up, factor[a]
        path = []
        while a in parent:
            path.append(a)
            a = parent[a]
        acc = 1.0
        for node in reversed(path):
            acc = factor[node] * acc
            parent[node], factor[node] = a, acc
        return a, (factor[path[0]] if path else 1.0)

    def union(a: str, b: str, s: float) -> bool:
        """Record a = s*b; return False if that adds nothing new (a redundant equation)."""
        ra, fa = find(a)
        rb, fb = find(b)
        if ra == rb:
            return False
        k = s * fb / fa  # ra = k * rb
        if ra in const and rb in const and abs(const[ra] - k * const[rb]) > 0:
            return False
        parent[ra], factor[ra] = rb, k
        if ra in const:
            const[rb] = const.pop(ra) / k
        return True

    remaining: list[FlatEquation] = []
    n_before = len(flat.equations) + len(flat.aliases)
    for a, b, s, origin in flat.aliases:
        if not union(a, b, s):
            remaining.append(FlatEquation(unknowns[a].sym - s * unknowns[b].sym, origin))
    for eq in flat.equations:
        r = eq.residual
        handled = False
        hint = eq.alias              # read off the class's template once (flatten)
        if hint is not None:
            if hint[0] == "pair":
                handled = union(hint[1], hint[2], hint[3])
            elif hint[0] == "const":
                root, f = find(hint[1])
                if root not in const:
                    const[root] = hint[2] / f
                    handled = True
        elif r.is_op(ca.OP_SUB) or r.is_op(ca.OP_ADD):
            lhs, rhs = r.dep(0), r.dep(1)
            sign = -1.0 if r.is_op(ca.OP_SUB) else 1.0
            la, ra_ = _signed_symbol(lhs, unknowns), _signed_symbol(rhs, unknowns)
            if la and ra_:
                # la_s*a + sign*ra_s*b = 0 -> a = -(sign*rs/ls) b
                handled = union(la[0], ra_[0], -sign * ra_[1] / la[1])
            elif la and rhs.is_constant():
                root, f = find(la[0])
                value = -sign * float(rhs) / la[1]   # a = value
                if root not in const:
                    const[root] = value / f
                    handled = True
            elif ra_ and lhs.is_constant():
                root, f = find(ra_[0])
                value = -float(lhs) / (sign * ra_[1])
                if root not in const:
                    const[root] = value / f
                    handled = True
        elif _signed_symbol(r, unknowns):
            name, s = _signed_symbol(r, unknowns)
            root, f = find(name)
            if root not in const:
                const[root] = 0.0
                handled = True
        if not handled:
            remaining.append(eq)

    # pick representatives: re-root each class at its best member
    classes: dict[str, list[tuple[str, float]]] = {}
    for name in unknowns:
        root, f = find(name)
        classes.setdefault(root, []).append((name, f))
    derivative = flat.context.derivative
    result = AliasResult(remaining, [], n_before=n_before)
    old: list[ca.SX] = []
    new: list[ca.SX] = []        # replacement = factor * new (one product in bulk)
    factors: list[float] = []
    # variables replaced by a scaled representative, by name: their columns are slices
    # of the stacked variable symbols (FlatModel.stack_variables), not stacked again
    old_names: list[str] = []
    new_names: list[str] = []
    name_factors: list[float] = []
    for root, members in classes.items():
        if root in const:
            value_root = const[root]
            for name, f in members:
                result.eliminated[name] = (None, f * value_root)
                old.append(unknowns[name].sym)
                new.append(ca.SX(1.0))
                factors.append(f * value_root)
                if name in derivative:
                    old.append(derivative[name])
                    new.append(ca.SX(1.0))
                    factors.append(0.0)
            continue
        if len(members) == 1:
            best_name, best_f = members[0]
            result.unknowns.append(best_name)
            if unknowns[best_name].start is not None:
                _merge_starts(result, flat, best_name, [(best_name, 1.0)])
            continue
        best_name, best_f = max(members, key=lambda m: _rank(unknowns[m[0]], m[0] in
                                                             derivative))
        result.unknowns.append(best_name)
        for name, f in members:
            if name == best_name:
                continue
            k = f / best_f  # name = k * best
            result.eliminated[name] = (best_name, k)
            old_names.append(name)
            new_names.append(best_name)
            name_factors.append(k)
            if name in derivative:
                old.append(derivative[name])
                new.append(flat.context.der_symbol(best_name))
                factors.append(k)
        _merge_starts(result, flat, best_name, [(n, f / best_f) for n, f in members])
    if old or old_names:
        pairs = []
        if old_names:
            pairs.append((flat.stack_variables(old_names),
                          flat.stack_variables(new_names) * ca.DM(name_factors)))
        if old:
            pairs.append((ca.vertcat(*old), ca.vertcat(*new) * ca.DM(factors)))
        res = ca.substitute([eq.residual for eq in remaining], [p[0] for p in pairs],
                            [p[1] for p in pairs])
        result.equations = [FlatEquation(r, eq.origin, eq.owner)
                            for r, eq in zip(res, remaining)]
    return result


def _rank(var, differentiated: bool):
    return (_PRIORITY_RANK.get(var.priority, 0) if var.start is not None else 0,
            differentiated, _KIND_RANK.get(var.kind, 0), -var.name.count("."),
            -len(var.name))


def _merge_starts(result: AliasResult, flat: FlatModel, rep: str, members) -> None:
    best = None
    for name, k in members:
        var = flat.variables[name]
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
