"""The structural pass on many rows: the Jacobian pattern found by sampling
(`mechatron.compiler.structure._pattern`), which forms the Jacobian on the way and hands
it to `mechatron.compiler.linear.reveal`, against CasADi's own pattern and Jacobian."""

import casadi as ca
import numpy as np
import pytest

import mechatron as mt
import mechatron.compiler.structure as st
from tests.compiler.test_flatten_templates import ladder


def _rows(n):
    """``n`` sparse rows (each in three variables, one nonlinear), a row of 100 variables
    (sparse to the probe, more than `DENSE_ROW` to `sparse_jacobian`) and a row in all
    of them, in a scrambled order."""
    x = ca.SX.sym("x", n)
    rows = [x[i] * x[(i + 1) % n] - ca.sin(x[(i + 7) % n]) for i in range(n)]
    rows.append(ca.sum1(x[: 100]) - 2 * x[5])
    rows.append(ca.sum1(ca.exp(x)))
    order = np.random.default_rng(3).permutation(len(rows)).tolist()
    return ca.vertcat(*[rows[k] for k in order]), x


def test_the_sampled_pattern_and_jacobian_equal_casadis(monkeypatch):
    expr, x = _rows(3000)
    monkeypatch.setattr(st, "_SAMPLED_PATTERN_ROWS", 1)
    pattern, jac = st._pattern(expr, x)
    assert jac is not None                  # the dense row was found, the path taken
    assert pattern == ca.jacobian_sparsity(expr, x)
    assert jac.sparsity() == pattern
    point = np.random.default_rng(4).uniform(-1.0, 1.0, x.numel())
    ours = ca.Function("ours", [x], [jac])(point)
    theirs = ca.Function("theirs", [x], [ca.jacobian(expr, x)])(point)
    assert ours.sparsity() == theirs.sparsity()
    np.testing.assert_allclose(ours.nonzeros(), theirs.nonzeros(), rtol=1e-14, atol=0)


def test_a_dense_row_on_columns_of_one_period_is_found(monkeypatch):
    """Columns repeat with a component's period (6 variables here); the dense row holds
    the second of each six, which every 64th column never meets (64 = 4 mod 6)."""
    n = 6000
    x = ca.SX.sym("x", n)
    rows = [x[i] - 2 * x[(i + 1) % n] for i in range(n)]
    rows.append(ca.sum1(x[1::6]))
    expr = ca.vertcat(*rows)
    monkeypatch.setattr(st, "_SAMPLED_PATTERN_ROWS", 1)
    pattern, jac = st._pattern(expr, x)
    assert jac is not None
    assert pattern == ca.jacobian_sparsity(expr, x)
    assert jac.sparsity() == pattern


def test_without_a_dense_row_the_pattern_is_casadis_and_no_jacobian_is_formed(
        monkeypatch):
    x = ca.SX.sym("x", 500)
    expr = ca.vertcat(*[x[i] - 2 * x[(i + 1) % 500] for i in range(500)])
    monkeypatch.setattr(st, "_SAMPLED_PATTERN_ROWS", 1)
    pattern, jac = st._pattern(expr, x)
    assert jac is None
    assert pattern == ca.jacobian_sparsity(expr, x)


def test_a_ladder_lowers_the_same_through_the_sampled_pattern(monkeypatch):
    """A ladder of 1000 sections (its reference node's flow balance holds 1000
    currents) lowered both ways: the same states, blocks and functions."""
    plain = mt.compile_model(ladder(1000))
    taken = []
    pattern = st._pattern

    def spy(expr, syms, narrow=None):
        out = pattern(expr, syms, narrow)
        taken.append(out[1] is not None)
        return out

    monkeypatch.setattr(st, "_SAMPLED_PATTERN_ROWS", 1)
    monkeypatch.setattr(st, "_pattern", spy)
    sampled = mt.compile_model(ladder(1000))
    assert any(taken)
    assert sampled.state_names == plain.state_names
    assert sampled.alg_names == plain.alg_names
    for key in ("blocks", "largest_block", "tearing_variables", "equations"):
        assert sampled.report[key] == plain.report[key], key
    _same_functions(sampled, plain, t=0.3, seed=5)


