"""The arrays behind `mechatron.compiler.linear.reveal`: the exact coefficients, the
columns with coefficients free of unknowns, each equation's linear part and the purely
linear equations, read off the Jacobian's entries in bulk. Checked against the same
quantities written here entry by entry, on scrambled random entries."""

from fractions import Fraction

import casadi as ca
import numpy as np
import pytest

import mechatron.compiler.linear as lin


def _entries(rng, n_rows, n_cols, density=0.2):
    """Random entries in CasADi's column-major order, with numbers (integral, zero,
    fractional, large) and NaN for a coefficient that depends on unknowns."""
    mask = rng.random((n_rows, n_cols)) < density
    cols, rows = np.nonzero(mask.T)                 # column by column, as get_triplet
    kind = rng.integers(0, 6, size=rows.size)
    values = np.where(kind == 0, np.nan,
             np.where(kind == 1, 0.0,
             np.where(kind == 2, rng.integers(-3, 4, size=rows.size).astype(float),
             np.where(kind == 3, rng.normal(size=rows.size),
             np.where(kind == 4, 2.0 ** 70, -1.0)))))
    return rows.astype(np.int64), cols.astype(np.int64), values


@pytest.mark.parametrize("seed", range(6))
def test_bulk_arrays_equal_the_entry_by_entry_reading(seed):
    rng = np.random.default_rng(seed)
    n_rows, n_cols = 40, 30
    rows, cols, values = _entries(rng, n_rows, n_cols)
    # coefficients given by parameters for some of the NaN entries, found later
    symbolic = np.flatnonzero(np.isnan(values))
    by_parameters = [(int(k), f"a{k}") for k in symbolic[::2]]

    # entry by entry, as reveal read them before
    const = [set() for _ in range(n_rows)]
    linear = [{} for _ in range(n_rows)]
    for r, c, v in zip(rows.tolist(), cols.tolist(), values.tolist()):
        if np.isnan(v):
            continue
        const[r].add(c)
        if v:
            linear[r][c] = int(v) if v.is_integer() else Fraction(v)
    for k, a in by_parameters:
        const[rows[k]].add(cols[k])
        linear[rows[k]][cols[k]] = a
    adj = [sorted(set(cols[rows == r].tolist()) | set(rng.choice(n_cols, 2).tolist()))
           for r in range(n_rows)]
    eliminable = (rng.random(n_cols) < 0.6).tolist()
    pure = [e for e in range(n_rows)
            if all(not eliminable[v] or v in const[e] for v in adj[e])]

    # in bulk
    fixed = ~np.isnan(values)
    take = np.flatnonzero(fixed & (values != 0))
    coefs = lin._exact_numbers(values[take])
    assert all(type(c) is (int if float(v).is_integer() else Fraction)
               for c, v in zip(coefs, values[take]))
    fixed[[k for k, _ in by_parameters]] = True
    take = np.concatenate([take, np.array([k for k, _ in by_parameters], dtype=np.int64)])
    coefs += [a for _, a in by_parameters]
    bulk_const = lin._Columns(n_rows, rows[fixed], cols[fixed])
    bulk_linear = lin._linear_rows(n_rows, rows[take], cols[take], coefs)

    assert len(bulk_const) == n_rows
    assert [bulk_const[e] for e in range(n_rows)] == const
    # the same coefficients, each row's columns in the same order (numbers by column,
    # then the parameters' by column): the exact elimination's ties follow this order
    assert [list(d.items()) for d in bulk_linear] == [list(d.items()) for d in linear]
    assert lin._purely_linear(adj, eliminable, bulk_const, n_cols) == pure

    # when the incidence is the entries' own pattern, read off the entries alone
    own = [sorted(cols[rows == r].tolist()) for r in range(n_rows)]
    own_pure = [e for e in range(n_rows)
                if all(not eliminable[v] or v in const[e] for v in own[e])]
    assert lin._purely_linear_entries(rows, cols, fixed, eliminable, n_rows) == own_pure
    assert lin._purely_linear(own, eliminable, bulk_const, n_cols) == own_pure


