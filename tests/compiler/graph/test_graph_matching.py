"""Tests of `maximum_matching`."""

import random

import numpy as np
import pytest

from mechatron.compiler.graph import Matching, maximum_matching
from mechatron.compiler.graph import matching as matching_module
from mechatron.compiler.graph.matching import _karp_sipser, _unique_matching


def assert_valid(matching, n_var, adj, allowed=None):
    """Pairs are incidences, both directions agree, only allowed variables used."""
    assert len(matching.eq_to_var) == len(adj)
    assert len(matching.var_to_eq) == n_var
    for e, v in enumerate(matching.eq_to_var):
        if v != -1:
            assert v in adj[e]
            assert matching.var_to_eq[v] == e
            assert allowed is None or v in allowed
    for v, e in enumerate(matching.var_to_eq):
        if e != -1:
            assert matching.eq_to_var[e] == v


def assert_maximum(matching, n_var, adj):
    """Koenig certificate: a vertex cover as small as the matching proves it maximum.

    Z is what alternating paths reach from the free equations; the cover is the
    equations outside Z and the variables inside Z.
    """
    z_eqs = set(matching.unmatched_equations)
    z_vars = set()
    todo = list(z_eqs)
    while todo:
        for v in adj[todo.pop()]:
            if v not in z_vars:
                z_vars.add(v)
                e = matching.var_to_eq[v]
                assert e != -1, "augmenting path left"
                if e not in z_eqs:
                    z_eqs.add(e)
                    todo.append(e)
    for e, row in enumerate(adj):
        for v in row:
            assert e not in z_eqs or v in z_vars
    assert (len(adj) - len(z_eqs)) + len(z_vars) == matching.size


def reference_size(n_var, adj):
    """Maximum matching size by simple recursive augmenting paths (small graphs)."""
    var_to_eq = [-1] * n_var

    def augment(e, seen):
        for v in adj[e]:
            if v not in seen:
                seen.add(v)
                if var_to_eq[v] == -1 or augment(var_to_eq[v], seen):
                    var_to_eq[v] = e
                    return True
        return False

    return sum(augment(e, set()) for e in range(len(adj)))


def test_perfect_matching_needs_augmenting_path():
    # Greedy pairs 0-0 first; equation 1 only has variable 0.
    adj = [[0, 1], [0], [1, 2]]
    m = maximum_matching(3, adj)
    assert_valid(m, 3, adj)
    assert m.eq_to_var == [1, 0, 2]
    assert m.size == 3
    assert m.unmatched_equations == []
    assert m.unmatched_variables == []


def test_imperfect_matching_reports_unmatched():
    adj = [[0], [0], [1, 2]]
    m = maximum_matching(3, adj)
    assert_valid(m, 3, adj)
    assert m.size == 2
    assert m.unmatched_equations in ([0], [1])
    assert m.unmatched_variables in ([1], [2])


def test_empty_system():
    m = maximum_matching(0, [])
    assert m == Matching([], [])


@pytest.mark.parametrize("allowed", [
    [True, False, True],
    np.array([1, 0, 1], dtype=bool),
    {0, 2},
    lambda v: v != 1,
])
def test_allowed_forms_exclude_variable(allowed):
    adj = [[1, 0], [1, 2]]
    m = maximum_matching(3, adj, allowed=allowed)
    assert_valid(m, 3, adj, allowed={0, 2})
    assert m.eq_to_var == [0, 2]
    assert m.var_to_eq[1] == -1


def test_allowed_wrong_length_raises():
    with pytest.raises(ValueError, match="one entry per variable"):
        maximum_matching(3, [[0]], allowed=[True])


def test_adjacency_out_of_range_raises():
    with pytest.raises(ValueError, match="variable 3, outside 0 .. 2"):
        maximum_matching(3, [[0, 3]])


def test_initial_matching_is_extended_not_modified():
    adj = [[0, 1], [0], [1, 2]]
    initial = Matching([0, -1, -1], [0, -1, -1])
    m = maximum_matching(3, adj, initial=initial)
    assert m.size == 3
    assert initial.eq_to_var == [0, -1, -1]


