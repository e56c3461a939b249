"""Electrical sources and the reference (ground)."""

import casadi as ca

from mechatron.core import Component, Input, Parameter, Variable
from mechatron.library.electrical.interfaces import OnePort, Pin, TwoPort


class ElectricalReference(Component, reference=True):
    """Electrical ground: ``port.v = 0``. Every circuit needs one."""

    port = Pin(doc="Grounded pin")

    def equations(self):
        return [self.port.v == 0]


class DCVoltageSource(OnePort):
    """Ideal constant voltage source: ``v = V`` whatever the current."""

    V = Parameter("V", default=1.0, doc="Voltage, p.v - n.v")

    def equations(self):
        return [self.v == self.V]


class ControlledVoltageSource(OnePort):
    """Ideal voltage source driven by a signal: ``v = u``."""

    u = Input("V", doc="Commanded voltage, p.v - n.v")

    def equations(self):
        return [self.v == self.u]


class DCCurrentSource(OnePort):
    """Ideal constant current source: ``i = I`` flows from p through the source to n.

    A positive ``I`` therefore pushes current out of ``n`` into the circuit.
    """

    I = Parameter("A", default=1.0, doc="Current from p to n through the source")  # noqa: E741

    def equations(self):
        return [self.i == self.I]


class ControlledCurrentSource(OnePort):
    """Ideal current source driven by a signal: ``i == u``.

    As for :class:`DCCurrentSource`, ``i`` flows from ``p`` through the source to ``n``, so
    a positive ``u`` pushes current out of ``n`` into the circuit.
    """

    u = Input("A", doc="Commanded current from p to n through the source")

    def equations(self):
        return [self.i == self.u]


class ACVoltageSource(OnePort):
    """Ideal sinusoidal voltage source (Simscape's ``AC Voltage Source``, Modelica's
    ``SineVoltage``).

    Equations: ``v == V_offset + V_amp sin(2 pi f t + phase)`` whatever the current.
    ``V_amp`` is the peak value (the RMS value is ``V_amp / sqrt(2)``).
    """

    V_amp = Parameter("V", default=1.0, doc="Peak amplitude")
    f = Parameter("Hz", default=50.0, min=0, doc="Frequency")
    phase = Parameter("rad", default=0.0, doc="Phase at t = 0")
    V_offset = Parameter("V", default=0.0, doc="DC offset")

    def equations(self):
        return [self.v == self.V_offset
                + self.V_amp * ca.sin(2 * ca.pi * self.f * self.time + self.phase)]


class ACCurrentSource(OnePort):
    """Ideal sinusoidal current source (Simscape's ``AC Current Source``, Modelica's
    ``SineCurrent``).

    Equations: ``i == I_offset + I_amp sin(2 pi f t + phase)``, with ``i`` flowing from
    ``p`` through the source to ``n`` (as :class:`DCCurrentSource`).
    """

    I_amp = Parameter("A", default=1.0, doc="Peak amplitude")
    f = Parameter("Hz", default=50.0, min=0, doc="Frequency")
    phase = Parameter("rad", default=0.0, doc="Phase at t = 0")
    I_offset = Parameter("A", default=0.0, doc="DC offset")

    def equations(self):
        return [self.i == self.I_offset
                + self.I_amp * ca.sin(2 * ca.pi * self.f * self.time + self.phase)]


class PWMVoltageSource(OnePort):
    """Ideal pulse-width-modulated voltage source with a fixed duty cycle.

    Equations: ``v == if_else(on, V_on, V_off)``; from ``delay`` on, the source is ``on``
    during the first ``duty/f`` of every period ``1/f`` (edge-aligned: rising edges at
    ``delay + k/f``, falling edges at ``delay + (k + duty)/f``); before ``delay`` it is
    off. The on-test is ``cos(theta - pi duty) > cos(pi duty)`` with
    ``theta = 2 pi f (t - delay)``, a continuous distance, so every edge is an event that
    the solver locates to its event tolerance (as ``blocks.Pulse``).

    Mean value over whole periods: ``V_off + duty (V_on - V_off)``.

    Limitations: ``duty`` 0 or 1 gives a constant output (a touching, never crossing,
    distance); switching is ideal (zero rise time).
    """

    V_on = Parameter("V", default=1.0, doc="Voltage while on")
    V_off = Parameter("V", default=0.0, doc="Voltage while off")
    f = Parameter("Hz", default=1e3, min=0, doc="Switching frequency")
    duty = Parameter("1", default=0.5, min=0, max=1, doc="Duty cycle, fraction of a period on")
    delay = Parameter("s", default=0.0, doc="Time of the first rising edge")
    on = Variable("1", doc="1 while on, else 0")

    def equations(self):
        t = self.time
        theta = 2 * ca.pi * self.f * (t - self.delay)
        # enabled half-way through the off-interval before the first pulse, so that the
        # enable never coincides with an edge (two simultaneous events)
        enable = self.delay - 0.5 * (1 - self.duty) / self.f <= t
        on = ca.logic_and(ca.cos(self.duty * ca.pi) < ca.cos(theta - ca.pi * self.duty),
                          enable)
        return [self.on == ca.if_else(on, 1, 0),
                self.v == self.V_off + self.on * (self.V_on - self.V_off)]

    def time_scales(self):
        return [self.duty / self.f, (1 - self.duty) / self.f]


