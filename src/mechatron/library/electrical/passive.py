"""Passive electrical components."""

import casadi as ca

from mechatron.core import Component, Input, Parameter, Variable, der, if_else
from mechatron.library.electrical.interfaces import OnePort, Pin, TwoPort
from mechatron.library.thermal.interfaces import HeatPort


class Resistor(OnePort):
    """Ideal linear resistor.

    Equations: ``v = R i``. Absorbs ``R i^2 >= 0``.
    """

    R = Parameter("Ohm", default=1.0, min=0, doc="Resistance")

    def equations(self):
        return [self.v == self.R * self.i]


class Inductor(OnePort):
    """Ideal linear inductor.

    Equations: ``v = L di/dt``. Stores ``L i^2 / 2``.
    """

    L = Parameter("H", default=1e-3, min=0, doc="Inductance")

    def equations(self):
        return [self.v == self.L * der(self.i)]


class Capacitor(OnePort):
    """Ideal linear capacitor.

    Equations: ``i = C dv/dt``. Stores ``C v^2 / 2``.
    """

    C = Parameter("F", default=1e-6, min=0, doc="Capacitance")

    def equations(self):
        return [self.i == self.C * der(self.v)]


class Diode(OnePort):
    """Piecewise-linear diode.

    Equations: ``i = (v - Vf)/Ron + Goff*Vf`` for ``v > Vf`` (conducting), ``i = Goff*v``
    otherwise (blocking). The characteristic is continuous at ``v = Vf``; the switch
    between the two segments is an event located by the solver.
    """

    Vf = Parameter("V", default=0.6, doc="Forward voltage")
    Ron = Parameter("Ohm", default=0.01, min=0, doc="On resistance")
    Goff = Parameter("S", default=1e-8, min=0, doc="Off conductance")
    on = Variable("1", doc="1 while conducting, else 0")

    def equations(self):
        conducting = self.v > self.Vf
        return [self.on == if_else(conducting, 1, 0),
                self.i == if_else(conducting, (self.v - self.Vf) / self.Ron
                                  + self.Goff * self.Vf, self.Goff * self.v)]


class VariableResistor(OnePort):
    """Linear resistor whose resistance is a signal.

    Equations: ``v == R i`` with ``R`` the input. Absorbs ``R i^2``.

    Limitations: ``R`` should stay >= 0 (a negative value makes the part a source); it is
    used as given, not clipped. ``R = 0`` is a short circuit.
    """

    R = Input("Ohm", doc="Resistance (signal)")

    def equations(self):
        return [self.v == self.R * self.i]


class HeatingResistor(OnePort):
    """Resistor with a linear temperature coefficient and a thermal port (Modelica's
    ``HeatingResistor``, a ``Resistor`` with ``useHeatPort``).

    Equations::

        R == R_ref (1 + alpha (heat_port.T - T_ref))
        v == R i
        P_loss == v i
        heat_port.Q == -P_loss

    Sign convention: the electrical loss leaves the component as heat through
    ``heat_port`` (``heat_port.Q`` is positive into the component, hence the minus sign),
    so the part stores no energy: electrical power in = heat out.

    Limitations: linear in temperature; with ``alpha < 0`` and a low temperature ``R`` can
    become negative (not checked).
    """

    heat_port = HeatPort(doc="Thermal port through which the loss leaves as heat")
    R_ref = Parameter("Ohm", default=1.0, min=0, doc="Resistance at T_ref")
    T_ref = Parameter("K", default=300.15, min=0, doc="Reference temperature")
    alpha = Parameter("1/K", default=0.0, doc="Temperature coefficient of resistance")
    R = Variable("Ohm", doc="Resistance at the port temperature")
    P_loss = Variable("W", doc="Dissipated power v*i")

    def equations(self):
        return [self.R == self.R_ref * (1 + self.alpha * (self.heat_port.T - self.T_ref)),
                self.v == self.R * self.i,
                self.P_loss == self.v * self.i,
                self.heat_port.Q == -self.P_loss]


class Potentiometer(Component):
    """Potentiometer: a resistor of total value ``R`` tapped by a wiper at the signal
    position ``x`` (0 at ``n``, 1 at ``p``), Simscape's ``Potentiometer``.

    Equations, with ``xc = min(max(x, 0), 1)`` and the end resistance ``R_min`` that keeps
    each section finite::

        R_pw == R xc + R_min          (section p - wiper)
        R_wn == R (1 - xc) + R_min    (section wiper - n)
        p.v - wiper.v == R_pw p.i
        wiper.v - n.v == -R_wn n.i
        p.i + n.i + wiper.i == 0

    Sign convention: pin currents are positive into the component.

    Limitations: the position is clipped to [0, 1] without an event (the characteristic
    has a kink there); linear taper only.
    """

    p = Pin(doc="Positive end of the track")
    n = Pin(doc="Negative end of the track")
    wiper = Pin(doc="Wiper")
    x = Input("1", doc="Wiper position, 0 at n and 1 at p")
    R = Parameter("Ohm", default=1e3, min=0, doc="Total track resistance")
    R_min = Parameter("Ohm", default=1e-3, min=0, doc="End resistance of each section")
    R_pw = Variable("Ohm", doc="Resistance between p and the wiper")
    R_wn = Variable("Ohm", doc="Resistance between the wiper and n")

    def equations(self):
        xc = ca.fmin(ca.fmax(self.x, 0), 1)
        return [self.R_pw == self.R * xc + self.R_min,
                self.R_wn == self.R * (1 - xc) + self.R_min,
                self.p.v - self.wiper.v == self.R_pw * self.p.i,
                self.wiper.v - self.n.v == -self.R_wn * self.n.i,
                self.p.i + self.n.i + self.wiper.i == 0]


class MutualInductor(TwoPort):
    """Two magnetically coupled inductors (Simscape's ``Mutual Inductor``, Modelica's
    ``Transformer``).

    Equations::

        v1 == L1 der(i1) + M der(i2)
        v2 == M der(i1) + L2 der(i2)

    Stores ``L1 i1^2 / 2 + M i1 i2 + L2 i2^2 / 2``. Both currents are positive into the
    dotted pins ``p1`` and ``p2``; a positive ``M`` means fluxes add for such currents.

    Limitations: requires ``M^2 < L1 L2`` (coupling factor below 1); at perfect coupling
    the inductance matrix is singular and the model has no solution (use
    ``IdealTransformer`` with a magnetizing inductor instead). No losses or saturation.
    """

    L1 = Parameter("H", default=1e-3, min=0, doc="Primary self-inductance")
    L2 = Parameter("H", default=1e-3, min=0, doc="Secondary self-inductance")
    M = Parameter("H", default=0.5e-3, doc="Mutual inductance")

    def equations(self):
        return [self.v1 == self.L1 * der(self.i1) + self.M * der(self.i2),
                self.v2 == self.M * der(self.i1) + self.L2 * der(self.i2)]
