"""Tests of `exact_elimination`: exact rank, exact cancellation, combinations that add up,
and short combinations on long chains."""

import random
from fractions import Fraction

import numpy as np
import pytest

from mechatron.compiler.graph.elimination import SparseRows, exact, exact_elimination


def combined(linear, comb):
    """Sum of ``m * linear[e]`` over the combination, with exact zeros dropped."""
    out = {}
    for e, m in comb.items():
        for v, a in linear[e].items():
            out[v] = out.get(v, 0) + m * a
    return {v: a for v, a in out.items() if a}


def test_two_current_laws_that_differ_by_states_only_reveal_the_cut_set():
    # columns: 0 c.i, 1 r.i (unknowns), 2 l.i, 3 src.i (knowns here)
    linear = [{0: 1, 1: 1, 3: -1},        # node 1: c.i + r.i = src.i
              {2: 1, 0: -1, 1: -1}]       # node 2: l.i = c.i + r.i
    out = exact_elimination(linear, [True, True, False, False])
    assert len(out.pivots) == 1, "two rows, rank one in the unknowns"
    (e, row), = out.rows.items()
    assert row == {2: 1, 3: -1} or row == {2: -1, 3: 1}
    assert combined(linear, out.combination(e)) == row
    assert out.changed(e)


def test_fractions_cancel_exactly():
    third = Fraction(1, 3)
    linear = [{0: third, 1: 1}, {0: 1, 1: 3, 2: 1}]
    out = exact_elimination(linear, [True, True, False])
    (e, row), = out.rows.items()
    assert set(row) == {2}, "0.333... x + y and x + 3 y differ by a factor 3 exactly"
    assert exact(0.1) == Fraction(0.1) and exact(-2.0) == -2 and type(exact(3.0)) is int


def test_random_integer_systems_rank_and_combinations():
    rng = random.Random(5)
    for _ in range(200):
        n_rows, n_cols = rng.randint(1, 7), rng.randint(1, 7)
        linear = [{v: rng.choice([-2, -1, 1, 1, 2, 3]) for v in range(n_cols)
                   if rng.random() < 0.4} for _ in range(n_rows)]
        # a few exact dependencies
        if n_rows > 2 and rng.random() < 0.5:
            linear[-1] = combined(linear, {0: 1, 1: -2})
        eliminable = [rng.random() < 0.7 for _ in range(n_cols)]
        out = exact_elimination(linear, eliminable)
        cols = [v for v in range(n_cols) if eliminable[v]]
        rows = [e for e in range(n_rows) if any(eliminable[v] for v in linear[e])]
        a = np.array([[float(linear[e].get(v, 0)) for v in cols] for e in rows]
                     ).reshape(len(rows), len(cols))
        assert len(out.pivots) == (np.linalg.matrix_rank(a) if a.size else 0)
        for e, row in out.rows.items():
            assert not any(eliminable[v] for v in row)
            comb = out.combination(e)
            assert comb[e] == 1 and all(k == e or k in out.pivots for k in comb)
            assert combined(linear, comb) == row


def test_a_long_chain_gives_short_combinations():
    """An RC ladder's current laws and branch relations: every reduced equation combines
    a handful of given ones, whatever the length (no path across the whole ladder)."""
    n = 300
    linear, eliminable = [], []

    def col(name, unknown=True):
        eliminable.append(unknown)
        return len(eliminable) - 1

    pot = [col(f"phi{k}") for k in range(n + 1)]
    cur = [col(f"i{k}") for k in range(n)]
    cap = [col(f"ic{k}") for k in range(n)]
    vc = [col(f"vc{k}", unknown=False) for k in range(n)]
    linear.append({pot[0]: 1})                                   # source: phi0 = V
    for k in range(n):
        linear.append({pot[k]: 1, pot[k + 1]: -1})               # R: phi_k - phi_k+1 = R i
        linear.append({vc[k]: 1, pot[k + 1]: -1})                # C: vc = phi_k+1
        linear.append({cap[k]: 1})                               # C: ic = C der(vc)
        law = {cur[k]: 1, cap[k]: -1}
        if k + 1 < n:
            law[cur[k + 1]] = -1
        linear.append(law)                                       # KCL at node k+1
    out = exact_elimination(linear, eliminable)
    assert len(out.rows) == n
    assert max(len(out.combination(e)) for e in out.rows) <= 6


