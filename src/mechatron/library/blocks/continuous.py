"""Continuous-time linear and PID blocks.

Transfer functions are realised in controllable canonical form, so a block of order
``n`` adds ``n`` states ``x1 .. xn`` (their start values are 0: the block starts at
rest). Coefficients are numbers fixed when the block is built (not tunable parameters).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from mechatron.core import Input, Parameter, Variable, der, when
from mechatron.errors import ModelError
from mechatron.library.blocks.interfaces import SISO, coefficients, sized, states

__all__ = ["Integrator", "LimitedIntegrator", "ResetIntegrator", "Derivative",
           "TransferFunction", "StateSpace", "FirstOrder", "SecondOrder", "PID"]


class Integrator(SISO):
    """``dy/dt = k u``; the initial value is the start value of ``y``
    (``Integrator(y=1.0)``)."""

    k = Parameter("1", default=1.0, doc="Gain")

    def equations(self):
        return [der(self.y) == self.k * self.u]


class LimitedIntegrator(SISO):
    """Integrator with output limits: ``dy/dt = k u`` except ``dy/dt = 0`` while ``y`` sits
    at ``y_max`` with ``k u > 0`` or at ``y_min`` with ``k u < 0``.

    Reaching a limit and leaving it (when the input changes sign) are events, so ``y``
    stops at the limit to the event tolerance and leaves it at the right instant.
    """

    k = Parameter("1", default=1.0, doc="Gain")
    y_min = Parameter("1", default=-1.0, doc="Lower limit")
    y_max = Parameter("1", default=1.0, doc="Upper limit")

    def equations(self):
        rate = self.k * self.u
        hold = ca.logic_or(ca.logic_and(self.y_max <= self.y, 0 < rate),
                           ca.logic_and(self.y <= self.y_min, rate < 0))
        return [der(self.y) == ca.if_else(hold, 0, rate)]


class ResetIntegrator(SISO):
    """``dy/dt = k u``, re-initialized to ``y_reset`` when the ``reset`` input rises
    through 0.5 (Simulink's external reset, ``rising``); a reset is an event."""

    reset = Input("1", doc="Reset signal (a rising edge through 0.5 resets)")
    k = Parameter("1", default=1.0, doc="Gain")
    y_reset = Parameter("1", default=0.0, doc="Value after a reset")

    def equations(self):
        return [der(self.y) == self.k * self.u,
                when(self.reset >= 0.5, update={self.y: self.y_reset})]


class Derivative(SISO):
    """Filtered derivative ``Y(s) = s / (T s + 1) U(s)``: ``T dx/dt = u - x``,
    ``y = (u - x) / T`` (the filter state ``x`` starts at 0)."""

    T = Parameter("s", default=1e-3, min=0, doc="Filter time constant")
    x = Variable("1", start=0.0, doc="Filter state (low-passed input)")

    def equations(self):
        return [self.T * der(self.x) == self.u - self.x,
                self.y == (self.u - self.x) / self.T]


class FirstOrder(SISO):
    """First-order lag ``T dy/dt + y = k u``."""

    k = Parameter("1", default=1.0, doc="Gain")
    T = Parameter("s", default=1.0, min=0, doc="Time constant")

    def equations(self):
        return [self.T * der(self.y) + self.y == self.k * self.u]


class SecondOrder(SISO):
    """Second-order system ``y'' + 2 D w y' + w^2 y = k w^2 u``."""

    k = Parameter("1", default=1.0, doc="Gain")
    w = Parameter("rad/s", default=1.0, min=0, doc="Natural angular frequency")
    D = Parameter("1", default=1.0, min=0, doc="Damping ratio")
    yd = Variable("1/s", start=0.0, doc="Derivative of the output")

    def equations(self):
        return [der(self.y) == self.yd,
                der(self.yd) == self.k * self.w ** 2 * self.u
                - 2 * self.D * self.w * self.yd - self.w ** 2 * self.y]


def _state_vector(block, n):
    return [getattr(block, f"x{i + 1}") for i in range(n)]


class TransferFunction(SISO):
    """``Y(s) = (b0 s^m + ... + bm) / (a0 s^n + ... + an) U(s)`` with ``m <= n``.

    Controllable canonical form: states ``x1 .. xn`` with ``x_i' = x_(i+1)``,
    ``x_n' = u - sum_i a_(n-i+1) x_i`` (monic denominator), output
    ``y = sum_i (b_(n-i+1) - b_0 a_(n-i+1)) x_i + b_0 u``. A biproper function
    (``m = n``) has direct feedthrough.

    Parameters
    ----------
    num, den : sequence of float
        Coefficients in descending powers of ``s`` (as ``scipy.signal.lti``).
    """

    def __new__(cls, num=(1.0,), den=(1.0, 1.0), **kwargs):
        n = len(np.trim_zeros(np.atleast_1d(np.asarray(den, dtype=float)), "f")) - 1
        return super().__new__(sized(cls, max(n, 0), states(max(n, 0))))

    def __init__(self, num=(1.0,), den=(1.0, 1.0), **kwargs):
        super().__init__(**kwargs)
        where = f"TransferFunction '{self.name or '(unnamed)'}'"
        b = np.trim_zeros(coefficients(num, "num", where), "f")
        a = np.trim_zeros(coefficients(den, "den", where), "f")
        if a.size == 0:
            raise ModelError(f"{where}: the denominator is zero.")
        if b.size > a.size:
            raise ModelError(f"{where}: improper transfer function (numerator of degree "
                             f"{b.size - 1} > denominator {a.size - 1}). Add poles, e.g. a "
                             "derivative filter.")
        b = np.concatenate([np.zeros(a.size - max(b.size, 1)), b if b.size else [0.0]])
        self._num, self._den = b / a[0], a / a[0]

    def equations(self):
        b, a = self._num, self._den
        n = a.size - 1
        if n == 0:
            return [self.y == b[0] * self.u]
        x = _state_vector(self, n)
        eqs = [der(x[i]) == x[i + 1] for i in range(n - 1)]
        eqs.append(der(x[n - 1]) == self.u - sum(a[n - i] * x[i] for i in range(n)))
        eqs.append(self.y == sum((b[n - i] - b[0] * a[n - i]) * x[i] for i in range(n))
                   + b[0] * self.u)
        return eqs


class StateSpace(SISO):
    """Single-input single-output state space ``x' = A x + B u``, ``y = C x + D u``;
    the states ``x1 .. xn`` start at 0.

    Parameters
    ----------
    A : (n, n) array_like
    B, C : (n,) array_like
    D : float
    """

    def __new__(cls, A=((-1.0,),), B=(1.0,), C=(1.0,), D=0.0, **kwargs):
        n = np.atleast_2d(np.asarray(A, dtype=float)).shape[0]
        return super().__new__(sized(cls, n, states(n)))

    def __init__(self, A=((-1.0,),), B=(1.0,), C=(1.0,), D=0.0, **kwargs):
        super().__init__(**kwargs)
        where = f"StateSpace '{self.name or '(unnamed)'}'"
        a = np.atleast_2d(np.asarray(A, dtype=float))
        n = a.shape[0]
        b = coefficients(B, "B", where)
        c = coefficients(C, "C", where)
        if a.shape != (n, n) or b.size != n or c.size != n:
            raise ModelError(f"{where}: A must be square (n x n) with B and C of length n; "
                             f"got A {a.shape}, B {b.size}, C {c.size}.")
        if not (np.all(np.isfinite(a)) and np.isfinite(float(D))):
            raise ModelError(f"{where}: A and D must be finite.")
        self._abcd = (a, b, c, float(D))

    def equations(self):
        a, b, c, d = self._abcd
        n = b.size
        x = _state_vector(self, n)
        eqs = [der(x[i]) == sum(a[i, j] * x[j] for j in range(n) if a[i, j]) + b[i] * self.u
               for i in range(n)]
        eqs.append(self.y == sum(c[i] * x[i] for i in range(n)) + d * self.u)
        return eqs


class PID(SISO):
    """PID controller (parallel form) with a filtered derivative, output limits and
    back-calculation anti-windup.

    ``v = Kp u + I + Kd N (u - x_d)``, ``dx_d/dt = N (u - x_d)``,
    ``y = min(max(v, y_min), y_max)``, ``dI/dt = Ki u + Kb (y - v)``.

    The input ``u`` is the control error. While the output is saturated the
    back-calculation term ``Kb (y - v)`` pulls the integrator back, so it stays bounded
    (at ``I = y_max - Kp u + Ki u / Kb`` for a constant error); ``Kb = 0`` disables it.
    Entering and leaving saturation are events.
    """

    Kp = Parameter("1", default=1.0, doc="Proportional gain")
    Ki = Parameter("1/s", default=0.0, doc="Integral gain")
    Kd = Parameter("s", default=0.0, doc="Derivative gain")
    N = Parameter("1/s", default=100.0, min=0, doc="Derivative filter bandwidth")
    y_min = Parameter("1", default=-float("inf"), doc="Lower output limit")
    y_max = Parameter("1", default=float("inf"), doc="Upper output limit")
    Kb = Parameter("1/s", default=0.0, min=0, doc="Back-calculation gain (anti-windup)")
    I = Variable("1", start=0.0, doc="Integral term")  # noqa: E741
    xd = Variable("1", start=0.0, doc="Derivative filter state")
    v = Variable("1", doc="Unsaturated output")

    def equations(self):
        sat = ca.if_else(self.y_max < self.v, self.y_max,
                         ca.if_else(self.v < self.y_min, self.y_min, self.v))
        return [der(self.xd) == self.N * (self.u - self.xd),
                self.v == self.Kp * self.u + self.I + self.Kd * self.N * (self.u - self.xd),
                self.y == sat,
                der(self.I) == self.Ki * self.u + self.Kb * (self.y - self.v)]
