"""Large systems: every pass is iterative, so long paths and chains must not recurse.

No timing assertion here (speed lives in bench/); these only have to complete.
"""

from mechatron.compiler.graph import (block_lower_triangular, dummy_derivatives,
                                      maximum_matching, pantelides, state_selection, tear)

N = 100_000


def test_matching_and_blt_on_a_long_chain():
    # Equation k holds x_{k+1} and x_k; the last one only x_{N-1}. A greedy pass pairs
    # every equation with x_{k+1}, leaving one augmenting path through the whole chain.
    adj = [[k + 1, k] for k in range(N - 1)] + [[N - 1]]
    m = maximum_matching(N, adj)
    assert m.size == N
    assert m.eq_to_var[:3] == [0, 1, 2]
    blocks = block_lower_triangular(N, adj, m)
    assert len(blocks) == N
    assert blocks[0].equations == [N - 1] and blocks[-1].equations == [0]


def test_blt_on_one_long_cycle():
    adj = [[k, (k + 1) % N] for k in range(N)]
    m = maximum_matching(N, adj)
    blocks = block_lower_triangular(N, adj, m)
    assert len(blocks) == 1 and len(blocks[0].equations) == N
    torn = tear(blocks[0].equations, blocks[0].variables, adj, lambda e, v: True)
    assert len(torn.tearing_vars) == 1 and len(torn.sequence) == N - 1


def test_index_reduction_of_a_long_chain_of_rigid_inertias(inertia_chain):
    n = N // 5
    chain = inertia_chain(n)
    ir = pantelides(chain.n_var, chain.adj, chain.var_to_diff)
    assert len(ir.differentiated) == n - 1
    states = state_selection(ir, dummy_derivatives(ir))
    assert len(states) == 1
