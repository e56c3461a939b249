"""Alias elimination (`compiler/alias.py`) against the equations it removes and against an
alias-class search written here: every removed equation holds identically once each
eliminated variable is replaced by its representative (or constant), each remaining
residual is the flat one with those replacements, and each class is represented by its
member of highest rank. Relations (`compiler/relations.py`) are found in every instance
of a class template, as instance by instance."""

import casadi as ca
import numpy as np
import pytest

import mechatron as mt
import mechatron.compiler.flatten as fl
from mechatron.compiler.alias import eliminate_aliases
from mechatron.library import electrical as el
from tests.compiler import test_flatten_templates as templates
from tests.compiler.test_flatten_templates import drive


def ladder() -> mt.System:
    return templates.ladder(4)


def _point(flat, rng):
    """Random values of every symbol of the flat model (variables, parameters,
    derivatives, time)."""
    syms = [v.sym for v in flat.variables.values()] + \
        [p.sym for p in flat.parameters.values()] + \
        list(flat.context.derivative.values()) + [flat.context.time]
    return ca.vertcat(*syms), rng.normal(size=len(syms))


@pytest.mark.parametrize("build", [ladder, drive])
def test_removed_equations_hold_and_remaining_ones_are_substituted(build):
    flat = fl.flatten(build())
    flat_residuals = [eq.residual for eq in flat.equations]
    names = list(flat.variables)     # a connection's alias names variables by number
    sym = [v.sym for v in flat.variables.values()]
    alias_residuals = [(sym[a] if isinstance(a, int) else flat.variables[a].sym) -
                       s * (sym[b] if isinstance(b, int) else flat.variables[b].sym)
                       for a, b, s, _ in flat.aliases]
    assert all(isinstance(x, str) and x in names or 0 <= x < len(names)
               for a, b, *_ in flat.aliases for x in (a, b))
    result = eliminate_aliases(flat)
    # every variable kept or eliminated, once
    assert sorted(result.unknowns + list(result.eliminated)) == sorted(flat.variables)
    assert not set(result.unknowns) & set(result.eliminated)
    # the replacements, written here from the mapping
    old, new = [], []
    for name, (rep, k) in result.eliminated.items():
        old.append(flat.variables[name].sym)
        new.append(ca.SX(k) if rep is None else k * flat.variables[rep].sym)
        der = flat.context.derivative.get(name)
        if der is not None:
            old.append(der)
            new.append(ca.SX(0) if rep is None else k * flat.context.der_symbol(rep))
    every = ca.vertcat(*alias_residuals, *flat_residuals)
    replaced = ca.substitute(every, ca.vertcat(*old), ca.vertcat(*new))
    sym_vec, values = _point(flat, np.random.default_rng(1))
    f = ca.Function("f", [sym_vec], [replaced, ca.vertcat(*result.residuals)])
    all_values, remaining = (np.array(x).ravel() for x in f(values))
    # at a random point: an equation removed vanishes, one kept is a remaining residual
    # (the flat one replaced), and every remaining residual is one of those
    matched = set()
    for k, r in enumerate(alias_residuals + flat_residuals):
        hits = np.flatnonzero(np.abs(remaining - all_values[k]) <=
                              1e-12 * (1 + np.abs(remaining)))
        if abs(all_values[k]) > 1e-12:
            assert len(hits), str(r)
        matched.update(hits.tolist())
    assert matched == set(range(len(remaining)))
    assert len(result.residuals) == result.stacked.numel()
    n_removed = len(alias_residuals) + len(flat_residuals) - len(result.residuals)
    assert n_removed == len(result.eliminated)     # one equation per eliminated variable
    # the stacked column is the list
    g = ca.Function("g", [sym_vec], [result.stacked - ca.vertcat(*result.residuals)])
    assert np.allclose(np.array(g(values)).ravel(), 0.0, atol=0.0)


_PRIORITY = {"high": 3, "low": 2, "none": 1}
_KIND = {"variable": 3, "output": 2, "across": 1, "through": 1, "input": 0}


