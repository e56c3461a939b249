"""Logic and routing: comparisons, logical operators, switches, lookup tables.

Boolean signals are 0.0 (false) and 1.0 (true). Comparisons are relations, so their
switching instants are events. The logical operators take Boolean inputs (a non-zero
input is true).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from mechatron.core import Component, Input, Output, Parameter
from mechatron.errors import DataError, ModelError
from mechatron.library.blocks.interfaces import MISO2, SISO, hat, piecewise_linear, sized
from mechatron.library.blocks.nonlinear import Quantizer

__all__ = ["Compare", "CompareToConstant", "LogicalOperator", "Not", "Switch",
           "MultiportSwitch", "LookupTable1D", "LookupTable2D", "ToBoolean", "Round"]

_OPS = {"<": lambda a, b: a < b, "<=": lambda a, b: a <= b, ">": lambda a, b: a > b,
        ">=": lambda a, b: a >= b}


def _check_op(op, where):
    if op not in ("<", "<=", ">", ">="):
        raise ModelError(f"{where}: unknown comparison {op!r}. Choose one of <, <=, >, >= "
                         "(equality of real signals is not a robust event).")
    return _OPS[op]


class Compare(MISO2):
    """Relational operator: ``y = 1`` if ``u1 op u2`` else 0 (``op`` in ``< <= > >=``)."""

    def __init__(self, op: str = "<", **kwargs):
        super().__init__(**kwargs)
        _check_op(op, "Compare")
        self._op = op

    def equations(self):
        return [self.y == ca.if_else(_OPS[self._op](self.u1, self.u2), 1.0, 0.0)]


class CompareToConstant(SISO):
    """``y = 1`` if ``u op c`` else 0."""

    c = Parameter("1", default=0.0, doc="Constant compared with")

    def __init__(self, op: str = ">=", **kwargs):
        super().__init__(**kwargs)
        _check_op(op, "CompareToConstant")
        self._op = op

    def equations(self):
        return [self.y == ca.if_else(_OPS[self._op](self.u, self.c), 1.0, 0.0)]


class ToBoolean(SISO):
    """``y = 1`` if ``u != 0`` else 0 (Simulink's conversion to boolean); the switching is
    an event (two relations, ``u > 0`` and ``u < 0``)."""

    def equations(self):
        return [self.y == ca.if_else(ca.logic_or(0 < self.u, self.u < 0), 1.0, 0.0)]


_LOGIC = {
    "and": lambda a, b: a * b, "or": lambda a, b: a + b - a * b,
    "xor": lambda a, b: a + b - 2 * a * b, "nand": lambda a, b: 1 - a * b,
    "nor": lambda a, b: 1 - (a + b - a * b),
}


class LogicalOperator(MISO2):
    """``y = u1 op u2`` for Boolean inputs (0/1), ``op`` in ``and or xor nand nor``,
    written as exact arithmetic on 0/1 (no events of its own)."""

    def __init__(self, op: str = "and", **kwargs):
        super().__init__(**kwargs)
        if op not in _LOGIC:
            raise ModelError(f"LogicalOperator: unknown operator {op!r}. Choose one of "
                             f"{', '.join(_LOGIC)}.")
        self._op = op

    def equations(self):
        return [self.y == _LOGIC[self._op](self.u1, self.u2)]


class Not(SISO):
    """``y = 1 - u`` for a Boolean input."""

    def equations(self):
        return [self.y == 1 - self.u]


class Switch(Component):
    """``y = u1`` while the control input ``u2 >= threshold``, else ``u3`` (Simulink's
    Switch); the switching is an event."""

    u1 = Input("1", doc="Passed while the control is at or above the threshold")
    u2 = Input("1", doc="Control input")
    u3 = Input("1", doc="Passed while the control is below the threshold")
    y = Output("1", doc="Output")
    threshold = Parameter("1", default=0.5, doc="Threshold of the control input")

    def equations(self):
        return [self.y == ca.if_else(self.threshold <= self.u2, self.u1, self.u3)]


class MultiportSwitch(Component):
    """``y = u<k>`` for the control ``c`` nearest to the integer ``k`` (1-based, clamped
    to 1 .. n): ``MultiportSwitch(n=3)`` has data inputs ``u1 u2 u3``. A change of the
    selected input (``c`` crossing ``k + 1/2``) is an event."""

    c = Input("1", doc="Control: the 1-based number of the input passed")
    y = Output("1", doc="Output")

    def __new__(cls, n: int = 2, **kwargs):
        if int(n) != n or n < 1:
            raise ModelError(f"MultiportSwitch: n must be a positive integer, got {n!r}.")
        n = int(n)
        extra = {f"u{k + 1}": Input("1", doc=f"Data input {k + 1}") for k in range(n)}
        return super().__new__(sized(cls, n, extra))

    def __init__(self, n: int = 2, **kwargs):
        super().__init__(**kwargs)
        self._n = int(n)

    def equations(self):
        n = self._n
        y = getattr(self, f"u{n}")
        for k in range(n - 1, 0, -1):   # c < k + 1/2 selects input k (or a lower one)
            y = ca.if_else(self.c < k + 0.5, getattr(self, f"u{k}"), y)
        return [self.y == y]


def _axis(values, name, where):
    arr = np.asarray(values, dtype=float).ravel()
    if arr.size < 2 or not np.all(np.isfinite(arr)) or np.any(np.diff(arr) <= 0):
        raise DataError(f"{where}: {name} must hold at least two finite, strictly "
                        f"increasing breakpoints, got {values!r}.")
    return arr


class LookupTable1D(SISO):
    """1-D lookup table ``y = interp(u; breakpoints, table)``: linear interpolation between
    breakpoints, end values held beyond them (kinks at the breakpoints are not events).

    Parameters
    ----------
    breakpoints : array_like
        Strictly increasing input values.
    table : array_like
        Output at each breakpoint.
    """

    def __init__(self, breakpoints=(0.0, 1.0), table=(0.0, 1.0), **kwargs):
        super().__init__(**kwargs)
        where = "LookupTable1D"
        bp = _axis(breakpoints, "breakpoints", where)
        tab = np.asarray(table, dtype=float).ravel()
        if tab.size != bp.size or not np.all(np.isfinite(tab)):
            raise DataError(f"{where}: table must hold {bp.size} finite values (one per "
                            f"breakpoint), got {tab.size}.")
        self._data = (bp, tab)

    def equations(self):
        bp, tab = self._data
        return [self.y == piecewise_linear(self.u, bp, tab)]


class LookupTable2D(MISO2):
    """2-D lookup table ``y = interp2(u1, u2; breakpoints1, breakpoints2, table)``:
    bilinear interpolation (the tensor product of 1-D linear interpolation);
    ``table[i, j]`` is the output at
    ``(breakpoints1[i], breakpoints2[j])`` for inputs ``(u1, u2)``; inputs are clamped to
    the breakpoint ranges."""

    def __init__(self, breakpoints1=(0.0, 1.0), breakpoints2=(0.0, 1.0),
                 table=((0.0, 0.0), (0.0, 0.0)), **kwargs):
        super().__init__(**kwargs)
        where = "LookupTable2D"
        b1 = _axis(breakpoints1, "breakpoints1", where)
        b2 = _axis(breakpoints2, "breakpoints2", where)
        tab = np.asarray(table, dtype=float)
        if tab.shape != (b1.size, b2.size) or not np.all(np.isfinite(tab)):
            raise DataError(f"{where}: table must be {b1.size} x {b2.size} finite values "
                            f"(breakpoints1 by breakpoints2), got shape {tab.shape}.")
        self._data = (b1, b2, tab)

    def equations(self):
        b1, b2, tab = self._data
        # bilinear interpolation: the tensor product of the 1-D hat functions
        h1 = [hat(self.u1, b1, i) for i in range(b1.size)]
        h2 = [hat(self.u2, b2, j) for j in range(b2.size)]
        y = 0
        for i in range(b1.size):
            row = sum(float(tab[i, j]) * h2[j] for j in range(b2.size) if tab[i, j])
            if not isinstance(row, int):
                y = y + h1[i] * row
        return [self.y == y]


class Round(Quantizer):
    """Conversion to an integer signal: ``y = round(u)`` (half up), each step an event
    (the quantizer with interval 1)."""

    q = Parameter("1", default=1.0, min=0, doc="Quantization interval")
