"""Tests of `pantelides` on small DAEs with known differentiation counts."""

import copy
import random

import pytest

from mechatron.compiler.graph import maximum_matching, pantelides
from mechatron.compiler.graph.pantelides import _copy_adjacency
from mechatron.errors import StructuralError


def check_index_reduction(ir, n_var, adj):
    """Invariants every result must satisfy, whatever the system."""
    n_eq = len(ir.adj)
    assert ir.adj[:len(adj)] == [list(dict.fromkeys(row)) for row in adj]
    assert len(ir.var_to_diff) == ir.n_var >= n_var
    assert len(ir.eq_to_diff) == n_eq
    # Every created variable and equation is the derivative of an existing one.
    assert set(range(n_var, ir.n_var)) <= set(ir.var_to_diff)
    assert set(range(len(adj), n_eq)) <= set(ir.eq_to_diff)
    # der(e) holds every variable of e and its derivative.
    for e, de in enumerate(ir.eq_to_diff):
        if de != -1:
            expected = set(ir.adj[e]) | {ir.var_to_diff[v] for v in ir.adj[e]}
            assert set(ir.adj[de]) == expected
    # Highest equations are matched to highest variables, nothing else is matched.
    m = ir.matching
    for e in range(n_eq):
        v = m.eq_to_var[e]
        if ir.eq_to_diff[e] == -1:
            assert v != -1 and v in ir.adj[e] and ir.var_to_diff[v] == -1
            assert m.var_to_eq[v] == e
        else:
            assert v == -1
    for v in range(ir.n_var):
        if ir.var_to_diff[v] != -1:
            assert m.var_to_eq[v] == -1


def test_pendulum_constraint_differentiated_twice(pendulum):
    ir = pantelides(pendulum.n_var, pendulum.adj, pendulum.var_to_diff)
    check_index_reduction(ir, pendulum.n_var, pendulum.adj)
    assert ir.differentiated == [(0, 1), (1, 1), (4, 2)]
    assert ir.n_eq == 9
    assert ir.n_var == 11
    d_constraint = ir.eq_to_diff[4]
    dd_constraint = ir.eq_to_diff[d_constraint]
    assert ir.eq_to_diff[dd_constraint] == -1
    dx, dy = ir.var_to_diff[0], ir.var_to_diff[1]
    assert (dx, dy) == (5, 6)
    ddx, ddy = ir.var_to_diff[dx], ir.var_to_diff[dy]
    assert {ddx, ddy} == {9, 10}
    assert ddx in ir.adj[dd_constraint] and ddy in ir.adj[dd_constraint]
    assert ir.diff_to_var[ddx] == dx
    assert ir.diff_to_eq[d_constraint] == 4
    # Highest derivatives: lam, dvx, dvy, ddx, ddy, matched to the five top equations.
    assert ir.matching.size == 5


def test_inertias_coupling_differentiated_once(inertias):
    ir = pantelides(inertias.n_var, inertias.adj, inertias.var_to_diff)
    check_index_reduction(ir, inertias.n_var, inertias.adj)
    assert ir.differentiated == [(2, 1)]
    assert ir.n_var == 5
    assert set(ir.adj[3]) == {0, 1, 3, 4}


def test_capacitor_on_source_differentiated_once(capacitor):
    ir = pantelides(capacitor.n_var, capacitor.adj, capacitor.var_to_diff)
    check_index_reduction(ir, capacitor.n_var, capacitor.adj)
    assert ir.differentiated == [(0, 1)]
    assert ir.adj[2] == [0, 2]
    assert ir.matching.eq_to_var == [-1, 1, 2]


def test_ode_is_left_alone(rc):
    ir = pantelides(rc.n_var, rc.adj, rc.var_to_diff)
    check_index_reduction(ir, rc.n_var, rc.adj)
    assert ir.differentiated == []
    assert ir.adj == rc.adj
    assert ir.eq_to_diff == [-1, -1]


def test_algebraic_variable_gets_a_derivative():
    # Variables x, dx, y, z. der(x) = z; x = y; y = sin(t): both constraints are
    # differentiated, which brings der(y) of the algebraic y into the system.
    adj = [[1, 3], [0, 2], [2]]
    ir = pantelides(4, adj, [1, -1, -1, -1])
    check_index_reduction(ir, 4, adj)
    assert ir.differentiated == [(1, 1), (2, 1)]
    assert ir.var_to_diff[2] == 4
    assert ir.n_var == 5


def test_inputs_are_not_modified(pendulum):
    adj, links = copy.deepcopy(pendulum.adj), list(pendulum.var_to_diff)
    pantelides(pendulum.n_var, pendulum.adj, pendulum.var_to_diff)
    assert pendulum.adj == adj and pendulum.var_to_diff == links


def test_overdetermined_system_names_the_equations():
    # Variables x, dx, z. der(x) = z; z = 1; z = 2: the last two fight over z.
    adj = [[1, 2], [2], [2]]
    with pytest.raises(StructuralError, match=r"equations \[1, 2\] involve only 1 "
                                              r"unknown\(s\) \[2\]") as info:
        pantelides(3, adj, [1, -1, -1])
    assert info.value.equations == [1, 2]
    assert info.value.variables == [2]