def test_malformed_input_is_refused():
    with pytest.raises(ValueError, match="column 5"):
        exact_elimination([{5: 1}], [True])


def test_the_given_equations_are_not_modified():
    """Rows left as they were may be returned as given; rows that change are copies."""
    rng = random.Random(11)
    for _ in range(100):
        n = rng.randint(3, 9)
        linear = [{v: rng.choice([-1, 1, 2, 0])
                   for v in rng.sample(range(n), rng.randint(1, 3))} for _ in range(n + 2)]
        before = [dict(row) for row in linear]
        out = exact_elimination(linear, [rng.random() < 0.8 for _ in range(n)])
        assert linear == before
        for e, row in out.rows.items():
            assert all(row.values()), "exact zeros are dropped"
            assert combined(linear, out.combination(e)) == row


def _sparse(linear):
    """``linear`` (a list of dictionaries) held as `SparseRows`, each row's columns in
    the dictionary's order."""
    lengths = [len(row) for row in linear]
    ptr = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
    cols = np.array([v for row in linear for v in row], dtype=np.int64)
    return SparseRows(ptr, cols, [a for row in linear for a in row.values()])


def _network(rng, n_nodes, extra):
    """Current laws and branch relations of a random connected network: a spanning
    tree of branches (no loop: every pivot a column single) plus ``extra`` branches
    that close loops; some columns known (states), coefficients +-1 and 2, rows and
    columns in a random order."""
    branches = [(k, rng.randrange(k)) for k in range(1, n_nodes)]
    branches += [tuple(rng.sample(range(n_nodes), 2)) for _ in range(extra)]
    n_var = n_nodes + 2 * len(branches)         # potentials, currents, voltages
    linear = []
    for b, (p, q) in enumerate(branches):
        cur, volt = n_nodes + 2 * b, n_nodes + 2 * b + 1
        linear.append({volt: 1, p: -1, q: 1})
        if rng.random() < 0.5:
            linear.append({cur: rng.choice([1, 2]), volt: -1})
    for node in range(1, n_nodes):
        law = {n_nodes + 2 * b: (1 if p == node else -1)
               for b, (p, q) in enumerate(branches) if node in (p, q)}
        linear.append(law)
    linear.append({0: 1})                        # the reference
    rng.shuffle(linear)
    rename = list(range(n_var))
    rng.shuffle(rename)
    linear = [{rename[v]: a for v, a in sorted(row.items(), key=lambda x: rng.random())}
              for row in linear]
    eliminable = [rng.random() < 0.85 for _ in range(n_var)]
    return linear, eliminable


@pytest.mark.parametrize("extra", [0, 1, 4])
def test_rows_held_as_arrays_eliminate_as_the_dictionaries(extra):
    """`SparseRows` (the rows as arrays, the column-single pivots taken on them when no
    equation would be updated) give the pivots in the same order, the same reduced rows
    and the same steps as the same rows given as dictionaries, networks with and
    without loops, rows taking part in any order."""
    rng = random.Random(100 + extra)
    fast = 0
    for _ in range(150):
        linear, eliminable = _network(rng, rng.randint(2, 14), extra)
        rows = [e for e in range(len(linear)) if rng.random() < 0.9]
        rng.shuffle(rows)
        want = exact_elimination(linear, eliminable, rows=rows)
        got = exact_elimination(_sparse(linear), eliminable, rows=rows)
        assert list(got.pivots.items()) == list(want.pivots.items())
        assert list(got.rows.items()) == list(want.rows.items())
        assert got.updates == want.updates
        fast += not want.updates
    assert fast > 20, "the arrays' own path was taken"


def test_rows_held_as_arrays_read_as_dictionaries():
    linear = [{3: 1, 0: -1}, {}, {1: Fraction(1, 3)}]
    rows = _sparse(linear)
    assert len(rows) == 3 and list(rows) == linear and rows[-1] == linear[2]
    assert rows[0:2] == linear[:2]
    with pytest.raises(IndexError):
        rows[3]
    with pytest.raises(ValueError, match="equation 0 names column 3"):
        exact_elimination(rows, [True] * 3, rows=[0, 2])
