"""Exact coefficients that are expressions of parameters: Laurent polynomials.

A coefficient such as a transformer's ratio ``N``, ``-N``, ``1/N`` or ``N1/N2`` is kept
as a Laurent polynomial with rational coefficients in *atoms*: numbered indeterminates
that stand for parameters (or for a parameter expression the caller cannot take apart,
e.g. ``sqrt(L1*L2)``). Sums, differences, products and division by a number or by a
single term are exact, and a result is zero only when it is zero for every value of the
atoms (the ring of Laurent polynomials over the rationals has no zero divisors). So an
elimination with these coefficients finds a cancellation only where it holds whatever
the parameters are, and decides nothing by rounding.

Results that hold no atom come back as ``int`` or ``Fraction``, so numeric coefficients
stay plain numbers.
"""

from __future__ import annotations

from fractions import Fraction

__all__ = ["Laurent", "atom", "is_symbolic"]

Monomial = tuple      # ((atom, exponent), ...) sorted by atom, exponents nonzero


class Laurent:
    """A Laurent polynomial in numbered atoms with ``int``/``Fraction`` coefficients.

    Build one with `atom`, then combine with ``+ - * /`` and numbers. Division is exact
    by a number or by a single term (``c * a**k * b**j``); anything else raises
    `ZeroDivisionError` (not representable: the caller keeps such an expression whole, as
    an atom of its own). ``bool(x)`` is False only for the zero polynomial, which never
    occurs: zero results are returned as the integer 0.
    """

    __slots__ = ("terms",)

    def __init__(self, terms: dict):
        self.terms = terms

    # -- construction ---------------------------------------------------------------------
    @staticmethod
    def make(terms: dict):
        """``terms`` without zero coefficients, as a number where no atom is left."""
        terms = {m: c for m, c in terms.items() if c}
        if not terms:
            return 0
        if len(terms) == 1 and () in terms:
            return _norm(terms[()])
        return Laurent(terms)

    # -- arithmetic -----------------------------------------------------------------------
    def __add__(self, other):
        terms = dict(self.terms)
        for m, c in _terms(other):
            terms[m] = terms.get(m, 0) + c
        return Laurent.make(terms)

    __radd__ = __add__

    def __neg__(self):
        return Laurent({m: -c for m, c in self.terms.items()})

    def __sub__(self, other):
        return self + (-_as_laurent(other))

    def __rsub__(self, other):
        return (-self) + other

    def __mul__(self, other):
        if not isinstance(other, Laurent):
            if not other:
                return 0
            return Laurent.make({m: c * other for m, c in self.terms.items()})
        terms: dict = {}
        for m1, c1 in self.terms.items():
            for m2, c2 in other.terms.items():
                m = _mono_mul(m1, m2, 1)
                terms[m] = terms.get(m, 0) + c1 * c2
        return Laurent.make(terms)

    __rmul__ = __mul__

    def __truediv__(self, other):
        if not isinstance(other, Laurent):
            return Laurent.make({m: _norm(Fraction(c) / other) for m, c in self.terms.items()})
        if len(other.terms) != 1:
            raise ZeroDivisionError("division by a sum of terms is not exact")
        (m2, c2), = other.terms.items()
        return Laurent.make({_mono_mul(m, m2, -1): _norm(Fraction(c) / c2)
                             for m, c in self.terms.items()})

    def __rtruediv__(self, other):
        if len(self.terms) != 1:
            raise ZeroDivisionError("division by a sum of terms is not exact")
        (m, c), = self.terms.items()
        return Laurent.make({_mono_mul((), m, -1): _norm(Fraction(other) / c)})

    def __bool__(self) -> bool:
        return bool(self.terms)

    def __eq__(self, other) -> bool:
        return not (self - other)

    def __hash__(self):
        return hash(frozenset(self.terms.items()))

    def __float__(self):
        raise TypeError("a coefficient that depends on parameters has no float value")

    def __repr__(self) -> str:
        parts = []
        for m, c in sorted(self.terms.items()):
            mono = "*".join(f"a{a}" + (f"**{k}" if k != 1 else "") for a, k in m)
            parts.append(f"{c}" + (f"*{mono}" if mono else ""))
        return "Laurent(" + " + ".join(parts) + ")"


def atom(k: int) -> Laurent:
    """The indeterminate number `k`."""
    return Laurent({((k, 1),): 1})


def is_symbolic(x) -> bool:
    """Whether `x` holds an atom (is not a plain number)."""
    return isinstance(x, Laurent)


def _as_laurent(x):
    return x if isinstance(x, Laurent) else Laurent({(): x})


def _terms(x):
    if isinstance(x, Laurent):
        return x.terms.items()
    return (((), x),) if x else ()


def _mono_mul(m1: Monomial, m2: Monomial, sign: int) -> Monomial:
    """Monomial ``m1 * m2**sign``."""
    if not m2:
        return m1
    exps = dict(m1)
    for a, k in m2:
        e = exps.get(a, 0) + sign * k
        if e:
            exps[a] = e
        else:
            exps.pop(a, None)
    return tuple(sorted(exps.items()))


def _norm(x):
    if type(x) is Fraction and x.denominator == 1:
        return x.numerator
    return x
