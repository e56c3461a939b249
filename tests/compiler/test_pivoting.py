"""`pivot_columns`: LAPACK's choice where norms differ, the first column where they tie,
and the same answer under rounding-level perturbation, scaling and row permutation."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import qr

from mechatron.compiler.pivoting import TIE_RTOL, largest, pivot_columns


def ulps(a, rng, n=4):
    """`a` with every entry moved by up to `n` units in the last place."""
    return a + rng.integers(-n, n + 1, size=a.shape) * np.spacing(np.abs(a))


def tied_matrix(rng, m, r):
    """An m x n matrix whose columns tie in norm at several steps of the pivoting:
    ``r`` random columns, each repeated with its sign flipped, and sums of pairs that
    repeat in the other order (``u + v`` and ``v + u`` are equal in floating point)."""
    base = rng.standard_normal((m, r))
    cols = []
    for j in range(r):
        cols += [base[:, j], -base[:, j]]
    for j in range(r - 1):
        cols += [base[:, j] + base[:, j + 1], base[:, j + 1] + base[:, j]]
    return np.column_stack(cols)


@pytest.mark.parametrize("shape", [(3, 5), (6, 6), (8, 13), (13, 15), (20, 40)])
def test_generic_matrices_pivot_like_lapack(shape):
    """An independent implementation (LAPACK dgeqp3 through SciPy) agrees when no two
    norms are close, and the chosen columns are nonsingular."""
    rng = np.random.default_rng(sum(shape))
    for _ in range(20):
        a = rng.standard_normal(shape) * rng.uniform(0.1, 10.0, size=shape[1])
        k = min(shape)
        ours = pivot_columns(a, k)
        _, _, piv = qr(a, pivoting=True)
        assert ours == list(piv[:k])
        assert np.linalg.matrix_rank(a[:, ours]) == k


def test_exact_tie_goes_to_the_first_column():
    # der(q) = w differentiated: der(der(q)) - der(w), the two columns tie exactly
    a = np.array([[1.0, -1.0], [0.0, 0.0]])
    assert pivot_columns(a, 1) == [0]
    assert pivot_columns(a[:, ::-1], 1) == [0]


def test_a_real_difference_beyond_the_tolerance_decides():
    a = np.array([[1.0, 1.0 + 10 * TIE_RTOL]])
    assert pivot_columns(a, 1) == [1]
    a = np.array([[1.0, 1.0 + TIE_RTOL / 10]])
    assert pivot_columns(a, 1) == [0]


def test_ties_after_projection_go_to_the_first_column():
    # the first pick is clear (column 0); what is left of columns 1 and 2 ties exactly
    a = np.array([[4.0, 1.0, 1.0],
                  [0.0, 1.0, -1.0],
                  [0.0, 0.0, 0.0]])
    assert pivot_columns(a, 2) == [0, 1]
    assert pivot_columns(a[:, [0, 2, 1]], 2) == [0, 1]


def test_dependent_columns_are_taken_in_order():
    # rank 1: after the first pick, the rest are zero up to rounding and tie
    a = np.outer([1.0, 2.0, 3.0], [1.0, 3.0, -2.0, 0.5])
    assert pivot_columns(a, 3) == [1, 0, 2]


def test_non_finite_entries_count_as_zero():
    a = np.array([[np.nan, 1.0], [np.inf, 0.0]])
    assert pivot_columns(a, 1) == [1]
    assert pivot_columns(a, 2) == [1, 0]


def test_edge_cases():
    assert pivot_columns(np.zeros((2, 0)), 1) == []
    assert pivot_columns(np.ones((2, 3)), 0) == []
    assert pivot_columns(np.ones((1, 3)), 3) == [0, 1, 2]
    with pytest.raises(ValueError, match="needs a matrix"):
        pivot_columns(np.ones(3), 1)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), m=st.integers(2, 12), r=st.integers(2, 6),
       scale=st.floats(1e-6, 1e6))
def test_tied_choice_is_stable_under_ulps_scaling_and_row_order(seed, m, r, scale):
    rng = np.random.default_rng(seed)
    a = tied_matrix(rng, m, r)
    k = min(m, a.shape[1])
    expected = pivot_columns(a, k)
    assert pivot_columns(ulps(a, rng), k) == expected
    assert pivot_columns(a * scale, k) == expected
    assert pivot_columns(a[rng.permutation(m)], k) == expected
    # a tie always went to the earlier column: each sign-flipped copy comes after the
    # column it copies, so it is never chosen before it
    pos = {j: i for i, j in enumerate(expected)}
    for j in range(0, 2 * r, 2):
        if j + 1 in pos:
            assert j in pos and pos[j] < pos[j + 1]


def test_largest_lists_ties_in_index_order():
    w = [0.5, 0.7071067811865476, 1e-4, 0.7071067811865475, 0.5, float("nan")]
    assert largest(w, 10, floor=1e-3) == [1, 3, 0, 4]
    assert largest(w, 2) == [1, 3]
    assert largest(w[::-1], 10, floor=1e-3) == [2, 4, 1, 5]
    assert largest([], 3) == []
