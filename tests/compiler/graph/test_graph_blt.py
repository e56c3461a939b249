"""Tests of `strongly_connected_components`, `block_lower_triangular` and
`block_order`."""

import random

import pytest

from mechatron.compiler.graph import (Block, block_lower_triangular, block_order,
                                      maximum_matching, strongly_connected_components)
from mechatron.compiler.graph.matching import Matching


def reachability(n, succ):
    """reach[u] = set of nodes reachable from u (u included), by plain search."""
    reach = []
    for u in range(n):
        seen, todo = {u}, [u]
        while todo:
            for w in succ[todo.pop()]:
                if w not in seen:
                    seen.add(w)
                    todo.append(w)
        reach.append(seen)
    return reach


def random_digraph(rng, n, p):
    return [[w for w in range(n) if rng.random() < p] for _ in range(n)]


@pytest.mark.parametrize("seed", range(60))
def test_tarjan_matches_brute_force(seed):
    rng = random.Random(seed)
    n = rng.randint(1, 30)
    succ = random_digraph(rng, n, rng.choice([0.03, 0.08, 0.15]))
    components = strongly_connected_components(n, succ)
    reach = reachability(n, succ)
    assert sorted(u for c in components for u in c) == list(range(n))
    where = {u: k for k, c in enumerate(components) for u in c}
    for u in range(n):
        same = {w for w in range(n) if w in reach[u] and u in reach[w]}
        assert set(components[where[u]]) == same
        for w in succ[u]:
            assert where[w] <= where[u]  # reverse topological order
    for c in components:
        assert c == sorted(c)


def test_tarjan_small_cases():
    assert strongly_connected_components(0, []) == []
    assert strongly_connected_components(1, [[0]]) == [[0]]
    assert strongly_connected_components(3, [[1], [2], []]) == [[2], [1], [0]]
    assert strongly_connected_components(3, [[1], [0], [0]]) == [[0, 1], [2]]


def test_tarjan_wrong_size_raises():
    with pytest.raises(ValueError, match="one entry per node"):
        strongly_connected_components(2, [[]])


def assert_blt_valid(n_var, adj, matching, blocks):
    """Each matched equation once; a block only uses earlier or own or unmatched vars."""
    placed = [e for b in blocks for e in b.equations]
    matched = [e for e, v in enumerate(matching.eq_to_var) if v != -1]
    assert sorted(placed) == matched
    solved = set()
    for b in blocks:
        assert b.variables == [matching.eq_to_var[e] for e in b.equations]
        own = set(b.variables)
        for e in b.equations:
            for v in adj[e]:
                assert matching.var_to_eq[v] == -1 or v in solved or v in own
        solved |= own


def test_triangular_system_gives_scalar_blocks_in_order():
    # x0 = 1; x1 = f(x0); x2 = g(x1, x0), listed backwards.
    adj = [[2, 1, 0], [1, 0], [0]]
    m = maximum_matching(3, adj)
    blocks = block_lower_triangular(3, adj, m)
    assert blocks == [Block([2], [0]), Block([1], [1]), Block([0], [2])]


def test_algebraic_loop_is_one_block():
    # e0: x0 + x1 = 1; e1: x0 - x1 = u; e2: x2 = x0 * x1.
    adj = [[0, 1], [0, 1], [2, 0, 1]]
    m = maximum_matching(3, adj)
    blocks = block_lower_triangular(3, adj, m)
    assert [b.equations for b in blocks] == [[0, 1], [2]]
    assert sorted(blocks[0].variables) == [0, 1]


def test_unmatched_equations_are_left_out():
    adj = [[0], [0], [0, 1]]
    m = Matching([0, -1, 1], [0, 2])
    blocks = block_lower_triangular(2, adj, m)
    assert [b.equations for b in blocks] == [[0], [2]]


def test_matching_of_wrong_size_raises():
    with pytest.raises(ValueError, match="expected \\(1, 2\\)"):
        block_lower_triangular(2, [[0]], Matching([0], [0]))