class ControlledPWMVoltageSource(OnePort):
    """PWM voltage source whose duty cycle is a signal: centre-aligned (triangular carrier)
    modulation, as a motor-drive inverter does.

    Equations: ``v == if_else(on, V_on, V_off)`` with ``on`` while the clipped duty
    ``d = min(max(duty, 0), 1)`` exceeds the triangular carrier
    ``c(t) = acos(cos(2 pi f (t - delay))) / pi`` (0 at ``delay + k/f``, 1 half a period
    later). The test is written ``cos(2 pi f (t - delay)) > cos(pi d)``, a smooth distance,
    so each edge is an event the solver locates. With a constant duty the pulses are
    centred on ``delay + k/f`` and the mean value is ``V_off + d (V_on - V_off)``.

    Limitations: a pulse (or gap) shorter than the solver's step may be missed when the
    duty signal is within a step's length of 0 or 1 (steps are limited to a quarter period).
    """

    duty = Input("1", doc="Duty cycle (clipped to [0, 1])")
    V_on = Parameter("V", default=1.0, doc="Voltage while on")
    V_off = Parameter("V", default=0.0, doc="Voltage while off")
    f = Parameter("Hz", default=1e3, min=0, doc="Carrier (switching) frequency")
    delay = Parameter("s", default=0.0, doc="Time of a carrier minimum (pulse centre)")
    on = Variable("1", doc="1 while on, else 0")

    def equations(self):
        d = ca.fmin(ca.fmax(self.duty, 0), 1)
        theta = 2 * ca.pi * self.f * (self.time - self.delay)
        return [self.on == ca.if_else(ca.cos(ca.pi * d) < ca.cos(theta), 1, 0),
                self.v == self.V_off + self.on * (self.V_on - self.V_off)]

    def time_scales(self):
        return [0.5 / self.f]


class VoltageControlledVoltageSource(TwoPort):
    """Linear voltage-controlled voltage source (Modelica's ``VCV``).

    Equations: ``i1 == 0`` (port 1 senses without drawing current) and
    ``v2 == gain v1``.
    """

    gain = Parameter("1", default=1.0, doc="Voltage gain v2/v1")

    def equations(self):
        return [self.i1 == 0, self.v2 == self.gain * self.v1]


class VoltageControlledCurrentSource(TwoPort):
    """Linear voltage-controlled current source (Modelica's ``VCC``).

    Equations: ``i1 == 0`` and ``i2 == G v1``. As for the other current sources, ``i2``
    flows from ``p2`` through the source to ``n2``: a positive ``G v1`` pushes current
    out of ``n2`` into the circuit.
    """

    G = Parameter("S", default=1.0, doc="Transconductance i2/v1")

    def equations(self):
        return [self.i1 == 0, self.i2 == self.G * self.v1]


class CurrentControlledVoltageSource(TwoPort):
    """Linear current-controlled voltage source (Modelica's ``CCV``).

    Equations: ``v1 == 0`` (port 1 is an ammeter, current ``i1`` from p1 to n1) and
    ``v2 == R_m i1``.
    """

    R_m = Parameter("Ohm", default=1.0, doc="Transresistance v2/i1")

    def equations(self):
        return [self.v1 == 0, self.v2 == self.R_m * self.i1]


class CurrentControlledCurrentSource(TwoPort):
    """Linear current-controlled current source (Modelica's ``CCC``).

    Equations: ``v1 == 0`` (port 1 is an ammeter) and ``i2 == gain i1``, ``i2`` flowing
    from ``p2`` through the source to ``n2``.
    """

    gain = Parameter("1", default=1.0, doc="Current gain i2/i1")

    def equations(self):
        return [self.v1 == 0, self.i2 == self.gain * self.i1]
