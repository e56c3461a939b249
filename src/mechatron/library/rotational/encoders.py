"""Drive sensors with digital outputs: the incremental encoder (quantized angle and speed,
read at a sample rate) and the three Hall sensors of a brushless motor."""

import casadi as ca

from mechatron.core import Clock, Output, Parameter, Variable, der, sample
from mechatron.library.rotational.interfaces import TwoFlange

__all__ = ["IncrementalEncoder", "HallSensor"]


class IncrementalEncoder(TwoFlange):
    """Incremental (quadrature) encoder read by a controller every ``Ts``: the count of
    edges, the quantized angle and the speed from the count difference. Shaft ``A``,
    housing ``B``; it takes no torque.

    Equations, with the shaft angle ``phi`` (A relative to B, its own state, start 0) and
    ticks ``t_k = offset + k Ts``::

        tau == 0,  der(phi) == w
        at t_k:  count := floor(phi cpr / (2 pi))
                 W := (floor(phi cpr / (2 pi)) - count) 2 pi / (cpr Ts)   (count before t_k)
        Phi == 2 pi count / cpr

    ``cpr`` is the counts per revolution after quadrature decoding (4 x the lines of the
    disc). The angle error is within one count, ``[0, 2 pi / cpr)``; the speed is the mean
    over the last sample period, quantized to ``2 pi / (cpr Ts)``. Between ticks the
    outputs are held.
    """

    cpr = Parameter("1", default=4096, min=1, doc="Counts per revolution (after quadrature)")
    Ts = Parameter("s", default=1e-3, min=0, doc="Sample time of the counter read-out")
    offset = Parameter("s", default=0.0, min=0, doc="Time of the first read-out")
    phi = Variable("rad", start=0.0, doc="Shaft angle, A relative to B")
    count = Variable("1", start=0.0, doc="Edge count at the last read-out")
    Phi = Output("rad", doc="Quantized angle, 2 pi count / cpr")
    W = Output("rad/s", start=0.0, doc="Speed from the last two read-outs")

    def equations(self):
        new = ca.floor(self.phi * self.cpr / (2 * ca.pi))
        return [self.tau == 0, der(self.phi) == self.w,
                self.Phi == 2 * ca.pi * self.count / self.cpr,
                sample(Clock(self.Ts, self.offset),
                       update={self.count: new,
                               self.W: (new - self.count) * 2 * ca.pi / (self.cpr * self.Ts)})]


class HallSensor(TwoFlange):
    """Three digital Hall sensors 120 electrical degrees apart, as in a brushless DC motor.
    Shaft ``A``, housing ``B``; it takes no torque.

    Equations, with the shaft angle ``phi`` (A relative to B, own state, start 0) and the
    electrical angle ``theta = p phi + theta_0``::

        tau == 0,  der(phi) == w
        h_a == if_else(sin(theta) > 0, 1, 0)
        h_b == if_else(sin(theta - 2 pi/3) > 0, 1, 0)
        h_c == if_else(sin(theta + 2 pi/3) > 0, 1, 0)

    Each output is high for half an electrical period; together they step through six
    states per electrical revolution, one edge every ``pi / 3`` electrical. Every edge is
    an event located by the solver.
    """

    p = Parameter("1", default=4, min=1, doc="Pole pairs")
    theta_0 = Parameter("rad", default=0.0, doc="Electrical angle at phi = 0")
    phi = Variable("rad", start=0.0, doc="Shaft angle, A relative to B")
    h_a = Output("1", doc="Hall sensor a (0 or 1)")
    h_b = Output("1", doc="Hall sensor b (0 or 1)")
    h_c = Output("1", doc="Hall sensor c (0 or 1)")

    def equations(self):
        theta = self.p * self.phi + self.theta_0
        return [self.tau == 0, der(self.phi) == self.w,
                self.h_a == ca.if_else(0 < ca.sin(theta), 1, 0),
                self.h_b == ca.if_else(0 < ca.sin(theta - 2 * ca.pi / 3), 1, 0),
                self.h_c == ca.if_else(0 < ca.sin(theta + 2 * ca.pi / 3), 1, 0)]
