"""Source blocks: signals of time alone.

Discontinuous sources (step, pulse) are written with relations of continuous distances,
so their switching instants are events located exactly by the variable-step solvers.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from mechatron.core import Component, Output, Parameter
from mechatron.errors import DataError
from mechatron.library.blocks.interfaces import piecewise_linear
from mechatron.library.blocks.waveforms import ramp_slope

__all__ = ["Constant", "Step", "Ramp", "Sine", "Pulse", "Chirp", "FromData", "KinematicPTP"]


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
    """Ramp: ``y = initial + slope*(t - start)`` from ``start`` on, ``initial`` before,
    held at ``initial + slope*duration`` from ``start + duration`` on.

    The default ``duration = inf`` never stops rising. Start and end of the rise are
    events (MSL's ``Ramp`` takes a ``height`` instead of a slope:
    ``slope = height/duration``).
    """

    y = Output("1", doc="Output")
    slope = Parameter("1/s", default=1.0, doc="Slope")
    start = Parameter("s", default=0.0, doc="Start time")
    initial = Parameter("1", default=0.0, doc="Initial value")
    duration = Parameter("s", default=float("inf"), min=0,
                         doc="Duration of the rise (inf: it never stops)")

    def equations(self):
        return [self.y == self.initial + ramp_slope(self.time, self.slope, self.duration,
                                                    self.start)]


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


class Chirp(Component):
    """Linear frequency sweep from ``f0`` at ``t = 0`` to ``f1`` at ``T``:
    ``y = amplitude * sin(2 pi (f0 t + (f1 - f0) t^2 / (2 T)))``; the instantaneous
    frequency ``f0 + (f1 - f0) t / T`` keeps rising after ``T``."""

    y = Output("1", doc="Output")
    amplitude = Parameter("1", default=1.0, doc="Amplitude")
    f0 = Parameter("Hz", default=0.1, min=0, doc="Frequency at t = 0")
    f1 = Parameter("Hz", default=10.0, min=0, doc="Frequency at t = T")
    T = Parameter("s", default=1.0, min=0, doc="Sweep time")

    def equations(self):
        t = self.time
        phase = 2 * ca.pi * (self.f0 * t + (self.f1 - self.f0) * t ** 2 / (2 * self.T))
        return [self.y == self.amplitude * ca.sin(phase)]


class FromData(Component):
    """A measured signal: ``y = interp(t; time, values)``, linear interpolation in a table.

    Before the first and after the last sample the end values are held. The table is one
    piecewise-linear expression of time (see ``interfaces.piecewise_linear``), so it runs
    in native code and generates C (kinks at the samples, no events: a variable-step
    solver steps over them with its error control; the cost grows with the number of
    samples).

    Parameters
    ----------
    time : array_like
        Sample times in s, strictly increasing, at least two.
    values : array_like
        Signal values, one per sample time.
    """

    y = Output("1", doc="Interpolated signal")

    def __init__(self, time=(0.0, 1.0), values=(0.0, 0.0), **kwargs):
        super().__init__(**kwargs)
        t = np.asarray(time, dtype=float).ravel()
        v = np.asarray(values, dtype=float).ravel()
        where = f"FromData '{self.name or '(unnamed)'}'"
        if t.size < 2 or t.size != v.size:
            raise DataError(f"{where}: time and values must have the same length >= 2, got "
                            f"{t.size} and {v.size}.")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
            bad = int(np.nonzero(~(np.isfinite(t) & np.isfinite(v)))[0][0])
            raise DataError(f"{where}: sample {bad} is not finite (t = {t[bad]!r}, value = "
                            f"{v[bad]!r}). Remove or fill missing samples.")
        if np.any(np.diff(t) <= 0):
            bad = int(np.nonzero(np.diff(t) <= 0)[0][0]) + 1
            raise DataError(f"{where}: time must increase strictly; sample {bad} "
                            f"(t = {t[bad]:g}) does not follow t = {t[bad - 1]:g}. "
                            "Sort the data and drop duplicate times.")
        self._table = (t, v)

    def equations(self):
        t, v = self._table
        return [self.y == piecewise_linear(self.time, t, v)]


class KinematicPTP(Component):
    """Point-to-point motion with limited speed and acceleration (MSL's
    ``KinematicPTP2``): from ``q_begin`` at ``start_time`` to ``q_end``, accelerating at
    ``qdd_max``, cruising at ``qd_max`` (if the distance allows it), decelerating at
    ``qdd_max``.

    With ``D = |q_end - q_begin|``, the peak speed ``v = min(qd_max, sqrt(D qdd_max))``
    (a triangle when ``D < qd_max^2 / qdd_max``), ``T_a = v / qdd_max``,
    ``T_v = D / v - T_a``, ``u = t - start_time``, ``T = 2 T_a + T_v`` and
    ``a = qdd_max sign(q_end - q_begin)``::

        qdd == a,  qd == a u,            q == q_begin + a u^2 / 2          0 <= u < T_a
        qdd == 0,  qd == a T_a,          q == q_begin + a T_a (u - T_a/2)  T_a <= u < T_a + T_v
        qdd == -a, qd == a (T - u),      q == q_end - a (T - u)^2 / 2      T_a + T_v <= u < T
        qdd == 0,  qd == 0,              q == q_end                        u >= T

    and ``q == q_begin`` before ``start_time``. Each phase change is an event; ``moving``
    is 1 during the motion. ``qd`` is continuous, ``q`` continuously differentiable.
    """

    q = Output("1", doc="Position reference")
    qd = Output("1", doc="Speed reference, dq/dt")
    qdd = Output("1", doc="Acceleration reference, d(qd)/dt")
    moving = Output("1", doc="1 during the motion, else 0")
    q_begin = Parameter("1", default=0.0, doc="Start position")
    q_end = Parameter("1", default=1.0, doc="End position")
    qd_max = Parameter("1/s", default=1.0, min=0, doc="Maximum speed (> 0)")
    qdd_max = Parameter("1/s^2", default=1.0, min=0, doc="Maximum acceleration (> 0)")
    start_time = Parameter("s", default=0.0, doc="Start of the motion")

    def equations(self):
        delta = self.q_end - self.q_begin
        dist = ca.fabs(delta)
        # (the floors keep sqrt and the divisions finite, with finite derivatives, when
        # q_end == q_begin: then a == 0 and q stays at q_begin)
        v = ca.fmin(self.qd_max, ca.sqrt(ca.fmax(dist * self.qdd_max, 1e-300)))
        t_a = v / self.qdd_max
        t_v = ca.fmax(dist / v - t_a, 0)
        t_end = 2 * t_a + t_v
        a = self.qdd_max * delta / ca.fmax(dist, 1e-300)  # its sign, no event
        u = self.time - self.start_time
        t0 = self.start_time
        accel = t0 <= self.time
        cruise = t0 + t_a <= self.time
        decel = t0 + t_a + t_v <= self.time
        done = t0 + t_end <= self.time
        r = t_end - u
        q = ca.if_else(done, self.q_end,
                       ca.if_else(decel, self.q_end - a * r ** 2 / 2,
                                  ca.if_else(cruise, self.q_begin + a * t_a * (u - t_a / 2),
                                             ca.if_else(accel, self.q_begin + a * u ** 2 / 2,
                                                        self.q_begin))))
        qd = ca.if_else(done, 0, ca.if_else(decel, a * r,
                                            ca.if_else(cruise, a * t_a,
                                                       ca.if_else(accel, a * u, 0))))
        qdd = ca.if_else(done, 0, ca.if_else(decel, -a, ca.if_else(cruise, 0,
                                                                  ca.if_else(accel, a, 0))))
        return [self.q == q, self.qd == qd, self.qdd == qdd,
                self.moving == ca.if_else(ca.logic_and(accel, ca.logic_not(done)), 1, 0)]
