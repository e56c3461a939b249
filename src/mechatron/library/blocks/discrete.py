"""Discrete-time blocks, updated exactly at their sample instants ``offset + k Ts``.

Each block is a set of discrete states changed only at its ticks (see
:mod:`mechatron.core.events`): at a tick the *outputs* of all blocks sampled then are
computed in signal-flow order (a block reads the new outputs of the blocks upstream), then
every block updates its internal states at once. Between ticks the outputs are held (a
zero-order hold), so a discrete block drives a continuous plant as a real digital
controller does. Initial values are the start values of the states (``UnitDelay(x=0.5)``);
the first tick is at ``offset`` (at ``t = 0`` by default).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from mechatron.core import Clock, Input, Output, Parameter, Variable, sample
from mechatron.errors import ModelError
from mechatron.library.blocks.interfaces import Sampled, coefficients, sized, states
from mechatron.units import to_si

__all__ = ["ZeroOrderHold", "UnitDelay", "Delay", "DiscreteIntegrator",
           "DiscreteTransferFunction", "DiscretePID", "PWM"]


class _SampledSISO(Sampled, partial=True):
    u = Input("1", doc="Input signal (read at the ticks)")
    y = Output("1", start=0.0, doc="Output signal (held between ticks)")

    def clock(self) -> Clock:
        return Clock(self.Ts, self.offset)


class ZeroOrderHold(_SampledSISO):
    """``y(t) = u(t_k)`` for ``t_k <= t < t_k+1``."""

    def equations(self):
        return [sample(self.clock(), output={self.y: self.u})]


class UnitDelay(_SampledSISO):
    """``y(t) = x_k``, ``x_k+1 = u(t_k)``: the input one sample late (``1/z``). The
    initial output is the start value of ``x``."""

    x = Variable("1", start=0.0, doc="State: the input at the previous tick")

    def equations(self):
        return [sample(self.clock(), output={self.y: self.x}, update={self.x: self.u})]


def _delay_samples(T, Ts, where: str) -> tuple[float, int]:
    """``(T, n)`` with ``n = T / Ts`` samples, which must be a whole number."""
    try:
        T = float(to_si(T, "s", f"{where}: T"))
        Ts = float(to_si(Ts, "s", f"{where}: Ts"))
    except Exception as exc:
        raise ModelError(f"{where}: {exc}") from None
    if not (T >= 0 and Ts > 0):
        raise ModelError(f"{where}: needs T >= 0 and Ts > 0, got T = {T:g} s, "
                         f"Ts = {Ts:g} s.")
    n = round(T / Ts)
    if abs(n * Ts - T) > 1e-9 * max(T, Ts):
        raise ModelError(f"{where}: the delay T = {T:g} s is not a whole number of sample "
                         f"times Ts = {Ts:g} s ({T / Ts:.6g}); a delay is exact on its "
                         f"sample grid only. Use T = {max(n, 1) * Ts:g} s, or a Ts that "
                         "divides T.")
    return T, n


class Delay(_SampledSISO):
    """Transport delay on a sample grid: ``y(t_k) = u(t_k - T)`` at the ticks
    ``t_k = offset + k Ts``, held between them.

    A shift register of ``n = T / Ts`` samples (``T`` a whole number of sample times,
    fixed when the block is built): ``y_k = x_n,k``, ``x_1,k+1 = u_k``,
    ``x_i,k+1 = x_i-1,k``. Exact for a signal that is constant between ticks (a DAC
    output, a sampled command), which is what a drive's computation and PWM delay act on;
    ``n = 0`` is a zero-order hold. Before the input has travelled through, the output is
    the registers' start value (0).

    In estimation (:mod:`mechatron.estimation`) a delay whose input is a measured input
    is applied to the data instead: each experiment's input is shifted by ``T`` on its own
    sample grid (exact when ``T`` is a whole number of its sample periods), and the rest
    of the model stays a smooth ODE.

    Parameters
    ----------
    T : float or str
        The delay, s (``"5 ms"``).
    Ts, offset
        Sample time and first tick, as every sampled block.
    """

    def __new__(cls, T=1e-3, **kwargs):
        _, n = _delay_samples(T, kwargs.get("Ts", 1e-3), "Delay")
        return super().__new__(sized(cls, n, states(n, what="Register")))

    def __init__(self, T=1e-3, **kwargs):
        super().__init__(**kwargs)
        where = f"Delay '{self.name or '(unnamed)'}'"
        self.T, self.n = _delay_samples(T, kwargs.get("Ts", 1e-3), where)
        #: Set by estimation: ``y = u`` (the delay is applied to the data instead).
        self.continuous = False

    def equations(self):
        x = [getattr(self, f"x{i + 1}") for i in range(self.n)]
        if self.continuous:
            return [self.y == self.u] + [xi == self.u for xi in x]
        if not x:
            return [sample(self.clock(), output={self.y: self.u})]
        upd = {x[0]: self.u, **{x[i]: x[i - 1] for i in range(1, self.n)}}
        return [sample(self.clock(), output={self.y: x[-1]}, update=upd)]


class DiscreteIntegrator(_SampledSISO):
    """Forward-Euler discrete integrator (Simulink's default):
    ``y_k = x_k``, ``x_k+1 = min(max(x_k + K Ts u_k, y_min), y_max)``."""

    K = Parameter("1", default=1.0, doc="Gain")
    y_min = Parameter("1", default=-float("inf"), doc="Lower limit of the state")
    y_max = Parameter("1", default=float("inf"), doc="Upper limit of the state")
    x = Variable("1", start=0.0, doc="State (the integral)")

    def equations(self):
        nxt = ca.fmin(ca.fmax(self.x + self.K * self.Ts * self.u, self.y_min), self.y_max)
        return [sample(self.clock(), output={self.y: self.x}, update={self.x: nxt})]


class DiscreteTransferFunction(_SampledSISO):
    """``Y(z) = (b0 z^m + ... + bm) / (a0 z^n + ... + an) U(z)`` with ``m <= n``.

    Controllable canonical form with states ``x1 .. xn``:
    ``x_i,k+1 = x_i+1,k``, ``x_n,k+1 = u_k - sum_i a_(n-i+1) x_i,k`` (monic denominator),
    ``y_k = sum_i (b_(n-i+1) - b_0 a_(n-i+1)) x_i,k + b_0 u_k``; ``y`` is held between
    ticks. Coefficients in descending powers of ``z`` (as ``scipy.signal.dlti``).
    """

    def __new__(cls, num=(1.0,), den=(1.0, -0.5), **kwargs):
        n = len(np.trim_zeros(np.atleast_1d(np.asarray(den, dtype=float)), "f")) - 1
        return super().__new__(sized(cls, max(n, 0), states(max(n, 0))))

    def __init__(self, num=(1.0,), den=(1.0, -0.5), **kwargs):
        super().__init__(**kwargs)
        where = f"DiscreteTransferFunction '{self.name or '(unnamed)'}'"
        b = np.trim_zeros(coefficients(num, "num", where), "f")
        a = np.trim_zeros(coefficients(den, "den", where), "f")
        if a.size == 0:
            raise ModelError(f"{where}: the denominator is zero.")
        if b.size > a.size:
            raise ModelError(f"{where}: non-causal transfer function (numerator degree "
                             f"{b.size - 1} > denominator degree {a.size - 1}).")
        b = np.concatenate([np.zeros(a.size - max(b.size, 1)), b if b.size else [0.0]])
        self._num, self._den = b / a[0], a / a[0]

    def equations(self):
        b, a = self._num, self._den
        n = a.size - 1
        x = [getattr(self, f"x{i + 1}") for i in range(n)]
        y = sum((b[n - i] - b[0] * a[n - i]) * x[i] for i in range(n)) + b[0] * self.u
        upd = {x[i]: x[i + 1] for i in range(n - 1)}
        if n:
            upd[x[n - 1]] = self.u - sum(a[n - i] * x[i] for i in range(n))
        return [sample(self.clock(), output={self.y: y}, update=upd)]


class DiscretePID(_SampledSISO):
    """Discrete PID on the error ``u`` with forward-Euler integration, a backward-difference
    derivative and output limits with conditional integration (clamping anti-windup):

    ``v_k = Kp u_k + I_k + Kd (u_k - u_k-1) / Ts``, ``y_k = min(max(v_k, y_min), y_max)``,
    ``I_k+1 = I_k + Ki Ts u_k`` unless the output is saturated and ``u_k`` drives it
    further (then ``I_k+1 = I_k``).
    """

    Kp = Parameter("1", default=1.0, doc="Proportional gain")
    Ki = Parameter("1/s", default=0.0, doc="Integral gain")
    Kd = Parameter("s", default=0.0, doc="Derivative gain")
    y_min = Parameter("1", default=-float("inf"), doc="Lower output limit")
    y_max = Parameter("1", default=float("inf"), doc="Upper output limit")
    I = Variable("1", start=0.0, doc="Integral term")  # noqa: E741
    e_prev = Variable("1", start=0.0, doc="Error at the previous tick")

    def equations(self):
        e = self.u
        v = self.Kp * e + self.I + self.Kd * (e - self.e_prev) / self.Ts
        y = ca.fmin(ca.fmax(v, self.y_min), self.y_max)
        wind = ca.logic_or(ca.logic_and(v > self.y_max, e > 0),
                           ca.logic_and(v < self.y_min, e < 0))
        integral = ca.if_else(wind, self.I, self.I + self.Ki * self.Ts * e)
        return [sample(self.clock(), output={self.y: y},
                       update={self.I: integral, self.e_prev: e})]


class PWM(Sampled):
    """Edge-aligned pulse-width modulator, as a microcontroller timer: at each period start
    ``t_k = offset + k Ts`` the duty cycle ``u`` is latched (clamped to [0, 1]) and the
    output is ``amplitude`` until ``t_k + u_k Ts``, then 0 until the next period.

    The latched switch-off time ``t_off`` is a discrete state; the comparison
    ``t < t_off`` is a relation, so both edges of every pulse are events (two per period,
    none for a duty of 0, one for a duty of 1). ``Ts`` is the switching period.
    """

    u = Input("1", doc="Duty cycle, latched at each period start")
    y = Output("1", doc="PWM output")
    amplitude = Parameter("1", default=1.0, doc="Output while on")
    t_off = Variable("s", start=-1.0, doc="State: switch-off time of the current pulse")

    def equations(self):
        duty = ca.fmin(ca.fmax(self.u, 0.0), 1.0)
        return [self.y == ca.if_else(self.time < self.t_off, self.amplitude, 0.0),
                sample(Clock(self.Ts, self.offset),
                       update={self.t_off: self.time + duty * self.Ts})]
