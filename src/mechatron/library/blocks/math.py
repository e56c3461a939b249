"""Math blocks: gains, sums, products and functions of signals.

Blocks with a kink or a jump (``Abs``, ``Sign``, ``Min``, ``Max``) are written with
relations, so the solver locates the switching instants as events.
"""

from __future__ import annotations

import casadi as ca

from mechatron.core import Component, Input, Output, Parameter
from mechatron.errors import ModelError
from mechatron.library.blocks.interfaces import MISO2, SISO

__all__ = ["Gain", "Add", "Add3", "Subtract", "Sum", "Product", "Divide", "Abs", "Sign",
           "Min", "Max", "MathFunction", "Atan2", "Bias"]


class Gain(SISO):
    """``y = k u``."""

    k = Parameter("1", default=1.0, doc="Gain")

    def equations(self):
        return [self.y == self.k * self.u]


class Bias(SISO):
    """``y = u + bias``."""

    bias = Parameter("1", default=0.0, doc="Bias added to the input")

    def equations(self):
        return [self.y == self.u + self.bias]


class Add(MISO2):
    """Weighted sum of two inputs: ``y = k1 u1 + k2 u2`` (Simulink's Sum, ``"++"``)."""

    k1 = Parameter("1", default=1.0, doc="Weight of u1")
    k2 = Parameter("1", default=1.0, doc="Weight of u2")

    def equations(self):
        return [self.y == self.k1 * self.u1 + self.k2 * self.u2]


class Subtract(Add):
    """``y = u1 - u2`` (Simulink's Sum ``"+-"``: a feedback comparison)."""

    k2 = Parameter("1", default=-1.0, doc="Weight of u2")


Sum = Add


class Add3(Component):
    """Weighted sum of three inputs: ``y = k1 u1 + k2 u2 + k3 u3``."""

    u1 = Input("1", doc="First input")
    u2 = Input("1", doc="Second input")
    u3 = Input("1", doc="Third input")
    y = Output("1", doc="Output")
    k1 = Parameter("1", default=1.0, doc="Weight of u1")
    k2 = Parameter("1", default=1.0, doc="Weight of u2")
    k3 = Parameter("1", default=1.0, doc="Weight of u3")

    def equations(self):
        return [self.y == self.k1 * self.u1 + self.k2 * self.u2 + self.k3 * self.u3]


class Product(MISO2):
    """``y = u1 u2``."""

    def equations(self):
        return [self.y == self.u1 * self.u2]


class Divide(MISO2):
    """``y = u1 / u2`` (no protection against ``u2 = 0``: the solver fails there)."""

    def equations(self):
        return [self.y == self.u1 / self.u2]


class Abs(SISO):
    """``y = |u|``; the kink at ``u = 0`` is an event."""

    def equations(self):
        return [self.y == ca.if_else(self.u < 0, -self.u, self.u)]


class Sign(SISO):
    """``y = sign(u)`` in {-1, 0, +1}; the jump at ``u = 0`` is an event."""

    def equations(self):
        return [self.y == ca.sign(self.u)]


class Min(MISO2):
    """``y = min(u1, u2)``; the switch of the smaller input is an event."""

    def equations(self):
        return [self.y == ca.if_else(self.u1 < self.u2, self.u1, self.u2)]


class Max(MISO2):
    """``y = max(u1, u2)``; the switch of the larger input is an event."""

    def equations(self):
        return [self.y == ca.if_else(self.u2 < self.u1, self.u1, self.u2)]


class Atan2(MISO2):
    """Four-quadrant arc tangent ``y = atan2(u1, u2)`` in rad (jump of 2 pi across the
    negative ``u2`` axis, not an event)."""

    def equations(self):
        return [self.y == ca.atan2(self.u1, self.u2)]


_FUNCTIONS = {
    "sin": ca.sin, "cos": ca.cos, "tan": ca.tan, "asin": ca.asin, "acos": ca.acos,
    "atan": ca.atan, "sinh": ca.sinh, "cosh": ca.cosh, "tanh": ca.tanh, "exp": ca.exp,
    "log": ca.log, "log10": lambda u: ca.log(u) / ca.log(10.0), "sqrt": ca.sqrt,
    "square": lambda u: u ** 2, "reciprocal": lambda u: 1 / u,
    "cube": lambda u: u ** 3,
}


class MathFunction(SISO):
    """``y = f(u)`` for a named function: ``sin cos tan asin acos atan sinh cosh tanh exp
    log log10 sqrt square cube reciprocal`` (Simulink's Math and Trigonometric Function
    blocks)."""

    def __init__(self, function: str = "sin", **kwargs):
        super().__init__(**kwargs)
        if function not in _FUNCTIONS:
            raise ModelError(f"MathFunction: unknown function {function!r}. Choose one of "
                             f"{', '.join(_FUNCTIONS)}.")
        self._function = function

    def equations(self):
        return [self.y == _FUNCTIONS[self._function](self.u)]