def test_invalid_initial_matching_raises():
    adj = [[0, 1], [0], [1, 2]]
    with pytest.raises(ValueError, match="equation 0 with variable 2"):
        maximum_matching(3, adj, initial=Matching([2, -1, -1], [-1, -1, 0]))


@pytest.mark.parametrize("seed", range(40))
def test_random_graphs_reach_maximum_size(seed):
    rng = random.Random(seed)
    n_eq, n_var = rng.randint(1, 25), rng.randint(1, 25)
    adj = [rng.sample(range(n_var), rng.randint(0, min(4, n_var))) for _ in range(n_eq)]
    m = maximum_matching(n_var, adj)
    assert_valid(m, n_var, adj)
    assert m.size == reference_size(n_var, adj)
    assert_maximum(m, n_var, adj)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("start", ["default", "initial"])
def test_large_random_graphs_are_maximum(seed, start):
    # Big enough for the Karp-Sipser start (default), or forced through the plain
    # greedy one (an empty initial matching).
    rng = random.Random(seed)
    n_eq = 3000
    n_var = n_eq + rng.choice([-200, 0, 200])
    adj = [rng.sample(range(n_var), rng.randint(1, 3)) for _ in range(n_eq)]
    initial = Matching([-1] * n_eq, [-1] * n_var) if start == "initial" else None
    m = maximum_matching(n_var, adj, initial=initial)
    assert_valid(m, n_var, adj)
    assert_maximum(m, n_var, adj)


def test_allowed_variables_on_a_large_graph():
    rng = random.Random(7)
    n = 2000
    adj = [rng.sample(range(n), 3) for _ in range(n)]
    allowed = {v for v in range(n) if v % 3}
    m = maximum_matching(n, adj, allowed=allowed)
    assert_valid(m, n, adj, allowed)
    assert_maximum(m, n, [[v for v in row if v in allowed] for row in adj])



def karp_sipser_by_rule(n_var, rows):
    """Karp-Sipser by its rule, plainly: a variable whose free degree fell to one is
    matched (the last such first), else an equation whose free degree fell to one,
    else the first free equation with its first free variable of least free degree.
    Degrees count entries in free rows (a repeated entry twice) and are checked
    against a recount at every step."""
    n_eq = len(rows)
    eq_to_var, var_to_eq = [-1] * n_eq, [-1] * n_var
    var_deg = [sum(row.count(v) for row in rows) for v in range(n_var)]
    eq_deg = [len(row) for row in rows]
    lone_vars = [v for v in range(n_var) if var_deg[v] == 1]
    lone_eqs = [e for e in range(n_eq) if eq_deg[e] == 1]
    while True:
        for v in range(n_var):
            if var_to_eq[v] == -1:
                assert var_deg[v] == sum(rows[e].count(v) for e in range(n_eq)
                                         if eq_to_var[e] == -1)
        if lone_vars:
            v = lone_vars.pop()
            if var_deg[v] != 1 or var_to_eq[v] != -1:
                continue
            e = min(e for e in range(n_eq) if eq_to_var[e] == -1 and v in rows[e])
        elif lone_eqs:
            e = lone_eqs.pop()
            if eq_deg[e] != 1 or eq_to_var[e] != -1:
                continue
            v = next(v for v in rows[e] if var_to_eq[v] == -1)
        else:
            free = [e for e in range(n_eq) if eq_to_var[e] == -1 and eq_deg[e]]
            if not free:
                return eq_to_var, var_to_eq
            e = free[0]
            v = min((u for u in rows[e] if var_to_eq[u] == -1), key=lambda u: var_deg[u])
        eq_to_var[e], var_to_eq[v] = v, e
        for u in rows[e]:
            if var_to_eq[u] == -1:
                var_deg[u] -= 1
                if var_deg[u] == 1:
                    lone_vars.append(u)
        for f in range(n_eq):
            for _ in range(rows[f].count(v) if eq_to_var[f] == -1 else 0):
                eq_deg[f] -= 1
                if eq_deg[f] == 1:
                    lone_eqs.append(f)