def test_overdetermined_through_derivatives():
    # x and der(x) are one unknown: x = 1 and der(x) = 0 cannot both hold.
    with pytest.raises(StructuralError, match=r"equations \[0, 1\]") as info:
        pantelides(2, [[0], [1]], [1, -1])
    assert info.value.variables == [0]


def test_empty_equation_is_singular():
    with pytest.raises(StructuralError, match=r"equations \[1\] involve only 0"):
        pantelides(1, [[0], []], [-1])


def test_max_rounds_bounds_the_index(pendulum):
    with pytest.raises(StructuralError, match="equation 4: still structurally singular "
                                              "after 1 differentiations") as info:
        pantelides(pendulum.n_var, pendulum.adj, pendulum.var_to_diff, max_rounds=1)
    assert info.value.equations == [4]


@pytest.mark.parametrize("links, message", [
    ([1, -1], "one entry per variable"),
    ([1, 0, -1], "cycle"),
    ([2, 2, -1], "derivative of both 0 and 1"),
    ([0, -1, -1], "not another variable"),
    ([5, -1, -1], "not another variable"),
])
def test_malformed_var_to_diff_raises(links, message):
    with pytest.raises(ValueError, match=message):
        pantelides(3, [[0], [1], [2]], links)


def chain_of_inertias(n):
    """n inertias coupled rigidly in a chain, driven by a torque on the first.

    Variables: w_k (k), tau_k coupling torques (n + k, k < n - 1), dw_k (2n - 1 + k).
    """
    w = list(range(n))
    tau = list(range(n, 2 * n - 1))
    dw = list(range(2 * n - 1, 3 * n - 1))
    adj = []
    for k in range(n):
        row = [dw[k]]
        if k > 0:
            row.append(tau[k - 1])
        if k < n - 1:
            row.append(tau[k])
        adj.append(row)
    for k in range(n - 1):
        adj.append([w[k], w[k + 1]])
    links = [dw[k] for k in range(n)] + [-1] * (2 * n - 1)
    return 3 * n - 1, adj, links


@pytest.mark.parametrize("seed", range(10))
def test_shuffled_chain_of_inertias(seed):
    n = 30
    n_var, adj, links = chain_of_inertias(n)
    order = list(range(len(adj)))
    random.Random(seed).shuffle(order)
    adj = [adj[e] for e in order]
    ir = pantelides(n_var, adj, links)
    check_index_reduction(ir, n_var, adj)
    coupling = sorted(order.index(n + k) for k in range(n - 1))
    assert ir.differentiated == [(e, 1) for e in coupling]


@pytest.mark.parametrize("seed", range(20))
def test_without_differentiation_the_matching_is_the_maximum_matching(seed):
    """The compiler reuses this matching as its own when nothing is differentiated:
    it must be `maximum_matching` onto the highest derivatives, pair for pair. Rows
    with repeated or unordered entries are matched as their deduplicated copies."""
    rng = random.Random(seed)
    n = rng.randint(3, 40)
    n_state = rng.randint(0, n // 3)
    # x_k with der(x_k) for k < n_state, then algebraic variables
    n_var = n + n_state
    links = [n + k for k in range(n_state)] + [-1] * (n - n_state) + [-1] * n_state
    highest = [d == -1 for d in links]
    adj = []
    for e in range(n - n_state):      # square in the highest derivatives, matchable
        unknowns = [v for v in range(n_var) if highest[v]]
        row = [unknowns[e]] + rng.sample(range(n_var), rng.randint(0, 3))
        rng.shuffle(row)
        adj.append(row + row[:rng.randint(0, 1)])     # sometimes an entry twice
    ir = pantelides(n_var, adj, links)
    check_index_reduction(ir, n_var, adj)
    if ir.differentiated:
        pytest.skip("this draw needs index reduction")
    expected = maximum_matching(n_var, [list(dict.fromkeys(r)) for r in adj],
                                allowed=highest)
    assert ir.matching == expected


def test_singular_system_is_refused_with_a_matching_onto_highest_derivatives():
    """The family check runs when the first matching leaves an equation out: here x
    and der(x) are one family, matched by two equations."""
    with pytest.raises(StructuralError, match=r"equations \[0, 1\] involve only 1 "):
        pantelides(2, [[0, 1], [1, 0]], [1, -1])


def test_rows_that_need_no_change_are_shared_and_the_others_are_new(pendulum):
    adj = [list(row) for row in pendulum.adj] + [[0, 0, 1], [1.0, 2]]
    ir = pantelides(pendulum.n_var, adj[:-2], pendulum.var_to_diff)
    increasing = [e for e in range(len(pendulum.adj))
                  if all(a < b for a, b in zip(adj[e], adj[e][1:]))]
    assert increasing and all(ir.adj[e] is adj[e] for e in increasing)
    assert all(ir.adj[e] == list(dict.fromkeys(adj[e]))
               for e in range(len(pendulum.adj)))
    rows = _copy_adjacency(pendulum.n_var, adj)
    assert rows[-2] == [0, 1] and rows[-2] is not adj[-2]      # a repeat left out
    assert rows[-1] == [1, 2] and all(type(v) is int for row in rows for v in row)