def _classes_here(flat):
    """Alias classes by a graph search over the alias equations (the connections' and
    those the class templates mark as ``a == s*b``), with the variables set to a
    constant."""
    edges: dict[str, set] = {n: set() for n in flat.variables}
    fixed = set()
    names = list(flat.variables)      # aliases and hints may name variables by number
    for a, b, *_ in flat.aliases:
        a = names[a] if isinstance(a, int) else a
        b = names[b] if isinstance(b, int) else b
        edges[a].add(b)
        edges[b].add(a)
    for eq in flat.equations:
        hint = eq.alias
        if hint is None or hint[0] == "none":
            continue
        a = names[hint[1]] if isinstance(hint[1], int) else hint[1]
        if hint[0] == "pair":
            b = names[hint[2]] if isinstance(hint[2], int) else hint[2]
            edges[a].add(b)
            edges[b].add(a)
        elif hint[0] == "const":
            fixed.add(a)
    seen, classes = set(), []
    for start in flat.variables:
        if start in seen:
            continue
        members, todo = [], [start]
        seen.add(start)
        while todo:
            v = todo.pop()
            members.append(v)
            for w in edges[v] - seen:
                seen.add(w)
                todo.append(w)
        classes.append(members)
    return classes, fixed


@pytest.mark.parametrize("build", [ladder, drive])
def test_each_class_is_represented_by_its_member_of_highest_rank(build):
    flat = fl.flatten(build())
    derivative = set(flat.context.derivative)
    result = eliminate_aliases(flat)
    order = {n: k for k, n in enumerate(flat.variables)}
    classes, fixed = _classes_here(flat)
    assert len(classes) == len(result.unknowns) + sum(
        1 for c in classes if fixed & set(c))

    def rank(name):
        v = flat.variables[name]
        return (_PRIORITY.get(v.priority, 0) if v.start is not None else 0,
                name in derivative, _KIND.get(v.kind, 0), -name.count("."), -len(name),
                -order[name])

    for members in classes:
        if fixed & set(members):
            assert all(result.eliminated[m][0] is None for m in members)
            continue
        best = max(members, key=rank)
        assert best in result.unknowns
        for m in members:
            if m != best:
                rep, k = result.eliminated[m]
                assert rep == best and abs(k) == 1.0
    # unknowns in the order of each class's first member
    firsts = [min(order[m] for m in c) for c in classes if not fixed & set(c)]
    assert [min(order[m] for m in c) for c in classes
            if not fixed & set(c)] == sorted(firsts)


class Rectifier(el.OnePort):
    """A resistor that conducts one way: ``i = v/R`` for ``v > 0``, else 0."""

    R = mt.Parameter("Ohm", default=1.0, doc="Forward resistance")

    def equations(self):
        return [self.i == ca.if_else(self.v > 0, self.v / self.R, 0)]


def rectifiers(n: int = 3) -> mt.System:
    m = mt.System("rectifiers")
    src = m.add("src", el.ACVoltageSource(V_amp=1.0, f=1.0))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.n, g.port)
    for k in range(n):
        d = m.add(f"d{k}", Rectifier(R=1.0 + k))
        m.connect(src.p, d.p)
        m.connect(d.n, g.port)
    return m


def test_relations_of_every_template_instance_are_found(monkeypatch):
    with_templates = mt.compile_model(rectifiers())
    monkeypatch.setattr(fl, "_template", lambda flat, el, templates: None)
    without = mt.compile_model(rectifiers())
    expected = [(f"d{k}", "<") for k in range(3)]
    assert with_templates.relations == without.relations == expected
    # and they switch: a rectifier conducts only in the positive half wave
    res = mt.simulate(with_templates, 1.0, log="all", t_out=np.linspace(0.0, 1.0, 201))
    v, i = res["d1.v"], res["d1.i"]
    assert np.allclose(i, np.where(v > 0, v / 2.0, 0.0), atol=1e-6)