def test_rows_known_to_be_narrow_are_left_out_of_the_probe_and_the_pattern_stays(
        monkeypatch):
    """The mask only spares the probe rows: the pattern is CasADi's whether it is right
    (the dense rows left in) or wrong (every row said narrow, the dense ones too)."""
    expr, x = _rows(3000)
    counts = np.diff(np.asarray(ca.jacobian_sparsity(expr, x).get_crs()[0]))
    monkeypatch.setattr(st, "_SAMPLED_PATTERN_ROWS", 1)
    right = counts < st.DENSE_ROW
    assert 0 < (~right).sum() < 5
    for narrow, found in ((right, True), (np.ones(counts.size, dtype=bool), False)):
        pattern, jac = st._pattern(expr, x, narrow)
        assert (jac is not None) == found
        assert pattern == ca.jacobian_sparsity(expr, x)


def test_the_rows_of_class_templates_and_short_sums_are_told_narrow_by_their_origins(
        monkeypatch):
    """In a ladder, the rows of the resistors', capacitors' and source's templates are
    narrow, and so are the flow sums of three terms; the reference node's flow sum is
    the one row not told."""
    seen = []
    csr = st._csr

    def spy(expr, syms, narrow=None):
        seen.append((expr, syms, narrow))
        return csr(expr, syms, narrow)

    monkeypatch.setattr(st, "_csr", spy)
    monkeypatch.setattr(st, "_SAMPLED_PATTERN_ROWS", 100)   # the mask is read from here on
    mt.compile_model(ladder(200))
    (expr, syms, narrow), = seen
    counts = np.diff(np.asarray(ca.jacobian_sparsity(expr, syms).get_crs()[0]))
    assert narrow is not None and narrow.size == counts.size
    assert (counts[narrow] < st.DENSE_ROW).all()
    assert np.flatnonzero(~narrow).tolist() == [np.argmax(counts)]   # the reference's


def test_the_incidence_rows_are_the_patterns_and_share_one_integer_per_column():
    """`_csr`'s rows are the Jacobian pattern's, row by row; a column held by several
    rows is one integer object in all of them (they live through the structural
    analysis), also past the small integers Python caches."""
    x = ca.SX.sym("x", 600)
    expr = ca.vertcat(*[x[k] * x[(k + 1) % 600] + x[599 - k] for k in range(600)])
    rows, sp, _ = st._csr(expr, x)
    ptr, col = sp.get_crs()
    assert sp == ca.jacobian_sparsity(expr, x)
    assert rows == [col[a:b] for a, b in zip(ptr, ptr[1:])]
    first: dict[int, int] = {}
    assert all(first.setdefault(v, v) is v for row in rows for v in row)
    assert max(first) > 256 and sum(map(len, rows)) > 2 * len(first)


def test_the_entries_of_a_sub_block_are_casadis():
    rng = np.random.default_rng(6)
    sp = ca.sparsify(ca.DM((rng.random((40, 50)) < 0.2).astype(float))).sparsity()
    assert 0 < sp.nnz() < 40 * 50 / 2
    rows, cols = (np.asarray(a, dtype=np.int64) for a in sp.get_triplet())
    es = rng.permutation(40)[:25].tolist()
    vs = rng.permutation(50)[:25].tolist()
    r, c = st._sub_entries(rows, cols, sp.shape, es, vs)
    theirs = sp.sub(es, vs, False)[0]
    assert sorted(zip(r.tolist(), c.tolist())) == sorted(zip(*theirs.get_triplet()))


