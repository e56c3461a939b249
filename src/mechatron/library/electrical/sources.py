"""Electrical sources and the reference (ground)."""

import casadi as ca

from mechatron.core import Component, Input, Parameter, Variable
from mechatron.library.blocks import waveforms as wf
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


# -- sources with a start time and an offset (Modelica's Electrical.Analog.Sources) -------

class _TimedVoltage(OnePort, partial=True):
    """A voltage source ``v == offset + w(t)`` whose waveform ``w`` is 0 before
    ``start_time`` (MSL's ``startTime``)."""

    offset = Parameter("V", default=0.0, doc="Voltage offset (the value before start_time)")
    start_time = Parameter("s", default=0.0, doc="Start time of the waveform (MSL's startTime)")

    def waveform(self):
        raise NotImplementedError

    def equations(self):
        return [self.v == self.offset + self.waveform()]


class _TimedCurrent(OnePort, partial=True):
    """A current source ``i == offset + w(t)``, ``i`` from ``p`` through the source to
    ``n``, whose waveform ``w`` is 0 before ``start_time``."""

    offset = Parameter("A", default=0.0, doc="Current offset (the value before start_time)")
    start_time = Parameter("s", default=0.0, doc="Start time of the waveform (MSL's startTime)")

    def waveform(self):
        raise NotImplementedError

    def equations(self):
        return [self.i == self.offset + self.waveform()]


class StepVoltage(_TimedVoltage):
    """Step voltage source (MSL's ``StepVoltage``).

    Equations: ``v == offset + if_else(t >= start_time, V, 0)``. The step is an event.
    """

    V = Parameter("V", default=1.0, doc="Height of the step")

    def waveform(self):
        return wf.step(self.time, self.V, self.start_time)


class StepCurrent(_TimedCurrent):
    """Step current source (MSL's ``StepCurrent``).

    Equations: ``i == offset + if_else(t >= start_time, I, 0)``, ``i`` from ``p`` through
    the source to ``n``. The step is an event.
    """

    I = Parameter("A", default=1.0, doc="Height of the step")  # noqa: E741

    def waveform(self):
        return wf.step(self.time, self.I, self.start_time)


class RampVoltage(_TimedVoltage):
    """Ramp voltage source (MSL's ``RampVoltage``): from ``offset`` at ``start_time`` up
    to ``offset + V`` at ``start_time + duration``, then held.

    Equations::

        v == offset                             t <  t0        (t0 = start_time)
        v == offset + V (t - t0) / duration     t0 <= t < t0 + duration
        v == offset + V                         t >= t0 + duration

    Both kinks are events. ``duration`` must be > 0.
    """

    V = Parameter("V", default=1.0, doc="Height of the ramp")
    duration = Parameter("s", default=1.0, min=0, doc="Duration of the rise (> 0)")

    def waveform(self):
        return wf.ramp(self.time, self.V, self.duration, self.start_time)


class RampCurrent(_TimedCurrent):
    """Ramp current source (MSL's ``RampCurrent``), ``i`` from ``p`` through the source to
    ``n``.

    Equations::

        i == offset                             t <  t0        (t0 = start_time)
        i == offset + I (t - t0) / duration     t0 <= t < t0 + duration
        i == offset + I                         t >= t0 + duration
    """

    I = Parameter("A", default=1.0, doc="Height of the ramp")  # noqa: E741
    duration = Parameter("s", default=1.0, min=0, doc="Duration of the rise (> 0)")

    def waveform(self):
        return wf.ramp(self.time, self.I, self.duration, self.start_time)


