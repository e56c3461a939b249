"""Causal signal blocks (the Simulink side): sources for now.

Outputs are ``y``; inputs ``u``. Discontinuous sources (step, pulse) are written with
relations of continuous distances, so their switching instants are events located exactly.
"""

import casadi as ca

from mechatron.core import Component, Output, Parameter

__all__ = ["Constant", "Step", "Ramp", "Sine", "Pulse"]


class Constant(Component):
    """Constant signal: ``y = value``."""

    y = Output("1", doc="Output")
    value = Parameter("1", default=1.0, doc="Value")

    def equations(self):
        return [self.y == self.value]


class Step(Component):
    """Step: ``y = initial`` before ``t_step``, ``final`` from ``t_step`` on."""

    y = Output("1", doc="Output")
    t_step = Parameter("s", default=0.0, doc="Step time")
    initial = Parameter("1", default=0.0, doc="Value before the step")
    final = Parameter("1", default=1.0, doc="Value from the step on")

    def equations(self):
        t = self.time
        return [self.y == ca.if_else(self.t_step <= t, self.final, self.initial)]


class Ramp(Component):
    """Ramp: ``y = initial + slope*(t - start)`` from ``start`` on, ``initial`` before."""

    y = Output("1", doc="Output")
    slope = Parameter("1/s", default=1.0, doc="Slope")
    start = Parameter("s", default=0.0, doc="Start time")
    initial = Parameter("1", default=0.0, doc="Initial value")

    def equations(self):
        t = self.time
        return [self.y == self.initial + ca.if_else(self.start <= t,
                                                    self.slope * (t - self.start), 0)]


class Sine(Component):
    """Sine wave: ``y = offset + amplitude * sin(2 pi f t + phase)``."""

    y = Output("1", doc="Output")
    amplitude = Parameter("1", default=1.0, doc="Amplitude")
    f = Parameter("Hz", default=1.0, min=0, doc="Frequency")
    phase = Parameter("rad", default=0.0, doc="Phase")
    offset = Parameter("1", default=0.0, doc="Offset")

    def equations(self):
        t = self.time
        return [self.y == self.offset + self.amplitude
                * ca.sin(2 * ca.pi * self.f * t + self.phase)]


class Pulse(Component):
    """Pulse train: ``amplitude`` during the first ``width`` (fraction) of each ``period``
    from ``delay`` on, else 0.

    The on-interval test is ``cos(theta - pi*width) > cos(pi*width)`` with
    ``theta = 2 pi (t - delay)/period``: a continuous distance, so every edge is an event
    located to the solver's event tolerance.
    """

    y = Output("1", doc="Output")
    amplitude = Parameter("1", default=1.0, doc="Amplitude")
    period = Parameter("s", default=1.0, min=0, doc="Period")
    width = Parameter("1", default=0.5, min=0, max=1, doc="Duty cycle (fraction of period)")
    delay = Parameter("s", default=0.0, doc="Start of the first pulse")

    def equations(self):
        t = self.time
        theta = 2 * ca.pi * (t - self.delay) / self.period
        on = ca.logic_and(ca.cos(self.width * ca.pi) < ca.cos(theta - ca.pi * self.width),
                          self.delay <= t)
        return [self.y == ca.if_else(on, self.amplitude, 0)]

    def time_scales(self):
        return [self.width * self.period, (1 - self.width) * self.period]
