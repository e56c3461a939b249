"""Ideal electrical elements: transformer, operational amplifiers, switch."""

import casadi as ca

from mechatron.core import Component, Input, Parameter, Variable
from mechatron.library.electrical.interfaces import OnePort, Pin, TwoPort

__all__ = ["IdealTransformer", "IdealOpAmp", "FiniteGainOpAmp", "SaturatingOpAmp",
           "IdealSwitch"]


class IdealTransformer(TwoPort):
    """Ideal transformer with turns ratio ``N = N1/N2`` (Modelica's ``IdealTransformer``
    without magnetizing inductance).

    Equations: ``v1 == N v2`` and ``i2 == -N i1``, so ``v1 i1 + v2 i2 == 0``: the power
    entering port 1 leaves at port 2. Currents are positive into the dotted pins ``p1``
    and ``p2``.

    Limitations: lossless, no magnetizing or leakage inductance; it transforms DC as well.
    Add those with separate inductors and resistors, or use :class:`MutualInductor`.
    """

    N = Parameter("1", default=1.0, doc="Turns ratio N1/N2 (primary to secondary)")

    def equations(self):
        return [self.v1 == self.N * self.v2, self.i2 == -self.N * self.i1]


class IdealOpAmp(Component):
    """Ideal operational amplifier, the nullor (Modelica's ``IdealOpAmp3Pin``).

    Equations: ``in_p.i == 0``, ``in_n.i == 0`` (no input current) and
    ``in_p.v == in_n.v`` (virtual short); the output voltage is whatever the external
    circuit (the feedback) requires, and the output current ``out.i`` flows to an
    implicit ground.

    Limitations: needs negative feedback to have a unique solution; no supply pins, so
    the output is unbounded and the output power is not accounted for (see
    :class:`SaturatingOpAmp` for limits).
    """

    in_p = Pin(doc="Non-inverting input")
    in_n = Pin(doc="Inverting input")
    out = Pin(doc="Output (current into the op-amp positive)")

    def equations(self):
        return [self.in_p.i == 0, self.in_n.i == 0, self.in_p.v == self.in_n.v]


class _LinearOpAmpInput(Component, partial=True):
    """Input stage of the finite-gain op-amps: ``v_in == in_p.v - in_n.v``,
    ``v_in == R_in in_p.i``, ``in_n.i == -in_p.i``."""

    in_p = Pin(doc="Non-inverting input")
    in_n = Pin(doc="Inverting input")
    out = Pin(doc="Output (current into the op-amp positive)")
    A = Parameter("1", default=1e5, doc="Open-loop voltage gain")
    R_in = Parameter("Ohm", default=1e6, min=0, doc="Input resistance between in_p and in_n")
    R_out = Parameter("Ohm", default=10.0, min=0, doc="Output resistance")
    v_in = Variable("V", doc="Differential input voltage in_p.v - in_n.v")

    def equations(self):
        return [self.v_in == self.in_p.v - self.in_n.v,
                self.v_in == self.R_in * self.in_p.i,
                self.in_n.i == -self.in_p.i]


class FiniteGainOpAmp(_LinearOpAmpInput):
    """Op-amp with finite gain, input and output resistance (Simscape's ``Finite-Gain
    Op-Amp`` without saturation).

    Equations::

        v_in == in_p.v - in_n.v
        v_in == R_in in_p.i,  in_n.i == -in_p.i
        out.v == A v_in + R_out out.i

    ``out.i`` is positive into the op-amp, so a sourcing output has ``out.i < 0`` and
    ``out.v`` below ``A v_in``. The output stage is referenced to an implicit ground.

    Limitations: linear (no output limits: see :class:`SaturatingOpAmp`), no bandwidth
    limit, no offset; the output power is not accounted for.
    """

    def equations(self):
        return [self.out.v == self.A * self.v_in + self.R_out * self.out.i]


class SaturatingOpAmp(_LinearOpAmpInput):
    """Finite-gain op-amp whose internal output voltage saturates at ``V_min``/``V_max``
    (Simscape's ``Finite-Gain Op-Amp`` with output limits).

    Equations::

        v_in == in_p.v - in_n.v
        v_in == R_in in_p.i,  in_n.i == -in_p.i
        v_int == if_else(A v_in <= V_max, if_else(V_min <= A v_in, A v_in, V_min), V_max)
        out.v == v_int + R_out out.i

    Entering and leaving saturation are events located by the solver. Sign convention as
    :class:`FiniteGainOpAmp`.

    Limitations: hard limits (no soft knee), no slew-rate limit, no supply pins. In a
    feedback loop a saturated output can be a second solution; the initialization starts
    from the linear region.
    """

    V_max = Parameter("V", default=15.0, doc="Upper limit of the internal output voltage")
    V_min = Parameter("V", default=-15.0, doc="Lower limit of the internal output voltage")
    v_int = Variable("V", doc="Internal (open-circuit) output voltage after the limits")

    def equations(self):
        u = self.A * self.v_in
        # written so that "true" (the mode the initialization starts from) is the linear
        # region: a saturated start in a feedback loop is another, spurious, solution
        return [self.v_int == ca.if_else(u <= self.V_max,
                                         ca.if_else(self.V_min <= u, u, self.V_min),
                                         self.V_max),
                self.out.v == self.v_int + self.R_out * self.out.i]


class IdealSwitch(OnePort):
    """Signal-controlled ideal switch with on-resistance and off-conductance (Simscape's
    ``Switch``, Modelica's ``IdealClosingSwitch`` with a threshold).

    Equations: ``closed == if_else(control > threshold, 1, 0)`` and
    ``i == if_else(control > threshold, v / R_on, G_off v)``. Opening and closing are
    events located by the solver.

    Limitations: ``R_on`` must be > 0 (``R_on = 0`` divides by zero); no arcing, no
    switching delay.
    """

    control = Input("1", doc="Control signal; the switch is closed while it exceeds threshold")
    R_on = Parameter("Ohm", default=1e-3, min=0, doc="Resistance when closed (must be > 0)")
    G_off = Parameter("S", default=1e-9, min=0, doc="Conductance when open")
    threshold = Parameter("1", default=0.5, doc="Control value above which it is closed")
    closed = Variable("1", doc="1 while closed, else 0")

    def equations(self):
        c = self.threshold < self.control
        return [self.closed == ca.if_else(c, 1, 0),
                self.i == ca.if_else(c, self.v / self.R_on, self.G_off * self.v)]