@pytest.mark.parametrize("seed", range(60))
def test_random_sparse_systems(seed):
    rng = random.Random(seed)
    n_eq = rng.randint(1, 40)
    n_var = n_eq + rng.randint(-3, 3)
    n_var = max(n_var, 1)
    adj = [rng.sample(range(n_var), rng.randint(1, min(3, n_var))) for _ in range(n_eq)]
    m = maximum_matching(n_var, adj)
    blocks = block_lower_triangular(n_var, adj, m)
    assert_blt_valid(n_var, adj, m, blocks)


def tarjan_by_recursion(n, succ):
    """Tarjan's algorithm as published (recursive): roots in increasing order,
    successors in list order, each component sorted when emitted."""
    index, low, on_stack, stack, out = {}, {}, set(), [], []

    def connect(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in succ[v]:
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            out.append(sorted(comp))

    for v in range(n):
        if v not in index:
            connect(v)
    return out


@pytest.mark.parametrize("seed", range(60))
def test_tarjan_emits_components_in_the_order_of_the_published_algorithm(seed):
    """The order of the blocks decides the order of the solved variables: it is the
    order of Tarjan's algorithm, self-loops, sinks and all."""
    rng = random.Random(100 + seed)
    n = rng.randint(1, 40)
    succ = random_digraph(rng, n, rng.choice([0.02, 0.05, 0.1, 0.2]))
    assert strongly_connected_components(n, succ) == tarjan_by_recursion(n, succ)


@pytest.mark.parametrize("seed", range(30))
def test_blt_order_follows_tarjan_on_the_dependency_graph(seed):
    rng = random.Random(200 + seed)
    n = rng.randint(1, 30)
    adj = [sorted(set([e] + rng.sample(range(n), rng.randint(0, 3)))) for e in range(n)]
    m = maximum_matching(n, adj)
    succ = [[m.var_to_eq[v] for v in row if m.var_to_eq[v] != -1] for row in adj]
    expected = tarjan_by_recursion(n, succ)
    blocks = block_lower_triangular(n, adj, m)
    assert [b.equations for b in blocks] == expected
    assert all(b.variables == [m.eq_to_var[e] for e in b.equations] for b in blocks)


@pytest.mark.parametrize("seed", range(30))
def test_block_order_holds_the_blocks_of_tarjan_as_arrays(seed):
    """`block_order` on a graph where some equations are left unmatched (more equations
    than variables, some equations of no variable): its arrays hold, block by block, the
    components of Tarjan's recursion on the dependency graph of the matched equations,
    each with its matched variables, and read as the same `Block` objects."""
    rng = random.Random(300 + seed)
    n_var = rng.randint(1, 25)
    n_eq = n_var + rng.randint(0, 6)
    adj = [sorted(rng.sample(range(n_var), rng.randint(0, min(3, n_var))))
           for _ in range(n_eq)]
    m = maximum_matching(n_var, adj)
    matched = {e for e, v in enumerate(m.eq_to_var) if v != -1}
    succ = [[m.var_to_eq[v] for v in row if m.var_to_eq[v] != -1 and m.var_to_eq[v] != e]
            if e in matched else [] for e, row in enumerate(adj)]
    expected = [c for c in tarjan_by_recursion(n_eq, succ) if c[0] in matched]
    order = block_order(n_var, adj, m)
    assert len(order) == len(expected)
    assert order.sizes().tolist() == [len(c) for c in expected]
    assert order.equations.tolist() == [e for c in expected for e in c]
    assert order.variables.tolist() == [m.eq_to_var[e] for c in expected for e in c]
    blocks = [Block(c, [m.eq_to_var[e] for e in c]) for c in expected]
    assert list(order) == blocks
    assert [order.block(k) for k in range(len(order))] == blocks
    assert block_lower_triangular(n_var, adj, m) == blocks