def test_numbers_read_by_one_function_of_the_symbols_equal_the_entry_by_entry_reading(
        monkeypatch):
    x, p, t, q = (ca.SX.sym(n, k) for n, k in (("x", 3), ("p", 2), ("t", 1), ("q", 1)))
    rows = ca.vertcat(2 * x[0] - x[1], p[0] * x[1] + 0.5 * x[2], x[0] * x[2] - ca.sin(t),
                      ca.if_else(x[0] > 0, 3 * x[1], x[1] / 4), -x[2] / 3 + 1e300 * x[0],
                      x[1] - q * x[2], ca.sqrt(p[1]) * x[0])
    jac = ca.jacobian(rows, x)
    expected = lin._numbers(jac)              # by the symbols each entry holds
    nz = jac.nz[:]
    for k in range(nz.numel()):
        if nz[k].is_constant():
            assert expected[k] == float(ca.evalf(nz[k]))
        else:
            assert np.isnan(expected[k])
    known = ca.vertcat(x, p, t)
    # q is not among them: the function of them has a free symbol, the other path runs;
    # so it does for a column that is not of distinct symbols
    np.testing.assert_array_equal(lin._numbers(jac, known), expected)
    np.testing.assert_array_equal(lin._numbers(jac, ca.vertcat(known, x[0])), expected)
    np.testing.assert_array_equal(lin._numbers(jac, ca.vertcat(known, 2 * q)), expected)
    # with every symbol given, the symbols of the entries are not looked up at all
    monkeypatch.setattr(ca, "symvar", None)
    np.testing.assert_array_equal(lin._numbers(jac, ca.vertcat(known, q)), expected)


@pytest.mark.parametrize("dense", [[0], [9], [0, 4, 5, 9], list(range(10))])
def test_rows_differentiated_apart_give_casadis_jacobian(dense):
    """`jacobian_apart` with the rows apart first, last, side by side and all of them:
    CasADi's own Jacobian, entry by entry, at a random point; ``expr`` is left as it
    was."""
    x = ca.SX.sym("x", 12)
    shared = ca.sin(x[3]) * x[4]             # a node that rows of both parts hold
    expr = ca.vertcat(*[x[k] * x[k + 1] - shared if k % 3 else ca.sum1(x[k:]) + shared
                        for k in range(10)])
    before = ca.Function("before", [x], [expr])
    ours = lin.jacobian_apart(expr, x, np.array(dense, dtype=np.int64))
    theirs = ca.jacobian(expr, x)
    assert ours.sparsity() == theirs.sparsity()
    point = np.random.default_rng(5).uniform(-1.0, 1.0, 12)
    np.testing.assert_array_equal(ca.Function("o", [x], [ours])(point).nonzeros(),
                                  ca.Function("t", [x], [theirs])(point).nonzeros())
    np.testing.assert_array_equal(ca.Function("e", [x], [expr])(point).full(),
                                  before(point).full())


def test_the_entries_that_depend_on_the_inputs_are_those_of_the_full_pattern():
    """`_depending` (one sweep, every input marked) against the rows of CasADi's pattern
    input by input, on entries of one input, of several, of none (a number, a product
    with zero) and of a comparison."""
    x = ca.SX.sym("x", 6)
    out = ca.vertcat(x[0], 3.0, x[1] * x[5], ca.SX(0) * x[2], x[3] > 0, ca.cos(2.0),
                     ca.if_else(x[4] > 1, 2.0, 3.0), x[2] - x[2] + 1)
    f = ca.Function("f", [x], [out])
    rows = np.unique(np.asarray(f.sparsity_jac(0, 0).get_triplet()[0], dtype=np.int64))
    np.testing.assert_array_equal(np.sort(lin._depending(f, 6)), rows)
    assert rows.size and rows.size < out.numel()     # both kinds are there
