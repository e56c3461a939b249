"""Electrical connector and the two-pin partial component."""

from mechatron.core import Across, Component, Connector, Through, Variable
from mechatron.core.domains import ELECTRICAL


class Pin(Connector, domain=ELECTRICAL):
    """Electrical pin."""

    v = Across("V", doc="Electric potential at the pin",
               hint="Is an electrical reference missing, or a pin left unconnected?")
    i = Through("A", doc="Current flowing into the pin")


class OnePort(Component, partial=True):
    """Two pins; current ``i`` enters at ``p`` and leaves at ``n``; ``v = p.v - n.v``."""

    p = Pin(doc="Positive pin")
    n = Pin(doc="Negative pin")
    v = Variable("V", doc="Voltage across, p.v - n.v")
    i = Variable("A", doc="Current from p to n through the component")

    def equations(self):
        return [self.v == self.p.v - self.n.v,
                self.p.i + self.n.i == 0,
                self.i == self.p.i]


class TwoPort(Component, partial=True):
    """Four pins forming two ports: port 1 (``p1``, ``n1``) and port 2 (``p2``, ``n2``).

    Equations: ``v1 = p1.v - n1.v``, ``p1.i + n1.i == 0``, ``i1 = p1.i`` and the same for
    port 2. Each current is positive flowing into the component at its ``p`` pin, so
    ``v1 i1 + v2 i2`` is the power absorbed.
    """

    p1 = Pin(doc="Positive pin of port 1")
    n1 = Pin(doc="Negative pin of port 1")
    p2 = Pin(doc="Positive pin of port 2")
    n2 = Pin(doc="Negative pin of port 2")
    v1 = Variable("V", doc="Voltage of port 1, p1.v - n1.v")
    i1 = Variable("A", doc="Current into p1 (and out of n1)")
    v2 = Variable("V", doc="Voltage of port 2, p2.v - n2.v")
    i2 = Variable("A", doc="Current into p2 (and out of n2)")

    def equations(self):
        return [self.v1 == self.p1.v - self.n1.v,
                self.p1.i + self.n1.i == 0,
                self.i1 == self.p1.i,
                self.v2 == self.p2.v - self.n2.v,
                self.p2.i + self.n2.i == 0,
                self.i2 == self.p2.i]
