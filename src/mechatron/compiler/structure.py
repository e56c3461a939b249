"""Passes 4 to 6 and lowering: structural analysis, index reduction, BLT with tearing,
and the symbolic solution of every block into a semi-explicit DAE

    x' = f(t, x, z, p, m),   0 = g(t, x, z, p, m)

where ``x`` are the states chosen by dummy-derivative selection, ``z`` the tearing
variables of the nonlinear algebraic loops that remain, ``p`` the parameters and ``m`` the
relation placeholders (modes). The graph algorithms come from :mod:`mechatron.compiler.graph`
and see only integer incidence; this module owns the symbols.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from mechatron.compiler.graph import (block_lower_triangular, dummy_derivatives,
                                      maximum_matching, pantelides, tear)
from mechatron.errors import StructuralError

__all__ = ["Lowered", "lower"]

_MAX_SYMBOLIC_SOLVE = 12   # linear torn blocks up to this size are solved symbolically


@dataclass
class Lowered:
    states: list[str]
    state_syms: list[ca.SX]
    alg: list[str]
    alg_syms: list[ca.SX]
    ode: list[ca.SX]
    residuals: list[ca.SX]
    assigned: list[ca.SX]            # symbols of explicitly solved unknowns, in order
    assigned_expr: list[ca.SX]       # their expressions (earlier ones may appear)
    differentiated: list[str] = field(default_factory=list)
    n_blocks: int = 0
    largest_block: int = 0
    n_torn: int = 0
    n_equations: int = 0
    n_unknowns: int = 0


def _csr(expr: ca.SX, syms: ca.SX) -> list[list[int]]:
    sp = ca.jacobian_sparsity(expr, syms)
    ptr, col = sp.get_crs()
    return [list(col[ptr[r]:ptr[r + 1]]) for r in range(sp.size1())]


def lower(name: str, residuals: list[ca.SX], origins: list[str], unknowns: list[str],
          syms: dict[str, ca.SX], derivative: dict[str, ca.SX], time: ca.SX,
          start_guess, hints: dict[str, str]) -> Lowered:
    """Index-reduce, sort, tear and solve the equations for the unknowns.

    Parameters
    ----------
    residuals, origins
        Equations (after alias elimination) and where each came from.
    unknowns
        Names of the unknowns (alias representatives); ``syms`` maps names to symbols and
        ``derivative`` names to derivative symbols.
    start_guess : callable
        ``start_guess(list_of_syms) -> ndarray``, numeric point for Jacobian-based choices.
    hints
        A hint per variable name for messages about unmatched variables.
    """
    # -- variables of the structural problem: unknowns and their derivatives -------------
    var_syms: list[ca.SX] = [syms[n] for n in unknowns]
    var_names: list[str] = list(unknowns)
    var_to_diff = [-1] * len(var_syms)
    for i, n in enumerate(unknowns):
        d = derivative.get(n)
        if d is not None:
            var_to_diff[i] = len(var_syms)
            var_syms.append(d)
            var_names.append(f"der({n})")
            var_to_diff.append(-1)
    res = list(residuals)
    orig = list(origins)
    adj = _csr(ca.vertcat(*res), ca.vertcat(*var_syms)) if res else []
    # derivative symbols that appear nowhere do not make their variable a state
    used = set(v for row in adj for v in row)
    for i, d in enumerate(var_to_diff):
        if d != -1 and d not in used:
            var_to_diff[i] = -1
    _check_counts(name, res, orig, var_names, var_to_diff, adj, hints)

    # -- index reduction ------------------------------------------------------------------
    try:
        ir = pantelides(len(var_syms), adj, var_to_diff)
    except StructuralError as exc:
        _raise_singular(name, orig, var_names, exc, hints)
    differentiated = []
    while len(var_syms) < ir.n_var:
        v = len(var_syms)
        base = ir.var_to_diff.index(v)
        var_syms.append(ca.SX.sym(f"der({var_names[base]})"))
        var_names.append(f"der({var_names[base]})")
    sym_index = {s.name(): i for i, s in enumerate(var_syms)}
    for e in range(len(res), len(ir.adj)):
        src = ir.eq_to_diff.index(e)
        res.append(_time_derivative(res[src], var_syms, sym_index, ir.var_to_diff, time))
        orig.append(f"d/dt[{orig[src]}]")
        differentiated.append(str(orig[src]))
    adj = ir.adj
    var_to_diff = ir.var_to_diff

    def select(eqs, candidates, k):
        jac = ca.jacobian(ca.vertcat(*[res[e] for e in eqs]),
                          ca.vertcat(*[var_syms[c] for c in candidates]))
        free = ca.symvar(jac)
        fun = ca.Function("jac_select", free, [jac])
        value = np.array(fun.call(start_guess(free))[0], dtype=float)
        value = np.atleast_2d(value).reshape(len(eqs), len(candidates))
        from scipy.linalg import qr
        _, _, piv = qr(value, pivoting=True)
        return [candidates[j] for j in piv[:k]]

    dummies = set(dummy_derivatives(ir, select=select)) if differentiated else set()
    states = [v for v, d in enumerate(var_to_diff) if d != -1 and d not in dummies]
    is_state = [False] * len(var_syms)
    for v in states:
        is_state[v] = True

    # -- matching of the non-states, BLT, tearing -----------------------------------------
    allowed = [not s for s in is_state]
    m = maximum_matching(len(var_syms), adj, allowed=allowed)
    if m.unmatched_equations or any(m.var_to_eq[v] == -1 for v in range(len(var_syms))
                                    if allowed[v]):
        _raise_structural(name, res, orig, var_names, m, allowed, hints)
    blocks = block_lower_triangular(len(var_syms), adj, m)
    out = Lowered(states=[var_names[v] for v in states], state_syms=[var_syms[v] for v in states],
                  alg=[], alg_syms=[], ode=[], residuals=[], assigned=[], assigned_expr=[],
                  differentiated=differentiated, n_blocks=len(blocks),
                  n_equations=len(res), n_unknowns=sum(allowed))
    coef_cache: dict[tuple[int, int], ca.SX | None] = {}

    def coefficient(e: int, v: int):
        """d res[e] / d v when res[e] is linear in v with a nonzero coefficient, else None."""
        key = (e, v)
        if key not in coef_cache:
            r, x = res[e], var_syms[v]
            coef = ca.jacobian(r, x)
            ok = not coef.is_zero() and not ca.depends_on(coef, x)
            coef_cache[key] = coef if ok else None
        return coef_cache[key]

    def solvable(e: int, v: int) -> bool:
        return coefficient(e, v) is not None

    for block in blocks:
        eqs, vs = block.equations, block.variables
        out.largest_block = max(out.largest_block, len(eqs))
        if len(eqs) == 1:
            e, v = eqs[0], vs[0]
            quick = _explicit(res[e], var_syms[v])
            if quick is not None:
                out.assigned.append(var_syms[v])
                out.assigned_expr.append(quick)
                continue
            coef = coefficient(e, v)
            if coef is not None:
                out.assigned.append(var_syms[v])
                out.assigned_expr.append(_solve_linear(res[e], var_syms[v], coef))
            else:
                out.alg.append(var_names[v])
                out.alg_syms.append(var_syms[v])
                out.residuals.append(res[e])
            continue
        _solve_block(out, eqs, vs, adj, res, var_syms, var_names, coefficient)
    for v in states:
        out.ode.append(var_syms[var_to_diff[v]])
    return out


def _is_symbol(expr: ca.SX, name: str) -> bool:
    return expr.is_symbolic() and expr.name() == name


def _explicit(r: ca.SX, x: ca.SX):
    """x from the common forms ``x - b``, ``b - x``, ``c*x - b`` with b, c free of x, read
    off the expression tree (cheaper than a Jacobian and a substitution); else None."""
    if not r.is_op(ca.OP_SUB):
        return None
    name = x.name()
    a, b = r.dep(0), r.dep(1)
    if _is_symbol(a, name):
        return None if ca.depends_on(b, x) else b
    if _is_symbol(b, name):
        return None if ca.depends_on(a, x) else a
    if a.is_op(ca.OP_MUL):
        c0, c1 = a.dep(0), a.dep(1)
        for factor, other in ((c1, c0), (c0, c1)):
            if _is_symbol(factor, name) and not ca.depends_on(other, x) \
                    and not ca.depends_on(b, x):
                return b / other
    return None


def _solve_linear(r: ca.SX, x: ca.SX, coef: ca.SX) -> ca.SX:
    """x from r(x) = coef*x + rest = 0."""
    rest = ca.substitute(r, x, ca.SX(0))
    return -rest / coef


def _solve_block(out: Lowered, eqs, vs, adj, res, var_syms, var_names, coefficient) -> None:
    t = tear(eqs, vs, adj, lambda e, v: coefficient(e, v) is not None)
    out.n_torn += len(t.tearing_vars)
    seq_syms = [var_syms[v] for _, v in t.sequence]
    seq_expr = [_solve_linear(res[e], var_syms[v], coefficient(e, v)) for e, v in t.sequence]
    resid = [res[e] for e in t.residuals]
    tv = [var_syms[v] for v in t.tearing_vars]
    if seq_syms:
        seq_expr, resid = ca.substitute_inplace(seq_syms, seq_expr, resid, False)
    rvec, zvec = ca.vertcat(*resid), ca.vertcat(*tv)
    if tv and len(tv) <= _MAX_SYMBOLIC_SOLVE and ca.is_linear(rvec, zvec):
        a = ca.jacobian(rvec, zvec)
        b = ca.substitute(rvec, zvec, ca.DM.zeros(zvec.shape))
        sol = -ca.solve(a, b) if len(tv) > 1 else -b / a
        for i, z in enumerate(tv):
            out.assigned.append(z)
            out.assigned_expr.append(sol[i])
    else:
        for v in t.tearing_vars:
            out.alg.append(var_names[v])
            out.alg_syms.append(var_syms[v])
        out.residuals.extend(resid)
    out.assigned.extend(seq_syms)
    out.assigned_expr.extend(seq_expr)


def _time_derivative(r: ca.SX, var_syms, sym_index, var_to_diff, time) -> ca.SX:
    vs, dvs = [], []
    for s in ca.symvar(r):
        i = sym_index.get(s.name())
        if i is not None:
            vs.append(s)
            dvs.append(var_syms[var_to_diff[i]])
    out = ca.jacobian(r, time) if ca.depends_on(r, time) else ca.SX(0)
    if vs:
        out = out + ca.jtimes(r, ca.vertcat(*vs), ca.vertcat(*dvs))
    return out


def _check_counts(name, res, orig, var_names, var_to_diff, adj, hints) -> None:
    """Over- and under-determined systems, with the suspects named."""
    highest = [d == -1 for d in var_to_diff]
    n_unknown = sum(highest)
    if len(res) == n_unknown:
        return
    m = maximum_matching(len(var_names), adj, allowed=highest)
    _raise_structural(name, res, orig, var_names, m, highest, hints)


def _raise_singular(name, orig, var_names, exc, hints) -> None:
    eqs = [str(orig[e]) for e in exc.equations if isinstance(e, int) and e < len(orig)]
    vs = [var_names[v] for v in exc.variables if isinstance(v, int) and v < len(var_names)]
    raise StructuralError(
        f"model '{name}': {len(eqs)} equations for {len(vs)} unknowns in a subsystem "
        f"({', '.join(vs[:8])}). Potential extra equation(s): {'; '.join(eqs[:8])}. "
        "Two components may fix the same quantity (e.g. two ideal voltage sources in "
        "parallel); remove one or put a resistance between them.",
        equations=eqs, variables=vs, path=name) from None


def _raise_structural(name, res, orig, var_names, m, allowed, hints) -> None:
    n_unknown = sum(allowed)
    extra_eq = [str(orig[e]) for e in m.unmatched_equations]
    free_var = [var_names[v] for v in range(len(var_names))
                if allowed[v] and m.var_to_eq[v] == -1]
    parts = [f"model '{name}': {len(res)} equations for {n_unknown} unknowns."]
    if extra_eq:
        parts.append("Potential extra equation(s): " + "; ".join(extra_eq[:8]) +
                     (" ..." if len(extra_eq) > 8 else "") + ".")
    if free_var:
        parts.append("Unmatched variable(s): " + ", ".join(free_var[:8]) +
                     (" ..." if len(free_var) > 8 else "") + ".")
    hint = next((hints.get(v.removeprefix("der(").removesuffix(")"))
                 for v in free_var if hints.get(v.removeprefix("der(").removesuffix(")"))),
                "")
    if extra_eq and not free_var:
        hint = hint or ("Two components may fix the same quantity (e.g. two ideal sources "
                        "in parallel); remove one or put a resistance between them.")
    elif not hint:
        hint = "Check for unconnected parts or a missing reference."
    parts.append(hint)
    raise StructuralError(" ".join(parts), equations=extra_eq, variables=free_var,
                          path=name)
