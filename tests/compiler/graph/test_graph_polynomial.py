"""Tests of `Laurent`: exact coefficients that depend on parameters, and the exact
elimination with them (a cut set closed through a transformer's ratio)."""

import operator
import random
from fractions import Fraction

import numpy as np
import pytest

from mechatron.compiler.graph.elimination import exact_elimination
from mechatron.compiler.graph.polynomial import Laurent, atom, is_symbolic


def value(x, point):
    """`x` evaluated with atom k = point[k] (an independent check of the arithmetic)."""
    if not isinstance(x, Laurent):
        return float(x)
    return sum(float(c) * np.prod([point[a] ** e for a, e in mono])
               for mono, c in x.terms.items())


def test_arithmetic_is_exact_and_cancels_to_plain_numbers():
    n, m = atom(0), atom(1)
    assert n - n == 0 and type(n - n) is int
    assert n * (1 / n) == 1 and type(n * (1 / n)) is int
    assert (n / m) * m == n
    assert (n + m) * (n - m) - (n * n - m * m) == 0
    assert (Fraction(1, 3) * n) * 3 == n
    assert is_symbolic(2 * n) and not is_symbolic(n / n)
    assert bool(n - m)
    with pytest.raises(ZeroDivisionError):
        _ = n / (n + m)         # not a single term: not represented


def test_random_expressions_agree_with_floats():
    rng = random.Random(3)
    point = [1.7, -0.6, 2.3]
    for _ in range(200):
        x, y = 1, 1
        for _ in range(4):
            a = rng.choice([atom(0), atom(1), atom(2), Fraction(rng.randint(-3, 3), 2)])
            op = rng.choice("+-*/")
            if op == "/" and not (isinstance(a, Laurent) or a):
                continue
            f = {"+": operator.add, "-": operator.sub, "*": operator.mul,
                 "/": operator.truediv}[op]
            x, y = f(x, a), f(y, value(a, point))
        assert value(x, point) == pytest.approx(y, rel=1e-12, abs=1e-12)


def test_a_cut_set_through_a_ratio_cancels_exactly():
    """Transformer secondary: i2 + N i1 = 0 (i1 from the source law i1 = I), then the
    two current laws of R || C in series with an inductor. Their combination leaves
    l.i = N I: only the ratio N (a parameter) links the inductor to the source."""
    N = atom(0)
    # columns: 0 i1, 1 i2, 2 r.i, 3 c.i (unknowns); 4 l.i (state), 5 I (source, known)
    linear = [{0: 1, 5: -1},               # i1 = I
              {1: 1, 0: N},                # i2 = -N i1
              {1: 1, 2: 1, 3: 1},          # node p2: i2 + r.i + c.i = 0
              {2: -1, 3: -1, 4: 1}]        # node after R || C: l.i = r.i + c.i
    out = exact_elimination(linear, [True, True, True, True, False, False])
    assert len(out.pivots) == 3
    (e, row), = out.rows.items()
    # the reduced row is a multiple of l.i - N I (sign and scale are the elimination's)
    scale = row[4]
    assert not is_symbolic(scale) and scale
    assert row[5] / scale == -N
    comb = out.combination(e)
    total = {}
    for k, m in comb.items():
        for v, a in linear[k].items():
            total[v] = total.get(v, 0) + m * a
    assert {v: a for v, a in total.items() if a} == row
    assert not any(is_symbolic(m) and m == 0 for m in comb.values())


def test_a_parameter_pivot_is_fraction_free_and_taken_last():
    """Only a ratio left to pivot on: the step scales the other row by it instead of
    dividing by it, and a numeric pivot in the same column is preferred."""
    N = atom(0)
    linear = [{0: N, 2: 1}, {0: 1, 1: 1}, {1: 1, 2: 2}]
    out = exact_elimination(linear, [True, True, False])
    assert out.pivots.get(1) == 0 or out.pivots.get(2) == 1   # numeric pivots first
    for e, row in out.rows.items():
        for a in row.values():
            if is_symbolic(a):
                assert all(k >= 0 for mono in a.terms for _, k in mono), \
                    "no negative power of a parameter: nothing divided by it"
