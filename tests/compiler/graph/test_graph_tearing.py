"""Tests of `tear`."""

import random

import pytest

from mechatron.compiler.graph import (block_lower_triangular, maximum_matching, tear)


def assert_executable(block_eqs, block_vars, adj, solvable, torn):
    """The sequence runs in order; residuals close the loop; counts balance."""
    inside = set(block_vars)
    assert len(torn.residuals) == len(torn.tearing_vars)
    seq_eqs = [e for e, _ in torn.sequence]
    seq_vars = [v for _, v in torn.sequence]
    assert sorted(seq_eqs + torn.residuals) == sorted(block_eqs)
    assert sorted(seq_vars + torn.tearing_vars) == sorted(block_vars)
    known = set(torn.tearing_vars)
    for e, v in torn.sequence:
        assert solvable(e, v)
        assert v in adj[e]
        assert {w for w in adj[e] if w in inside} - {v} <= known
        known.add(v)
    assert known == inside


def test_single_solvable_equation_is_a_sequence():
    torn = tear([4], [7], {4: [7, 1]}, lambda e, v: True)
    assert (torn.sequence, torn.residuals, torn.tearing_vars) == ([(4, 7)], [], [])


def test_single_unsolvable_equation_is_a_residual():
    torn = tear([4], [7], {4: [7, 1]}, lambda e, v: False)
    assert (torn.sequence, torn.residuals, torn.tearing_vars) == ([], [4], [7])


def test_linear_ring_needs_one_tearing_variable():
    # e_k: x_k + x_{k+1} = c_k around a ring of 5 equations.
    n = 5
    adj = [[k, (k + 1) % n] for k in range(n)]
    torn = tear(range(n), range(n), adj, lambda e, v: True)
    assert_executable(range(n), range(n), adj, lambda e, v: True, torn)
    assert len(torn.tearing_vars) == 1
    assert len(torn.sequence) == n - 1


def test_variable_of_a_single_equation_is_solved_last():
    # Each x_k is only solvable from e_k; e_0 is a ring equation that also feeds an
    # extra variable y appearing only in e_3 (solved last, backward).
    adj = {0: [0, 1], 1: [1, 2], 2: [2, 0], 3: [3, 0, 1]}
    solvable = lambda e, v: v == e  # noqa: E731
    torn = tear([0, 1, 2, 3], [0, 1, 2, 3], adj, solvable)
    assert_executable([0, 1, 2, 3], [0, 1, 2, 3], adj, solvable, torn)
    assert len(torn.tearing_vars) == 1
    assert torn.sequence[-1] == (3, 3)


def test_variable_solvable_nowhere_is_torn():
    # Newton's law with an implicit friction term: v cannot be isolated anywhere.
    adj = {0: [0, 1], 1: [0, 1]}
    solvable = lambda e, v: v == 1 and e == 0  # noqa: E731
    torn = tear([0, 1], [0, 1], adj, solvable)
    assert_executable([0, 1], [0, 1], adj, solvable, torn)
    assert torn.tearing_vars == [0]
    assert torn.sequence == [(0, 1)] and torn.residuals == [1]


def test_triangular_block_needs_no_tearing():
    adj = {0: [0], 1: [0, 1], 2: [1, 2, 0]}
    torn = tear([2, 0, 1], [2, 1, 0], adj, lambda e, v: True)
    assert torn.tearing_vars == [] and torn.residuals == []
    assert torn.sequence == [(0, 0), (1, 1), (2, 2)]


def test_non_square_block_raises():
    with pytest.raises(ValueError, match="2 equations and 1 variables"):
        tear([0, 1], [0], [[0], [0]], lambda e, v: True)


def test_repeated_entries_raise():
    with pytest.raises(ValueError, match="twice"):
        tear([0, 0], [0, 1], [[0, 1]], lambda e, v: True)


@pytest.mark.parametrize("seed", range(80))
def test_random_blocks_are_executable(seed):
    rng = random.Random(seed)
    n = rng.randint(2, 40)
    adj = [rng.sample(range(n), rng.randint(1, 3)) for _ in range(n)]
    hard = {(e, v) for e in range(n) for v in adj[e] if rng.random() < 0.3}
    solvable = lambda e, v: (e, v) not in hard  # noqa: E731
    m = maximum_matching(n, adj)
    for block in block_lower_triangular(n, adj, m):
        torn = tear(block.equations, block.variables, adj, solvable)
        assert_executable(block.equations, block.variables, adj, solvable, torn)
        assert len(torn.tearing_vars) <= len(block.equations)
        if len(block.equations) == 1:
            e, v = block.equations[0], block.variables[0]
            expected = ([(e, v)], []) if solvable(e, v) else ([], [e])
            assert (torn.sequence, torn.residuals) == expected