class PulseVoltage(_TimedVoltage):
    """Pulse voltage source (MSL's ``PulseVoltage``): a train of rectangular pulses of
    height ``V`` above ``offset``, the first rising at ``start_time``.

    Equations: ``v == offset + V`` during ``[start_time + k period, start_time + (k +
    width) period)``, ``k = 0, 1, ...``, and ``v == offset`` otherwise. ``width`` is a
    fraction of the period (MSL's ``width`` is in percent: ``width = 0.3`` is MSL's 30).
    Every edge is an event located by the solver (no ``nperiod``: the train never ends).
    """

    V = Parameter("V", default=1.0, doc="Pulse height")
    width = Parameter("1", default=0.5, min=0, max=1, doc="Pulse width, fraction of period")
    period = Parameter("s", default=1.0, min=0, doc="Period (> 0)")

    def waveform(self):
        return wf.pulse(self.time, self.V, self.width, self.period, self.start_time)

    def time_scales(self):
        return [self.width * self.period, (1 - self.width) * self.period]


class PulseCurrent(_TimedCurrent):
    """Pulse current source (MSL's ``PulseCurrent``), ``i`` from ``p`` through the source
    to ``n``.

    Equations: ``i == offset + I`` during ``[start_time + k period, start_time + (k +
    width) period)``, ``k = 0, 1, ...``, and ``i == offset`` otherwise (``width`` a
    fraction of the period).
    """

    I = Parameter("A", default=1.0, doc="Pulse height")  # noqa: E741
    width = Parameter("1", default=0.5, min=0, max=1, doc="Pulse width, fraction of period")
    period = Parameter("s", default=1.0, min=0, doc="Period (> 0)")

    def waveform(self):
        return wf.pulse(self.time, self.I, self.width, self.period, self.start_time)

    def time_scales(self):
        return [self.width * self.period, (1 - self.width) * self.period]


class TrapezoidVoltage(_TimedVoltage):
    """Periodic trapezoidal voltage source (MSL's ``TrapezoidVoltage``).

    From ``start_time`` on, in each period (phase ``s`` from the period's start)::

        v == offset + V s / rising                           0 <= s < rising
        v == offset + V                                      rising <= s < rising + width
        v == offset + V (1 - (s - rising - width) / falling)  ... until rising + width + falling
        v == offset                                          rest of the period

    and ``v == offset`` before ``start_time``. The four corners are events. Requires
    ``rising > 0``, ``falling > 0`` and ``rising + width + falling <= period``; the train
    never ends (no ``nperiod``).
    """

    V = Parameter("V", default=1.0, doc="Amplitude of the trapezoid")
    rising = Parameter("s", default=1e-3, min=0, doc="Rising duration (> 0)")
    width = Parameter("s", default=2e-3, min=0, doc="Duration held at the amplitude")
    falling = Parameter("s", default=1e-3, min=0, doc="Falling duration (> 0)")
    period = Parameter("s", default=1e-2, min=0, doc="Period")

    def waveform(self):
        return wf.trapezoid(self.time, self.V, self.rising, self.width, self.falling,
                            self.period, self.start_time)

    def time_scales(self):
        return [self.rising, self.width, self.falling,
                self.period - self.rising - self.width - self.falling]


class TrapezoidCurrent(_TimedCurrent):
    """Periodic trapezoidal current source (MSL's ``TrapezoidCurrent``), ``i`` from ``p``
    through the source to ``n``.

    From ``start_time`` on, in each period (phase ``s`` from the period's start)::

        i == offset + I s / rising                           0 <= s < rising
        i == offset + I                                      rising <= s < rising + width
        i == offset + I (1 - (s - rising - width) / falling)  ... until rising + width + falling
        i == offset                                          rest of the period
    """

    I = Parameter("A", default=1.0, doc="Amplitude of the trapezoid")  # noqa: E741
    rising = Parameter("s", default=1e-3, min=0, doc="Rising duration (> 0)")
    width = Parameter("s", default=2e-3, min=0, doc="Duration held at the amplitude")
    falling = Parameter("s", default=1e-3, min=0, doc="Falling duration (> 0)")
    period = Parameter("s", default=1e-2, min=0, doc="Period")

    def waveform(self):
        return wf.trapezoid(self.time, self.I, self.rising, self.width, self.falling,
                            self.period, self.start_time)

    def time_scales(self):
        return [self.rising, self.width, self.falling,
                self.period - self.rising - self.width - self.falling]