@pytest.mark.parametrize("seed", range(30))
def test_karp_sipser_start_follows_its_rule(seed):
    """The start that decides which maximum matching is returned (and so which
    equation the compiler solves for which variable) picks its pairs by the rule."""
    rng = random.Random(seed)
    n_eq, n_var = rng.randint(1, 30), rng.randint(1, 30)
    rows = [[rng.randrange(n_var) for _ in range(rng.randint(0, 4))] for _ in range(n_eq)]
    if seed % 3 == 0:    # no repeated entries, as the compiler gives them
        rows = [list(dict.fromkeys(row)) for row in rows]
    eq_to_var, var_to_eq = _karp_sipser(n_var, rows)
    assert (eq_to_var, var_to_eq) == karp_sipser_by_rule(n_var, rows)
    assert_valid(Matching(eq_to_var, var_to_eq), n_var, rows)


def loop_free(rng, n_eq, unused=0):
    """Equations that can be solved one after another, each for its own variable from
    those of up to three equations solved before it (a triangular system, its equations,
    variables and row entries shuffled), plus ``unused`` variables that appear nowhere:
    the maximum matching is unique."""
    order = rng.sample(range(n_eq), n_eq)           # the order they can be solved in
    own = rng.sample(range(n_eq + unused), n_eq)    # each equation's variable
    adj = [[] for _ in range(n_eq)]
    for k, e in enumerate(order):
        before = rng.sample(range(k), min(k, rng.randint(0, 3)))
        adj[e] = [own[e]] + [own[order[j]] for j in before]
        rng.shuffle(adj[e])
    return n_eq + unused, adj, own


def by_python_steps(monkeypatch, n_var, adj, allowed=None):
    """`maximum_matching` by its own greedy start and phases alone."""
    with monkeypatch.context() as patch:
        patch.setattr(matching_module, "UNIQUE_MIN_EQUATIONS", 1 << 62)
        return maximum_matching(n_var, adj, allowed=allowed)


@pytest.mark.parametrize("seed", range(4))
def test_a_large_loop_free_system_is_matched_on_arrays_as_by_the_python_steps(
        seed, monkeypatch):
    """A network without algebraic loops has one maximum matching: found on arrays (the
    fast path is taken), it is the one the greedy start and phases give, pair for pair."""
    rng = random.Random(seed)
    n_var, adj, own = loop_free(rng, 600 + 100 * seed, unused=7 * seed)
    fast = _unique_matching(n_var, adj, np.array([v for row in adj for v in row]), None)
    assert fast is not None and fast.eq_to_var == own
    assert maximum_matching(n_var, adj) == fast == by_python_steps(monkeypatch, n_var, adj)


@pytest.mark.parametrize("seed", range(60))
def test_the_matching_is_the_same_with_or_without_the_array_path(seed, monkeypatch):
    """Whatever the graph (loops, free variables, empty rows, variables not allowed),
    the path on arrays either declines or gives the very matching of the Python steps."""
    rng = random.Random(seed)
    kind = seed % 3
    if kind == 0:                   # loop-free: the array path answers
        n_var, adj, _ = loop_free(rng, rng.randint(1, 40), unused=rng.randint(0, 3))
    else:                           # anything: mostly declined
        n_eq, n_var = rng.randint(1, 30), rng.randint(1, 30)
        adj = [rng.sample(range(n_var), rng.randint(0, min(3, n_var))) for _ in range(n_eq)]
        if kind == 2:               # a loop of two equations in two variables, or more
            adj += [[n_var, n_var + 1], [n_var + 1, n_var]]
            n_var += 2
    allowed = None if seed % 4 else {v for v in range(n_var) if rng.random() < 0.8}
    monkeypatch.setattr(matching_module, "UNIQUE_MIN_EQUATIONS", 0)
    got = maximum_matching(n_var, adj, allowed=allowed)
    assert got == by_python_steps(monkeypatch, n_var, adj, allowed)
    assert_valid(got, n_var, adj, allowed)


@pytest.mark.parametrize("n_var,adj", [
    (2, [[0, 1], [1, 0]]),              # a loop: two matchings
    (2, [[0, 1]]),                      # a variable left free that appears
    (1, [[0], [0]]),                    # an equation left free that has a variable
    (3, [[0], [0, 1, 2], [1, 2]]),      # a loop behind a forced pair
])
def test_the_array_path_declines_a_graph_with_several_maximum_matchings(n_var, adj):
    flat = np.array([v for row in adj for v in row], dtype=np.int64)
    assert _unique_matching(n_var, adj, flat, None) is None