def test_one_equation_blocks_zeroed_piece_by_piece_give_the_same_functions(monkeypatch):
    """The one-equation blocks of a ladder of 300 sections solved with their colours
    zeroed in pieces of 7 rows (`_zeroed`, as on columns of a million rows) and at once:
    the same states and functions, value for value."""
    whole = mt.compile_model(ladder(300))
    pieces = []
    zeroed = st._zeroed

    def spy(ex, xs):
        pieces.append(ex.numel())
        return zeroed(ex, xs)

    monkeypatch.setattr(st, "_ZEROED_PIECE", 7)
    monkeypatch.setattr(st, "_zeroed", spy)
    cut = mt.compile_model(ladder(300))
    assert max(pieces) > 2 * 7             # some colour was cut into pieces
    assert cut.state_names == whole.state_names
    assert cut.alg_names == whole.alg_names
    _same_functions(cut, whole, t=0.7, seed=11, draws=3)


def test_one_equation_blocks_solved_together_are_the_ones_solved_alone():
    """`_solve_singles` on a chain of blocks given in a shuffled order (each equation
    holds its variable and an earlier block's, so the blocks need colours), one block
    not linear in its variable and two whose coefficients hold each other's: each block it
    solves is the one-by-one solution `_solve_linear`, in the place it gives; the
    three others are left out."""
    n = 40
    x = ca.SX.sym("x", n)
    p = ca.SX.sym("p")
    res = [x[0] - p] + [x[i] - 2 * x[i - 1] + (i % 3) * x[i // 2] - i * p
                        for i in range(1, n)]
    res[17] = x[17] * x[17] - x[3]         # not linear in x[17]
    res[29] = x[29] * x[5] + 1             # linear, by a coefficient holding x[5]...
    res[5] = x[5] * x[29] - p              # ...and x[5]'s by one holding x[29]
    order = np.random.default_rng(3).permutation(n).tolist()
    es = [100 + k for k in order]          # equation numbers as a model's, not 0..n-1
    eqs = {100 + k: res[k] for k in range(n)}
    syms = [x[k] for k in range(n)]
    X, solved, pieces = st._solve_singles(
        [eqs.get(e, ca.SX(0)) for e in range(100 + n)], syms, es, order)
    # each block's place among the solved, by its equation
    places = {es[i]: place for place, i in enumerate(solved)}
    at = [places.get(e, -1) for e in range(100 + n)]
    sols = ca.vertcat(*pieces)
    assert len(solved) == len(places) == sols.numel() == n - 3
    assert {k for k in range(n) if at[100 + k] < 0} == {5, 17, 29}
    f = ca.Function("f", [x, p], [sols, X])
    g = ca.Function("g", [x, p], [ca.vertcat(*[st._solve_linear(
        res[k], x[k], ca.jacobian(res[k], x[k])) for k in range(n)])])
    point = np.linspace(0.3, 1.7, n)
    got, stacked = (np.asarray(v).ravel() for v in f(point, 0.7))
    want = np.asarray(g(point, 0.7)).ravel()
    for k in range(n):
        if at[100 + k] >= 0:
            place = at[100 + k]
            assert stacked[solved[place]] == point[k]           # its variable
            assert got[place] == pytest.approx(want[k], rel=1e-14, abs=1e-14)


def _same_functions(a, b, t: float, seed: int, draws: int = 1) -> None:
    """The derivatives and logged variables of the compiled models ``a`` and ``b`` equal
    value for value at time ``t``, at ``draws`` random states."""
    rng = np.random.default_rng(seed)
    for _ in range(draws):
        x = rng.uniform(-1.0, 1.0, b.f_ode.size1_in(1))
        args = (t, x, np.zeros(b.f_ode.size1_in(2)), b.p0)
        np.testing.assert_array_equal(np.asarray(a.f_ode(*args)),
                                      np.asarray(b.f_ode(*args)))
        np.testing.assert_array_equal(np.asarray(a.f_out(*args)),
                                      np.asarray(b.f_out(*args)))
