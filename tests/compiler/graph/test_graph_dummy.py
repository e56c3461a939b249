"""Tests of `dummy_derivatives` and `state_selection`."""

import random

import pytest

from mechatron.compiler.graph import (dummy_derivatives, maximum_matching, pantelides,
                                      state_selection)
from mechatron.errors import StructuralError


def reduce(system, **options):
    ir = pantelides(system.n_var, system.adj, system.var_to_diff)
    dummies = dummy_derivatives(ir, **options)
    return ir, dummies, state_selection(ir, dummies)


def assert_square_and_matchable(ir, dummies, states):
    """Dummies are derivatives; non-state variables match every equation one to one."""
    for dv in dummies:
        assert ir.diff_to_var[dv] != -1
    unknowns = set(range(ir.n_var)) - set(states)
    assert len(unknowns) == ir.n_eq
    m = maximum_matching(ir.n_var, ir.adj, allowed=unknowns)
    assert m.unmatched_equations == []


def names(system, indices):
    return {system.names[v] if v < system.n_var else v for v in indices}


def test_pendulum_keeps_one_position_and_one_velocity(pendulum):
    ir, dummies, states = reduce(pendulum)
    assert_square_and_matchable(ir, dummies, states)
    assert len(states) == 2
    assert len(names(pendulum, states) & {"x", "y"}) == 1
    assert len(names(pendulum, states) & {"vx", "vy"}) == 1
    # Four dummies: both second derivatives of the positions, one velocity derivative
    # (der(vx) or der(vy)) and one position derivative (der(x) or der(y)).
    assert len(dummies) == 4
    assert {ir.var_to_diff[5], ir.var_to_diff[6]} <= set(dummies)


def test_pendulum_default_choice(pendulum):
    _, dummies, states = reduce(pendulum)
    assert names(pendulum, states) == {"x", "vx"}
    assert names(pendulum, dummies) == {"dy", "dvy", 9, 10}


def test_pendulum_priority_steers_the_states(pendulum):
    priority = [0.0] * pendulum.n_var
    priority[pendulum.index("x")] = 1.0   # higher: rather a dummy
    priority[pendulum.index("vx")] = 1.0
    ir, dummies, states = reduce(pendulum, priority=priority)
    assert_square_and_matchable(ir, dummies, states)
    assert names(pendulum, states) == {"y", "vy"}


def test_inertias_keep_one_speed(inertias):
    ir, dummies, states = reduce(inertias)
    assert_square_and_matchable(ir, dummies, states)
    assert names(inertias, dummies) == {"dw2"}
    assert names(inertias, states) == {"w1"}


def test_inertias_priority_on_short_list(inertias):
    # A priority list over the first variables only; missing entries count as 0.
    ir, dummies, states = reduce(inertias, priority=[1.0])
    assert_square_and_matchable(ir, dummies, states)
    assert names(inertias, states) == {"w2"}


def test_capacitor_on_source_has_no_state(capacitor):
    ir, dummies, states = reduce(capacitor)
    assert_square_and_matchable(ir, dummies, states)
    assert dummies == [capacitor.index("dv")]
    assert states == []


def test_ode_has_no_dummy(rc):
    ir, dummies, states = reduce(rc)
    assert dummies == []
    assert states == [rc.index("v")]


def test_algebraic_variable_derivative_becomes_dummy():
    # Variables x, dx, y, z. der(x) = z; x = y; y = sin(t).
    ir = pantelides(4, [[1, 3], [0, 2], [2]], [1, -1, -1, -1])
    dummies = dummy_derivatives(ir)
    states = state_selection(ir, dummies)
    assert_square_and_matchable(ir, dummies, states)
    assert sorted(dummies) == [1, 4]  # der(x) and the created der(y)
    assert states == []


def test_select_callback_sees_rows_candidates_and_count(inertias):
    ir = pantelides(inertias.n_var, inertias.adj, inertias.var_to_diff)
    calls = []

    def select(eqs, candidates, k):
        calls.append((eqs, candidates, k))
        return [candidates[-1]]

    dummies = dummy_derivatives(ir, select=select)
    assert calls == [([3], [4, 3], 1)]  # preferred dummy first: higher index
    assert dummies == [3]
    assert state_selection(ir, dummies) == [1]


def test_select_callback_walks_down_the_levels(pendulum):
    ir = pantelides(pendulum.n_var, pendulum.adj, pendulum.var_to_diff)
    levels = []

    def select(eqs, candidates, k):
        levels.append((sorted(eqs), sorted(candidates), k))
        return [v for v in candidates if v != 8][:k]  # der(vy) stays: vy is a state

    dummies = dummy_derivatives(ir, select=select)
    d_constraint = ir.eq_to_diff[4]
    dd_constraint = ir.eq_to_diff[d_constraint]
    assert levels[0] == (sorted([dd_constraint, ir.eq_to_diff[0], ir.eq_to_diff[1]]),
                         [7, 8, 9, 10], 3)
    assert levels[1][0] == [d_constraint] and levels[1][2] == 1
    assert len(levels) == 2
    states = state_selection(ir, dummies)
    assert_square_and_matchable(ir, dummies, states)
    assert 3 in states


def test_select_returning_too_few_is_singular(inertias):
    ir = pantelides(inertias.n_var, inertias.adj, inertias.var_to_diff)
    with pytest.raises(StructuralError, match=r"equations \[3\] are singular .* only 0 "
                                              r"of 1 dummy") as info:
        dummy_derivatives(ir, select=lambda eqs, candidates, k: [])
    assert info.value.equations == [3]


def test_select_returning_a_non_candidate_raises(inertias):
    ir = pantelides(inertias.n_var, inertias.adj, inertias.var_to_diff)
    with pytest.raises(ValueError, match="at most 1 distinct variables"):
        dummy_derivatives(ir, select=lambda eqs, candidates, k: [2])


def test_chain_of_rigid_inertias_keeps_one_state(inertia_chain):
    chain = inertia_chain(40)
    ir = pantelides(chain.n_var, chain.adj, chain.var_to_diff)
    dummies = dummy_derivatives(ir)
    states = state_selection(ir, dummies)
    assert_square_and_matchable(ir, dummies, states)
    assert len(states) == 1


def random_dae(rng):
    """A random DAE with a transversal: equation i holds a member of family perm[i].

    Each family is a chain x, der(x), ... of 1 to 3 variables given upfront.
    """
    n = rng.randint(1, 8)
    chains, n_var, links = [], 0, []
    for _ in range(n):
        length = rng.randint(1, 3)
        chain = list(range(n_var, n_var + length))
        links += chain[1:] + [-1]
        chains.append(chain)
        n_var += length
    perm = rng.sample(range(n), n)
    adj = []
    for i in range(n):
        row = {rng.choice(chains[perm[i]])}
        for _ in range(rng.randint(0, 2)):
            row.add(rng.choice(rng.choice(chains)))
        adj.append(sorted(row))
    return n_var, adj, links


@pytest.mark.parametrize("seed", range(200))
def test_random_daes_reduce_to_square_systems(seed):
    rng = random.Random(seed)
    n_var, adj, links = random_dae(rng)
    ir = pantelides(n_var, adj, links)
    priority = [rng.random() for _ in range(n_var)] if seed % 2 else None
    dummies = dummy_derivatives(ir, priority=priority)
    states = state_selection(ir, dummies)
    assert_square_and_matchable(ir, dummies, states)
