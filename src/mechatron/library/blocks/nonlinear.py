"""Nonlinear blocks: saturation, dead zone, relay, quantizer, rate limiter, backlash.

Every switching of these blocks is an event located by the solver. Blocks with memory
(relay, quantizer) keep it in a discrete state changed by ``when`` actions (see
:mod:`mechatron.core.events`), so there is no chattering at their thresholds.
"""

from __future__ import annotations

import casadi as ca

from mechatron.core import Parameter, Variable, der, when
from mechatron.library.blocks.interfaces import SISO

__all__ = ["Saturation", "DeadZone", "Relay", "Quantizer", "RateLimiter", "Backlash"]


class Saturation(SISO):
    """``y = min(max(u, lower), upper)``."""

    lower = Parameter("1", default=-1.0, doc="Lower limit")
    upper = Parameter("1", default=1.0, doc="Upper limit")

    def equations(self):
        return [self.y == ca.if_else(self.upper < self.u, self.upper,
                                     ca.if_else(self.u < self.lower, self.lower, self.u))]


class DeadZone(SISO):
    """``y = 0`` for ``start <= u <= end``, ``u - end`` above, ``u - start`` below."""

    start = Parameter("1", default=-0.5, doc="Lower end of the dead zone")
    end = Parameter("1", default=0.5, doc="Upper end of the dead zone")

    def equations(self):
        below = ca.if_else(self.u < self.start, self.u - self.start, 0)
        return [self.y == ca.if_else(self.end < self.u, self.u - self.end, below)]


class Relay(SISO):
    """Relay with hysteresis: switches on when ``u >= on_point``, off when
    ``u <= off_point`` (``off_point < on_point``), and otherwise keeps its state.

    ``y = off_value + q (on_value - off_value)`` with the state ``q`` in {0, 1} set by two
    ``when`` actions. At the start ``q`` is 1 if ``u >= on_point``, 0 if
    ``u <= off_point``, else its start value (``Relay(q=1)`` starts on).
    """

    on_point = Parameter("1", default=0.5, doc="Input at which the relay switches on")
    off_point = Parameter("1", default=-0.5, doc="Input at which it switches off")
    on_value = Parameter("1", default=1.0, doc="Output while on")
    off_value = Parameter("1", default=0.0, doc="Output while off")
    q = Variable("1", start=0.0, doc="State: 1 on, 0 off")

    def equations(self):
        return [self.y == self.off_value + self.q * (self.on_value - self.off_value),
                when(self.u >= self.on_point, update={self.q: 1.0}),
                when(self.u <= self.off_point, update={self.q: 0.0})]


class Quantizer(SISO):
    """``y = q round(u / q)``: the nearest multiple of the interval ``q``.

    The level ``n`` is a discrete state changed when ``u`` leaves
    ``[(n - 1/2) q, (n + 1/2) q)`` (two ``when`` actions whose thresholds move with
    ``n``), so each step of the staircase is an event.
    """

    q = Parameter("1", default=0.1, min=0, doc="Quantization interval")
    n = Variable("1", start=0.0, doc="State: the current level (an integer)")

    def equations(self):
        level = ca.floor(self.u / self.q + 0.5)
        return [self.y == self.q * self.n,
                # at a located crossing u sits on the threshold: step at least one level
                when(self.u >= (self.n + 0.5) * self.q,
                     update={self.n: ca.fmax(self.n + 1, level)}),
                when(self.u < (self.n - 0.5) * self.q,
                     update={self.n: ca.fmin(self.n - 1, level)})]


class RateLimiter(SISO):
    """Rate limiter: ``y`` tracks ``u`` with time constant ``T`` and a slope limited to
    ``[falling, rising]``: ``dy/dt = min(max((u - y) / T, falling), rising)``.

    The tracking lag is ``T`` times the input's slope (choose ``T`` well below the time
    scales of interest); reaching and leaving a slope limit are events.
    """

    rising = Parameter("1/s", default=1.0, min=0, doc="Largest rising slope")
    falling = Parameter("1/s", default=-1.0, max=0, doc="Largest falling slope (<= 0)")
    T = Parameter("s", default=1e-3, min=0, doc="Tracking time constant")

    def equations(self):
        r = (self.u - self.y) / self.T
        return [der(self.y) == ca.if_else(self.rising < r, self.rising,
                                          ca.if_else(r < self.falling, self.falling, r))]


class Backlash(SISO):
    """Backlash (play) of total width ``width``: ``y`` does not move while
    ``|u - y| < width / 2``; beyond, it is dragged along with time constant ``T``:
    ``dy/dt = (u - y - width/2) / T`` above, ``(u - y + width/2) / T`` below.

    Engaging and disengaging are events. The drag lag is ``T`` times the input's slope.
    """

    width = Parameter("1", default=0.2, min=0, doc="Total play")
    T = Parameter("s", default=1e-4, min=0, doc="Drag time constant")

    def equations(self):
        gap = self.u - self.y
        half = self.width / 2
        below = ca.if_else(gap < -half, (gap + half) / self.T, 0)
        return [der(self.y) == ca.if_else(half < gap, (gap - half) / self.T, below)]
