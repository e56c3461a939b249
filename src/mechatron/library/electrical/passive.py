"""Passive electrical components."""

from mechatron.core import Parameter, Variable, der, if_else
from mechatron.library.electrical.interfaces import OnePort


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