class ExpSineVoltage(_TimedVoltage):
    """Exponentially damped sine voltage source (MSL's ``ExpSineVoltage``).

    Equations, with ``u = t - start_time``::

        v == offset + V exp(-damping u) sin(2 pi f u + phase)    t >= start_time
        v == offset                                              t <  start_time

    The start is an event (a jump unless ``phase`` is 0).
    """

    V = Parameter("V", default=1.0, doc="Amplitude at start_time")
    f = Parameter("Hz", default=2.0, min=0, doc="Frequency")
    phase = Parameter("rad", default=0.0, doc="Phase at start_time")
    damping = Parameter("1/s", default=1.0, doc="Damping coefficient (decay rate)")

    def waveform(self):
        return wf.exp_sine(self.time, self.V, self.f, self.phase, self.damping,
                           self.start_time)


class ExpSineCurrent(_TimedCurrent):
    """Exponentially damped sine current source (MSL's ``ExpSineCurrent``), ``i`` from
    ``p`` through the source to ``n``.

    Equations, with ``u = t - start_time``::

        i == offset + I exp(-damping u) sin(2 pi f u + phase)    t >= start_time
        i == offset                                              t <  start_time
    """

    I = Parameter("A", default=1.0, doc="Amplitude at start_time")  # noqa: E741
    f = Parameter("Hz", default=2.0, min=0, doc="Frequency")
    phase = Parameter("rad", default=0.0, doc="Phase at start_time")
    damping = Parameter("1/s", default=1.0, doc="Damping coefficient (decay rate)")

    def waveform(self):
        return wf.exp_sine(self.time, self.I, self.f, self.phase, self.damping,
                           self.start_time)


class _Table:
    """Mixin: a constructor argument ``table`` of rows ``(time, value)``.

    The table's numbers carry no units (times in s, values in the source's unit), so the
    dimension check, which would read a slope times a time as a time, is off for these
    classes (their other equations are those of ``OnePort``)."""

    check_dimensions = False

    def _init_table(self, table):
        where = f"{type(self).__name__} '{self.name or '(unnamed)'}'"
        self._table = wf.check_table(table, where)

    def table_waveform(self):
        times, values = self._table
        return wf.table(self.time - self.start_time, times, values)


class TableVoltage(_Table, _TimedVoltage):
    """Voltage source interpolating a table (MSL's ``TableVoltage``).

    Equations: ``v == offset + interp(t - start_time; table)``, linear interpolation in
    the rows ``(time, value)`` of ``table``; the first value is held before the first time
    and the last after the last one; two rows with the same time are a jump. Every
    breakpoint is an event (kinks and jumps are located, not smoothed).

    Parameters
    ----------
    table : sequence of (time, value)
        Times in s (non-decreasing, relative to ``start_time``), values in V.
    """

    def __init__(self, table=((0.0, 0.0), (1.0, 1.0)), **kwargs):
        super().__init__(**kwargs)
        self._init_table(table)

    def waveform(self):
        return self.table_waveform()


class TableCurrent(_Table, _TimedCurrent):
    """Current source interpolating a table (MSL's ``TableCurrent``), ``i`` from ``p``
    through the source to ``n``.

    Equations: ``i == offset + interp(t - start_time; table)`` (as :class:`TableVoltage`).

    Parameters
    ----------
    table : sequence of (time, value)
        Times in s (non-decreasing, relative to ``start_time``), values in A.
    """

    def __init__(self, table=((0.0, 0.0), (1.0, 1.0)), **kwargs):
        super().__init__(**kwargs)
        self._init_table(table)

    def waveform(self):
        return self.table_waveform()
